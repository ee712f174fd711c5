//! Libraries that must be refused before any of their code runs.

use rtk_tests::*;

fn scene(class: &str) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
root = "x"
integrator = "normals"
[cameras.c]
class = "pinhole"
[objects.x]
class = "{class}"
panic_in = "never"
"#
    )
}

fn run_with(dir: &std::path::Path, class: &str) -> Run {
    let folder = plugin_folder(dir, &[class]);
    let (run, img) = render_scene(
        &scene(class),
        &["--plugin-path", folder.path().to_str().unwrap()],
    );
    assert!(img.is_none());
    run
}

#[test]
fn a_plugin_built_against_another_kernel_abi_is_refused() {
    let run = run_with(other_abi_dir(), "otherabi");
    assert!(!run.ok);
    let e = &run.stderr;
    assert!(
        e.contains("plugin 'otherabi'") && e.contains("does not match this rtk's kernel records"),
        "{e}"
    );
    assert!(e.contains("Rebuild the plugin against rtk-kernel"), "{e}");
    assert!(
        e.contains("mismatched type (expected u32, found u64)"),
        "the difference is named: {e}"
    );
    assert!(e.contains("generation: u64"), "the field is named: {e}");
}

#[test]
fn a_plugin_built_against_abi_2_is_refused_with_both_versions_and_the_fix() {
    let run = run_with(abi_v2_dir(), "abiv2");
    assert!(!run.ok);
    let e = &run.stderr;
    assert!(
        e.contains("plugin 'abiv2'") && e.contains("was built against ABI 2 (rtk-abi 2.0.0)"),
        "{e}"
    );
    let ours = format!(
        "this rtk uses ABI 3 (rtk-abi {}). Rebuild the plugin against rtk-kernel 0.1.0",
        rtk_kernel::abi::ABI_CRATE_VERSION
    );
    assert!(e.contains(&ours), "{e}");
}

#[test]
fn a_plugin_built_against_a_later_minor_abi_and_another_bvh_loads() {
    let folder = plugin_folder(later_minor_dir(), &["laterminor"]);
    let (run, img) = render_scene(
        &scene("laterminor"),
        &["--plugin-path", folder.path().to_str().unwrap()],
    );
    assert!(run.ok && img.is_some(), "{}", run.stderr);
}

#[test]
fn a_library_that_is_not_a_plugin_is_refused() {
    let run = run_with(fixtures_dir(), "notplugin");
    assert!(!run.ok);
    assert!(
        run.stderr.contains("is not an rtk plugin"),
        "{}",
        run.stderr
    );
}

#[test]
fn a_plugin_built_with_panic_abort_is_refused() {
    let run = run_with(fixtures_dir(), "abortplugin");
    assert!(!run.ok);
    assert!(
        run.stderr.contains("plugin 'abortplugin'") && run.stderr.contains("panic = \"abort\""),
        "{}",
        run.stderr
    );
}

#[test]
fn the_same_fixture_loads_when_it_is_sound() {
    // Control: the panicky fixture, told not to panic, renders.
    let folder = plugin_folder(fixtures_dir(), &["panicky"]);
    let (run, img) = render_scene(
        &scene("panicky"),
        &["--plugin-path", folder.path().to_str().unwrap()],
    );
    assert!(run.ok, "{}", run.stderr);
    assert!(img.unwrap().data.iter().any(|&v| v > 0.0));
}
