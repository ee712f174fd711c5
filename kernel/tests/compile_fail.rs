//! Safe plugin code cannot misuse the boundary: each file in `ui/` is a
//! plugin-side attempt that must not compile (with the error in its
//! `.stderr` file) — calling a raw entry, forging a child, a live handle or
//! a scene, changing a shared child, keeping the scene or a material past
//! the call. Together with `#![forbid(unsafe_code)]` in every plugin crate
//! (checked by `tests/tests/hygiene.rs`) and the counted handles (a child or
//! an emitter kept past its world still answers: `tests/tests/soundness.rs`),
//! this is what makes the ABI sound by construction rather than by
//! discipline.

#[test]
fn plugin_code_cannot_misuse_the_boundary() {
    trybuild::TestCases::new().compile_fail("tests/ui/*.rs");
}
