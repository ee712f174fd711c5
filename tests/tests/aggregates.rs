//! Every aggregate returns exactly the `list`'s answer: nearest hit (t,
//! primitive, barycentrics) and any-hit, ray for ray, on randomized scenes of
//! spheres and triangle meshes (overlapping, coplanar, shared edges,
//! degenerate triangles, coincident copies, transformed instances, a nested
//! aggregate) and adversarial rays (axis-parallel, ±0 components, along cell
//! boundaries, from box corners and faces). Through the real binary:
//! `rtk trace --rays FILE --aggregate CLASS --out HITS` (docs/trace.md).

use rtk_tests::*;
use std::fmt::Write as _;
use std::path::Path;

/// The aggregates that must match the list (every one that is built).
const AGGREGATES: &[&str] = &["bvh", "grid", "octree", "kdtree", "slabs", "raycls"];

/// A random scene; `inner` is the class of the nested cluster.
fn scene(seed: u64, dir: &Path, inner: &str) -> String {
    scene_with(seed, dir, inner, "")
}

/// [`scene`] with `extra` lines (parameters) in the root's and the nested
/// cluster's definitions.
fn scene_with(seed: u64, dir: &Path, inner: &str, extra: &str) -> String {
    let mut r = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let mut s = String::from(
        "[render]\nroot = \"world\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n",
    );
    let mut children = Vec::new();
    // Spheres, some overlapping, two exact duplicates (ties between children).
    for i in 0..40 {
        let c = [r.f(-8.0, 8.0), r.f(-8.0, 8.0), r.f(-8.0, 8.0)];
        let rad = r.f(0.1, 1.5);
        writeln!(
            s,
            "[objects.s{i}]\nclass = \"sphere\"\ncenter = [{}, {}, {}]\nradius = {rad}",
            c[0], c[1], c[2]
        )
        .unwrap();
        children.push(format!("\"s{i}\""));
    }
    children.push("\"s3\"".into());
    children.push("\"s3\"".into());
    // Meshes: random soup (with degenerate and duplicated triangles), a grid
    // of coplanar quads sharing edges on integer coordinates, a closed box.
    for (m, text) in [soup(&mut r), plane_grid(), box_mesh()].iter().enumerate() {
        std::fs::write(dir.join(format!("m{m}.obj")), text).unwrap();
        writeln!(
            s,
            "[objects.m{m}]\nclass = \"mesh\"\nfile = \"m{m}.obj\"\naccel = \"none\""
        )
        .unwrap();
        children.push(format!("\"m{m}\""));
    }
    // Transformed instances of a mesh and a sphere.
    children.push("{ object = \"m2\", transform = [{ scale = 0.5 }, { rotate_y = 30.0 }, { translate = [3.0, 1.0, -2.0] }] }".into());
    children.push("{ object = \"s5\", transform = [{ translate = [0.0, 0.0, 4.0] }] }".into());
    // A nested cluster of the class under test.
    writeln!(s, "[objects.cluster]\nclass = \"{inner}\"\n{extra}\nchildren = [\"s1\", \"s2\", \"m1\", {{ object = \"m0\", transform = [{{ translate = [1.0, 2.0, 3.0] }}] }}]").unwrap();
    children.push("\"cluster\"".into());
    writeln!(
        s,
        "[objects.world]\nclass = \"list\"\n{extra}\nchildren = [{}]",
        children.join(", ")
    )
    .unwrap();
    s
}

