//! `rtk trace`: the Embree anchor's ray sets, reproduced bit for bit, and
//! its reference answers on the bunny (RAYS.md §6); ray and hit files.

use rtk_tests::*;

fn trace_json(args: &[&str]) -> serde_json::Value {
    let run = Run::from(rtk(args).output().unwrap());
    assert!(run.ok, "{}", run.stderr);
    run.stats()
}

/// RAYS.md's reference values for the bunny: the generated rays hash as the
/// anchor's, and rtk's hits are Embree's (count exactly; the sum of hit
/// distances to the rounding of t).
#[test]
fn bunny_reproduces_the_embree_anchors_reference_values() {
    let bunny = root().join("scenes/meshes/bunny.ply");
    let b = bunny.to_str().unwrap();
    let p = trace_json(&["trace", b, "--rayset", "primary", "--json"]);
    assert_eq!(p["rays_hash"], "b00145327fe5a943");
    assert_eq!(p["hits"], 499_784);
    let sum_t = p["sum_t"].as_f64().unwrap();
    assert!((sum_t - 5_240_886.603_462).abs() / sum_t < 1e-7, "{sum_t}");
    let i = trace_json(&["trace", b, "--rayset", "incoherent", "--json"]);
    assert_eq!(i["rays_hash"], "33fcf27827eb0eac");
    assert_eq!(i["hits"], 320_866);
    let sum_t = i["sum_t"].as_f64().unwrap();
    assert!((sum_t - 828_418.789_716).abs() / sum_t < 1e-7, "{sum_t}");
    let o = trace_json(&["trace", b, "--rayset", "incoherent", "--occluded", "--json"]);
    assert_eq!(o["hits"], 320_866, "every ray that hits is occluded");
}

/// Saved rays trace to the same hits as the generated set; the hit file has
/// one 16-byte record per ray; a malformed ray file is refused.
#[test]
fn ray_and_hit_files() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = root().join("scenes/meshes/bunny.ply");
    let (rays, hits_a, hits_b) = (
        dir.path().join("rays.bin"),
        dir.path().join("a.bin"),
        dir.path().join("b.bin"),
    );
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let a = trace_json(&[
        "trace",
        &s(&bunny),
        "--rayset",
        "incoherent",
        "--save-rays",
        &s(&rays),
        "--out",
        &s(&hits_a),
        "--json",
    ]);
    let b = trace_json(&[
        "trace",
        &s(&bunny),
        "--rays",
        &s(&rays),
        "--out",
        &s(&hits_b),
        "--json",
    ]);
    assert_eq!(a["hits"], b["hits"]);
    let (ha, hb) = (
        std::fs::read(&hits_a).unwrap(),
        std::fs::read(&hits_b).unwrap(),
    );
    assert_eq!(ha.len(), (1 << 20) * 16);
    assert_eq!(ha, hb);
    std::fs::write(&rays, [0u8; 33]).unwrap();
    let run = Run::from(
        rtk(&["trace", &s(&bunny), "--rays", &s(&rays)])
            .output()
            .unwrap(),
    );
    assert!(
        !run.ok && run.stderr.contains("whole number"),
        "{}",
        run.stderr
    );
}
