//! `rtk stress`: the numerics catalogue (docs/numerics.md) through the real
//! plugins. The quick size runs here and every measurement must pass; the
//! full size is `stress_full` (ignored: minutes).

use rtk_tests::*;

/// The catalogue's cases that exist today: a case dropped from `rtk stress`
/// fails here rather than passing silently.
const CASES: &[&str] = &[
    "T1", "T2", "T3", "T4", "A1", "A2", "A3", "A4", "A5", "Q1", "Q2", "Q3", "S1", "S2", "S3", "S4",
    "S5", "X1", "X2", "X3", "V1", "V2", "V3", "I1", "I2", "I3",
];

fn stress(args: &[&str]) {
    let mut all = vec!["stress", "--json", "--threads", "2"];
    all.extend_from_slice(args);
    let out = rtk(&all).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<serde_json::Value> = serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("{e}: {stdout}\n{}", String::from_utf8_lossy(&out.stderr)));
    let failed: Vec<String> = lines
        .iter()
        .filter(|l| l["pass"] != true)
        .map(|l| {
            format!(
                "{} {} {} = {} (target {})",
                l["case"], l["setup"], l["metric"], l["value"], l["target"]
            )
        })
        .collect();
    assert!(failed.is_empty(), "failed:\n{}", failed.join("\n"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for id in CASES {
        assert!(
            lines.iter().any(|l| l["case"] == *id),
            "case {id} missing from rtk stress"
        );
    }
}

#[test]
fn stress_quick_passes_every_case() {
    stress(&["--quick"]);
}

#[test]
#[ignore = "minutes: the catalogue's full sizes (README: long tests)"]
fn stress_full() {
    stress(&[]);
}
