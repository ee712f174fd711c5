//! T1–T4: the watertight triangle test (docs/numerics.md rules 1–4) through
//! the `mesh` plugin, under the `bvh` the shell builds by default (the
//! 4-wide screen, then the exact test) and under `accel = "none"` (the
//! mesh's own loop): edge-aimed rays never fall between two triangles,
//! rays from inside a closed mesh always hit, degenerate triangles are never
//! reported, and huge coordinates give a finite hit or are refused when the
//! scene is built.

use super::aggregates::{bits, mesh_def, show};
use super::bench::*;
use super::Case;
use anyhow::Result;
use rtk_kernel::abi::{Hit, Ray};
use rtk_kernel::geom::{intersect_triangle_f64, is_degenerate};
use rtk_kernel::glam::{DVec2, DVec3, Vec3};
use rtk_kernel::RngState;
use rtk_shell::World;
use std::collections::HashMap;

/// docs/numerics.md T1.
pub const T1: Case = Case {
    id: "T1",
    title: "shared edge: rays aimed at a quad's diagonal",
    run: rays_at_a_shared_edge_never_leak,
};

/// docs/numerics.md T2.
pub const T2: Case = Case {
    id: "T2",
    title: "closed mesh: every ray from inside hits",
    run: rays_from_inside_a_closed_mesh_always_hit,
};

/// docs/numerics.md T3.
pub const T3: Case = Case {
    id: "T3",
    title: "degenerate, needle and tiny triangles in a closed mesh",
    run: hard_triangles_neither_leak_nor_report_degenerates,
};

/// docs/numerics.md T4.
pub const T4: Case = Case {
    id: "T4",
    title: "huge coordinates: a finite hit or refused at build",
    run: huge_coordinates_hit_finitely_or_are_refused,
};

/// A scene whose root is the mesh in `file`, under the shell's default
/// `accel` (a `bvh`).
fn mesh_scene(file: &str) -> String {
    format!(
        "{}[objects.m]\nclass = \"mesh\"\nfile = \"{file}\"\n",
        header("m")
    )
}

/// The same mesh tested triangle by triangle (`accel = "none"`).
fn bare_scene(file: &str) -> String {
    format!("{}{}", header("m"), mesh_def("m", file))
}

/// The triangle a hit names (the innermost entry of its stack).
fn prim(h: &Hit) -> usize {
    h.stack[h.depth as usize - 1] as usize
}

fn f64v(p: [f32; 3]) -> DVec3 {
    Vec3::from(p).as_dvec3()
}

/// T1: the quad (±1, ±1, 0) split along its v0–v2 diagonal, rotated at
/// random, scaled and moved; rays from 0.5–3 (scaled) units on either side
/// aimed at points of the diagonal computed in f64 from the f32 vertices,
/// at least 1e-5 of its length from its ends (those are corners of the
/// quad's open boundary, where a ray may rightly pass outside). A quad
/// smaller than 16 ulps of its position is no quad in f32, so 1e-3 at 1e5
/// is left out.
///
/// A leak is a ray that hits neither triangle: through the quad (its
/// `bvh`) or through each triangle alone (`accel = "none"`), which also
/// counts the rays both accept. A double hit is no error (the ray meets the
/// edge both triangles contain, and the tie rule picks one), but parity and
/// all-hits users count it twice (catalogue C3); the bound of 1e-3 flags a
/// test that accepts on both sides of an edge beyond exact collinearity.
fn rays_at_a_shared_edge_never_leak(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(20_000, 400_000);
    let mut rng = RngState::seeded(0x71);
    let mut lines = Vec::new();
    let (mut doubles, mut total) = (0u64, 0u64);
    for &(scale, dist) in &[
        (1e-3, 0.0),
        (1.0, 0.0),
        (1e3, 0.0),
        (1e-3, 1e3),
        (1.0, 1e3),
        (1e3, 1e3),
        (1.0, 1e5),
        (1e3, 1e5),
    ] {
        let leaks = quad_edge_leaks(b, &mut rng, scale, dist, n, &mut doubles)?;
        total += n as u64;
        lines.push(Line::count(
            format!("scale {} |c| {}, {n} rays", mag(scale), mag(dist)),
            "edge leaks",
            leaks,
        ));
    }
    lines.push(Line::new(
        format!("all 8 above, {total} rays"),
        "edge double hits (rate)",
        doubles as f64 / total as f64,
        Target::AtMost(1e-3),
    ));
    lines.push(the_oblikovati_ray(b)?);
    Ok(lines)
}

