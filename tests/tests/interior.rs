//! The paper's fifth operation, `in_interior`, through the real plugins in
//! this process: points against closed forms, Monte-Carlo volumes of every
//! closed class against their exact volumes, open classes answering that
//! they have none, and objects far from the origin under nested transforms.
//! (`rtk conform`'s `interior-parity` check holds each class to the parity
//! of its own `intersect`.)

use rtk_kernel::abi::{Interior, TraceCtx};
use rtk_kernel::glam::{DVec3, Vec3};
use rtk_kernel::RngState;
use rtk_shell::World;
use rtk_tests::{root, world_from};
use std::f64::consts::PI;

/// A scene rooted at `world` (a list over `children`), computed about the
/// world's origin unless `origin` says otherwise.
fn scene(defs: &str, children: &str, origin: &str) -> String {
    format!(
        "[render]\nroot = \"world\"\nintegrator = \"normals\"\norigin = {origin}\n\
         [cameras.c]\nclass = \"pinhole\"\neye = [0.0, 0.0, 10.0]\n\
         {defs}\n[objects.world]\nclass = \"list\"\nchildren = [{children}]\n"
    )
}

fn at(w: &World, p: [f64; 3]) -> Interior {
    let o = w.desc.render.origin;
    let q = Vec3::new(
        (p[0] - o[0]) as f32,
        (p[1] - o[1]) as f32,
        (p[2] - o[2]) as f32,
    );
    let mut ctx = TraceCtx::new(0, 1, 0);
    let a = w.root.in_interior(&mut ctx, q, 0.0);
    assert!(ctx.failure().is_none(), "{:?}", ctx.failure());
    a
}

/// The fraction of `n` uniform points of the box `[lo, hi]` inside the
/// world, on two threads (a stream per thread, fixed seeds).
fn inside_fraction(w: &World, lo: [f64; 3], hi: [f64; 3], n: usize) -> f64 {
    let threads = 2;
    let counts: Vec<u64> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..threads)
            .map(|ti| {
                s.spawn(move || {
                    let mut rng = RngState::seeded(1000 + ti as u64);
                    let mut ctx = TraceCtx::new(ti as u32, threads as u32, 0);
                    let mut inside = 0u64;
                    for _ in 0..n / threads {
                        let p: [f32; 3] = std::array::from_fn(|k| {
                            (lo[k] + (hi[k] - lo[k]) * rng.next_f64()) as f32
                        });
                        if w.root.in_interior(&mut ctx, p, 0.0).is_inside() {
                            inside += 1;
                        }
                    }
                    assert!(ctx.failure().is_none(), "{:?}", ctx.failure());
                    inside
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().expect("thread")).collect()
    });
    counts.iter().sum::<u64>() as f64 / ((n / threads) * threads) as f64
}

/// The Monte-Carlo volume of the world in `[lo, hi]` is within
/// max(0.5 %, 4σ) of `exact` (10⁶ points).
fn assert_volume(what: &str, w: &World, lo: [f64; 3], hi: [f64; 3], exact: f64) {
    let n = 1_000_000;
    let box_volume: f64 = (0..3).map(|k| hi[k] - lo[k]).product();
    let f = inside_fraction(w, lo, hi, n);
    let v = f * box_volume;
    let sigma = box_volume * (f * (1.0 - f) / n as f64).sqrt();
    let tol = (0.005 * exact).max(4.0 * sigma);
    assert!(
        (v - exact).abs() <= tol,
        "{what}: volume {v:.5} against {exact:.5} (tolerance {tol:.5}, σ {sigma:.5})"
    );
}

