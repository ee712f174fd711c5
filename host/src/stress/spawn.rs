//! S1–S4: rays spawned from surfaces must leave the surface they start on
//! (no self-hits at any scale or angle), yet not jump over a neighbouring
//! surface (thin gaps), and shadow rays between two surfaces must not be
//! stopped by either end.

use super::bench::*;
use super::Case;
use anyhow::Result;
use rtk_kernel::abi::{Hit, LocalGeom, Ray};
use rtk_kernel::geom::{spawn_ray, spawn_ray_between};
use rtk_kernel::glam::DVec3;
use rtk_kernel::sdk::shading::{on_side, reflect_at};
use rtk_kernel::RngState;

/// docs/numerics.md S1.
pub const S1: Case = Case {
    id: "S1",
    title: "self-intersection of spawned rays across scales",
    run: spawned_rays_never_rehit_their_surface,
};

/// docs/numerics.md S2.
pub const S2: Case = Case {
    id: "S2",
    title: "grazing spawned rays, binned by cos θ",
    run: grazing_spawned_rays_never_rehit_their_surface,
};

/// docs/numerics.md S3.
pub const S3: Case = Case {
    id: "S3",
    title: "thin gaps: the offset must not jump a neighbour",
    run: spawned_rays_cross_thin_gaps,
};

/// docs/numerics.md S4.
pub const S4: Case = Case {
    id: "S4",
    title: "shadow rays between two surface points",
    run: shadow_rays_between_surface_points_are_unblocked,
};

/// Which primitive a hit found: the (child, primitive) choice at every level.
fn path(h: &Hit) -> Vec<u32> {
    h.stack[..h.depth as usize].to_vec()
}

/// The scales of S1: (|centre|, triangle or sphere size).
const SCALES: [(f64, f64); 6] = [
    (1.0, 1.0),
    (1e3, 1.0),
    (1e4, 1.0),
    (1e5, 1.0),
    (1.0, 1e-3),
    (1e3, 1e2),
];

/// A cloud of `n` random triangles of size `size` about `c`, far enough
/// apart that a spawned ray meeting one is not a self-hit by accident.
fn triangles(rng: &mut RngState, c: DVec3, size: f64, n: usize) -> Mesh {
    let mut verts = Vec::new();
    let mut tris = Vec::new();
    for i in 0..n {
        let centre = c + unit_vector(rng) * (size * 20.0 * (1.0 + rng.next_f64()));
        for _ in 0..3 {
            verts.push((centre + unit_vector(rng) * size).as_vec3().to_array());
        }
        let k = 3 * i as u32;
        tris.push([k, k + 1, k + 2]);
    }
    Mesh { verts, tris }
}

/// A hit on triangle `i` of `m`, from a random point on a random side, with
/// its local geometry; `None` when the aimed ray found another primitive.
fn hit_on(
    probe: &mut Probe,
    rng: &mut RngState,
    m: &Mesh,
    i: usize,
    size: f64,
) -> Result<Option<(Ray, Hit, LocalGeom)>> {
    let v = m.tris[i].map(|k| DVec3::from(m.verts[k as usize].map(f64::from)));
    let (b1, b2) = (rng.next_f64(), rng.next_f64());
    let (b1, b2) = if b1 + b2 > 1.0 {
        (1.0 - b1, 1.0 - b2)
    } else {
        (b1, b2)
    };
    let target = v[0] + (v[1] - v[0]) * b1 + (v[2] - v[0]) * b2;
    let o = target + unit_vector(rng) * (size * 2.0);
    let r = ray(o, (target - o).normalize());
    let Some(h) = probe.nearest(&r)? else {
        return Ok(None);
    };
    let g = probe.geom(&r, &h)?;
    Ok(Some((r, h, g)))
}

/// Spawned rays over the hemisphere the arriving ray came from, counted
/// when they meet the primitive they leave.
fn spawned_rays_never_rehit_their_surface(b: &mut Bench) -> Result<Vec<Line>> {
    let (tris, per) = (b.n(40, 400), b.n(25, 500));
    let mut rng = RngState::seeded(0x51);
    let mut lines = Vec::new();
    for (mag_c, size) in SCALES {
        let c = unit_vector(&mut rng) * mag_c;
        let m = triangles(&mut rng, c, size, tris);
        let (spawned, rehits) = triangle_self_hits(b, &mut rng, &m, tris, per, size)?;
        let setup = format!("triangle |c| {} size {}", mag(mag_c), mag(size));
        lines.push(Line::count(
            format!("{setup}, {spawned} rays"),
            "self-hits",
            rehits,
        ));

        let (spawned, rehits) = sphere_self_hits(b, &mut rng, c, size, tris, per)?;
        lines.push(Line::count(
            format!("sphere |c| {} r {}, {spawned} rays", mag(mag_c), mag(size)),
            "self-hits",
            rehits,
        ));
    }
    lines.push(denormal_camera(b)?);
    Ok(lines)
}

