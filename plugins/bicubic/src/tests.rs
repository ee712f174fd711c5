//! The patch intersector against references: a planar patch against its
//! plane, closed patch surfaces against leaks at their seams, and normals at
//! collapsed corners. Inputs are rounded to f32 as the renderer's rays are.

use crate::bpt;
use crate::patch::{dot, Patch, V3};
use rtk_kernel::RngState;

const TEAPOT: &str = include_str!("../../../scenes/meshes/teapot.bpt");

fn f32r(v: V3) -> V3 {
    v.map(|x| x as f32 as f64)
}

fn nearest(patches: &[Patch], o: V3, d: V3) -> Option<(f64, usize, f64, f64)> {
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for (i, p) in patches.iter().enumerate() {
        let t_max = best.map_or(f64::INFINITY, |b| b.0);
        if let Some(h) = p.intersect(o, d, 0.0, t_max) {
            best = Some((h.t, i, h.u, h.v));
        }
    }
    best
}

fn teapot() -> Vec<Patch> {
    let (idx, verts) = bpt::parse(TEAPOT).expect("teapot parses");
    assert_eq!((idx.len(), verts.len()), (32, 306));
    idx.iter()
        .map(|q| Patch::new(q.map(|k| f32r(verts[k as usize])), 4))
        .collect()
}

#[test]
fn planar_patch_matches_its_plane() {
    // The plane y = x/4 + z/2 + 1/8 over x ∈ [-1, 2], z ∈ [0.5, 2]: control
    // points on a grid of 1/1024 in x and z, so y is exact and every
    // control point lies exactly on the plane; the boundary control points
    // are collinear along each edge, so the patch covers exactly the
    // rectangle's image, parameterised unevenly (interior points moved).
    let mut rng = RngState::seeded(11);
    let (x0, x1, z0, z1) = (-1.0, 2.0, 0.5, 2.0);
    let grid = |x: f64| (x * 1024.0).round() / 1024.0;
    let plane_y = |x: f64, z: f64| 0.25 * x + 0.5 * z + 0.125;
    let mut cp = [[0.0; 3]; 16];
    for i in 0..4 {
        for j in 0..4 {
            let (mut s, mut t) = (i as f64 / 3.0, j as f64 / 3.0);
            if (1..3).contains(&i) && (1..3).contains(&j) {
                s += 0.06 * (rng.next_f64() - 0.5);
                t += 0.06 * (rng.next_f64() - 0.5);
            }
            let (x, z) = (grid(x0 + s * (x1 - x0)), grid(z0 + t * (z1 - z0)));
            cp[4 * i + j] = [x, plane_y(x, z), z];
        }
    }
    assert_eq!(cp, cp.map(f32r), "exact in f32");
    let patch = Patch::new(cp, 4);
    let n = [0.25, -1.0, 0.5];
    let (mut hits, mut misses) = (0, 0);
    for _ in 0..20_000 {
        let x = x0 - 0.5 + rng.next_f64() * (x1 - x0 + 1.0);
        let z = z0 - 0.5 + rng.next_f64() * (z1 - z0 + 1.0);
        let target = [x, plane_y(x, z), z];
        let side = if rng.next_f64() < 0.5 { 1.0 } else { -1.0 };
        let o = f32r(std::array::from_fn(|k| {
            target[k] + side * n[k] * (0.5 + 2.0 * rng.next_f64()) + (rng.next_f64() - 0.5) * 2.0
        }));
        let d = f32r(std::array::from_fn(|k| target[k] - o[k]));
        // The reference, f64 on the rounded inputs: the plane n·p = -1/8.
        let tr = (-0.125 - dot(n, o)) / dot(n, d);
        let (hx, hz) = (o[0] + tr * d[0], o[2] + tr * d[2]);
        let m = 1e-6;
        let inside = hx > x0 + m && hx < x1 - m && hz > z0 + m && hz < z1 - m;
        let outside = hx < x0 - m || hx > x1 + m || hz < z0 - m || hz > z1 + m;
        let got = patch.intersect(o, d, 0.0, f64::INFINITY);
        if inside && tr > 0.0 {
            let h = got.unwrap_or_else(|| panic!("missed inside at x={hx}, z={hz}"));
            assert!(
                (h.t - tr).abs() <= 1e-9 * tr.abs().max(1.0),
                "t {} against the plane's {tr}",
                h.t
            );
            hits += 1;
        } else if outside || tr <= 0.0 {
            assert!(got.is_none(), "hit outside at x={hx}, z={hz}: {got:?}");
            misses += 1;
        }
    }
    assert!(
        hits > 5_000 && misses > 3_000,
        "{hits} hits, {misses} misses"
    );
}

