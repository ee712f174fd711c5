//! Plugin crates contain no `unsafe`: the SDK holds all of it, and the
//! compiler holds them to it.

use rtk_tests::root;

/// Plugins are kept free of `unsafe` by the compiler, not by a text search:
/// every plugin crate, fixture and `rtk new` template forbids it at its
/// root (the export macros' `#[no_mangle]` comes from the SDK's macro, which
/// the lint does not flag; `authoring::authoring_new_*` builds the templates
/// with the attribute).
#[test]
fn plugin_crates_forbid_unsafe_code() {
    let mut roots: Vec<std::path::PathBuf> = Vec::new();
    for d in ["plugins", "tests/fixtures"] {
        for e in std::fs::read_dir(root().join(d)).unwrap().flatten() {
            let lib = e.path().join("src/lib.rs");
            // `notplugin` is a library that is not an rtk plugin: it
            // exports a symbol by hand, which needs `unsafe`'s attribute.
            if lib.is_file() && !e.path().ends_with("notplugin") {
                roots.push(lib);
            }
        }
    }
    for e in std::fs::read_dir(root().join("host/templates"))
        .unwrap()
        .flatten()
    {
        if e.path().extension().is_some_and(|x| x == "rs") {
            roots.push(e.path());
        }
    }
    assert!(roots.len() >= 45, "{roots:?}");
    for f in roots {
        let text = std::fs::read_to_string(&f).unwrap();
        let header: Vec<&str> = text
            .lines()
            .take_while(|l| l.starts_with("//!") || l.starts_with("#!["))
            .collect();
        assert!(
            header.contains(&"#![forbid(unsafe_code)]"),
            "{} does not forbid unsafe code at its root",
            f.display()
        );
    }
}