/// splitmix64: the tests' own generator (the test crate links no kernel).
struct Rng(u64);
impl Rng {
    fn u(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn f(&mut self, lo: f64, hi: f64) -> f32 {
        (lo + (hi - lo) * self.u()) as f32
    }
}

fn soup(r: &mut Rng) -> String {
    let mut s = String::new();
    let mut n = 0;
    for t in 0..300 {
        let c = [r.f(-8.0, 8.0), r.f(-8.0, 8.0), r.f(-8.0, 8.0)];
        for _ in 0..3 {
            writeln!(
                s,
                "v {} {} {}",
                c[0] + r.f(-1.5, 1.5),
                c[1] + r.f(-1.5, 1.5),
                c[2] + r.f(-1.5, 1.5)
            )
            .unwrap();
        }
        writeln!(s, "f {} {} {}", n + 1, n + 2, n + 3).unwrap();
        if t % 50 == 0 {
            // The same triangle again (a tie within the mesh) and a degenerate one.
            writeln!(s, "f {} {} {}", n + 1, n + 2, n + 3).unwrap();
            writeln!(s, "f {} {} {}", n + 1, n + 1, n + 2).unwrap();
        }
        n += 3;
    }
    s
}

/// 8x8 unit quads in the plane y = 0 on integer coordinates: every edge
/// shared, every vertex on a cell boundary of any grid with integer cells.
fn plane_grid() -> String {
    let mut s = String::new();
    for j in 0..=8 {
        for i in 0..=8 {
            writeln!(s, "v {} 0 {}", i - 4, j - 4).unwrap();
        }
    }
    for j in 0..8 {
        for i in 0..8 {
            let a = j * 9 + i + 1;
            writeln!(
                s,
                "f {} {} {}\nf {} {} {}",
                a,
                a + 1,
                a + 10,
                a,
                a + 10,
                a + 9
            )
            .unwrap();
        }
    }
    s
}

fn box_mesh() -> String {
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
     f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n"
        .into()
}

/// Rays: random, and adversarial.
fn rays(seed: u64) -> Vec<[f32; 8]> {
    let mut r = Rng(seed ^ 0xABCD_EF01);
    let mut out = Vec::new();
    for k in 0..6000 {
        let mut o = [r.f(-12.0, 12.0), r.f(-12.0, 12.0), r.f(-12.0, 12.0)];
        let mut d = [r.f(-1.0, 1.0), r.f(-1.0, 1.0), r.f(-1.0, 1.0)];
        match k % 6 {
            // Axis-parallel, with ±0 in the other components.
            1 => d = [[1.0, 0.0, -0.0], [0.0, -1.0, 0.0], [-0.0, 0.0, 1.0]][k % 3],
            // Along cell boundaries: integer origins, axis-parallel.
            2 => {
                o = o.map(|x| x.round());
                d = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]][(k / 6) % 3];
            }
            // In the plane of the quads, at grazing incidence.
            3 => {
                o[1] = 0.0;
                d[1] = 0.0;
            }
            // From a corner or a face of the closed box.
            4 => {
                o = [[-1.0, -1.0, -1.0], [1.0, 0.3, -0.2], [0.0, 1.0, 0.5]][k % 3];
            }
            _ => {}
        }
        if d.iter().all(|&x| x == 0.0) {
            d = [0.0, 0.0, 1.0];
        }
        let t_max = if k % 7 == 0 {
            r.f(0.5, 10.0)
        } else {
            f32::INFINITY
        };
        out.push([o[0], o[1], o[2], d[0], d[1], d[2], 0.0, t_max]);
    }
    out
}

fn write_rays(p: &Path, rays: &[[f32; 8]]) {
    let bytes: Vec<u8> = rays
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    std::fs::write(p, bytes).unwrap();
}

/// Trace with the root of class `class`; returns the hit file's bytes.
fn trace(dir: &Path, scene: &Path, rays: &Path, class: &str, occluded: bool) -> Vec<u8> {
    let out = dir.join(format!("hits-{class}-{occluded}.bin"));
    let mut args = vec![
        "trace",
        scene.to_str().unwrap(),
        "--rays",
        rays.to_str().unwrap(),
        "--aggregate",
        class,
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "2",
        // Several passes: query ids (the mailboxes' marks) must never repeat
        // on a thread, across chunks and passes (a regression once).
        "--iters",
        "3",
        "--json",
    ];
    if occluded {
        args.push("--occluded");
    }
    let run = Run::from(rtk(&args).output().unwrap());
    assert!(run.ok, "{class}: {}", run.stderr);
    std::fs::read(out).unwrap()
}

/// The mismatching rays of two hit files, described.
fn mismatches(a: &[u8], b: &[u8]) -> Vec<String> {
    a.chunks(16)
        .zip(b.chunks(16))
        .enumerate()
        .filter(|(_, (x, y))| x != y)
        .map(|(i, (x, y))| format!("ray {i}: list {x:?} vs {y:?}"))
        .collect()
}

fn check(seed: u64, class: &str) {
    check_with(seed, class, "")
}