/// T1 at one scale and distance: `n` rays at the diagonal of a random
/// quad, through the quad (its `bvh`) and each triangle alone. Returns the
/// leaks; double hits are added to `doubles`.
fn quad_edge_leaks(
    b: &mut Bench,
    rng: &mut RngState,
    scale: f64,
    dist: f64,
    n: usize,
    doubles: &mut u64,
) -> Result<u64> {
    let rot = rotation(rng);
    let c = unit_vector(rng) * dist;
    let verts: Vec<[f32; 3]> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(x, y)| {
            (c + rot * DVec3::new(x, y, 0.0) * scale)
                .as_vec3()
                .to_array()
        })
        .collect();
    let mesh = |tris: Vec<[u32; 3]>| Mesh {
        verts: verts.clone(),
        tris,
    };
    b.write_obj("t1-quad.obj", &mesh(vec![[0, 1, 2], [0, 2, 3]]))?;
    b.write_obj("t1-a.obj", &mesh(vec![[0, 1, 2]]))?;
    b.write_obj("t1-b.obj", &mesh(vec![[0, 2, 3]]))?;
    let wq = b.scene(&mesh_scene("t1-quad.obj"))?;
    let wa = b.scene(&bare_scene("t1-a.obj"))?;
    let wb = b.scene(&bare_scene("t1-b.obj"))?;
    let (mut pq, mut pa, mut pb) = (Probe::new(&wq), Probe::new(&wa), Probe::new(&wb));
    let normal = rot * DVec3::Z;
    let (p0, p2) = (f64v(verts[0]), f64v(verts[2]));
    let mut leaks = 0u64;
    for _ in 0..n {
        let p = p0 + (p2 - p0) * (1e-5 + (1.0 - 2e-5) * rng.next_f64());
        let side = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
        let along = rot * DVec3::new(4.0 * rng.next_f64() - 2.0, 4.0 * rng.next_f64() - 2.0, 0.0);
        let height = side * (0.5 + 2.5 * rng.next_f64());
        let o = (p + (normal * height + along) * scale).as_vec3();
        let d = (p - o.as_dvec3()).normalize().as_vec3();
        let ray = ray32(o, d);
        let quad = pq.nearest(&ray)?;
        let (a, bb) = (pa.nearest(&ray)?, pb.nearest(&ray)?);
        if quad.is_none() || (a.is_none() && bb.is_none()) {
            if leaks == 0 {
                eprintln!(
                    "T1 scale {scale:e} |c| {dist:e}: leak (quad {}, a {}, b {}); ray {}",
                    show(&quad),
                    show(&a),
                    show(&bb),
                    bits(&ray)
                );
            }
            leaks += 1;
        }
        if a.is_some() && bb.is_some() {
            *doubles += 1;
        }
    }
    Ok(leaks)
}

/// The failing ray of Oblikovati#2146, against the quad (±5, ±5, 0),
/// under the bvh and with no acceleration.
fn the_oblikovati_ray(b: &mut Bench) -> Result<Line> {
    let quad = Mesh {
        verts: vec![
            [-5.0, -5.0, 0.0],
            [5.0, -5.0, 0.0],
            [5.0, 5.0, 0.0],
            [-5.0, 5.0, 0.0],
        ],
        tris: vec![[0, 1, 2], [0, 2, 3]],
    };
    b.write_obj("t1-wild.obj", &quad)?;
    let mut leaks = 0;
    for scene in [mesh_scene("t1-wild.obj"), bare_scene("t1-wild.obj")] {
        let w = b.scene(&scene)?;
        let ray = ray32(
            Vec3::new(0.0, 0.0, 10.0),
            Vec3::new(0.30458447, 0.30458447, -0.9024725),
        );
        if Probe::new(&w).nearest(&ray)?.is_none() {
            leaks += 1;
        }
    }
    Ok(Line::count(
        "Oblikovati#2146 ray, bvh and none",
        "edge leaks",
        leaks,
    ))
}

