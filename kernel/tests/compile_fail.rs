//! Safe plugin code cannot reach a raw record or call an entry: each file in
//! `ui/` is a plugin-side attempt that must not compile (with the error in
//! its `.stderr` file). Together with the no-`unsafe` check on plugin crates
//! (`tests/tests/hygiene.rs`), this is what makes the ABI sound by
//! construction rather than by discipline.

#[test]
fn plugin_code_cannot_reach_raw_records() {
    trybuild::TestCases::new().compile_fail("tests/ui/*.rs");
}
