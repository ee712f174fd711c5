//! Plugin crates contain no `unsafe`: the SDK holds all of it.

use rtk_tests::root;

fn rust_files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn plugin_crates_have_no_unsafe() {
    let mut files = Vec::new();
    for d in ["plugins", "tests/fixtures"] {
        for e in std::fs::read_dir(root().join(d)).unwrap().flatten() {
            if e.path().join("src").is_dir() {
                rust_files(&e.path().join("src"), &mut files);
            }
        }
    }
    assert!(files.len() >= 15, "{files:?}");
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        assert!(!text.contains("unsafe"), "{} uses unsafe", f.display());
    }
}
