//! A plugin that panics or fails, anywhere, gives an error naming it, a
//! non-zero exit and no output file: nothing is swallowed into a default.

use rtk_tests::*;

fn run(where_: &str) -> Run {
    let folder = plugin_folder(fixtures_dir(), &["panicky"]);
    let scene = format!(
        "[render]\nwidth = 8\nheight = 8\nroot = \"x\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
         [objects.x]\nclass = \"panicky\"\npanic_in = \"{where_}\"\n"
    );
    let (run, img) = render_scene(&scene, &["--plugin-path", folder.path().to_str().unwrap()]);
    assert!(img.is_none());
    assert!(!run.ok);
    run
}

fn says(r: &Run, needle: &str) {
    assert!(
        r.stderr.contains(needle),
        "missing {needle:?} in:\n{}",
        r.stderr
    );
}

#[test]
fn panic_in_create() {
    let r = run("create");
    says(
        &r,
        "plugin `panicky` panicked in create: deliberate panic in create",
    );
    says(&r, "objects.x");
}

/// A panic in `add_child` (the object given a child to hold).
#[test]
fn panic_in_add_child() {
    let folder = plugin_folder(fixtures_dir(), &["panicky"]);
    let scene = "[render]\nwidth = 8\nheight = 8\nroot = \"x\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
                 [objects.s]\nclass = \"sphere\"\n\
                 [objects.x]\nclass = \"panicky\"\npanic_in = \"add_child\"\nchildren = [\"s\"]\n";
    let (r, img) = render_scene(scene, &["--plugin-path", folder.path().to_str().unwrap()]);
    assert!(!r.ok && img.is_none());
    says(
        &r,
        "plugin `panicky` panicked in add_child: deliberate panic in add_child",
    );
    says(&r, "objects.x");
}

#[test]
fn panic_in_prepare() {
    says(
        &run("prepare"),
        "plugin `panicky` panicked in prepare: deliberate panic in prepare",
    );
}

#[test]
fn panic_in_a_parallel_for_task() {
    says(
        &run("parallel_task"),
        "plugin `panicky` panicked in prepare: a parallel_for task panicked: deliberate panic in task 777",
    );
}

#[test]
fn panic_in_bounds() {
    let r = run("bounds");
    says(
        &r,
        "plugin `panicky` panicked in bounds: deliberate panic in bounds",
    );
    says(&r, "render");
}

#[test]
fn panic_in_intersect() {
    says(
        &run("intersect"),
        "plugin `panicky` panicked in intersect: deliberate panic in intersect",
    );
}

#[test]
fn panic_in_local_geom() {
    says(
        &run("local_geom"),
        "plugin `panicky` panicked in local_geom: deliberate panic in local_geom",
    );
}

/// A panic in a shadow ray's any-hit query, reached through a light and a
/// Lambert shader: the failure crosses two more plugins and still stops the render.
#[test]
fn panic_in_occluded_under_whitted() {
    let folder = plugin_folder(fixtures_dir(), &["panicky"]);
    let scene = "[render]\nwidth = 8\nheight = 8\nroot = \"w\"\n[cameras.c]\nclass = \"pinhole\"\n\
                 [lights.l]\nclass = \"point\"\nposition = [0.0, 0.0, 10.0]\n\
                 [shaders.s]\nclass = \"lambert\"\n\
                 [objects.x]\nclass = \"panicky\"\npanic_in = \"occluded\"\n\
                 [objects.w]\nclass = \"list\"\nchildren = [{ object = \"x\", shader = \"s\" }]\n";
    let (r, img) = render_scene(scene, &["--plugin-path", folder.path().to_str().unwrap()]);
    assert!(!r.ok && img.is_none());
    says(
        &r,
        "plugin `panicky` panicked in occluded: deliberate panic in occluded",
    );
}

/// Render the `panicky` fixture with `fault` in `intersect`: the process's
/// exit status, its stderr, and whether it wrote the output.
#[cfg(unix)]
fn render_fault(fault: &str, extra: &[&str]) -> (std::process::ExitStatus, String, bool) {
    let folder = plugin_folder(fixtures_dir(), &["panicky"]);
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("fault.toml");
    std::fs::write(
        &scene,
        format!(
            "[render]\nwidth = 8\nheight = 8\nroot = \"x\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
             [objects.x]\nclass = \"panicky\"\npanic_in = \"intersect\"\nfault = \"{fault}\"\n"
        ),
    )
    .unwrap();
    let out = dir.path().join("fault.png");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(&["--plugin-path", folder.path().to_str().unwrap()]);
    args.extend_from_slice(extra);
    let o = rtk(&args).output().unwrap();
    (
        o.status,
        String::from_utf8_lossy(&o.stderr).into_owned(),
        out.exists(),
    )
}

/// An abort inside a plugin cannot be caught, but it is named: the host's
/// SIGABRT handler finds the plugin's library on the aborting stack. The
/// process still dies of SIGABRT (a shell or a farm sees the signal), and
/// writes nothing.
#[test]
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn an_abort_in_a_plugin_names_the_plugin_and_keeps_the_signal() {
    use std::os::unix::process::ExitStatusExt;
    let (status, stderr, wrote) = render_fault("abort", &[]);
    assert_eq!(status.signal(), Some(6), "{status:?}: {stderr}");
    assert!(
        stderr.contains("plugin `panicky` (")
            && stderr.contains("librtk_panicky.so) stopped the process with SIGABRT"),
        "{stderr}"
    );
    assert!(!wrote);
}

/// A plugin call that never returns does not hang the host when a time
/// limit is given: past the limit and a grace period the render threads
/// name the plugin they are in, and rtk exits with status 124.
#[test]
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn a_plugin_call_that_never_returns_is_stopped_after_the_time_limit() {
    let (status, stderr, wrote) = render_fault("hang", &["--time-limit", "0.5", "--threads", "2"]);
    assert_eq!(status.code(), Some(124), "{stderr}");
    assert!(stderr.contains("a plugin call does not return"), "{stderr}");
    assert!(stderr.contains("inside plugin `panicky`"), "{stderr}");
    assert!(!wrote);
}