/// T2: pbrt-v4's `Triangle.Watertight` recipe. A 16×16 UV sphere with
/// vertex radii jittered in [1, 6] (poles and seam shared), rays from the
/// r = ½ ball inside, in random directions and aimed exactly at vertices,
/// with the mesh at |c| = 0, 1e3, 1e5. Every ray from inside must hit (see
/// [`leak`]). Where a vertex fan holds a nearly edge-on triangle, pbrt's
/// `t ≤ δt → reject` leaks; rtk rechecks such hits in f64 (rule 4).
fn rays_from_inside_a_closed_mesh_always_hit(b: &mut Bench) -> Result<Vec<Line>> {
    let (random, aimed) = (b.n(20_000, 200_000), b.n(20_000, 1_000_000));
    let every = b.n(4, 20);
    let mut rng = RngState::seeded(0x72);
    let mut lines = Vec::new();
    let mut nonfinite = 0u64;
    for &dist in &[0.0, 1e3, 1e5] {
        let c = unit_vector(&mut rng) * dist;
        let mesh = uv_sphere(c, 16, 16, |_| 1.0 + 5.0 * rng.next_f64());
        b.write_obj("t2.obj", &mesh)?;
        let wb = b.scene(&mesh_scene("t2.obj"))?;
        let wn = b.scene(&bare_scene("t2.obj"))?;
        let (mut pb, mut pn) = (Probe::new(&wb), Probe::new(&wn));
        let (mut leaks, mut leaks_bare, mut bare) = (0u64, 0u64, 0u64);
        for k in 0..random + aimed {
            let o = (c + unit_vector(&mut rng) * (0.5 * rng.next_f64().cbrt())).as_vec3();
            let d = if k < random {
                unit_vector(&mut rng).as_vec3()
            } else {
                let v = mesh.verts[(rng.next_u32() as usize) % mesh.verts.len()];
                (f64v(v) - o.as_dvec3()).normalize().as_vec3()
            };
            let ray = ray32(o, d);
            let mut check = |h: &Option<Hit>, what: &str, count: &mut u64| match h {
                None => leak(&mesh, &ray, &format!("T2 |c| {dist:e} ({what})"), count),
                Some(h) if !h.t.is_finite() => nonfinite += 1,
                _ => {}
            };
            check(&pb.nearest(&ray)?, "bvh", &mut leaks);
            if k % every == 0 {
                bare += 1;
                check(&pn.nearest(&ray)?, "none", &mut leaks_bare);
            }
        }
        lines.push(Line::count(
            format!("|c| {}, bvh, {random}+{aimed} rays", mag(dist)),
            "leaks",
            leaks,
        ));
        lines.push(Line::count(
            format!("|c| {}, accel none, {bare} rays", mag(dist)),
            "leaks",
            leaks_bare,
        ));
    }
    lines.push(Line::count("all above", "non-finite t", nonfinite));
    Ok(lines)
}

/// The closed box [−1, 1]³ about `c` whose faces hold T3's hard triangles,
/// and what to aim at.
struct Hard {
    mesh: Mesh,
    /// The vertices the hard triangles meet at.
    special: Vec<[f32; 3]>,
    /// Needles (one along an edge, one along a diagonal).
    needles: Vec<usize>,
    /// The 1e-6 triangle.
    tiny: usize,
    /// The needles' aspect (length over height).
    aspect: f64,
    /// The diagonal that three collinear vertices lie on.
    diagonal: (DVec3, DVec3),
}

/// The points of [`hard_box`]'s faces in a face's (u, v) square: its
/// corners A, B, C, D, the needles' apexes q (h above AB) and q2 (h/√2
/// off the diagonal), the centre m, and the 1e-6 triangle t0, t1, t2.
#[derive(Clone, Copy)]
struct FacePoints {
    a: DVec2,
    b: DVec2,
    cc: DVec2,
    d: DVec2,
    q: DVec2,
    m: DVec2,
    t0: DVec2,
    t1: DVec2,
    t2: DVec2,
    q2: DVec2,
}

impl FacePoints {
    fn new(h: f64) -> FacePoints {
        FacePoints {
            a: DVec2::new(-1.0, -1.0),
            b: DVec2::new(1.0, -1.0),
            cc: DVec2::new(1.0, 1.0),
            d: DVec2::new(-1.0, 1.0),
            q: DVec2::new(0.0, -1.0 + h),
            m: DVec2::ZERO,
            t0: DVec2::new(0.3, 0.2),
            t1: DVec2::new(0.3 + 1e-6, 0.2),
            t2: DVec2::new(0.3, 0.2 + 1e-6),
            q2: DVec2::new(0.2 + h / 2.0, 0.2 - h / 2.0),
        }
    }

