// Integrators and shaders see the host through `Scene`, which neither hands
// out its record nor can be made from one without `unsafe`.
#![forbid(unsafe_code)]
use rtk_kernel::abi::SceneRef;
use rtk_kernel::Scene;

fn main() {
    fn grab(s: &Scene) -> &SceneRef {
        s.raw()
    }
    fn forge(r: &SceneRef) -> &Scene {
        unsafe { Scene::from_record(r) }
    }
    let _ = (grab, forge);
}