/// S1 on the triangles `m` (of `size`): spawned rays over the hemisphere
/// each hit's ray came from, `per` a hit; returns (spawned, self-hits).
fn triangle_self_hits(
    b: &mut Bench,
    rng: &mut RngState,
    m: &Mesh,
    tris: usize,
    per: usize,
    size: f64,
) -> Result<(u64, u64)> {
    b.write_obj("s1.obj", m)?;
    let world = b.scene(&format!(
        "{}[objects.m]\nclass = \"mesh\"\nfile = \"s1.obj\"\n",
        header("m")
    ))?;
    let mut probe = Probe::new(&world);
    let (mut spawned, mut rehits) = (0u64, 0u64);
    for i in 0..tris {
        let Some((r, h, g)) = hit_on(&mut probe, rng, m, i, size)? else {
            continue;
        };
        let back = -r.dir.v().as_dvec3();
        for _ in 0..per {
            let w = hemisphere(rng, back).as_vec3();
            let s = spawn_ray(&g, w, &r);
            spawned += 1;
            if let Some(h2) = probe.nearest(&s)? {
                if path(&h2) == path(&h) {
                    rehits += 1;
                }
            }
        }
    }
    Ok((spawned, rehits))
}

/// S1 on a sphere at `c` of radius `size`: rays leaving outwards never
/// meet it again (it is convex), rays leaving inwards meet only its far
/// side; returns (spawned, failures).
fn sphere_self_hits(
    b: &mut Bench,
    rng: &mut RngState,
    c: DVec3,
    size: f64,
    tris: usize,
    per: usize,
) -> Result<(u64, u64)> {
    let world = b.scene(&format!(
        "{}[objects.s]\nclass = \"sphere\"\ncenter = {}\nradius = {}\n",
        header("s"),
        vec3(c.to_array()),
        num(size)
    ))?;
    let mut probe = Probe::new(&world);
    let (mut spawned, mut rehits) = (0u64, 0u64);
    for _ in 0..tris {
        let o = c + unit_vector(rng) * (size * 3.0);
        let target = c + unit_vector(rng) * (size * 0.7);
        let r = ray(o, (target - o).normalize());
        let Some(h) = probe.nearest(&r)? else {
            continue;
        };
        let g = probe.geom(&r, &h)?;
        let n = g.ng.v().as_dvec3();
        let n = if n.dot(g.p.v().as_dvec3() - c) < 0.0 {
            -n
        } else {
            n
        };
        for k in 0..per {
            let out = k % 2 == 0;
            let w = hemisphere(rng, if out { n } else { -n });
            let s = spawn_ray(&g, w.as_vec3(), &r);
            spawned += 1;
            match probe.nearest(&s)? {
                Some(_) if out => rehits += 1,
                // The far side lies at the chord 2r·cos(angle to −n).
                Some(h2) if (h2.t as f64) < 0.5 * 2.0 * size * w.dot(-n) => rehits += 1,
                None if !out => rehits += 1,
                _ => {}
            }
        }
    }
    Ok((spawned, rehits))
}

/// The converse of a self-hit: a camera one denormal (1.4e-45) above a
/// floor, looking down at it, must see the floor in every pixel, where the
/// t bounds of f32 and f64 alike cannot tell t ≈ 1e-45 from 0 (the exact
/// orientation test decides, docs/numerics.md rule 4). Rendered through
/// the render loop about the world's origin, so the eye stays a denormal.
fn denormal_camera(b: &mut Bench) -> Result<Line> {
    let size = b.n(64, 256);
    let floor = Mesh {
        verts: vec![
            [-10.0, 0.0, -10.0],
            [10.0, 0.0, -10.0],
            [10.0, 0.0, 10.0],
            [-10.0, 0.0, 10.0],
        ],
        tris: vec![[0, 2, 1], [0, 3, 2]],
    };
    b.write_obj("floor.obj", &floor)?;
    let world = b.scene(&format!(
        "[render]\nwidth = {size}\nheight = {size}\nroot = \"f\"\norigin = \"world\"\n\
         background = [1.0, 1.0, 1.0]\nintegrator = \"normals\"\n\
         [cameras.c]\nclass = \"pinhole\"\neye = [0.3, 1e-45, 0.2]\nlook_at = [0.5, -1.0, 0.4]\nfov_y = 60.0\n\
         [objects.f]\nclass = \"mesh\"\nfile = \"floor.obj\"\n"
    ))?;
    let film = b.render(&world)?;
    let missed = film.pixels.iter().filter(|p| **p == [1.0; 3]).count();
    Ok(Line::count(
        format!("camera 1e-45 above a floor, {size}^2"),
        "pixels missing the floor",
        missed as u64,
    ))
}