    /// The six faces' triangles, in the order [`hard_box`] describes.
    fn faces(&self) -> [Vec<[DVec2; 3]>; 6] {
        let FacePoints {
            a,
            b,
            cc,
            d,
            q,
            m,
            t0,
            t1,
            t2,
            q2,
        } = *self;
        [
            vec![[a, b, cc], [a, cc, d]],
            vec![[a, b, q], [b, cc, q], [cc, d, q], [d, a, q]],
            vec![
                [a, b, m],
                [b, cc, m],
                [cc, d, m],
                [d, a, m],
                [a, m, cc],
                [a, a, b],
                [b, m, d],
            ],
            vec![
                [a, b, t1],
                [a, t1, t0],
                [b, cc, t1],
                [cc, t2, t1],
                [cc, d, t2],
                [d, a, t0],
                [d, t0, t2],
                [t0, t1, t2],
            ],
            vec![[a, cc, d], [a, b, q2], [b, cc, q2], [cc, a, q2]],
            vec![[a, b, cc], [a, cc, d]],
        ]
    }
}

/// Each face is triangulated in its own (u, v) square, counter-clockwise
/// seen from outside; vertices are rounded to f32 once and shared by
/// position, so every edge is shared exactly. The faces: plain; a fan about
/// a vertex h from an edge (a needle); a fan about the centre with the
/// zero-area triangles (A, m, C) and (B, m, D) (collinear vertices on
/// existing edges) and (A, A, B) (a repeated vertex); a 1e-6 triangle inside
/// the face; a diagonal split with a vertex h/√2 off the diagonal (a needle
/// across the face); plain.
///
/// h is 2e-6 (aspect 1e6) where f32 can hold it (|c| = 0), else 4 ulps of
/// the coordinates: a thinner needle's apex rounds onto its base edge, and
/// the mesh then has a T-junction, which no intersector closes. The 1e-6
/// triangle may collapse (below an ulp at |c| = 1e3, as the catalogue asks):
/// it lies inside the face, so its fan stays closed.
fn hard_box(c: DVec3) -> Hard {
    let top = (c.abs().max_element() + 1.0) as f32;
    let h = 2e-6f64.max(4.0 * (top.next_up() - top) as f64);
    let fp = FacePoints::new(h);
    let faces = fp.faces();
    let FacePoints {
        a,
        cc,
        q,
        m,
        t0,
        t1,
        t2,
        q2,
        ..
    } = fp;
    let mut mesh = Mesh {
        verts: vec![],
        tris: vec![],
    };
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut hard = Hard {
        mesh: Mesh {
            verts: vec![],
            tris: vec![],
        },
        special: vec![],
        needles: vec![],
        tiny: 0,
        aspect: 2.0 / h,
        diagonal: (DVec3::ZERO, DVec3::ZERO),
    };
    for (f, tris) in faces.iter().enumerate() {
        let (axis, sign) = (f / 2, if f % 2 == 0 { 1.0 } else { -1.0 });
        let e = |k: usize| {
            let mut v = DVec3::ZERO;
            v[k % 3] = 1.0;
            v
        };
        let n = e(axis) * sign;
        let (u, v) = if sign > 0.0 {
            (e(axis + 1), e(axis + 2))
        } else {
            (e(axis + 2), e(axis + 1))
        };
        let at = |p: DVec2| c + n + u * p.x + v * p.y;
        if f == 2 {
            hard.diagonal = (at(a), at(cc));
        }
        for (k, t) in tris.iter().enumerate() {
            let ids = t.map(|p| {
                let x = at(p).as_vec3().to_array();
                *index.entry(x.map(f32::to_bits)).or_insert_with(|| {
                    mesh.verts.push(x);
                    mesh.verts.len() as u32 - 1
                })
            });
            let i = mesh.tris.len();
            match (f, k) {
                (1, 0) | (4, 3) => hard.needles.push(i),
                (3, 7) => hard.tiny = i,
                _ => {}
            }
            mesh.tris.push(ids);
        }
        for p in [q, m, t0, t1, t2, q2] {
            hard.special.push(at(p).as_vec3().to_array());
        }
    }
    hard.mesh = mesh;
    hard
}