/// A closed surface of 6 patches: a cube's faces with their control points
/// pushed onto the unit sphere. Shared edges have identical control points.
fn puffed_cube() -> Vec<Patch> {
    let mut out = vec![];
    for axis in 0..3 {
        for sign in [-1.0f64, 1.0] {
            let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut cp = [[0.0; 3]; 16];
            for i in 0..4 {
                for j in 0..4 {
                    let mut p = [0.0; 3];
                    p[axis] = sign;
                    p[a1] = -1.0 + 2.0 * i as f64 / 3.0;
                    p[a2] = -1.0 + 2.0 * j as f64 / 3.0;
                    let l = dot(p, p).sqrt();
                    cp[4 * i + j] = f32r(p.map(|x| x / l));
                }
            }
            out.push(Patch::new(cp, 4));
        }
    }
    out
}

#[test]
fn puffed_cube_shares_its_edges_exactly() {
    let ps = puffed_cube();
    // Every boundary control point appears in at least two patches.
    for (i, p) in ps.iter().enumerate() {
        for (k, c) in p.cp.iter().enumerate() {
            let (r, s) = (k / 4, k % 4);
            if r == 0 || r == 3 || s == 0 || s == 3 {
                let shared = ps
                    .iter()
                    .enumerate()
                    .any(|(j, q)| j != i && q.cp.contains(c));
                assert!(shared, "patch {i} point {k}");
            }
        }
    }
}

/// Rays from inside a closed patch surface, aimed exactly at points on the
/// shared edges (and corners) of its patches: each must hit, at or before
/// its target. Returns (rays, leaks).
fn leak_count(
    ps: &[Patch],
    seams: &[(usize, u8)],
    inside: V3,
    jitter: f64,
    n: usize,
) -> (usize, usize) {
    let mut rng = RngState::seeded(99);
    let mut leaks = 0;
    for r in 0..n {
        let (pi, edge) = seams[r % seams.len()];
        let s = match r % 7 {
            0 => 0.0,
            1 => 1.0,
            _ => rng.next_f64(),
        };
        let (u, v) = match edge {
            0 => (0.0, s),
            1 => (1.0, s),
            2 => (s, 0.0),
            _ => (s, 1.0),
        };
        let target = ps[pi].eval(u, v).p;
        let o = f32r(std::array::from_fn(|k| {
            inside[k] + (rng.next_f64() - 0.5) * 2.0 * jitter
        }));
        let d = f32r(std::array::from_fn(|k| target[k] - o[k]));
        match nearest(ps, o, d) {
            Some((t, ..)) if t <= 1.0 + 1e-6 => {}
            _ => leaks += 1,
        }
    }
    (n, leaks)
}

#[test]
fn no_leaks_at_the_seams_of_a_closed_patch_surface() {
    let ps = puffed_cube();
    let seams: Vec<(usize, u8)> = (0..6).flat_map(|p| (0..4).map(move |e| (p, e))).collect();
    let (n, leaks) = leak_count(&ps, &seams, [0.0; 3], 0.5, 60_000);
    assert_eq!(leaks, 0, "{leaks} of {n} rays aimed at seams escaped");
    // Random directions from inside, too.
    let mut rng = RngState::seeded(5);
    let mut escaped = 0;
    for _ in 0..20_000 {
        let o = f32r(std::array::from_fn(|_| (rng.next_f64() - 0.5) * 0.8));
        let d = f32r(std::array::from_fn(|_| rng.next_f64() - 0.5));
        if nearest(&ps, o, d).is_none() {
            escaped += 1;
        }
    }
    assert_eq!(escaped, 0, "{escaped} random rays escaped");
}

