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

/// `--aggregate` swapping a scene root's class drops the old class's
/// parameters (a `list` has no `width`), says so on stderr, and answers as
/// the root's own class does.
#[test]
fn aggregate_swap_drops_the_old_class_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = root().join("scenes/meshes/bunny.ply");
    let scene = dir.path().join("bvh.toml");
    std::fs::write(
        &scene,
        format!(
            "[render]\nroot = \"world\"\nintegrator = \"normals\"\n\
             [cameras.none]\nclass = \"pinhole\"\n\
             [objects.mesh]\nclass = \"mesh\"\nfile = {:?}\naccel = \"none\"\n\
             [objects.world]\nclass = \"bvh\"\nwidth = 4\nmax_leaf = 6\nchildren = [\"mesh\"]\n",
            bunny.to_str().unwrap()
        ),
    )
    .unwrap();
    // 200 rays down through the bunny's middle (its box: x within ±4.96,
    // y 0 to 9.65), in the ray file's layout.
    let mut rays = Vec::new();
    for i in 0..200 {
        let o = [-4.0 + 0.04 * i as f32, 20.0, 0.0];
        for x in o.into_iter().chain([0.0, -1.0, 0.0, 0.0, f32::INFINITY]) {
            rays.extend_from_slice(&x.to_le_bytes());
        }
    }
    let ray_file = dir.path().join("rays.bin");
    std::fs::write(&ray_file, rays).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let run = |class: &str| {
        Run::from(
            rtk(&[
                "trace",
                &s(&scene),
                "--rays",
                &s(&ray_file),
                "--aggregate",
                class,
                "--json",
            ])
            .output()
            .unwrap(),
        )
    };
    let (list, bvh) = (run("list"), run("bvh"));
    assert!(list.ok, "{}", list.stderr);
    assert!(
        ["width", "max_leaf", "dropped"]
            .iter()
            .all(|w| list.stderr.contains(w)),
        "{}",
        list.stderr
    );
    assert!(bvh.ok && !bvh.stderr.contains("dropped"), "{}", bvh.stderr);
    let (l, b) = (list.stats(), bvh.stats());
    assert!(b["hits"].as_u64().unwrap() > 100, "{b}");
    for key in ["hits", "sum_t", "sum_prim"] {
        assert_eq!(l[key], b[key], "{key}");
    }
}

/// Every walk of the bvh (`simd`) this CPU runs gives the same hit, ray for
/// ray (the hit files are equal byte for byte), on the incoherent and
/// occlusion rays of `scenes/walks.toml` (the bunny), chosen through
/// `rtk trace --set`. A walk the CPU lacks is refused by name.
#[test]
fn every_bvh_walk_gives_the_same_hits() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = root().join("scenes/walks.toml");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    // What `Bvh::supports` checks for each walk.
    #[cfg(target_arch = "x86_64")]
    let has = |w: &str| {
        use std::arch::is_x86_feature_detected as x;
        let avx2 = x!("avx2") && x!("fma") && x!("bmi1") && x!("bmi2") && x!("popcnt");
        let avx2 = avx2 && x!("lzcnt");
        match w {
            "avx2" => avx2,
            "avx512" => avx2 && x!("avx512f") && x!("avx512vl") && x!("avx512bw") && x!("avx512dq"),
            _ => true,
        }
    };
    #[cfg(not(target_arch = "x86_64"))]
    let has = |w: &str| matches!(w, "auto" | "portable");
    for occluded in [false, true] {
        let mut first: Option<Vec<u8>> = None;
        for walk in ["auto", "portable", "avx2", "avx512"] {
            let out = dir.path().join(format!("{walk}.bin"));
            let mut args = vec![
                "trace".to_string(),
                s(&bunny),
                "--rayset".into(),
                "incoherent".into(),
                "--set".into(),
                format!("objects.world.simd={walk}"),
                "--out".into(),
                s(&out),
            ];
            if occluded {
                args.push("--occluded".into());
            }
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let run = Run::from(rtk(&args).output().unwrap());
            if !has(walk) {
                assert!(
                    !run.ok && run.stderr.contains("key `simd`"),
                    "{walk}: {}",
                    run.stderr
                );
                continue;
            }
            assert!(run.ok, "{walk}: {}", run.stderr);
            let hits = std::fs::read(&out).unwrap();
            match &first {
                None => first = Some(hits),
                Some(f) => assert!(f == &hits, "{walk} differs (occluded: {occluded})"),
            }
        }
    }
}

/// `--stream` traces through the root's ray-stream entries, 64 rays a
/// batch, and writes the single-ray path's hit file byte for byte, nearest
/// and any hit, on scenes of nested aggregates, CSG and ray classification
/// (ties resolved the same way: the records hold the leaf's primitive and
/// its uv too).
#[test]
fn stream_path_writes_the_single_ray_hit_file() {
    let dir = tempfile::tempdir().unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    for scene in ["cornell", "nested", "csg", "raycls"] {
        let file = root().join(format!("scenes/{scene}.toml"));
        for occluded in [false, true] {
            let mut files = Vec::new();
            for stream in [false, true] {
                let out = dir.path().join(format!("{scene}-{occluded}-{stream}.bin"));
                let mut args = vec![
                    "trace".to_string(),
                    s(&file),
                    "--rayset".into(),
                    "incoherent".into(),
                    "--out".into(),
                    s(&out),
                    "--json".into(),
                ];
                if occluded {
                    args.push("--occluded".into());
                }
                if stream {
                    args.push("--stream".into());
                }
                let args: Vec<&str> = args.iter().map(String::as_str).collect();
                let j = trace_json(&args);
                assert_eq!(j["path"], if stream { "stream" } else { "single" });
                files.push(std::fs::read(&out).unwrap());
            }
            assert_eq!(files[0].len(), (1 << 20) * 16, "{scene}");
            assert!(
                files[0].chunks(16).any(|r| r[..4] != [0, 0, 0x80, 0x7f]),
                "{scene}: some ray hits"
            );
            assert!(
                files[0] == files[1],
                "{scene} (occluded: {occluded}): the stream path's hits differ"
            );
        }
    }
}