/// T3: the closed box of [`hard_box`] at |c| = 0, 1e3, 1e5, rays from the
/// r = ½ ball inside aimed at the vertices the hard triangles meet at, into
/// the needles and the tiny triangle, along the collinear diagonal, and in
/// random directions. No ray may leak (bvh or none), no hit may name a
/// zero-area triangle, normals must be finite and unit, and nothing in the
/// hit's record (t, p, its error, normals, tangents, uv) may be non-finite.
fn hard_triangles_neither_leak_nor_report_degenerates(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(20_000, 300_000);
    let mut rng = RngState::seeded(0x73);
    let mut lines = Vec::new();
    for &dist in &[0.0, 1e3, 1e5] {
        let c = unit_vector(&mut rng) * dist;
        let hard = hard_box(c);
        let m = &hard.mesh;
        b.write_obj("t3.obj", m)?;
        let tri = |i: usize| m.tris[i].map(|k| m.verts[k as usize]);
        let zero_area: Vec<bool> = (0..m.tris.len())
            .map(|i| is_degenerate(&tri(i).map(|p| p.map(f64::from))))
            .collect();
        let wb = b.scene(&mesh_scene("t3.obj"))?;
        let wn = b.scene(&bare_scene("t3.obj"))?;
        let (mut leaks, mut degenerate, mut normals, mut nonfinite) = (0u64, 0u64, 0u64, 0u64);
        for world in [&wb, &wn] {
            let mut probe = Probe::new(world);
            let mut r = RngState::seeded(0x730 + dist as u64);
            for k in 0..n {
                let o = (c + unit_vector(&mut r) * (0.5 * r.next_f64().cbrt())).as_vec3();
                let inside = |r: &mut RngState, i: usize| {
                    let (x, y) = (r.next_f64(), r.next_f64());
                    let (x, y) = if x + y > 1.0 {
                        (1.0 - x, 1.0 - y)
                    } else {
                        (x, y)
                    };
                    let v = tri(i);
                    f64v(v[0]) * (1.0 - x - y) + f64v(v[1]) * x + f64v(v[2]) * y
                };
                let target = match k % 5 {
                    0 => f64v(hard.special[(r.next_u32() as usize) % hard.special.len()]),
                    1 => inside(&mut r, hard.needles[k / 5 % hard.needles.len()]),
                    2 => inside(&mut r, hard.tiny),
                    3 => {
                        let (a, cc) = hard.diagonal;
                        a + (cc - a) * r.next_f64()
                    }
                    _ => o.as_dvec3() + unit_vector(&mut r),
                };
                let ray = ray32(o, (target - o.as_dvec3()).normalize().as_vec3());
                let Some(h) = probe.nearest(&ray)? else {
                    leak(m, &ray, &format!("T3 |c| {dist:e}"), &mut leaks);
                    continue;
                };
                if zero_area[prim(&h)] {
                    degenerate += 1;
                }
                let g = probe.geom(&ray, &h)?;
                let unit = |v: Vec3| v.is_finite() && (v.length() - 1.0).abs() <= 1e-5;
                if !(unit(g.ng.v()) && unit(g.ns.v())) {
                    normals += 1;
                }
                let fields = [g.p, g.p_err, g.ng, g.ns, g.dpdu, g.dpdv];
                if !(h.t.is_finite()
                    && fields.iter().all(|v| v.is_finite())
                    && g.uv.iter().all(|x| x.is_finite()))
                {
                    nonfinite += 1;
                }
            }
        }
        let setup = format!(
            "|c| {} needles 1:{:.0e}, 2x{n} rays",
            mag(dist),
            hard.aspect
        );
        lines.push(Line::count(&setup, "leaks", leaks));
        lines.push(Line::count(&setup, "zero-area triangles hit", degenerate));
        lines.push(Line::count(&setup, "non-finite/non-unit normals", normals));
        lines.push(Line::count(setup, "non-finite in hit record", nonfinite));
    }
    Ok(lines)
}