/// S1's triangles with directions at a fixed angle to the surface: a
/// normal offset does not depend on it, so every bin must be clean.
fn grazing_spawned_rays_never_rehit_their_surface(b: &mut Bench) -> Result<Vec<Line>> {
    let (tris, per) = (b.n(40, 400), b.n(10, 100));
    let mut rng = RngState::seeded(0x52);
    let bins = [1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1];
    let mut rehits = [0u64; 6];
    let mut spawned = 0u64;
    for (mag_c, size) in [(1.0, 1.0), (1e3, 1.0), (1e5, 1.0)] {
        let c = unit_vector(&mut rng) * mag_c;
        let m = triangles(&mut rng, c, size, tris);
        b.write_obj("s2.obj", &m)?;
        let world = b.scene(&format!(
            "{}[objects.m]\nclass = \"mesh\"\nfile = \"s2.obj\"\n",
            header("m")
        ))?;
        let mut probe = Probe::new(&world);
        for i in 0..tris {
            let Some((r, h, g)) = hit_on(&mut probe, &mut rng, &m, i, size)? else {
                continue;
            };
            let ng = g.ng.v().as_dvec3();
            let n = if ng.dot(r.dir.v().as_dvec3()) > 0.0 {
                -ng
            } else {
                ng
            };
            for (bin, &cos) in bins.iter().enumerate() {
                for _ in 0..per {
                    let t = unit_vector(&mut rng).reject_from(n).normalize();
                    let w = (n * cos + t * (1.0 - cos * cos).sqrt()).as_vec3();
                    // As a mirror lobe would: kept on its side (shading::on_side).
                    let w = on_side(w, g.ng.v(), n.dot(ng) as f32);
                    let s = spawn_ray(&g, w, &r);
                    spawned += 1;
                    if let Some(h2) = probe.nearest(&s)? {
                        if path(&h2) == path(&h) {
                            rehits[bin] += 1;
                        }
                    }
                }
            }
        }
    }
    let mut lines: Vec<Line> = bins
        .iter()
        .zip(rehits)
        .map(|(cos, n)| {
            Line::count(
                format!("cos θ {cos:e}, |c| 1..1e5, {} rays", spawned / 6),
                "self-hits",
                n,
            )
        })
        .collect();
    lines.push(smooth_mirror(b, &mut rng)?);
    Ok(lines)
}

/// Grazing mirror reflections off a coarse convex mesh with smooth vertex
/// normals: the mirror direction about the shading normal can point below
/// the facet it leaves (rule 13 turns it back). A reflection leaving a
/// convex object outwards never meets it again, so every hit is a ray that
/// passed through the surface.
fn smooth_mirror(b: &mut Bench, rng: &mut RngState) -> Result<Line> {
    let rays = b.n(4000, 100_000);
    b.write_obj("smooth.obj", &uv_sphere(DVec3::ZERO, 8, 16, |_| 1.0))?;
    let world = b.scene(&format!(
        "{}[objects.m]\nclass = \"mesh\"\nfile = \"smooth.obj\"\nnormals = \"vertex\"\n",
        header("m")
    ))?;
    let mut probe = Probe::new(&world);
    let mut through = 0u64;
    for _ in 0..rays {
        // Aim at the silhouette band seen from a random direction.
        let view = unit_vector(rng);
        let side = unit_vector(rng).reject_from(view).normalize();
        let target = side * (0.9 + 0.1 * rng.next_f64());
        let o = target - view * 5.0;
        let r = ray(o, view);
        let Some(h) = probe.nearest(&r)? else {
            continue;
        };
        let g = probe.geom(&r, &h)?;
        let wo = -r.dir.v().normalize();
        let ns = g.ns.v();
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        let s = spawn_ray(&g, reflect_at(&g, wo, n), &r);
        if probe.nearest(&s)?.is_some() {
            through += 1;
        }
    }
    Ok(Line::count(
        format!("smooth-normal mirror, grazing, {rays} rays"),
        "reflections through surface",
        through,
    ))
}

