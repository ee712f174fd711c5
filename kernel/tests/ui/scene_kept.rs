// The scene is lent for one call: an integrator cannot keep it.
use rtk_kernel::{Color, Ray, Scene, TraceCtx};
use std::sync::Mutex;

static KEPT: Mutex<Option<&'static Scene>> = Mutex::new(None);

fn main() {
    fn li(_ctx: &mut TraceCtx, scene: &Scene, _ray: &Ray) -> Color {
        *KEPT.lock().unwrap() = Some(scene);
        Color::BLACK
    }
    let _ = li;
}