/// T4: the triangle (−s, −s, 0), (s, −s, 0), (0, s, 0) seen from about
/// (0, 0, s), for s = 1e7 … 1e30. The edge functions grow like s² and t's
/// numerator like s³: f32 gives t = ∞ from about 1e13 and NaN from 1e19, so
/// the mesh plugin must refuse |x| > 1e12 when the scene is built (rule 1),
/// and below that every hit must be finite and agree with the f64 test on
/// the same inputs. Rays are aimed inside the triangle (barycentrics ≥
/// 0.01), where f32 and f64 cannot disagree about hitting. Also a closed
/// mesh at 2²⁴, where the f32 spacing is 2, must not leak.
fn huge_coordinates_hit_finitely_or_are_refused(b: &mut Bench) -> Result<Vec<Line>> {
    let per = b.n(1_000, 50_000);
    let mut rng = RngState::seeded(0x74);
    let (mut accepted, mut refused) = (0u64, 0u64);
    let mut t = HugeTally::default();
    for &s in &[
        1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 3e12, 1e13, 1e15, 1e19, 1e20, 1e25, 1e30,
    ] {
        let v = [[-s, -s, 0.0], [s, -s, 0.0], [0.0, s, 0.0]].map(|p| p.map(|x| x as f32));
        b.write_obj(
            "t4.obj",
            &Mesh {
                verts: v.to_vec(),
                tris: vec![[0, 1, 2]],
            },
        )?;
        let scene = mesh_scene("t4.obj");
        if v[1][0] as f64 > 1e12 {
            refused += 1;
            if b.build_error(&scene).is_none() {
                eprintln!("T4 s {s:e}: a mesh beyond 1e12 was accepted");
                accepted += 1;
            }
            continue;
        }
        let w = b.scene(&scene)?;
        t.trace(&w, &mut rng, s, v, per)?;
    }
    let traced = t.traced;
    let mut lines = vec![
        Line::count(
            format!("s 1e7..1e12, {traced} rays"),
            "non-finite t",
            t.nonfinite,
        ),
        Line::count(
            format!("s 1e7..1e12, {traced} rays"),
            "hit/miss differs from f64",
            t.misses,
        ),
        Line::new(
            format!("s 1e7..1e12, {traced} rays"),
            "max |t-t64|/t64",
            t.worst,
            Target::AtMost(1e-6),
        ),
        Line::count(
            format!("s 3e12..1e30, {refused} meshes"),
            "out-of-range input accepted",
            accepted,
        ),
    ];
    lines.extend(closed_mesh_far_away(b, &mut rng)?);
    Ok(lines)
}

/// T4's measures over the triangles it traces.
#[derive(Default)]
struct HugeTally {
    nonfinite: u64,
    /// Hit or miss unlike the f64 test's.
    misses: u64,
    /// The largest relative error of t against f64.
    worst: f64,
    traced: u64,
}

impl HugeTally {
    /// `per` rays at T4's triangle of size `s` (vertices `v`) in `w`, the
    /// first from (0, 0, s) straight down, the rest from random points
    /// above it aimed inside it (barycentrics ≥ 0.01), against the f64 test.
    fn trace(
        &mut self,
        w: &World,
        rng: &mut RngState,
        s: f64,
        v: [[f32; 3]; 3],
        per: usize,
    ) -> Result<()> {
        let mut probe = Probe::new(w);
        let v64 = v.map(|p| p.map(f64::from));
        for k in 0..per {
            let (o, d) = if k == 0 {
                (Vec3::new(0.0, 0.0, s as f32), Vec3::NEG_Z)
            } else {
                aimed_inside(rng, s, &v64)
            };
            let ray = ray32(o, d);
            self.traced += 1;
            let got = probe.nearest(&ray)?;
            let want = intersect_triangle_f64(
                o.as_dvec3().to_array(),
                d.as_dvec3().to_array(),
                v64,
                0.0,
                f64::INFINITY,
            );
            match (got, want) {
                (Some(h), _) if !h.t.is_finite() => self.nonfinite += 1,
                (Some(h), Some(r)) => self.worst = self.worst.max((h.t as f64 - r.t).abs() / r.t),
                (None, None) => {}
                _ => {
                    if self.misses == 0 {
                        eprintln!(
                            "T4 s {s:e}: f32 {} vs f64 {want:?}; ray {}",
                            show(&got),
                            bits(&ray)
                        );
                    }
                    self.misses += 1;
                }
            }
        }
        Ok(())
    }
}