/// Concentric spheres r and r + g, and parallel planes g apart: a ray
/// crossing the first surface outwards must meet the second. The minimum
/// resolvable gap is the smallest g, in ulps of |p|, from which every larger
/// gap tried is crossed correctly.
fn spawned_rays_cross_thin_gaps(b: &mut Bench) -> Result<Vec<Line>> {
    let rays = b.n(300, 5000);
    let gaps_ulps = [256.0, 64.0, 32.0, 16.0, 8.0, 4.0, 2.0];
    let mut rng = RngState::seeded(0x53);
    let mut lines = Vec::new();
    for mag_c in [0.0, 1e5] {
        let c = unit_vector(&mut rng) * mag_c;
        // The ulp at the surfaces' largest coordinate.
        let ulp = |x: f64| (x as f32).next_up() as f64 - x as f32 as f64;
        let pmax = c.abs().max_element() + 1.0;
        let u = ulp(pmax);
        // The smallest gap from which every larger one passed, per surface.
        let (mut sphere_ok, mut plane_ok) = (None, None);
        let (mut sphere_all, mut plane_all) = (true, true);
        for &k in &gaps_ulps {
            let g = k * u;
            let bad = concentric_spheres_crossed(b, &mut rng, c, g, rays)?;
            sphere_all &= bad == 0;
            if sphere_all {
                sphere_ok = Some(k);
            }

            let bad_p = parallel_planes_crossed(b, &mut rng, c, g, rays)?;
            plane_all &= bad_p == 0;
            if plane_all {
                plane_ok = Some(k);
            }
        }
        for (what, ok) in [("spheres", sphere_ok), ("planes", plane_ok)] {
            lines.push(Line::new(
                format!("concentric {what} |c| {}", mag(mag_c)),
                "min resolvable gap (ulps)",
                ok.unwrap_or(f64::INFINITY),
                Target::AtMost(16.0),
            ));
        }
    }
    Ok(lines)
}

/// S3's spheres about `c` of radius 1 and 1 + `g`: rays from the centre
/// must hit the inner one, and their spawned continuations the outer one;
/// returns the failures.
fn concentric_spheres_crossed(
    b: &mut Bench,
    rng: &mut RngState,
    c: DVec3,
    g: f64,
    rays: usize,
) -> Result<u64> {
    let world = b.scene(&format!(
        "{}[objects.a]\nclass = \"sphere\"\ncenter = {c}\nradius = 1.0\n\
         [objects.b]\nclass = \"sphere\"\ncenter = {c}\nradius = {}\n\
         [objects.w]\nclass = \"list\"\nchildren = [\"a\", \"b\"]\n",
        header("w"),
        num(1.0 + g),
        c = vec3(c.to_array()),
    ))?;
    let mut probe = Probe::new(&world);
    let mut bad = 0u64;
    for _ in 0..rays {
        let d = unit_vector(rng);
        let r = ray(c, d);
        let Some(h) = probe.nearest(&r)? else {
            bad += 1;
            continue;
        };
        if h.stack[0] != 0 {
            bad += 1;
            continue;
        }
        let geo = probe.geom(&r, &h)?;
        let s = spawn_ray(&geo, r.dir.v(), &r);
        match probe.nearest(&s)? {
            Some(h2) if h2.stack[0] == 1 => {}
            _ => bad += 1,
        }
    }
    Ok(bad)
}

