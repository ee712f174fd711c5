//! The user's promise: drop a new aggregate plugin into a plugins folder and
//! render with it, without rebuilding rtk.

use rtk_tests::*;

fn scene(inner: &str) -> String {
    format!(
        r#"
[render]
width = 96
height = 72
root = "world"
integrator = "whitted"
[cameras.main]
class = "pinhole"
eye = [2.0, 6.0, 24.0]
look_at = [0.0, 4.0, 0.0]
fov_y = 35.0
[lights.key]
class = "point"
position = [10.0, 18.0, 12.0]
intensity = [500.0, 480.0, 440.0]
[shaders.clay]
class = "lambert"
albedo = [0.8, 0.6, 0.4]
[objects.bunny]
class = "mesh"
file = "{bunny}"
[objects.ball]
class = "sphere"
center = [5.0, 2.0, 0.0]
radius = 2.0
[objects.inner]
class = "{inner}"
children = [{{ object = "bunny", shader = "clay" }}, "ball"]
[objects.world]
class = "list"
children = ["inner"]
"#,
        bunny = root().join("scenes/meshes/bunny.ply").display()
    )
}

fn digest(p: &std::path::Path) -> Vec<u8> {
    std::fs::read(p).unwrap()
}

#[test]
fn a_dropped_in_aggregate_renders_exactly_like_list() {
    let rtk_before = digest(&rtk_path());
    let plugins = plugin_folder(fixtures_dir(), &["dropin"]);
    let (a, ia) = render_scene(
        &scene("dropin"),
        &["--plugin-path", plugins.path().to_str().unwrap(), "--stats"],
    );
    assert!(a.ok, "{}", a.stderr);
    let (b, ib) = render_scene(&scene("list"), &[]);
    assert!(b.ok, "{}", b.stderr);
    let (ia, ib) = (ia.unwrap(), ib.unwrap());
    assert!(ia.data.iter().any(|&v| v > 0.1));
    assert!(
        ia.data
            .iter()
            .zip(&ib.data)
            .all(|(x, y)| x.to_bits() == y.to_bits()),
        "images differ"
    );
    // The drop-in was really used, from the temporary folder.
    let mapped = a.stats()["plugins_mapped"].to_string();
    assert!(
        mapped.contains(
            &plugins
                .path()
                .join("librtk_dropin.so")
                .display()
                .to_string()
        ),
        "{mapped}"
    );
    // rtk itself was not rebuilt.
    assert_eq!(rtk_before, digest(&rtk_path()));
}
