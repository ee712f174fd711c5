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
    conform_with(lib, &[])
}

/// `rtk conform LIB --quick` with more arguments.
fn conform_with(lib: &std::path::Path, extra: &[&str]) -> Run {
    Run::from(conform_output(lib, extra))
}

fn conform_output(lib: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "conform",
        lib.to_str().unwrap(),
        "--quick",
        "--plugin-path",
        bin_dir().to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    rtk(&args).output().unwrap()
}

fn built_in(class: &str) -> std::path::PathBuf {
    bin_dir().join(format!("librtk_{class}.so"))
}

fn fixture(class: &str) -> std::path::PathBuf {
    fixtures_dir().join(format!("librtk_{class}.so"))
}

/// Passes: no FAIL line, and each of `lines` printed.
fn passes(what: &str, r: &Run, lines: &[&str]) {
    assert!(r.ok, "{what}:\n{}\n{}", r.stdout, r.stderr);
    assert!(!r.stdout.contains("FAIL"), "{what}:\n{}", r.stdout);
    for l in lines {
        assert!(r.stdout.contains(l), "{what}: no `{l}` in\n{}", r.stdout);
    }
}

#[test]
fn conform_passes_every_built_in_aggregate() {
    for class in ["list", "bvh", "grid", "octree", "kdtree", "slabs", "raycls"] {
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
        "roughplastic",
        "plastic",
        "roughdielectric",
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

/// Every built-in object class: primitives as they are (those that need
/// parameters from `--params` or their README's example), classes with a
/// fixed number of children against an oracle of another construction.
#[test]
fn conform_passes_every_built_in_object() {
    for class in ["sphere", "disk", "cylinder", "cone", "torus", "fractal"] {
        let r = conform(&built_in(class));
        passes(
            class,
            &r,
            &[
                "pass  children               none: checked as a primitive",
                "pass  nested-inside-bvh",
                "pass  interval-respected",
                "pass  local-geom",
            ],
        );
    }
    // No parameters given: the README's first example that builds.
    for class in ["polygon", "bicubic"] {
        let r = conform(&built_in(class));
        passes(
            class,
            &r,
            &[
                "pass  params                 none refused",
                "pass  nested-inside-bvh",
            ],
        );
    }
    let floor = root().join("scenes/meshes/floor.obj");
    let r = conform_with(
        &built_in("mesh"),
        &[
            "--params",
            &format!("file = {:?}, normals = \"face\"", floor.to_str().unwrap()),
        ],
    );
    passes("mesh", &r, &["pass  nested-inside-bvh", "pass  local-geom"]);
    // csg: the union of disjoint closed children is the list of them.
    let r = conform_with(
        &built_in("csg"),
        &["--params", "op = \"union\"", "--oracle", "list"],
    );
    passes(
        "csg union",
        &r,
        &[
            "pass  children               exactly 2",
            "pass  nearest-hit            2400 rays agree with `list`",
            "pass  bvh-nested-inside",
        ],
    );
    // Intersection and difference have no oracle: consistency only, the
    // oracle checks reported as skipped.
    for op in ["intersection", "difference"] {
        let r = conform_with(&built_in("csg"), &["--params", &format!("op = \"{op}\"")]);
        passes(
            op,
            &r,
            &[
                "skip  nearest-hit            (no oracle",
                "pass  interval-respected",
            ],
        );
    }
    // motion at one pose is the transform of it, and the other way round
    // (scale 2 and a translation: both round them alike).
    let keys = "keyframes = [{ time = 0.0, translate = [0.5, -0.25, 1.0], scale = 2.0 }]";
    let steps = "steps = [{ scale = 2.0 }, { translate = [0.5, -0.25, 1.0] }]";
    let r = conform_with(
        &built_in("motion"),
        &[
            "--params",
            keys,
            "--oracle",
            "transform",
            "--oracle-params",
            steps,
        ],
    );
    passes(
        "motion",
        &r,
        &[
            "pass  children               exactly 1",
            "pass  nearest-hit            2400 rays agree with `transform`",
        ],
    );
    let r = conform_with(
        &built_in("transform"),
        &[
            "--params",
            steps,
            "--oracle",
            "motion",
            "--oracle-params",
            keys,
        ],
    );
    passes(
        "transform",
        &r,
        &["pass  nearest-hit            2400 rays agree with `motion`"],
    );
    // Moving: no oracle, consistency over random times.
    let r = conform_with(
        &built_in("motion"),
        &["--params", "keyframes = [{ time = 0.0 }, { time = 1.0, translate = [1.0, 0.5, 0.0], rotate = { axis = [0.0, 1.0, 0.0], angle = 90.0 } }]"],
    );
    passes(
        "moving motion",
        &r,
        &["skip  nearest-hit", "pass  bounds-contain-hits"],
    );
}

#[test]
fn conform_passes_every_built_in_camera_light_and_integrator() {
    for (class, extra, lines) in [
        (
            "pinhole",
            &[][..],
            &["pass  not-mirrored", "pass  pixel-centres"][..],
        ),
        (
            "thinlens",
            &["--params", "aperture_radius = 0.2, focus_distance = 3.0"][..],
            &["pass  not-mirrored", "pass  time-in-shutter"][..],
        ),
        (
            "point",
            &[],
            &[
                "pass  delta-light",
                "pass  points-on-light",
                "skip  pdf-integrates",
            ],
        ),
        (
            "directional",
            &[],
            &["pass  delta-light", "pass  points-on-light"],
        ),
        (
            "projector",
            &[],
            &["pass  delta-light", "pass  points-on-light"],
        ),
        (
            "constant",
            &[],
            &[
                "pass  pdf-integrates",
                "pass  li-matches-le",
                "skip  delta-light",
            ],
        ),
        (
            "envmap",
            &[],
            &[
                "pass  pdf-integrates",
                "pass  li-matches-le",
                "skip  delta-light",
            ],
        ),
        (
            "path",
            &[],
            &[
                "pass  furnace",
                "pass  black-without-light",
                "pass  deterministic",
            ],
        ),
        (
            "whitted",
            &[],
            &["pass  furnace", "pass  black-without-light"],
        ),
        (
            "distributed",
            &[],
            &["pass  furnace", "pass  concurrent-queries"],
        ),
        // Not a radiance estimator: the two energy checks do not apply.
        (
            "normals",
            &["--skip", "furnace", "--skip", "black-without-light"],
            &["skip  furnace                (--skip)", "pass  finite"],
        ),
    ] {
        let r = conform_with(&built_in(class), extra);
        passes(class, &r, lines);
    }
}

/// The fixtures' defects, each failing its check by name: a light whose
/// `pdf_li` is twice its sampling density, a mirrored camera, an
/// integrator that counts direct light twice.
#[test]
fn conform_names_the_check_each_broken_kind_fails() {
    for (lib, params, fails, passes_) in [
        (
            fixture("panickylight"),
            "defect = \"pdf\"",
            &["pdf-matches-sample", "pdf-integrates"][..],
            "li-matches-le",
        ),
        (
            fixture("panickycamera"),
            "defect = \"mirrored\"",
            &["not-mirrored"][..],
            "pixel-centres",
        ),
        (
            fixture("panickyintegrator"),
            "defect = \"double\"",
            &["furnace"][..],
            "black-without-light",
        ),
    ] {
        let extra: &[&str] = if params.is_empty() {
            &[]
        } else {
            &["--params", params]
        };
        let r = conform_with(&lib, extra);
        assert!(!r.ok, "{}: {}", lib.display(), r.stdout);
        for f in fails {
            assert!(
                r.stdout.contains(&format!("FAIL  {f}")),
                "{f}:\n{}",
                r.stdout
            );
        }
        assert!(
            r.stdout.contains(&format!("pass  {passes_}")),
            "{}",
            r.stdout
        );
        assert!(r.stderr.contains("fails"), "{}", r.stderr);
    }
    // The same fixtures without the defect pass.
    for f in [
        "panickylight",
        "panickycamera",
        "panickyintegrator",
        "panickyshader",
    ] {
        let r = conform(&fixture(f));
        passes(f, &r, &["pass  unknown-key-refused"]);
    }
}

/// `panics-reported`: with `--panic-param panic_in`, each entry of each
/// kind panics in turn and is reported naming the plugin and the entry.
#[test]
fn conform_panics_reported_for_every_kind() {
    for (f, entries) in [
        (
            "panicky",
            "create, add_child, prepare, bounds, intersect, occluded, local_geom",
        ),
        ("panickyshader", "create, lobes, eval, sample, pdf, emitted"),
        ("panickylight", "create, sample_li, le, pdf_li"),
        ("panickycamera", "create, generate_ray"),
        ("panickyintegrator", "create, li"),
    ] {
        let r = conform_with(&fixture(f), &["--panic-param", "panic_in"]);
        passes(
            f,
            &r,
            &[&format!(
                "pass  panics-reported        caught and reported with the plugin's name: {entries}"
            )],
        );
        assert!(!r.stdout.contains("not provoked"), "{}", r.stdout);
    }
    // A parameter that makes no entry panic fails the check.
    let r = conform_with(&built_in("sphere"), &["--panic-param", "radius"]);
    assert!(!r.ok, "{}", r.stdout);
    assert!(r.stdout.contains("FAIL  panics-reported"), "{}", r.stdout);
}

/// A plugin that panics during the suite: the check under way fails with
/// the plugin's name and the entry, conform exits 1 (no crash, no abort).
#[test]
fn conform_reports_a_panic_in_each_entry_with_the_plugin_name() {
    for entry in [
        "create",
        "add_child",
        "prepare",
        "bounds",
        "intersect",
        "occluded",
        "local_geom",
    ] {
        // add_child: conform finds no child count the plugin accepts.
        let extra = [
            "--params",
            &format!("panic_in = \"{entry}\""),
            "--children",
            if entry == "add_child" { "1" } else { "0" },
        ];
        let out = conform_output(&fixture("panicky"), &extra);
        assert_eq!(out.status.code(), Some(1), "{entry}: {out:?}");
        let r = Run::from(out);
        let fail = r
            .stdout
            .lines()
            .find(|l| l.starts_with("FAIL"))
            .unwrap_or_else(|| panic!("{entry}: no FAIL line:\n{}", r.stdout));
        assert!(fail.contains("`panicky`"), "{entry}: {fail}");
        assert!(
            fail.contains(&format!("panicked in {entry}: deliberate panic in {entry}")),
            "{fail}"
        );
        assert!(r.stderr.contains("`panicky` fails"), "{}", r.stderr);
    }
    for (f, entry) in [
        ("panickyshader", "sample"),
        ("panickylight", "sample_li"),
        ("panickycamera", "generate_ray"),
        ("panickyintegrator", "li"),
    ] {
        let out = conform_output(
            &fixture(f),
            &["--params", &format!("panic_in = \"{entry}\"")],
        );
        assert_eq!(out.status.code(), Some(1), "{f}: {out:?}");
        let r = Run::from(out);
        assert!(
            r.stdout
                .contains(&format!("plugin `{f}` panicked in {entry}")),
            "{f}: {}",
            r.stdout
        );
    }
}

#[test]
fn conform_refuses_bad_arguments() {
    let sphere = built_in("sphere");
    for (args, says) in [
        (&["--params", "class = \"x\""][..], "not a parameter"),
        (&["--params", "radius = "][..], "not a TOML table"),
        (&["--skip", "no-such-check"][..], "no check of that name"),
        (&["--oracle", "list"][..], "--oracle"),
    ] {
        let r = conform_with(&sphere, args);
        assert!(!r.ok && r.stderr.contains(says), "{args:?}: {}", r.stderr);
    }
    // A plugin refusing the parameters given: the refusal, naming the key.
    let r = conform_with(&built_in("mesh"), &["--params", "normals = \"face\""]);
    assert!(!r.ok, "{}", r.stdout);
    assert!(
        r.stdout.contains("FAIL  children") && r.stdout.contains("missing key `file`"),
        "{}",
        r.stdout
    );
    // @FILE: parameters from a file, its relative paths from its folder.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::copy(
        root().join("scenes/meshes/floor.obj"),
        tmp.path().join("floor.obj"),
    )
    .unwrap();
    std::fs::write(tmp.path().join("p.toml"), "file = \"floor.obj\"\n").unwrap();
    let at = format!("@{}", tmp.path().join("p.toml").display());
    let r = conform_with(&built_in("mesh"), &["--params", &at, "--json"]);
    assert!(r.ok, "{}\n{}", r.stdout, r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).expect("json");
    assert_eq!(v["failed"], 0, "{}", r.stdout);
    assert!(
        v["params"].as_str().unwrap().contains("floor.obj"),
        "{}",
        r.stdout
    );
}

/// `stream-parity` on a fixture whose stream entries are its own (a lane
/// loop after a root pass) and right: the check runs, on all three object
/// entries, and passes.
#[test]
fn conform_stream_parity_passes_right_stream_entries() {
    let r = conform(&fixture("streamsphere"));
    passes(
        "streamsphere",
        &r,
        &["pass  stream-parity          intersect_batch, occluded_batch, local_geom_batch: "],
    );
    assert!(r.stdout.contains("bit for bit"), "{}", r.stdout);
}

/// `stream-parity` on a fixture whose stream entries are one ulp off in `t`
/// on the last hit lane of full batches of 64 (and drop that lane from
/// `occluded_batch`'s mask): the only check that fails, naming the entry,
/// the batch, the lane and both `t`s.
#[test]
fn conform_stream_parity_names_the_lane_a_broken_stream_differs_in() {
    let r = conform(&fixture("brokenstream"));
    assert!(!r.ok, "{}", r.stdout);
    let fails: Vec<&str> = r.stdout.lines().filter(|l| l.starts_with("FAIL")).collect();
    assert_eq!(fails.len(), 1, "{}", r.stdout);
    let f = fails[0];
    assert!(f.starts_with("FAIL  stream-parity"), "{f}");
    for says in [
        "intersect_batch: ",
        "(64 queries from #",
        "active 0xffffffffffffffff",
        ", lane ",
        ": t ",
        "intersect's ",
        "occluded_batch: ",
    ] {
        assert!(f.contains(says), "no `{says}` in {f}");
    }
    assert!(r.stdout.contains("pass  nested-inside-bvh"), "{}", r.stdout);
    assert!(r.stderr.contains("`brokenstream` fails"), "{}", r.stderr);
}

/// Plugins on the SDK's default stream entries (loops over the single-ray
/// ones, in the plugin) pass with the check run, every kind that has them;
/// a plugin whose record has no stream entries (as one built before
/// rtk-abi 3.1) passes as it did, with the check skipped, saying why.
#[test]
fn conform_stream_parity_defaults_pass_and_absent_entries_skip() {
    for (class, entries) in [
        (
            "sphere",
            "intersect_batch, occluded_batch, local_geom_batch: ",
        ),
        (
            "list",
            "intersect_batch, occluded_batch, local_geom_batch: ",
        ),
        ("point", "sample_li_batch: "),
        ("path", "li_batch: "),
    ] {
        let r = conform(&built_in(class));
        passes(
            class,
            &r,
            &[&format!("pass  stream-parity          {entries}")],
        );
    }
    let r = conform(&without_streams_dir().join("librtk_nostreams.so"));
    passes(
        "nostreams",
        &r,
        &[
            "skip  stream-parity          (the plugin has no stream entries",
            "pass  nested-inside-bvh",
        ],
    );
    assert!(
        r.stdout.contains("loop over its single-ray entries"),
        "{}",
        r.stdout
    );
}

/// Every built-in plugin passes its suite with no arguments at all: a
/// class that needs a file (`mesh`) or that some checks do not fit
/// (`normals` estimates no radiance) says so in its README's `conform`
/// block, which the report quotes; the area light is checked on an
/// emitting ball the shell binds it to.
#[test]
fn conform_passes_every_built_in_plugin_with_no_arguments() {
    let mut libs: Vec<_> = std::fs::read_dir(bin_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            n.starts_with("librtk_") && n.ends_with(".so")
        })
        .collect();
    libs.sort();
    assert!(
        libs.len() >= 30,
        "only {} built-in plugins found",
        libs.len()
    );
    for lib in &libs {
        let r = conform(lib);
        assert!(r.ok, "{}:\n{}\n{}", lib.display(), r.stdout, r.stderr);
        assert!(
            r.stdout.contains(" 0 failed"),
            "{}: {}",
            lib.display(),
            r.stdout
        );
    }
    let r = conform(&built_in("normals"));
    assert!(
        r.stdout.contains(
            "skip  furnace                (the plugin's README: estimates shading normals"
        ),
        "{}",
        r.stdout
    );
    let r = conform(&built_in("mesh"));
    assert!(r.stdout.contains("tetrahedron.obj"), "{}", r.stdout);
    let r = conform(&built_in("area"));
    assert!(r.stdout.contains("pass  pdf-matches-hit"), "{}", r.stdout);
}

/// `rtk conform` runs the checks in a child process of itself: a plugin
/// that aborts in the middle of them is named (by the child's SIGABRT
/// handler), the suite reports the stop as a failure of its own and exits
/// non-zero rather than dying with the plugin.
#[test]
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn conform_survives_a_plugin_that_aborts_and_names_it() {
    let r = conform_with(
        &fixture("panicky"),
        &["--params", "panic_in = \"intersect\"\nfault = \"abort\""],
    );
    assert!(!r.ok);
    assert!(
        r.stdout.contains("FAIL  (the suite)") && r.stdout.contains("signal 6"),
        "{}",
        r.stdout
    );
    assert!(
        r.stderr.contains("plugin `panicky` (") && r.stderr.contains("SIGABRT"),
        "{}",
        r.stderr
    );
}