#[test]
fn no_leaks_at_the_teapot_body_seams() {
    let ps = teapot();
    // Body (patches 5-12) and bottom (29-32): every edge of each.
    let seams: Vec<(usize, u8)> = (4..12)
        .chain(28..32)
        .flat_map(|p| (0..4).map(move |e| (p, e)))
        .collect();
    let (n, leaks) = leak_count(&ps, &seams, [0.0, 0.0, 1.0], 0.3, 40_000);
    assert_eq!(
        leaks, 0,
        "{leaks} of {n} rays aimed at the teapot's body seams escaped"
    );
}

#[test]
fn no_nan_normal_at_collapsed_corners() {
    let ps = teapot();
    // Lid knob (patches 21-24) and bottom (29-32) collapse their u = 0 edge.
    for &i in &[20usize, 21, 22, 23, 28, 29, 30, 31] {
        for k in 0..=20 {
            let v = k as f64 / 20.0;
            for u in [0.0, 1e-12, 1e-6] {
                let n = ps[i].normal(u, v).expect("a normal");
                assert!(
                    n.iter().all(|x| x.is_finite()),
                    "patch {i} ({u}, {v}): {n:?}"
                );
                assert!((dot(n, n) - 1.0).abs() < 1e-9);
                if u == 0.0 {
                    // At the apex and the bottom centre the surface is flat,
                    // its normal along the axis.
                    assert!(n[2].abs() > 0.999, "patch {i} apex normal {n:?}");
                }
            }
        }
    }
    // Rays straight at the knob's apex hit it and get a finite normal.
    let mut rng = RngState::seeded(3);
    for r in 0..2000 {
        let off = if r == 0 {
            0.0
        } else {
            1e-3 * (rng.next_f64() - 0.5)
        };
        let o = f32r([off, -off * 0.5, 10.0]);
        let d = [0.0, 0.0, -1.0];
        let (t, i, u, v) = nearest(&ps, o, d).expect("the knob is hit");
        assert!((t - (10.0 - 3.15)).abs() < 1e-3, "t = {t}");
        let n = ps[i].normal(u, v).expect("a normal");
        assert!(
            n.iter().all(|x| x.is_finite()) && n[2].abs() > 0.99,
            "{n:?} at ({u}, {v})"
        );
    }
}

#[test]
fn bad_patch_files_are_refused_with_a_reason() {
    assert!(bpt::parse("").unwrap_err().contains("ends"));
    assert!(bpt::parse("1\n1,2,3").unwrap_err().contains("ends"));
    let one = format!("1\n{}\n1\n0,0,0\n", vec!["2"; 16].join(","));
    assert!(bpt::parse(&one).unwrap_err().contains("vertex 2"));
    let zero = format!("1\n{}\n1\n0,0,0\n", vec!["0"; 16].join(","));
    assert!(bpt::parse(&zero).unwrap_err().contains("1-based"));
}