fn check_with(seed: u64, class: &str, extra: &str) {
    let dir = tempfile::tempdir().unwrap();
    // The oracle is all lists; the other scene has `class` at the root and
    // in the nested cluster.
    let oracle = dir.path().join("list.toml");
    std::fs::write(&oracle, scene(seed, dir.path(), "list")).unwrap();
    let sp = dir.path().join("scene.toml");
    std::fs::write(&sp, scene_with(seed, dir.path(), class, extra)).unwrap();
    let rp = dir.path().join("rays.bin");
    write_rays(&rp, &rays(seed));
    for occluded in [false, true] {
        let want = trace(dir.path(), &oracle, &rp, "list", occluded);
        let got = trace(dir.path(), &sp, &rp, class, occluded);
        assert_eq!(want.len(), got.len());
        let m = mismatches(&want, &got);
        assert!(
            m.is_empty(),
            "{class} {extra} (occluded {occluded}, seed {seed}): {} mismatches, e.g. {:?}",
            m.len(),
            &m[..m.len().min(5)]
        );
    }
}

#[test]
fn every_aggregate_matches_the_list() {
    let avail = rtk_plugins_available();
    for class in AGGREGATES {
        assert!(
            avail.contains(&class.to_string()),
            "aggregate `{class}` is not built"
        );
        for seed in [1, 2] {
            check(seed, class);
        }
    }
}

/// The `bvh`'s options change the work, never the answer: its second
/// volumes (issue 12: spheres and slabs around spheres, triangles, rotated
/// instances and a nested cluster) and both widths (4-wide SSE; 8-wide is
/// the default where the CPU has AVX2).
#[test]
fn bvh_options_match_the_list() {
    for extra in [
        "bound = \"sphere\"",
        "bound = \"slabs\"",
        "width = 4",
        "width = 8",
        "width = 4\nbound = \"slabs\"",
    ] {
        for seed in [1, 2, 3] {
            check_with(seed, "bvh", extra);
        }
    }
}

/// `raycls` at its extremes: one candidate per cell, no subdivision at all
/// (the sorted root lists alone), and a budget too small for its roots (so
/// every ray takes the exhaustive path) still answer exactly as `list`.
#[test]
fn raycls_matches_the_list_at_any_setting() {
    for extra in [
        "max_candidates = 1",
        "max_depth = 0",
        "max_candidates = 2\nmax_depth = 64",
        "max_memory_mb = 0.0001",
    ] {
        check_with(3, "raycls", extra);
    }
}

/// `count` small random triangles in [-8, 8]³ as an OBJ file.
fn small_soup(r: &mut Rng, count: usize) -> String {
    let mut s = String::new();
    for t in 0..count {
        let c = [r.f(-8.0, 8.0), r.f(-8.0, 8.0), r.f(-8.0, 8.0)];
        for _ in 0..3 {
            let v = [
                c[0] + r.f(-0.4, 0.4),
                c[1] + r.f(-0.4, 0.4),
                c[2] + r.f(-0.4, 0.4),
            ];
            writeln!(s, "v {} {} {}", v[0], v[1], v[2]).unwrap();
        }
        writeln!(s, "f {} {} {}", 3 * t + 1, 3 * t + 2, 3 * t + 3).unwrap();
    }
    s
}

/// A scene of one `small_soup` mesh of `count` triangles, flattened into a
/// root of class `class` with the parameter lines `extra`.
fn soup_scene(dir: &Path, count: usize, class: &str, extra: &str) -> std::path::PathBuf {
    let mesh = dir.join("soup.obj");
    if !mesh.exists() {
        std::fs::write(&mesh, small_soup(&mut Rng(0x50FA), count)).unwrap();
    }
    let p = dir.join(format!("soup-{class}.toml"));
    std::fs::write(
        &p,
        format!(
            "[render]\nroot = \"world\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
             [objects.soup]\nclass = \"mesh\"\nfile = \"soup.obj\"\naccel = \"none\"\n\
             [objects.world]\nclass = \"{class}\"\n{extra}\nchildren = [\"soup\"]\n"
        ),
    )
    .unwrap();
    p
}