/// A ray from a random point above T4's triangle of size `s` (vertices
/// `v64`), aimed at a point inside it: its origin and direction.
fn aimed_inside(rng: &mut RngState, s: f64, v64: &[[f64; 3]; 3]) -> (Vec3, Vec3) {
    let (x, y) = (rng.next_f64(), rng.next_f64());
    let (x, y) = if x + y > 1.0 {
        (1.0 - x, 1.0 - y)
    } else {
        (x, y)
    };
    let bc = [1.0 - x - y, x, y].map(|w| 0.01 + 0.97 * w);
    let p = (0..3).fold(DVec3::ZERO, |p, i| p + DVec3::from(v64[i]) * bc[i]);
    let o = DVec3::new(
        s * (rng.next_f64() - 0.5),
        s * (rng.next_f64() - 0.5),
        s * (0.5 + 1.5 * rng.next_f64()),
    )
    .as_vec3();
    (o, (p - o.as_dvec3()).normalize().as_vec3())
}

/// T4's closed mesh at 2^24, radii 50-100 (its vertices snap to even
/// integers): rays from inside must not leak nor give a non-finite t.
fn closed_mesh_far_away(b: &mut Bench, rng: &mut RngState) -> Result<Vec<Line>> {
    let n = b.n(10_000, 200_000);
    let c = DVec3::splat(2f64.powi(24));
    let mesh = uv_sphere(c, 16, 16, |_| 50.0 + 50.0 * rng.next_f64());
    b.write_obj("t4-far.obj", &mesh)?;
    let w = b.scene(&mesh_scene("t4-far.obj"))?;
    let mut probe = Probe::new(&w);
    let (mut leaks, mut nonfinite) = (0u64, 0u64);
    for k in 0..n {
        let o = (c + unit_vector(rng) * (20.0 * rng.next_f64().cbrt())).as_vec3();
        let d = if k % 2 == 0 {
            unit_vector(rng).as_vec3()
        } else {
            let v = mesh.verts[(rng.next_u32() as usize) % mesh.verts.len()];
            (f64v(v) - o.as_dvec3()).normalize().as_vec3()
        };
        let ray = ray32(o, d);
        match probe.nearest(&ray)? {
            None => leak(&mesh, &ray, "T4 mesh at 2^24", &mut leaks),
            Some(h) if !h.t.is_finite() => nonfinite += 1,
            _ => {}
        }
    }
    let setup = format!("closed mesh at 2^24, {n} rays");
    Ok(vec![
        Line::count(&setup, "leaks", leaks),
        Line::count(setup, "non-finite t", nonfinite),
    ])
}

/// A ray from inside the closed mesh `m` found nothing: count it as a
/// leak, unless its origin lies outside the mesh (winding number 0, in
/// f64), where a miss is right: jittered radii can bring an edge closer to
/// the centre than the ball the origins are drawn from. The first few
/// leaks are printed with the f64 test's answer over every triangle.
fn leak(m: &Mesh, ray: &Ray, what: &str, count: &mut u64) {
    let o = ray.origin.v();
    let w = winding(m, o.as_dvec3());
    if w.abs() < 0.5 {
        return;
    }
    if *count < 3 {
        eprintln!(
            "{what}: leak (winding {w:.3}, f64 {:?}); ray {}",
            nearest64(m, o, ray.dir.v()),
            bits(ray)
        );
    }
    *count += 1;
}

/// The winding number of the closed mesh `m` about `o`, in f64 (solid
/// angles, Van Oosterom and Strackee): ±1 inside, 0 outside.
fn winding(m: &Mesh, o: DVec3) -> f64 {
    let mut sum = 0.0;
    for t in &m.tris {
        let [a, b, c] = t.map(|k| f64v(m.verts[k as usize]) - o);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c));
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        sum += 2.0 * det.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// The nearest hit of the f64 test over every triangle of `m`.
fn nearest64(m: &Mesh, o: Vec3, d: Vec3) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for (i, t) in m.tris.iter().enumerate() {
        let v = t.map(|k| m.verts[k as usize].map(f64::from));
        if let Some(h) = intersect_triangle_f64(
            o.as_dvec3().to_array(),
            d.as_dvec3().to_array(),
            v,
            0.0,
            best.map_or(f64::INFINITY, |b| b.0),
        ) {
            best = Some((h.t, i));
        }
    }
    best
}