/// S3's two parallel squares `g` apart, crossed from below: a ray hitting
/// the lower one must, spawned on, hit the upper; returns the failures.
fn parallel_planes_crossed(
    b: &mut Bench,
    rng: &mut RngState,
    c: DVec3,
    g: f64,
    rays: usize,
) -> Result<u64> {
    let z0 = c.z as f32;
    let z1 = (c.z + g) as f32;
    let sq = |z: f32| {
        [
            [c.x as f32 - 2.0, c.y as f32 - 2.0, z],
            [c.x as f32 + 2.0, c.y as f32 - 2.0, z],
            [c.x as f32 + 2.0, c.y as f32 + 2.0, z],
            [c.x as f32 - 2.0, c.y as f32 + 2.0, z],
        ]
    };
    let mut verts = sq(z0).to_vec();
    verts.extend(sq(z1));
    let m = Mesh {
        verts,
        tris: vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
    };
    b.write_obj("s3.obj", &m)?;
    let world = b.scene(&format!(
        "{}[objects.m]\nclass = \"mesh\"\nfile = \"s3.obj\"\n",
        header("m")
    ))?;
    let mut probe = Probe::new(&world);
    let mut bad_p = 0u64;
    for _ in 0..rays {
        let target = c + DVec3::new(rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0, 0.0);
        let o = target - DVec3::new(0.3, 0.2, 1.0 + rng.next_f64());
        let r = ray(o, (target - o).normalize());
        let Some(h) = probe.nearest(&r)? else {
            bad_p += 1;
            continue;
        };
        let lower = path(&h).last().is_some_and(|&e| e < 2);
        if !lower {
            bad_p += 1;
            continue;
        }
        let geo = probe.geom(&r, &h)?;
        let s = spawn_ray(&geo, r.dir.v(), &r);
        match probe.nearest(&s)? {
            Some(h2) if path(&h2).last().is_some_and(|&e| e >= 2) => {}
            _ => bad_p += 1,
        }
    }
    Ok(bad_p)
}

/// Pairs of points on the inside of a closed box (rays from inside find
/// them, so each has its real local geometry), edge-sharing pairs
/// included: a shadow ray between them crosses empty space.
fn shadow_rays_between_surface_points_are_unblocked(b: &mut Bench) -> Result<Vec<Line>> {
    let pairs = b.n(3000, 200_000);
    let mut rng = RngState::seeded(0x54);
    let mut lines = Vec::new();
    for mag_c in [0.0, 1e4] {
        let c = unit_vector(&mut rng) * mag_c;
        // Rotated: the faces of an axis-aligned box have exact coordinates,
        // which would hide the far end's error.
        let turn = rotation(&mut rng);
        let mut m = box_mesh(DVec3::ZERO, DVec3::splat(0.5));
        for v in &mut m.verts {
            *v = (c + turn * DVec3::from(v.map(f64::from)))
                .as_vec3()
                .to_array();
        }
        b.write_obj("s4.obj", &m)?;
        let world = b.scene(&format!(
            "{}[objects.m]\nclass = \"mesh\"\nfile = \"s4.obj\"\n",
            header("m")
        ))?;
        let mut probe = Probe::new(&world);
        let mut point = |rng: &mut RngState, near_edge: bool| -> Result<Option<(Ray, LocalGeom)>> {
            let mut d = unit_vector(rng);
            if near_edge {
                // Aim within 1e-3 of an edge: two box coordinates near ±0.5.
                let i = (rng.next_f64() * 3.0) as usize % 3;
                let mut t = DVec3::ZERO;
                for k in 0..3 {
                    t[k] = if k == i {
                        rng.next_f64() - 0.5
                    } else {
                        (0.5 - 1e-3 * rng.next_f64()).copysign(d[k])
                    };
                }
                d = turn * t.normalize();
            }
            let r = ray(c, d);
            Ok(match probe.nearest(&r)? {
                Some(h) => Some((r, probe.geom(&r, &h)?)),
                None => None,
            })
        };
        let mut found = Vec::with_capacity(2 * pairs);
        for k in 0..2 * pairs {
            if let Some(p) = point(&mut rng, k % 4 < 2)? {
                found.push(p);
            }
        }
        let mut blocked = 0u64;
        let mut tried = 0u64;
        for pair in found.chunks_exact(2) {
            let ((r, from), (_, to)) = (&pair[0], &pair[1]);
            // Two points of one face: the segment lies in its plane, where
            // blocked and clear are both right. A face is two triangles
            // whose normals, computed from rotated vertices, differ by an
            // ulp or two: compare them with a tolerance, not exactly.
            if from.ng.v().dot(to.ng.v()) > 1.0 - 1e-5 {
                continue;
            }
            let s = spawn_ray_between(from, to, r);
            tried += 1;
            if probe.occluded(&s)? {
                blocked += 1;
            }
        }
        lines.push(Line::count(
            format!("box |c| {}, {tried} pairs", mag(mag_c)),
            "false occlusions",
            blocked,
        ));
    }
    Ok(lines)
}
