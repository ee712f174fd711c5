//! Bad scenes: each gives a clear error naming file, line, object and key,
//! a non-zero exit, and no output file.

use rtk_tests::*;

const GOOD: &str = r#"[render]
width = 8
height = 8
root = "world"
integrator = "normals"

[cameras.main]
class = "pinhole"

[objects.ball]
class = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0

[objects.world]
class = "list"
children = [{ object = "ball" }]
"#;

/// Replace `from` by `to` in the good scene and check the error mentions every needle.
fn bad(from: &str, to: &str, needles: &[&str]) {
    assert!(GOOD.contains(from), "{from}");
    let (run, img) = render_scene(&GOOD.replace(from, to), &[]);
    assert!(!run.ok, "expected failure for {to:?}");
    assert!(img.is_none());
    for n in needles {
        assert!(run.stderr.contains(n), "missing {n:?} in: {}", run.stderr);
    }
}

#[test]
fn the_good_scene_renders() {
    let (run, img) = render_scene(GOOD, &[]);
    assert!(run.ok, "{}", run.stderr);
    assert!(img.is_some());
}

#[test]
fn missing_file() {
    let out = rtk(&[
        "render",
        "/nonexistent/scene.toml",
        "-o",
        "/tmp/rtk-never.png",
    ])
    .output()
    .unwrap();
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("/nonexistent/scene.toml") && e.contains("cannot read"),
        "{e}"
    );
}

#[test]
fn toml_syntax_error() {
    bad(
        "width = 8",
        "width = = 8",
        &["scene.toml:2:", "TOML syntax error"],
    );
}

#[test]
fn unknown_key_in_render() {
    bad(
        "width = 8",
        "widht = 8",
        &["scene.toml:2:1", "render", "key `widht`", "unknown key"],
    );
}

#[test]
fn unknown_key_in_plugin_parameters() {
    bad(
        "center = [",
        "centre = [",
        &[
            "scene.toml:12:1",
            "objects.ball",
            "key `centre`",
            "unknown field",
        ],
    );
}

#[test]
fn wrong_type_in_plugin_parameters() {
    bad(
        "radius = 1.0",
        "radius = \"big\"",
        &[
            "scene.toml:13:10",
            "objects.ball",
            "key `radius`",
            "expected a number, found the string \"big\"",
        ],
    );
}

#[test]
fn wrong_type_in_render() {
    bad(
        "width = 8",
        "width = \"wide\"",
        &["scene.toml:2:9", "key `width`", "expected an integer"],
    );
}

#[test]
fn nan_number() {
    bad(
        "center = [0.0, 0.0, 0.0]",
        "center = [0.0, nan, 0.0]",
        &[
            "scene.toml:12:16",
            "objects.ball",
            "key `center[1]`",
            "finite",
        ],
    );
}

#[test]
fn infinite_number() {
    bad(
        "radius = 1.0",
        "radius = inf",
        &["scene.toml:13:10", "key `radius`", "finite"],
    );
}

#[test]
fn negative_radius() {
    bad(
        "radius = 1.0",
        "radius = -1.0",
        &[
            "scene.toml:13:10",
            "objects.ball",
            "key `radius`",
            "positive",
        ],
    );
}

#[test]
fn unknown_reference() {
    bad(
        "{ object = \"ball\" }",
        "{ object = \"bal\" }",
        &[
            "scene.toml:17:",
            "objects.world.children[0]",
            "key `object`",
            "no object named `bal`",
            "objects defined: ball, world",
        ],
    );
}

#[test]
fn unknown_shader_reference() {
    bad(
        "{ object = \"ball\" }",
        "{ object = \"ball\", shader = \"red\" }",
        &["scene.toml:17:", "key `shader`", "no shader named `red`"],
    );
}

#[test]
fn instancing_cycle() {
    let scene = GOOD
        .replace(
            "class = \"sphere\"",
            "class = \"list\"\nchildren = [\"world\"]",
        )
        .replace("center = [0.0, 0.0, 0.0]\nradius = 1.0\n", "");
    let (run, _) = render_scene(&scene, &[]);
    assert!(!run.ok);
    assert!(
        run.stderr
            .contains("instancing cycle: world -> ball -> world"),
        "{}",
        run.stderr
    );
    assert!(
        run.stderr.contains("objects.ball.children[0]") && run.stderr.contains("key `object`"),
        "{}",
        run.stderr
    );
}

#[test]
fn bad_set_override_names_the_command_line() {
    let (run, _) = render_scene(GOOD, &["--set", "render.spp=0"]);
    assert!(!run.ok);
    assert!(
        run.stderr.contains("--set render.spp=0") && run.stderr.contains("key `spp`"),
        "{}",
        run.stderr
    );
}

#[test]
fn bad_output_extension_is_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let sp = dir.path().join("s.toml");
    std::fs::write(&sp, GOOD).unwrap();
    let out = rtk(&[
        "render",
        sp.to_str().unwrap(),
        "-o",
        dir.path().join("x.jpg").to_str().unwrap(),
    ])
    .output()
    .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png or .exr"));
}

#[test]
fn singular_transform() {
    bad("{ object = \"ball\" }", "{ object = \"ball\", transform = [{ translate = [1.0, 0.0, 0.0] }, { scale = [1.0, 0.0, 1.0] }] }", &["scene.toml:17:", "objects.world.children[0]", "key `transform[1]`", "singular"]);
}

#[test]
fn transform_step_with_two_keys() {
    bad(
        "{ object = \"ball\" }",
        "{ object = \"ball\", transform = [{ scale = 2.0, rotate_y = 3.0 }] }",
        &["key `transform[0]`", "exactly one key"],
    );
}

