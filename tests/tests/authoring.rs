//! For plugin authors: `rtk new` writes a crate that builds out of tree and
//! renders with no edit.

use rtk_tests::*;

/// `rtk new KIND NAME`, build it, render its scene with it on the plugin path.
fn new_build_render(kind: &str, name: &str) {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path().join("tmp");
    let run = Run::from(
        rtk(&["new", kind, name, "--dir", dir.to_str().unwrap()])
            .output()
            .expect("run rtk"),
    );
    assert!(run.ok, "rtk new {kind}: {}", run.stderr);
    for f in ["Cargo.toml", "src/lib.rs", "README.md", "scene.toml"] {
        assert!(dir.join(f).is_file(), "rtk new {kind} wrote no {f}");
    }
    let built = build_plugin_crate(&dir);
    let plugins = plugin_folder(&built, &[name]);
    let (r, img) = render_file(
        &dir.join("scene.toml"),
        tmp.path(),
        &["--plugin-path", plugins.path().to_str().unwrap(), "--stats"],
    );
    assert!(r.ok, "rendering the {kind} scene: {}", r.stderr);
    let img = img.unwrap();
    assert!(img.data.iter().any(|&v| v > 0.05), "{kind}: a black image");
    let mapped = r.stats()["plugins_mapped"].to_string();
    assert!(mapped.contains(&format!("librtk_{name}")), "{mapped}");
}

#[test]
fn authoring_new_aggregate_builds_and_renders() {
    new_build_render("aggregate", "myagg");
}

/// Every kind (run with `--ignored`: six out-of-tree builds).
#[test]
#[ignore]
fn authoring_all_kinds() {
    for kind in [
        "object",
        "aggregate",
        "shader",
        "integrator",
        "camera",
        "light",
    ] {
        new_build_render(kind, &format!("my{kind}_all"));
    }
}

#[test]
fn authoring_new_refuses_bad_names_and_folders() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let d = tmp.path().to_str().unwrap();
    let r = Run::from(
        rtk(&["new", "aggregate", "bvh", "--dir", d])
            .output()
            .unwrap(),
    );
    assert!(!r.ok && r.stderr.contains("built-in"), "{}", r.stderr);
    let r = Run::from(
        rtk(&["new", "shader", "my-shader", "--dir", d])
            .output()
            .unwrap(),
    );
    assert!(
        !r.ok && r.stderr.contains("not a class name"),
        "{}",
        r.stderr
    );
    std::fs::write(tmp.path().join("x"), "").unwrap();
    let r = Run::from(rtk(&["new", "light", "lamp", "--dir", d]).output().unwrap());
    assert!(!r.ok && r.stderr.contains("not empty"), "{}", r.stderr);
}

#[test]
fn bench_aggregate_prints_one_row_per_aggregate_and_set() {
    let mesh = root().join("scenes/meshes/floor.obj");
    let r = Run::from(
        rtk(&[
            "bench-aggregate",
            "grid",
            "--against",
            "bvh",
            "--mesh",
            mesh.to_str().unwrap(),
            "--rays",
            "2000",
            "--threads",
            "2",
        ])
        .output()
        .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
    for set in ["primary", "incoherent", "occluded"] {
        for class in ["grid", "bvh"] {
            assert!(
                r.stdout.lines().any(|l| {
                    let w: Vec<&str> = l.split_whitespace().collect();
                    w.len() >= 3 && w[0] == "floor.obj" && w[1] == set && w[2] == class
                }),
                "no {set} row for {class}:\n{}",
                r.stdout
            );
        }
    }
    let j = Run::from(
        rtk(&[
            "bench-aggregate",
            "grid",
            "--against",
            "bvh",
            "--mesh",
            mesh.to_str().unwrap(),
            "--rays",
            "500",
            "--json",
        ])
        .output()
        .unwrap(),
    );
    assert!(j.ok, "{}", j.stderr);
    let v: serde_json::Value = serde_json::from_str(&j.stdout).expect("json");
    assert_eq!(v["rows"].as_array().unwrap().len(), 6, "{}", j.stdout);
}

fn conform(lib: &std::path::Path) -> Run {
    Run::from(
        rtk(&[
            "conform",
            lib.to_str().unwrap(),
            "--quick",
            "--plugin-path",
            bin_dir().to_str().unwrap(),
        ])
        .output()
        .unwrap(),
    )
}

#[test]
fn conform_passes_every_built_in_aggregate() {
    for class in ["list", "bvh", "grid", "octree", "kdtree"] {
        let lib = bin_dir().join(format!("librtk_{class}.so"));
        let r = conform(&lib);
        assert!(r.ok, "{class}:\n{}\n{}", r.stdout, r.stderr);
        assert!(r.stdout.contains("pass  nearest-hit"), "{}", r.stdout);
        assert!(!r.stdout.contains("FAIL"), "{}", r.stdout);
    }
}

#[test]
fn conform_names_the_check_a_broken_aggregate_fails() {
    let r = conform(&fixtures_dir().join("librtk_brokenagg.so"));
    assert!(!r.ok, "{}", r.stdout);
    assert!(r.stdout.contains("FAIL  ties-lowest-index"), "{}", r.stdout);
    assert!(r.stdout.contains("pass  nearest-hit"), "{}", r.stdout);
    assert!(r.stderr.contains("brokenagg"), "{}", r.stderr);
}

#[test]
fn conform_passes_every_built_in_shader() {
    for class in [
        "lambert",
        "phong",
        "flat",
        "conductor",
        "dielectric",
        "roughconductor",
    ] {
        let lib = bin_dir().join(format!("librtk_{class}.so"));
        let r = conform(&lib);
        assert!(r.ok, "{class}:\n{}\n{}", r.stdout, r.stderr);
        assert!(r.stdout.contains("pass  energy"), "{}", r.stdout);
        assert!(!r.stdout.contains("FAIL"), "{}", r.stdout);
    }
}

#[test]
fn conform_names_the_checks_a_broken_shader_fails() {
    let r = conform(&fixtures_dir().join("librtk_brokenshader.so"));
    assert!(!r.ok, "{}", r.stdout);
    assert!(
        r.stdout.contains("FAIL  pdf-matches-sample"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("FAIL  pdf-integrates"), "{}", r.stdout);
    assert!(r.stdout.contains("pass  energy"), "{}", r.stdout);
    assert!(r.stderr.contains("brokenshader"), "{}", r.stderr);
}

/// Each broken fixture fails the check its defect breaks, by name: the
/// first hit instead of the nearest, bounds too small, and a query counter
/// incremented by a load and a store (a data race that shows only when
/// threads query at once).
#[test]
fn conform_names_each_broken_fixtures_check() {
    for (fixture, check, passes) in [
        ("brokennearest", "nearest-hit", "any-hit"),
        ("brokenbounds", "bounds-contain-hits", "nearest-hit"),
        ("brokenrace", "concurrent-queries", "nearest-hit"),
    ] {
        let r = conform(&fixtures_dir().join(format!("librtk_{fixture}.so")));
        assert!(!r.ok, "{fixture}: {}", r.stdout);
        assert!(
            r.stdout.contains(&format!("FAIL  {check}")),
            "{fixture}: {}",
            r.stdout
        );
        assert!(
            r.stdout.contains(&format!("pass  {passes}")),
            "{fixture}: {}",
            r.stdout
        );
        assert!(r.stderr.contains(fixture), "{}", r.stderr);
    }
}