/// An independent f64 reference: subdivide the patch (de Casteljau, halving
/// u and v) wherever the ray meets the box of the control points (which
/// holds the surface, by the convex hull property) down to sub-patches
/// 2^-`depth` of the parameter square; the nearest such box's entry is the
/// hit, within the box's size.
fn subdivided_t(cp: &[V3; 16], o: V3, d: V3, depth: u32, t_best: f64) -> Option<f64> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in cp {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (mut t0, mut t1) = (0.0f64, t_best);
    for k in 0..3 {
        let inv = 1.0 / d[k];
        let (mut a, mut b) = ((lo[k] - o[k]) * inv, (hi[k] - o[k]) * inv);
        if inv < 0.0 {
            std::mem::swap(&mut a, &mut b);
        }
        if a.is_nan() || b.is_nan() {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        t0 = t0.max(a);
        t1 = t1.min(b);
    }
    if t0 > t1 {
        return None;
    }
    if depth == 0 {
        return Some(t0);
    }
    // Split each row in u, then each column in v, at 1/2.
    let half = |a: [V3; 4]| -> ([V3; 4], [V3; 4]) {
        let m = |x: V3, y: V3| {
            [
                0.5 * (x[0] + y[0]),
                0.5 * (x[1] + y[1]),
                0.5 * (x[2] + y[2]),
            ]
        };
        let (b0, b1, b2) = (m(a[0], a[1]), m(a[1], a[2]), m(a[2], a[3]));
        let (c0, c1) = (m(b0, b1), m(b1, b2));
        let e = m(c0, c1);
        ([a[0], b0, c0, e], [e, c1, b2, a[3]])
    };
    let mut quads = [[[0.0; 3]; 16]; 4];
    // Control point 4 i + j weighs B_i(u) B_j(v): i runs along u.
    for j in 0..4 {
        let (a, b) = half([cp[j], cp[4 + j], cp[8 + j], cp[12 + j]]);
        for i in 0..4 {
            quads[0][4 * i + j] = a[i];
            quads[1][4 * i + j] = b[i];
        }
    }
    let mut out = [[[0.0; 3]; 16]; 4];
    for (q, src) in [(0usize, 0usize), (2, 1)] {
        for i in 0..4 {
            let row = [
                quads[src][4 * i],
                quads[src][4 * i + 1],
                quads[src][4 * i + 2],
                quads[src][4 * i + 3],
            ];
            let (a, b) = half(row);
            for j in 0..4 {
                out[q][4 * i + j] = a[j];
                out[q + 1][4 * i + j] = b[j];
            }
        }
    }
    let mut best = t_best;
    let mut found = None;
    for sub in &out {
        if let Some(t) = subdivided_t(sub, o, d, depth - 1, best) {
            if t < best {
                best = t;
                found = Some(t);
            }
        }
    }
    found
}

/// Random rays at the teapot, the Newton intersector against the
/// subdivision reference: hit or miss agree except within the reference's
/// resolution of a silhouette, and t agrees to the reference's box size
/// where the ray is not grazing.
#[test]
fn teapot_matches_a_subdivision_reference_on_random_rays() {
    let patches = teapot();
    let cps: Vec<[V3; 16]> = teapot_control_points();
    let mut rng = RngState::seeded(0xb1c);
    let (mut mismatches, mut compared, mut worst) = (0, 0, 0.0f64);
    let n = 1500;
    for _ in 0..n {
        let dir = |rng: &mut RngState| {
            let z = 2.0 * rng.next_f64() - 1.0;
            let a = std::f64::consts::TAU * rng.next_f64();
            let r = (1.0 - z * z).sqrt();
            [r * a.cos(), r * a.sin(), z]
        };
        let s = dir(&mut rng);
        let o = f32r([10.0 * s[0], 10.0 * s[1] + 1.5, 10.0 * s[2]]);
        let target = [
            -3.0 + 6.5 * rng.next_f64(),
            0.0 + 3.2 * rng.next_f64(),
            -2.0 + 4.0 * rng.next_f64(),
        ];
        let d = f32r([target[0] - o[0], target[1] - o[1], target[2] - o[2]]);
        let newton = nearest(&patches, o, d);
        let mut reference: Option<f64> = None;
        for cp in &cps {
            let best = reference.unwrap_or(f64::INFINITY);
            if let Some(t) = subdivided_t(cp, o, d, 18, best) {
                reference = Some(reference.map_or(t, |r: f64| r.min(t)));
            }
        }
        match (newton, reference) {
            (Some((t, i, u, v)), Some(r)) => {
                let nrm = patches[i].normal(u, v);
                let len = dot(d, d).sqrt();
                let grazing = nrm.is_none_or(|nv| (dot(nv, d) / len).abs() < 0.1);
                if !grazing {
                    compared += 1;
                    worst = worst.max((t - r).abs() * len);
                }
            }
            (None, None) => {}
            _ => mismatches += 1,
        }
    }
    // Boxes 2^-18 of a patch: about 1e-5 units; a silhouette ray may
    // disagree within that.
    assert!(
        mismatches <= n / 200,
        "{mismatches} hit/miss mismatches in {n}"
    );
    assert!(compared > n / 10, "only {compared} rays compared");
    assert!(worst < 2e-4, "largest distance error {worst}");
}

fn teapot_control_points() -> Vec<[V3; 16]> {
    let (idx, verts) = bpt::parse(TEAPOT).expect("teapot parses");
    idx.iter()
        .map(|q| q.map(|k| f32r(verts[k as usize])))
        .collect()
}
