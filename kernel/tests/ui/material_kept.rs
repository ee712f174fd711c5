// A material borrows the scene it came from: it cannot outlive the call.
use rtk_kernel::{LocalGeom, Material, Scene};

fn main() {
    fn keep(scene: &Scene, g: &LocalGeom) -> Material<'static> {
        scene.material(g).unwrap()
    }
    let _ = keep;
}