/// Rays in the pattern a renderer casts: from four eye points (outside and
/// inside the scene) in every direction, and from random points; one in 40
/// from a million units away, aimed near the scene, and one in 40 from 1e14
/// along z, nearly (too far for `raycls` to classify: it tests every
/// primitive).
fn eye_rays(n: usize) -> Vec<[f32; 8]> {
    let mut r = Rng(0xE7E5);
    let eyes = [
        [0.0, 3.0, 25.0],
        [-20.0, 10.0, -4.0],
        [0.5, 0.25, -0.75],
        [4.0, -4.0, 4.0],
    ];
    (0..n)
        .map(|k| {
            let o = if k % 5 == 4 {
                [r.f(-12.0, 12.0), r.f(-12.0, 12.0), r.f(-12.0, 12.0)]
            } else {
                eyes[k % 4]
            };
            let mut d = [r.f(-1.0, 1.0), r.f(-1.0, 1.0), r.f(-1.0, 1.0)];
            if k % 4 == 0 {
                // Towards the scene, as a camera looks.
                d = [d[0] * 0.3, d[1] * 0.3, -1.0];
            }
            if k % 40 == 3 {
                let aim = [r.f(-9.0, 9.0), r.f(-9.0, 9.0), r.f(-9.0, 9.0)];
                let o = [6e5, -4.8e5, 6.4e5];
                let d = [aim[0] - o[0], aim[1] - o[1], aim[2] - o[2]];
                return [o[0], o[1], o[2], d[0], d[1], d[2], 0.0, f32::INFINITY];
            }
            if k % 40 == 23 {
                let (x, y) = (r.f(-9.0, 9.0), r.f(-9.0, 9.0));
                let (a, b) = (r.f(-5.0, 5.0) * 1e-14, r.f(-5.0, 5.0) * 1e-14);
                return [x, y, 1e14, a, b, -1.0, 0.0, f32::INFINITY];
            }
            let t_max = if k % 7 == 0 { 12.0 } else { f32::INFINITY };
            [o[0], o[1], o[2], d[0], d[1], d[2], 0.0, t_max]
        })
        .collect()
}

/// `rtk trace` with `threads` threads, one pass; the hit file and stderr.
fn trace_threads(scene: &Path, rays: &Path, threads: u32, occluded: bool) -> (Vec<u8>, String) {
    let out = scene.with_extension(format!("{threads}-{occluded}.hits"));
    let threads = threads.to_string();
    let mut args = vec![
        "trace",
        scene.to_str().unwrap(),
        "--rays",
        rays.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--threads",
        &threads,
        "--json",
    ];
    if occluded {
        args.push("--occluded");
    }
    let run = Run::from(rtk(&args).output().unwrap());
    assert!(run.ok, "{}", run.stderr);
    (std::fs::read(out).unwrap(), run.stderr)
}

/// `raycls` builds its cells while tracing, from every thread at once: 8
/// threads on a fresh structure (36,864 rays, nine chunks of the trace's
/// 4096, so all of them run; most rays from four shared eye points, so they
/// race for the same cells) give, byte for byte, the hits of one thread,
/// and those are `list`'s.
#[test]
fn raycls_builds_concurrently_with_the_answers_of_one_thread() {
    let dir = tempfile::tempdir().unwrap();
    let rays = dir.path().join("rays.bin");
    write_rays(&rays, &eye_rays(9 * 4096));
    let list = soup_scene(dir.path(), 1500, "list", "");
    let scene = soup_scene(dir.path(), 1500, "raycls", "max_candidates = 4");
    for occluded in [false, true] {
        let (want, _) = trace_threads(&list, &rays, 2, occluded);
        let (one, _) = trace_threads(&scene, &rays, 1, occluded);
        let (eight, _) = trace_threads(&scene, &rays, 8, occluded);
        let m = mismatches(&one, &eight);
        assert!(
            m.is_empty(),
            "8 threads against 1 (occluded {occluded}): {} mismatches, e.g. {:?}",
            m.len(),
            &m[..m.len().min(5)]
        );
        let m = mismatches(&want, &one);
        assert!(
            m.is_empty(),
            "raycls against list (occluded {occluded}): {} mismatches, e.g. {:?}",
            m.len(),
            &m[..m.len().min(5)]
        );
    }
}

/// The figures of a `raycls stats:` line on stderr.
fn raycls_stats(stderr: &str) -> std::collections::HashMap<String, u64> {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("raycls stats:"))
        .unwrap_or_else(|| panic!("no stats line in {stderr}"));
    line["raycls stats:".len()..]
        .split_whitespace()
        .filter_map(|kv| {
            let (k, v) = kv.split_once('=')?;
            Some((k.to_string(), v.parse().ok()?))
        })
        .collect()
}

