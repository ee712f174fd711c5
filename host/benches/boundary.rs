//! The cost of the plugin boundary: the same triangles traced through the
//! `mesh` plugin inside the `list` plugin (two indirect calls per ray, through
//! the kernel's records) against a direct loop over the kernel's triangle
//! routine, in ns per ray. The mesh uses `accel = "none"` so both sides test
//! every triangle, and the hit checksums must agree.
//!
//! Run: `cargo build --release --workspace && cargo bench -p rtk-host --bench boundary`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use rtk_kernel::abi::*;
use rtk_kernel::geom::intersect_triangle;
use rtk_shell::{PluginPath, Registry, Sequential};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("root")
        .to_path_buf()
}

/// Read the binary little-endian PLY of `scenes/meshes` (float xyz, uchar-int faces).
fn read_ply(p: &Path) -> Vec<[[f32; 3]; 3]> {
    let b = std::fs::read(p).expect("ply");
    let end = b
        .windows(11)
        .position(|w| w == b"end_header\n")
        .expect("header")
        + 11;
    let head = std::str::from_utf8(&b[..end]).expect("utf8");
    let count = |e: &str| -> usize {
        head.lines()
            .find_map(|l| l.strip_prefix(&format!("element {e} ")))
            .expect("count")
            .trim()
            .parse()
            .expect("n")
    };
    let (nv, nf) = (count("vertex"), count("face"));
    let f = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().expect("4"));
    let v: Vec<[f32; 3]> = (0..nv)
        .map(|i| [f(end + 12 * i), f(end + 12 * i + 4), f(end + 12 * i + 8)])
        .collect();
    let mut o = end + 12 * nv;
    (0..nf)
        .map(|_| {
            assert_eq!(b[o], 3);
            let idx = |k: usize| {
                i32::from_le_bytes(b[o + 1 + 4 * k..o + 5 + 4 * k].try_into().expect("4")) as usize
            };
            let t = [v[idx(0)], v[idx(1)], v[idx(2)]];
            o += 13;
            t
        })
        .collect()
}

fn rays(n: usize) -> Vec<Ray> {
    let mut s = RngState::seeded(1);
    let mut u = || s.next_f32();
    (0..n)
        .map(|_| {
            let o = rtk_kernel::glam::Vec3::new(u() * 30.0 - 15.0, u() * 20.0 - 5.0, 25.0);
            let t = rtk_kernel::glam::Vec3::new(u() * 10.0 - 5.0, u() * 10.0, u() * 7.0 - 3.5);
            Ray::new(o, (t - o).normalize())
        })
        .collect()
}

fn ctx() -> TraceCtx {
    TraceCtx::new(0, 1, 0)
}

fn bench(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("rtk-bench-boundary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let bunny = root().join("scenes/meshes/bunny.ply");
    let one_tri = dir.join("one.obj");
    std::fs::write(&one_tri, "v -5 0 0\nv 5 0 0\nv 0 10 0\nf 1 2 3\n").expect("obj");
    let exe_dir = PathBuf::from(env!("CARGO_BIN_EXE_rtk"))
        .parent()
        .expect("dir")
        .to_path_buf();
    let rays = rays(4096);
    let mut group = c.benchmark_group("boundary");
    group.throughput(Throughput::Elements(rays.len() as u64));
    for (name, file, tris) in [
        ("bunny-3674", bunny.clone(), read_ply(&bunny)),
        (
            "one-triangle",
            one_tri.clone(),
            vec![[[-5.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 10.0, 0.0]]],
        ),
    ] {
        let scene = format!(
            "[render]\nroot = \"world\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
             [objects.m]\nclass = \"mesh\"\nfile = \"{}\"\naccel = \"none\"\n[objects.world]\nclass = \"list\"\nchildren = [\"m\"]\n",
            file.display()
        );
        let sp = dir.join(format!("{name}.toml"));
        std::fs::write(&sp, scene).expect("scene");
        let mut reg = Registry::new(PluginPath {
            dirs: vec![exe_dir.clone()],
        });
        let world =
            rtk_shell::load(&sp, &[], &mut reg, &Sequential).unwrap_or_else(|e| panic!("{e}"));
        let root_obj = &world.root;

        // Both paths must find the same hits.
        let mut cx = ctx();
        let through: f64 = rays
            .iter()
            .map(|r| {
                let mut h = Hit::new();
                if root_obj.intersect(&mut cx, r, &mut h) {
                    h.t as f64
                } else {
                    0.0
                }
            })
            .sum();
        let direct_t = |r: &Ray| -> Option<f32> {
            let mut best: Option<f32> = None;
            for t in &tris {
                if let Some(h) = intersect_triangle(
                    r.origin.to_array(),
                    r.dir.to_array(),
                    *t,
                    r.t_min,
                    best.unwrap_or(r.t_max),
                ) {
                    best = Some(h.t);
                }
            }
            best
        };
        let direct: f64 = rays
            .iter()
            .map(|r| direct_t(r).map_or(0.0, |t| t as f64))
            .sum();
        assert_eq!(through, direct, "{name}: plugin and direct hit sums differ");

        group.bench_with_input(
            BenchmarkId::new("mesh-in-list-plugins", name),
            &rays,
            |b, rays| {
                let mut cx = ctx();
                b.iter(|| {
                    let mut n = 0u32;
                    for r in rays {
                        let mut h = Hit::new();
                        n += root_obj.intersect(&mut cx, r, &mut h) as u32;
                    }
                    n
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new("direct-kernel-routine", name),
            &rays,
            |b, rays| b.iter(|| rays.iter().filter(|r| direct_t(r).is_some()).count()),
        );
        // The direct loop plus what the plugin path also does per ray besides
        // calling through the records: initialise a hit stack and record the hit.
        group.bench_with_input(
            BenchmarkId::new("direct-with-hit-stack", name),
            &rays,
            |b, rays| {
                b.iter(|| {
                    let mut n = 0u32;
                    for r in rays {
                        let mut h = std::hint::black_box(Hit::new());
                        if let Some(t) = direct_t(r) {
                            h.record_leaf(1, t, 0, [0.0, 0.0]);
                            h.record_child(0, 0);
                            n += 1;
                        }
                        std::hint::black_box(&h);
                    }
                    n
                })
            },
        );
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