#[test]
fn spheres_and_tori_answer_their_closed_forms() {
    let w = world_from(&scene(
        "[objects.s]\nclass = \"sphere\"\ncenter = [0.2, -0.1, 0.4]\nradius = 1.3\n\
         [objects.t]\nclass = \"torus\"\ncenter = [5.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\n\
         major_radius = 1.0\nminor_radius = 0.3\n",
        "\"s\", \"t\"",
        "\"world\"",
    ));
    assert_eq!(at(&w, [0.2, -0.1, 0.4]), Interior::INSIDE);
    assert_eq!(at(&w, [0.2 + 1.29, -0.1, 0.4]), Interior::INSIDE);
    assert_eq!(at(&w, [0.2 + 1.31, -0.1, 0.4]), Interior::OUTSIDE);
    // The torus's tube: at distance 1 from its centre in its plane, inside;
    // its centre (the hole) and above the tube, outside.
    assert_eq!(at(&w, [6.0, 0.0, 0.0]), Interior::INSIDE);
    assert_eq!(at(&w, [5.0, 1.25, 0.0]), Interior::INSIDE);
    assert_eq!(at(&w, [5.0, 0.0, 0.0]), Interior::OUTSIDE);
    assert_eq!(at(&w, [6.0, 0.0, 0.31]), Interior::OUTSIDE);
}

#[test]
fn open_and_flat_classes_have_no_interior() {
    let floor = root().join("scenes/meshes/floor.obj");
    let teapot = root().join("scenes/meshes/teapot.bpt");
    let w = world_from(&scene(
        &format!(
            "[objects.d]\nclass = \"disk\"\nradius = 1.0\n\
             [objects.f]\nclass = \"mesh\"\nfile = \"{}\"\n\
             [objects.t]\nclass = \"bicubic\"\nfile = \"{}\"\n",
            floor.display(),
            teapot.display()
        ),
        "\"d\", \"f\", \"t\"",
        "\"world\"",
    ));
    for p in [[0.0, 0.0, 0.0], [0.1, 0.5, 0.2], [10.0, 3.0, -2.0]] {
        assert_eq!(at(&w, p), Interior::NONE, "{p:?}");
    }
    // Cylinders and cones are open unless `caps` closes them.
    let w = world_from(&scene(
        "[objects.c]\nclass = \"cylinder\"\n[objects.k]\nclass = \"cone\"\napex = [3.0, 1.0, 0.0]\naxis = [0.0, -1.0, 0.0]\n",
        "\"c\", \"k\"",
        "\"world\"",
    ));
    assert_eq!(at(&w, [0.0, 0.5, 0.0]), Interior::NONE);
    assert_eq!(at(&w, [3.0, 0.2, 0.0]), Interior::NONE);
}

#[test]
fn capped_cylinders_and_cones_answer_their_closed_forms() {
    let w = world_from(&scene(
        "[objects.c]\nclass = \"cylinder\"\nradius = 0.5\ncaps = true\n\
         [objects.k]\nclass = \"cone\"\napex = [3.0, 1.0, 0.0]\naxis = [0.0, -1.0, 0.0]\nradius = 0.5\ncaps = true\n",
        "\"c\", \"k\"",
        "\"world\"",
    ));
    // The cylinder: y in (0, 1), within 0.5 of the y axis.
    assert_eq!(at(&w, [0.0, 0.5, 0.0]), Interior::INSIDE);
    assert_eq!(at(&w, [0.49, 0.01, 0.0]), Interior::INSIDE);
    assert_eq!(at(&w, [0.0, 1.01, 0.0]), Interior::OUTSIDE);
    assert_eq!(at(&w, [0.51, 0.5, 0.0]), Interior::OUTSIDE);
    // The cone: apex at y = 1, base of radius 0.5 at y = 0.
    assert_eq!(at(&w, [3.0, 0.5, 0.0]), Interior::INSIDE);
    assert_eq!(at(&w, [3.24, 0.5, 0.0]), Interior::INSIDE);
    assert_eq!(at(&w, [3.26, 0.5, 0.0]), Interior::OUTSIDE);
    assert_eq!(at(&w, [3.0, -0.01, 0.0]), Interior::OUTSIDE);
}