/// A 2 MiB budget on 4000 triangles with `max_candidates = 1` (the table
/// and the roots take about 0.7 MiB of it): the cells the rays ask for
/// would take far more (splits are refused), yet the answers are `list`'s,
/// and the bytes counted never passed the budget.
#[test]
fn raycls_stays_within_its_memory_budget() {
    let dir = tempfile::tempdir().unwrap();
    let rays = dir.path().join("rays.bin");
    write_rays(&rays, &eye_rays(8_000));
    let list = soup_scene(dir.path(), 4000, "list", "");
    let extra = "max_candidates = 1\nmax_depth = 64\nmax_memory_mb = 2\nstats = true";
    let scene = soup_scene(dir.path(), 4000, "raycls", extra);
    for occluded in [false, true] {
        let (want, _) = trace_threads(&list, &rays, 2, occluded);
        let (got, stderr) = trace_threads(&scene, &rays, 2, occluded);
        let m = mismatches(&want, &got);
        assert!(
            m.is_empty(),
            "raycls under its budget against list (occluded {occluded}): {} mismatches, e.g. {:?}",
            m.len(),
            &m[..m.len().min(5)]
        );
        let s = raycls_stats(&stderr);
        assert_eq!(s["budget_bytes"], 2 << 20, "{stderr}");
        assert!(s["refused"] > 0, "the budget was never reached: {stderr}");
        assert!(s["peak_bytes"] <= s["budget_bytes"], "{stderr}");
        assert!(s["memory_bytes"] <= s["peak_bytes"], "{stderr}");
        assert!(s["cells"] > 20, "{stderr}");
    }
}

/// Long randomized run: `cargo test --release -p rtk-tests -- --ignored aggregates_long`.
#[test]
#[ignore]
fn aggregates_long_randomized() {
    for class in AGGREGATES {
        for seed in 10..60 {
            check(seed, class);
        }
    }
}

/// The classes in the build folder.
fn rtk_plugins_available() -> Vec<String> {
    std::fs::read_dir(bin_dir())
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            n.strip_prefix("librtk_")?
                .strip_suffix(".so")
                .map(str::to_string)
        })
        .collect()
}

/// Swapping the bunny scene's root aggregate and the meshes' `accel` among
/// the aggregates gives the same image, bit for bit.
#[test]
fn swapping_aggregates_leaves_the_bunny_image_unchanged() {
    let scene = root().join("scenes/bunny.toml");
    let dir = tempfile::tempdir().unwrap();
    let render = |root_class: &str, accel: &str| {
        let sets = [
            format!("objects.world.class={root_class}"),
            format!("objects.bunny.accel={accel}"),
            format!("objects.floor.accel={accel}"),
            "render.width=96".into(),
            "render.height=72".into(),
        ];
        let mut args = Vec::new();
        for s in &sets {
            args.push("--set");
            args.push(s.as_str());
        }
        let (run, img) = render_file(&scene, dir.path(), &args);
        assert!(run.ok, "{root_class}/{accel}: {}", run.stderr);
        img.unwrap()
    };
    let reference = render("list", "none");
    assert!(reference.data.iter().any(|&v| v > 0.0));
    let mut classes: Vec<&str> = AGGREGATES.to_vec();
    classes.push("list");
    for root_class in &classes {
        for accel in AGGREGATES {
            let img = render(root_class, accel);
            assert!(
                img == reference,
                "root {root_class}, accel {accel}: the image differs"
            );
        }
    }
}

/// The meta-hierarchy of `scenes/nested.toml` (an octree of grids of
/// kd-trees and bvh-wrapped meshes) renders exactly what flat lists render.
#[test]
fn nested_aggregates_render_what_flat_lists_render() {
    let scene = root().join("scenes/nested.toml");
    let dir = tempfile::tempdir().unwrap();
    let small = ["--set", "render.width=128", "--set", "render.height=80"];
    let (run, nested) = render_file(&scene, dir.path(), &small);
    assert!(run.ok, "{}", run.stderr);
    let mut flat_args = small.to_vec();
    for s in [
        "objects.field.class=list",
        "objects.cluster.class=list",
        "objects.balls.class=list",
        "objects.bunny.accel=none",
        "objects.ground.accel=none",
    ] {
        flat_args.extend(["--set", s]);
    }
    let (run, flat) = render_file(&scene, dir.path(), &flat_args);
    assert!(run.ok, "{}", run.stderr);
    let (nested, flat) = (nested.unwrap(), flat.unwrap());
    assert!(nested.data.iter().any(|&v| v > 0.0));
    assert!(
        nested == flat,
        "the nested hierarchy's image differs from the flat one"
    );
}
