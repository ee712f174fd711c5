// Integrators and shaders see the host through `Scene`, which neither hands
// out its record nor can be made from one.
use rtk_kernel::abi::SceneRef;
use rtk_kernel::Scene;

fn main() {
    fn grab(s: &Scene) -> &SceneRef {
        s.raw()
    }
    fn forge(r: &SceneRef) -> Scene<'_> {
        Scene::new(r)
    }
    let _ = (grab, forge);
}