#[test]
fn image_too_large() {
    bad(
        "width = 8\nheight = 8",
        "width = 65536\nheight = 65536",
        &["scene.toml:2:9", "key `width`", "limit"],
    );
}

#[test]
fn date_time_value() {
    bad(
        "width = 8",
        "width = 1979-05-27",
        &["scene.toml:2:9", "date-times are not used"],
    );
}

#[test]
fn integrator_of_the_wrong_type() {
    bad(
        "integrator = \"normals\"",
        "integrator = 5",
        &[
            "scene.toml:5:14",
            "key `integrator`",
            "class name or a table",
        ],
    );
}

/// A DAG that doubles at each of 30 levels expands to 2^30 instances, which
/// a `list` at each level would visit on every ray: refused with the limit
/// named, before anything is created; raising the limit lets the check pass.
#[test]
fn exploding_instancing_is_refused() {
    let mut s = String::from(
        "[render]\nwidth = 4\nheight = 4\nroot = \"l30\"\nintegrator = \"normals\"\n\
         [cameras.main]\nclass = \"pinhole\"\n[objects.l0]\nclass = \"sphere\"\n",
    );
    for k in 1..=30 {
        s += &format!(
            "[objects.l{k}]\nclass = \"list\"\nchildren = [\"l{p}\", \"l{p}\"]\n",
            p = k - 1
        );
    }
    let (run, img) = render_scene(&s, &[]);
    assert!(!run.ok && img.is_none());
    assert!(
        run.stderr.contains("1.074e9") && run.stderr.contains("max_instances"),
        "{}",
        run.stderr
    );
    // 20 levels (about a million) are within the default limit.
    let (run, _) = render_scene(&s.replace("root = \"l30\"", "root = \"l20\""), &[]);
    assert!(!run.stderr.contains("max_instances"), "{}", run.stderr);
}

/// `include`: the included files' sections merge into the scene; an error
/// inside one names that file and line; loops, definitions given twice and
/// (with --safe) files outside the scene's folder are refused.
#[test]
fn includes_merge_and_report_their_own_files() {
    let dir = tempfile::tempdir().unwrap();
    let parts = dir.path().join("parts");
    std::fs::create_dir(&parts).unwrap();
    let write = |p: &std::path::Path, s: &str| std::fs::write(p, s).unwrap();
    write(
        &dir.path().join("main.toml"),
        "include = [\"parts/camera.toml\", \"parts/ball.toml\"]\n[render]\nwidth = 8\nheight = 8\nroot = \"world\"\nintegrator = \"normals\"\n[objects.world]\nclass = \"list\"\nchildren = [\"ball\"]\n",
    );
    write(
        &parts.join("camera.toml"),
        "[cameras.main]\nclass = \"pinhole\"\n",
    );
    write(
        &parts.join("ball.toml"),
        "include = \"more.toml\"\n[objects.ball]\nclass = \"sphere\"\nradius = 1.0\n",
    );
    write(
        &parts.join("more.toml"),
        "[shaders.unused]\nclass = \"lambert\"\n",
    );
    let main = dir.path().join("main.toml");
    let out = tempfile::tempdir().unwrap();
    let (run, whole) = render_file(&main, out.path(), &[]);
    assert!(run.ok, "{}", run.stderr);
    // The same scene in one file renders the same image.
    let (run, single) = render_scene(&GOOD.replace("center = [0.0, 0.0, 0.0]\n", ""), &[]);
    assert!(run.ok, "{}", run.stderr);
    assert_eq!(whole.unwrap().data, single.unwrap().data);

    let fails = |what: &str, needles: &[&str]| {
        let out = tempfile::tempdir().unwrap();
        let (run, img) = render_file(&main, out.path(), &[]);
        assert!(!run.ok && img.is_none(), "{what} accepted");
        for n in needles {
            assert!(
                run.stderr.contains(n),
                "{what}: missing {n:?} in {}",
                run.stderr
            );
        }
    };
    write(
        &parts.join("ball.toml"),
        "include = \"more.toml\"\n[objects.ball]\nclass = \"sphere\"\nradius = -1.0\n",
    );
    fails("a bad value", &["ball.toml:4:10", "objects.ball", "radius"]);
    write(
        &parts.join("ball.toml"),
        "include = \"../main.toml\"\n[objects.ball]\nclass = \"sphere\"\n",
    );
    fails("a loop", &["ball.toml:1:11", "include loop"]);
    write(
        &parts.join("ball.toml"),
        "[objects.ball]\nclass = \"sphere\"\n[objects.world]\nclass = \"list\"\n",
    );
    fails(
        "a definition twice",
        &["ball.toml:3:10", "objects.world", "defined both"],
    );
    let elsewhere = tempfile::tempdir().unwrap();
    let outside = elsewhere.path().join("shaders.toml");
    write(&outside, "[shaders.x]\nclass = \"lambert\"\n");
    write(
        &parts.join("ball.toml"),
        &format!(
            "include = {:?}\n[objects.ball]\nclass = \"sphere\"\n",
            outside.display().to_string()
        ),
    );
    let out = tempfile::tempdir().unwrap();
    let (run, _) = render_file(&main, out.path(), &[]);
    assert!(run.ok, "{}", run.stderr);
    let out = tempfile::tempdir().unwrap();
    let (run, _) = render_file(&main, out.path(), &["--safe"]);
    assert!(!run.ok && run.stderr.contains("--safe"), "{}", run.stderr);
}