/// A closed UV sphere as an OBJ file, and its exact (polyhedral) volume.
fn uv_sphere_obj(dir: &std::path::Path, r: f64, rings: usize, segs: usize) -> (String, f64) {
    let mut v = vec![[0.0, r, 0.0]];
    for i in 1..rings {
        let th = PI * i as f64 / rings as f64;
        for j in 0..segs {
            let ph = 2.0 * PI * j as f64 / segs as f64;
            v.push([
                r * th.sin() * ph.cos(),
                r * th.cos(),
                r * th.sin() * ph.sin(),
            ]);
        }
    }
    v.push([0.0, -r, 0.0]);
    let ring = |i: usize, j: usize| 1 + (i - 1) * segs + j % segs;
    let mut f = Vec::new();
    for j in 0..segs {
        f.push([0, ring(1, j + 1), ring(1, j)]);
        let last = v.len() - 1;
        f.push([last, ring(rings - 1, j), ring(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segs {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j + 1),
                ring(i + 1, j),
            );
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    // Volume by the divergence theorem: the signed tetrahedra from the origin
    // (vertices in f32, as the mesh reads them).
    let p32 = |k: usize| DVec3::from(v[k].map(|x| x as f32 as f64));
    let vol: f64 = f
        .iter()
        .map(|t| p32(t[0]).dot(p32(t[1]).cross(p32(t[2]))) / 6.0)
        .sum();
    let mut text = String::new();
    for p in &v {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &f {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    let path = dir.join("uvsphere.obj");
    std::fs::write(&path, text).expect("obj");
    (path.display().to_string(), vol.abs())
}

/// Six flat bicubic patches closing the unit cube [0, 1]³.
fn cube_patches() -> String {
    let face = |o: [f64; 3], a: [f64; 3], b: [f64; 3]| {
        let pts: Vec<String> = (0..16)
            .map(|k| {
                let (i, j) = ((k / 4) as f64 / 3.0, (k % 4) as f64 / 3.0);
                let p: [f64; 3] = std::array::from_fn(|c| o[c] + i * a[c] + j * b[c]);
                format!("[{}, {}, {}]", p[0], p[1], p[2])
            })
            .collect();
        format!("[{}]", pts.join(", "))
    };
    let (x, y, z) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let faces = [
        face([0.0; 3], y, x),
        face([0.0, 0.0, 1.0], x, y),
        face([0.0; 3], x, z),
        face([0.0, 1.0, 0.0], z, x),
        face([0.0; 3], z, y),
        face([1.0, 0.0, 0.0], y, z),
    ];
    format!("patches = [{}]\n", faces.join(", "))
}

/// What is measured, its definitions, the box sampled and the exact volume.
type VolumeCase = (&'static str, String, [f64; 3], [f64; 3], f64);

#[test]
fn monte_carlo_volumes_of_the_closed_classes_match_their_exact_volumes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (obj, mesh_volume) = uv_sphere_obj(dir.path(), 1.0, 24, 48);
    let cube = root().join("scenes/meshes/cube.obj");
    let cases: Vec<VolumeCase> = vec![
        (
            "sphere",
            "[objects.x]\nclass = \"sphere\"\ncenter = [0.2, -0.1, 0.4]\nradius = 1.3\n".into(),
            [-1.2, -1.5, -1.0],
            [1.6, 1.3, 1.8],
            4.0 / 3.0 * PI * 1.3f64.powi(3),
        ),
        (
            "torus",
            "[objects.x]\nclass = \"torus\"\naxis = [1.0, 2.0, 0.5]\nmajor_radius = 1.0\nminor_radius = 0.3\n".into(),
            [-1.4, -1.4, -1.4],
            [1.4, 1.4, 1.4],
            2.0 * PI * PI * 1.0 * 0.3 * 0.3,
        ),
        (
            "cylinder with caps",
            "[objects.x]\nclass = \"cylinder\"\nbase = [0.1, -0.5, 0.2]\naxis = [0.3, 1.0, -0.2]\nheight = 1.5\nradius = 0.6\ncaps = true\n".into(),
            [-1.0, -1.2, -1.0],
            [1.2, 1.5, 1.3],
            PI * 0.36 * 1.5,
        ),
        (
            "cone with caps",
            "[objects.x]\nclass = \"cone\"\napex = [0.0, 1.0, 0.0]\naxis = [0.0, -1.0, 0.4]\nheight = 1.6\nradius = 0.8\ncaps = true\n".into(),
            [-1.0, -1.0, -0.5],
            [1.0, 1.2, 1.6],
            PI * 0.64 * 1.6 / 3.0,
        ),
        (
            "mesh (a closed UV sphere)",
            format!("[objects.x]\nclass = \"mesh\"\nfile = \"{obj}\"\n"),
            [-1.1, -1.1, -1.1],
            [1.1, 1.1, 1.1],
            mesh_volume,
        ),
        (
            "mesh (the unit cube)",
            format!("[objects.x]\nclass = \"mesh\"\nfile = \"{}\"\n", cube.display()),
            [-0.7, -0.7, -0.7],
            [0.7, 0.7, 0.7],
            1.0,
        ),
        (
            "bicubic (a cube of flat patches)",
            format!("[objects.x]\nclass = \"bicubic\"\n{}", cube_patches()),
            [-0.2, -0.2, -0.2],
            [1.2, 1.2, 1.2],
            1.0,
        ),
        (
            "csg (a sphere less an overlapping one)",
            "[objects.a]\nclass = \"sphere\"\n[objects.x]\nclass = \"csg\"\nop = \"difference\"\n\
             children = [\"a\", { object = \"a\", transform = [{ translate = [1.0, 0.0, 0.0] }] }]\n"
                .into(),
            [-1.1, -1.1, -1.1],
            [1.1, 1.1, 1.1],
            // A unit sphere less the lens two unit spheres a unit apart share.
            4.0 / 3.0 * PI - PI * 5.0 / 12.0,
        ),
        (
            "transform (a sphere scaled by 2, 1.5, 0.5)",
            "[objects.a]\nclass = \"sphere\"\n[objects.x]\nclass = \"transform\"\nchildren = [\"a\"]\n\
             steps = [{ scale = [2.0, 1.5, 0.5] }, { rotate_y = 30.0 }]\n"
                .into(),
            [-2.2, -1.7, -2.2],
            [2.2, 1.7, 2.2],
            4.0 / 3.0 * PI * 1.5,
        ),
        (
            "bvh over two disjoint spheres",
            "[objects.a]\nclass = \"sphere\"\n[objects.x]\nclass = \"bvh\"\n\
             children = [\"a\", { object = \"a\", transform = [{ translate = [3.0, 0.0, 0.0] }] }]\n"
                .into(),
            [-1.1, -1.1, -1.1],
            [4.1, 1.1, 1.1],
            2.0 * 4.0 / 3.0 * PI,
        ),
    ];
    for (what, defs, lo, hi, exact) in cases {
        let w = world_from(&scene(&defs, "\"x\"", "\"world\""));
        assert_volume(what, &w, lo, hi, exact);
    }
}

#[test]
fn nested_transforms_far_from_the_origin_keep_their_interiors() {
    // A sphere of radius 10 at 1e5..3e5 from the origin, under two nested
    // transforms, seen by a camera beside it (the renderer computes about
    // the camera: docs/numerics.md X3).
    let c = [1.0e5, -2.0e5, 3.0e5];
    let defs = format!(
        "[objects.s]\nclass = \"sphere\"\nradius = 10.0\n\
         [objects.inner]\nclass = \"list\"\nchildren = [{{ object = \"s\", transform = [{{ rotate_x = 40.0 }}, {{ translate = [{}, {}, 0.0] }}] }}]\n",
        c[0], c[1]
    );
    let text = scene(
        &defs,
        &format!(
            "{{ object = \"inner\", transform = [{{ rotate_z = 0.0 }}, {{ translate = [0.0, 0.0, {}] }}] }}",
            c[2]
        ),
        "\"camera\"",
    )
    .replace("eye = [0.0, 0.0, 10.0]", &format!("eye = [{}, {}, {}]", c[0], c[1], c[2] + 40.0));
    let w = world_from(&text);
    let mut rng = RngState::seeded(77);
    for _ in 0..2000 {
        let d = rtk_kernel::sdk::shading::uniform_sphere([rng.next_f32(), rng.next_f32()]);
        let d = d.as_dvec3();
        let p_in = DVec3::from(c) + d * 9.9;
        let p_out = DVec3::from(c) + d * 10.1;
        assert_eq!(at(&w, p_in.to_array()), Interior::INSIDE, "{p_in}");
        assert_eq!(at(&w, p_out.to_array()), Interior::OUTSIDE, "{p_out}");
    }
}
