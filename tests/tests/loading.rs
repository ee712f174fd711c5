//! Only the plugins reachable from the root are loaded, counted from what the
//! OS has mapped into the rtk process (/proc/self/maps), not from a log line.

use rtk_tests::*;

const SCENE: &str = r#"
[render]
width = 16
height = 16
root = "world"
integrator = "normals"
camera = "main"

[cameras.main]
class = "pinhole"

[cameras.unused]
class = "nosuchcamera"

[shaders.unused]
class = "flat"

[objects.ball]
class = "sphere"

[objects.unreachable]
class = "nosuchclass"
children = ["ball"]

[objects.world]
class = "list"
children = ["ball", "ball"]
"#;

fn mapped_classes(stats: &serde_json::Value) -> Vec<String> {
    let mut v: Vec<String> = stats["plugins_mapped"]
        .as_array()
        .expect("plugins_mapped")
        .iter()
        .map(|p| {
            let f = std::path::Path::new(p.as_str().unwrap())
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned();
            f.trim_start_matches("librtk_")
                .trim_end_matches(".so")
                .to_string()
        })
        .collect();
    v.sort();
    v
}

#[test]
#[cfg(target_os = "linux")]
fn maps_exactly_the_reachable_plugins() {
    let (run, _) = render_scene(SCENE, &["--stats"]);
    assert!(run.ok, "{}", run.stderr);
    let s = run.stats();
    assert_eq!(mapped_classes(&s), ["list", "normals", "pinhole", "sphere"]);
    // `ball` is instanced twice but created once (a DAG): ball + world.
    assert_eq!(s["objects_created"], 2);
}

#[test]
#[cfg(target_os = "linux")]
fn a_scene_with_fewer_classes_maps_fewer_plugins() {
    let scene = SCENE.replace("root = \"world\"", "root = \"ball\"");
    let (run, _) = render_scene(&scene, &["--stats"]);
    assert!(run.ok, "{}", run.stderr);
    assert_eq!(
        mapped_classes(&run.stats()),
        ["normals", "pinhole", "sphere"]
    );
}

#[test]
fn unknown_class_lists_folders_and_classes() {
    let scene = SCENE.replace("root = \"world\"", "root = \"unreachable\"");
    let (run, _) = render_scene(&scene, &[]);
    assert!(!run.ok);
    let e = &run.stderr;
    assert!(e.contains("scene.toml:22:9"), "{e}");
    assert!(
        e.contains("objects.unreachable") && e.contains("unknown class `nosuchclass`"),
        "{e}"
    );
    assert!(e.contains("folders searched"), "{e}");
    assert!(e.contains(&bin_dir().display().to_string()), "{e}");
    assert!(
        e.contains("classes found there:") && e.contains("sphere") && e.contains("pinhole"),
        "{e}"
    );
}

#[test]
fn class_names_are_identifiers_not_paths() {
    let scene = SCENE.replace("class = \"sphere\"", "class = \"../../tmp/evil\"");
    let (run, _) = render_scene(&scene, &[]);
    assert!(!run.ok);
    assert!(run.stderr.contains("plain identifier"), "{}", run.stderr);
}

#[test]
fn plugins_command_lists_kinds_and_parameters() {
    let out = rtk(&["plugins"]).output().unwrap();
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "sphere  [object]",
        "list  [object]",
        "pinhole  [camera]",
        "normals  [integrator]",
        "flat  [shader]",
        "| `radius` |",
    ] {
        assert!(s.contains(needle), "missing {needle:?} in:\n{s}");
    }
}

#[test]
fn version_flag() {
    let out = rtk(&["--version"]).output().unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("rtk "));
}
