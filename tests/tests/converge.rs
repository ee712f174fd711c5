//! `rtk diff` and `rtk converge`: the metrics of the Mitsuba anchor's
//! compare.py on files with known errors, the CSV and plot a convergence run
//! writes, and the refusal of bad references.

use rtk_tests::*;
use std::path::Path;

/// A PFM (RGB, little-endian, rows bottom to top) of `w` x `h` with every
/// pixel's three channels given by `f(x, y)` (y = 0 at the top).
fn write_pfm(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) {
    let mut b = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for y in (0..h).rev() {
        for x in 0..w {
            for v in f(x, y) {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, b).unwrap();
}

/// A .npy, float32 (H, W, 3), C order, row 0 at the top.
fn write_npy(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) {
    let dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({h}, {w}, 3), }}\n");
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    b.extend_from_slice(dict.as_bytes());
    for y in 0..h {
        for x in 0..w {
            for v in f(x, y) {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, b).unwrap();
}

fn metric(stdout: &str, name: &str) -> f64 {
    stdout
        .lines()
        .find_map(|l| l.strip_prefix(&format!("{name} ")))
        .unwrap_or_else(|| panic!("no `{name}` line in:\n{stdout}"))
        .trim()
        .parse()
        .unwrap()
}

/// Two 4x2 images differing by 0.5 in one channel of the top-left pixel and
/// by 0.25 in all channels of the bottom-right one: known RMSE and relMSE.
#[test]
fn diff_reports_known_rmse_and_relmse() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.pfm"), dir.path().join("b.pfm"));
    write_pfm(&b, 4, 2, |_, _| [0.5, 0.5, 0.5]);
    write_pfm(&a, 4, 2, |x, y| match (x, y) {
        (0, 0) => [1.0, 0.5, 0.5],
        (3, 1) => [0.75, 0.75, 0.75],
        _ => [0.5, 0.5, 0.5],
    });
    let run = Run::from(
        rtk(&["diff", a.to_str().unwrap(), b.to_str().unwrap()])
            .output()
            .unwrap(),
    );
    assert!(run.ok, "{}", run.stderr);
    // 24 values: one squared error of 0.25, three of 0.0625.
    let se = 0.25 + 3.0 * 0.0625;
    let rmse = (se / 24.0f64).sqrt();
    let relmse = se / (0.25 + 0.01) / 24.0;
    assert!(
        (metric(&run.stdout, "rmse") - rmse).abs() < 1e-12,
        "{}",
        run.stdout
    );
    assert!(
        (metric(&run.stdout, "relmse") - relmse).abs() < 1e-12,
        "{}",
        run.stdout
    );

    // The same image as a .npy (row 0 at the top, where PFM stores the
    // bottom row first) reads the same: no error.
    let npy = dir.path().join("a.npy");
    write_npy(&npy, 4, 2, |x, y| match (x, y) {
        (0, 0) => [1.0, 0.5, 0.5],
        (3, 1) => [0.75, 0.75, 0.75],
        _ => [0.5, 0.5, 0.5],
    });
    let run = Run::from(
        rtk(&["diff", npy.to_str().unwrap(), a.to_str().unwrap()])
            .output()
            .unwrap(),
    );
    assert!(run.ok, "{}", run.stderr);
    assert_eq!(metric(&run.stdout, "rmse"), 0.0, "{}", run.stdout);

    // Different sizes: refused, both named.
    write_pfm(&b, 2, 4, |_, _| [0.5; 3]);
    let run = Run::from(
        rtk(&["diff", a.to_str().unwrap(), b.to_str().unwrap()])
            .output()
            .unwrap(),
    );
    assert!(!run.ok);
    assert!(run.stderr.contains("differ in size"), "{}", run.stderr);
    assert!(
        run.stderr.contains("4x2") && run.stderr.contains("2x4"),
        "{}",
        run.stderr
    );
}

/// A small run: 2 sample counts x 2 seeds, a CSV of 4 rows with the header
/// the anchor's tools read, distinct seeds, and a plot that decodes.
#[test]
fn converge_writes_csv_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let scene = root().join("scenes/default.toml");
    let run = Run::from(
        rtk(&[
            "converge",
            scene.to_str().unwrap(),
            "--analytic",
            "constant:0,0,0",
            "--spp",
            "1,2",
            "--seeds",
            "2",
            "--set",
            "render.width=32",
            "--set",
            "render.height=24",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap(),
    );
    assert!(run.ok, "{}", run.stderr);
    assert!(run.stdout.contains("slope"), "{}", run.stdout);
    assert_eq!(
        run.stderr
            .lines()
            .filter(|l| l.starts_with("converge: "))
            .count(),
        4,
        "one progress line per render:\n{}",
        run.stderr
    );

    let csv = std::fs::read_to_string(out.join("converge.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header[..5],
        ["spp", "seed", "wall_seconds", "rmse", "relmse"]
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    let mut seeds: Vec<&str> = rows.iter().map(|r| r[1]).collect();
    seeds.sort();
    seeds.dedup();
    assert_eq!(seeds.len(), 4, "no two renders share a seed: {csv}");
    for r in &rows {
        assert!(r[0] == "1" || r[0] == "2", "{csv}");
        let t: f64 = r[2].parse().unwrap();
        let rmse: f64 = r[3].parse().unwrap();
        let relmse: f64 = r[4].parse().unwrap();
        assert!(t > 0.0 && rmse > 0.0 && relmse > 0.0, "{csv}");
        // Against black: relmse = mean(v^2) / 0.01 = rmse^2 * 100.
        assert!(
            (relmse - rmse * rmse * 100.0).abs() < 1e-9 * relmse,
            "{csv}"
        );
    }

    let png = image::open(out.join("converge.png")).expect("the plot decodes");
    assert!(png.width() > 100 && png.height() > 100);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("converge.json")).unwrap()).unwrap();
    assert_eq!(json["points"].as_array().unwrap().len(), 2);
    // No temporary files left behind.
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
}

/// Bad `--analytic` specs are refused before any render, naming the spec.
#[test]
fn converge_refuses_bad_specs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let scene = root().join("scenes/default.toml");
    for spec in ["furnace:le=1,albedo=1.5", "nonesuch:1", "constant:1,2"] {
        let run = Run::from(
            rtk(&[
                "converge",
                scene.to_str().unwrap(),
                "--analytic",
                spec,
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap(),
        );
        assert!(!run.ok, "{spec} was accepted");
        assert!(
            run.stderr.contains(&format!("--analytic `{spec}`")),
            "{spec}: {}",
            run.stderr
        );
        assert!(!out.exists(), "nothing written for a refused spec");
    }
}
