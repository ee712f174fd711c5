//! Golden translations: every `tests/golden/NAME.xml` imports to exactly
//! `tests/golden/NAME.toml`, and its warnings (if any) are exactly the
//! lines of `NAME.warnings`. One file per Mitsuba construct; the files
//! `include`d by a case, and the meshes, live in `golden/inc/` and
//! `golden/meshes/` or beside the cases (any `.xml` under a sub-folder is
//! not a case).
//!
//! The expected files are the specification: `RTK_BLESS=1 cargo test -p
//! rtk-import --test golden` rewrites them from the importer's output, and
//! each rewritten file must then be read by hand before it is committed.
//!
//! The paths are relative to the crate (cargo runs tests there), so the
//! header's `from tests/golden/NAME.xml` is the same on every machine.

use rtk_import::{import, Options};
use std::path::{Path, PathBuf};

const DIR: &str = "tests/golden";

/// The case names: the `.xml` files directly in [`DIR`], sorted.
fn cases() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(DIR)
        .expect("tests/golden")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "xml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A line diff of `want` and `got` (longest common subsequence), `-` for
/// expected lines missing, `+` for lines the importer wrote instead.
fn diff(want: &str, got: &str) -> String {
    let (a, b): (Vec<&str>, Vec<&str>) = (want.lines().collect(), got.lines().collect());
    let mut lcs = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for i in (0..a.len()).rev() {
        for j in (0..b.len()).rev() {
            lcs[i][j] = if a[i] == b[j] {
                lcs[i + 1][j + 1] + 1
            } else {
                lcs[i + 1][j].max(lcs[i][j + 1])
            };
        }
    }
    let (mut i, mut j, mut out) = (0, 0, String::new());
    while i < a.len() || j < b.len() {
        if i < a.len() && j < b.len() && a[i] == b[j] {
            out += &format!("  {}\n", a[i]);
            (i, j) = (i + 1, j + 1);
        } else if j < b.len() && (i == a.len() || lcs[i][j + 1] >= lcs[i + 1][j]) {
            out += &format!("+ {}\n", b[j]);
            j += 1;
        } else {
            out += &format!("- {}\n", a[i]);
            i += 1;
        }
    }
    out
}

/// Compare `got` with the file `path` (absent = empty), or rewrite it when
/// blessing. Returns the mismatch's report.
fn check(path: &Path, got: &str, bless: bool) -> Option<String> {
    let want = std::fs::read_to_string(path).unwrap_or_default();
    if want == got {
        return None;
    }
    if bless {
        if got.is_empty() {
            std::fs::remove_file(path).expect("removing an empty expected file");
        } else {
            std::fs::write(path, got).expect("writing the expected file");
        }
        eprintln!("blessed {} (read it before committing)", path.display());
        return None;
    }
    Some(format!(
        "{} differs (- expected, + imported; RTK_BLESS=1 rewrites it):\n{}",
        path.display(),
        diff(&want, got)
    ))
}

#[test]
fn every_golden_xml_translates_to_its_toml() {
    let bless = std::env::var_os("RTK_BLESS").is_some_and(|v| v == "1");
    let names = cases();
    assert!(names.len() >= 40, "only {} golden cases", names.len());
    let opts = Options {
        out_dir: PathBuf::from(DIR),
        ..Default::default()
    };
    let mut failures = Vec::new();
    for name in &names {
        let xml = Path::new(DIR).join(format!("{name}.xml"));
        let imported = match import(&xml, &opts) {
            Ok(i) => i,
            Err(e) => {
                failures.push(format!("{name}.xml is refused: {e}"));
                continue;
            }
        };
        let mut warnings = imported.warnings.join("\n");
        if !warnings.is_empty() {
            warnings.push('\n');
        }
        let toml_path = Path::new(DIR).join(format!("{name}.toml"));
        let warn_path = Path::new(DIR).join(format!("{name}.warnings"));
        failures.extend(check(&toml_path, &imported.toml, bless));
        failures.extend(check(&warn_path, &warnings, bless));
    }
    assert!(
        failures.is_empty(),
        "{} of {} golden cases fail:\n\n{}",
        failures.len(),
        names.len(),
        failures.join("\n")
    );
}

#[test]
fn every_expected_file_has_its_case() {
    let names = cases();
    for e in std::fs::read_dir(DIR).unwrap().flatten() {
        let p = e.path();
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
        if matches!(ext, "toml" | "warnings") {
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            assert!(names.contains(&stem), "{} has no {stem}.xml", p.display());
        }
    }
}

#[test]
fn the_diff_marks_the_changed_lines() {
    let d = diff("a\nb\nc\n", "a\nx\nc\n");
    assert_eq!(d, "  a\n+ x\n- b\n  c\n");
}
