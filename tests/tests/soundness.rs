//! The boundary is sound by construction (docs/design.md, "Sound by
//! construction"): what a plugin is handed stays valid for as long as the
//! plugin holds it. Here the `keeper` fixture keeps a child in a `static`
//! past the world it came from — safe code, no `unsafe` — and a second world
//! answers every query from it: the answers must be the kept sphere's, and
//! valgrind's memcheck must find no invalid read or write doing it.

use rtk_kernel::abi::{Hit, Ray, TraceCtx};
use rtk_kernel::glam::Vec3;
use rtk_kernel::RngState;
use rtk_tests::{bin_dir, fixtures_dir, world_with_plugins};

fn keeper_scene(keep: bool) -> String {
    format!(
        "[render]\nroot = \"world\"\nintegrator = \"normals\"\norigin = \"world\"\n\
         [cameras.c]\nclass = \"pinhole\"\n\
         [objects.ball]\nclass = \"sphere\"\ncenter = [0.5, 0.0, 0.0]\nradius = 2.0\n\
         [objects.world]\nclass = \"keeper\"\nkeep = {keep}\nchildren = {}\n",
        if keep { "[\"ball\"]" } else { "[]" }
    )
}

/// Build a world that hands the sphere to the keeper, drop it, build one
/// that answers from the kept sphere, and check its answers against the
/// sphere's closed form.
fn kept_child_answers_correctly() {
    let dirs = [bin_dir(), fixtures_dir()];
    drop(world_with_plugins(&keeper_scene(true), &dirs));
    let w = world_with_plugins(&keeper_scene(false), &dirs);
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut rng = RngState::seeded(5);
    let c = Vec3::new(0.5, 0.0, 0.0);
    for _ in 0..200 {
        let o = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0), 10.0);
        let ray = Ray::new(o, Vec3::new(0.0, 0.0, -1.0));
        let mut hit = Hit::new();
        let found = w.root.intersect(&mut ctx, &ray, &mut hit);
        // The sphere's nearest root along -z from z = 10.
        let d2 = (o.x - c.x).powi(2) + (o.y - c.y).powi(2);
        let expect = (d2 < 4.0).then(|| 10.0 - (4.0 - d2).sqrt());
        match (found, expect) {
            (true, Some(t)) => assert!((hit.t - t).abs() < 1e-4, "t {} against {t}", hit.t),
            (false, None) => {}
            _ => panic!("from {o}: hit {found}, expected {expect:?}"),
        }
    }
    assert!(ctx.failure().is_none(), "{:?}", ctx.failure());
}

#[test]
fn a_child_kept_past_its_world_still_answers() {
    kept_child_answers_correctly();
}

/// The same, in a copy of this test binary run under valgrind's memcheck:
/// any read or write of freed memory fails it. (Valgrind is on every
/// machine rtk is built on; this test fails rather than passes if it is not.)
#[test]
fn a_child_kept_past_its_world_is_clean_under_memcheck() {
    if std::env::var_os("RTK_UNDER_MEMCHECK").is_some() {
        return kept_child_answers_correctly();
    }
    // Build the plugins and fixtures before valgrind runs (it would be slow).
    let _ = (bin_dir(), fixtures_dir());
    let exe = std::env::current_exe().expect("test binary");
    let out = std::process::Command::new("valgrind")
        .args(["--tool=memcheck", "--error-exitcode=99", "--quiet"])
        .arg(&exe)
        .args([
            "soundness::a_child_kept_past_its_world_is_clean_under_memcheck",
            "--exact",
            "--test-threads=1",
        ])
        .env("RTK_UNDER_MEMCHECK", "1")
        .output()
        .expect("valgrind is needed for this test: apt-get install valgrind");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "memcheck failed ({:?}):\n{err}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("1 passed"),
        "the check did not run under valgrind"
    );
}
