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
