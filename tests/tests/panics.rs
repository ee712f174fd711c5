//! A plugin that panics gives an error naming it, a non-zero exit and no output.

use rtk_tests::*;

fn run(where_: &str) -> Run {
    let folder = plugin_folder(fixtures_dir(), &["panicky"]);
    let scene = format!(
        "[render]\nwidth = 8\nheight = 8\nroot = \"x\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
         [objects.x]\nclass = \"panicky\"\npanic_in = \"{where_}\"\n"
    );
    let (run, img) = render_scene(&scene, &["--plugin-path", folder.path().to_str().unwrap()]);
    assert!(img.is_none());
    run
}

#[test]
fn panic_in_create() {
    let r = run("create");
    assert!(!r.ok);
    assert!(
        r.stderr
            .contains("plugin 'panicky' panicked in create: deliberate panic in create"),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("objects.x"), "{}", r.stderr);
}

#[test]
fn panic_in_prepare() {
    let r = run("prepare");
    assert!(!r.ok);
    assert!(
        r.stderr.contains("plugin 'panicky' panicked in prepare"),
        "{}",
        r.stderr
    );
}

#[test]
fn panic_in_intersect() {
    let r = run("intersect");
    assert!(!r.ok);
    assert!(
        r.stderr
            .contains("plugin `panicky` panicked in intersect: deliberate panic in intersect"),
        "{}",
        r.stderr
    );
}

#[test]
fn panic_in_a_parallel_for_task() {
    let r = run("parallel_task");
    assert!(!r.ok);
    assert!(
        r.stderr
            .contains("plugin 'panicky' panicked in prepare: a parallel_for task panicked"),
        "{}",
        r.stderr
    );
}
