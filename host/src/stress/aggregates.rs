//! A1–A5: every aggregate returns exactly the `list`'s answer over the same
//! children, on the catalogue's adversarial ray sets: axis-parallel rays with
//! ±0 components from faces, edges and corners (A1), rays grazing the edges
//! of flat boxes far from the origin (A2), random scenes with ties, nesting
//! and instances (A3), the DDA's corner cases (A4), and hits of a nested
//! aggregate that lie beyond the current cell (A5).
//!
//! Why exact equality and no tolerance: ties at equal `t` go to the lowest
//! (child, primitive) (docs/numerics.md rule 11) and every structure runs
//! the same primitive tests, so any difference in `t` or in the path of
//! (child, primitive) on the hit stack is a hit lost or invented by the
//! traversal. Meshes are children with `accel = "none"`, so that under `list`
//! and under a flattening aggregate the hit stacks have the same shape.

use super::bench::*;
use super::Case;
use anyhow::{bail, Result};
use rtk_kernel::abi::{Hit, Ray, Stats, TraceCtx};
use rtk_kernel::geom::{intersect_triangle, RayBoxPrecomp};
use rtk_kernel::glam::{DVec3, Vec3};
use rtk_kernel::{Bounds3, RngState};
use rtk_shell::World;

/// docs/numerics.md A1.
pub const A1: Case = Case {
    id: "A1",
    title: "axis-parallel rays, ±0 components, origins on faces/edges/corners",
    run: axis_parallel_rays_agree_with_the_list,
};

/// docs/numerics.md A2.
pub const A2: Case = Case {
    id: "A2",
    title: "flat leaf boxes far from the origin: no false misses",
    run: flat_boxes_far_away_lose_no_hits,
};

/// docs/numerics.md A3.
pub const A3: Case = Case {
    id: "A3",
    title: "every aggregate, nested, equals brute force (list)",
    run: aggregates_match_the_list_on_random_scenes,
};

/// docs/numerics.md A4.
pub const A4: Case = Case {
    id: "A4",
    title: "grid/octree/kd-tree DDA corner cases on a 64^3 grid",
    run: dda_corner_cases_agree_with_the_list,
};

/// docs/numerics.md A5.
pub const A5: Case = Case {
    id: "A5",
    title: "aggregate nested in a grid: out-of-cell hits, mailboxes",
    run: nested_aggregates_keep_out_of_cell_hits,
};

/// Traces single rays through a world's root, as [`Probe`] does, and keeps
/// the counters the performance guards read: node and primitive tests, and
/// the query ids drawn (one per entry into a mailboxed aggregate).
struct Tracer<'w> {
    world: &'w World,
    ctx: TraceCtx,
}

impl<'w> Tracer<'w> {
    /// A tracer on thread 0 of 1.
    fn new(world: &'w World) -> Self {
        Tracer {
            world,
            ctx: TraceCtx::new(0, 1, 0),
        }
    }

    /// The nearest hit, if any.
    fn nearest(&mut self, ray: &Ray) -> Result<Option<Hit>> {
        let mut hit = Hit::new();
        let found = self.world.root.intersect(&mut self.ctx, ray, &mut hit);
        self.check()?;
        Ok(found.then_some(hit))
    }

    /// Whether anything lies on the ray's interval.
    fn occluded(&mut self, ray: &Ray) -> Result<bool> {
        let r = self.world.root.occluded(&mut self.ctx, ray);
        self.check()?;
        Ok(r)
    }

    /// The counters so far.
    fn stats(&self) -> &Stats {
        &self.ctx.stats
    }

    /// Query ids drawn so far.
    fn queries(&self) -> u64 {
        self.ctx.query_counter()
    }

    fn check(&self) -> Result<()> {
        if let Some((class, msg)) = self.ctx.failure() {
            bail!("plugin `{class}` {msg}");
        }
        Ok(())
    }
}

/// Do two answers name the same hit: the same `t`, bit for bit, and the same
/// (child, primitive) at every level of the stack.
fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.t.to_bits() == b.t.to_bits()
                && a.depth == b.depth
                && a.stack[..a.depth as usize] == b.stack[..b.depth as usize]
        }
        _ => false,
    }
}

/// A hit, short: `t` and the (child, primitive) path.
pub(super) fn show(h: &Option<Hit>) -> String {
    match h {
        None => "miss".into(),
        Some(h) => {
            let path: Vec<String> = (0..h.depth as usize)
                .map(|l| format!("({})", h.stack[l]))
                .collect();
            format!("t {:?} ({:#010x}) {}", h.t, h.t.to_bits(), path.join(""))
        }
    }
}

/// A ray, reproducibly: values and f32 bits (docs/numerics.md §3: a failing
/// ray is printed bit-exactly so it can become a regression test).
pub(super) fn bits(r: &Ray) -> String {
    let (o, d) = (r.origin.to_array(), r.dir.to_array());
    format!(
        "o {o:?} d {d:?} t_max {:?} (bits o {:08x?} d {:08x?} t_max {:08x})",
        r.t_max,
        o.map(f32::to_bits),
        d.map(f32::to_bits),
        r.t_max.to_bits()
    )
}

/// A mesh object (no acceleration of its own: the parent's structure, or
/// `list`, decides how its triangles are visited).
pub(super) fn mesh_def(name: &str, file: &str) -> String {
    format!("[objects.{name}]\nclass = \"mesh\"\nfile = \"{file}\"\naccel = \"none\"\n")
}

/// A sphere object.
fn sphere_def(name: &str, c: Vec3, r: f32) -> String {
    format!(
        "[objects.{name}]\nclass = \"sphere\"\ncenter = {}\nradius = {}\n",
        vec3f(c),
        num(r as f64)
    )
}

/// A trace-only scene: `defs`, and the root `world` of the class (and
/// parameters) `root` over `children` (TOML instance expressions).
fn world_toml(defs: &str, root: &str, children: &[String]) -> String {
    format!(
        "{}{defs}[objects.world]\n{root}\nchildren = [{}]\n",
        header("world"),
        children.join(", ")
    )
}

/// `class = "..."` plus parameters, as the lines of an object table.
fn class(c: &str, params: &str) -> String {
    format!("class = \"{c}\"\n{params}")
}

/// A ray over `(0, t_max)`.
fn ray_to(o: Vec3, d: Vec3, t_max: f32) -> Ray {
    let mut r = ray32(o, d);
    r.t_max = t_max;
    r
}

/// The f32 vertices of a triangle of a mesh.
fn tri_of(m: &Mesh, i: usize) -> [[f32; 3]; 3] {
    m.tris[i].map(|k| m.verts[k as usize])
}

/// A point of a triangle from barycentrics, in f64 from the f32 vertices.
fn bary(v: &[[f32; 3]; 3], b: [f64; 3]) -> DVec3 {
    (0..3).fold(DVec3::ZERO, |p, k| p + Vec3::from(v[k]).as_dvec3() * b[k])
}

/// Barycentrics within `eps` (relative) of the edge opposite a random vertex.
fn near_edge(rng: &mut RngState, eps: f64) -> [f64; 3] {
    let e = (rng.next_u32() % 3) as usize;
    let mut b = [0.0; 3];
    b[e] = eps * rng.next_f64();
    let s = (1.0 - b[e]) * rng.next_f64();
    b[(e + 1) % 3] = s;
    b[(e + 2) % 3] = 1.0 - b[e] - s;
    b
}

/// One aggregate under test.
struct Subject {
    label: String,
    world: World,
}

/// What the comparison of one subject with the oracle found.
#[derive(Default, Clone)]
struct Tally {
    /// The oracle hits, the subject misses.
    false_misses: u64,
    /// Nearest answers that differ (false misses included).
    nearest: u64,
    /// Of those, answers with the same `t` and another primitive: the tie
    /// rule broken.
    ties: u64,
    /// Any-hit answers that differ.
    any_hit: u64,
    /// Non-finite `t` returned.
    nonfinite: u64,
    /// Primitive tests over all nearest queries.
    prim_tests: u64,
    /// Most nodes (cells) visited by one nearest query.
    max_nodes: u64,
    /// Most query ids drawn by one nearest query.
    max_queries: u64,
    /// Query ids drawn over all nearest queries.
    queries: u64,
}

/// Trace `rays` through the oracle (`list`) and through every subject, and
/// tally the differences; the first few are printed with their rays' bits.
fn compare(
    id: &str,
    oracle: &World,
    subjects: &[Subject],
    rays: &[Ray],
) -> Result<(Tally, Vec<Tally>)> {
    let mut o = Tracer::new(oracle);
    let mut tracers: Vec<Tracer> = subjects.iter().map(|s| Tracer::new(&s.world)).collect();
    let mut want_tally = Tally::default();
    let mut tallies = vec![Tally::default(); subjects.len()];
    let mut printed = 0;
    for ray in rays {
        let p0 = o.stats().prim_tests;
        let want = o.nearest(ray)?;
        want_tally.prim_tests += o.stats().prim_tests - p0;
        if want.is_some_and(|h| !h.t.is_finite()) {
            want_tally.nonfinite += 1;
        }
        let want_any = o.occluded(ray)?;
        for ((s, tr), t) in subjects.iter().zip(&mut tracers).zip(&mut tallies) {
            let (n0, p0, q0) = (tr.stats().node_tests, tr.stats().prim_tests, tr.queries());
            let got = tr.nearest(ray)?;
            t.max_nodes = t.max_nodes.max(tr.stats().node_tests - n0);
            t.prim_tests += tr.stats().prim_tests - p0;
            t.max_queries = t.max_queries.max(tr.queries() - q0);
            t.queries += tr.queries() - q0;
            if got.is_some_and(|h| !h.t.is_finite()) {
                t.nonfinite += 1;
            }
            let any = tr.occluded(ray)?;
            let bad_nearest = !same(&want, &got);
            if bad_nearest {
                t.nearest += 1;
                if let (Some(w), Some(g)) = (&want, &got) {
                    if w.t.to_bits() == g.t.to_bits() {
                        t.ties += 1;
                    }
                }
                if want.is_some() && got.is_none() {
                    t.false_misses += 1;
                }
            }
            if any != want_any {
                t.any_hit += 1;
            }
            if (bad_nearest || any != want_any) && printed < 5 {
                printed += 1;
                eprintln!(
                    "{id} {}: list {} (any {want_any}) vs {} (any {any}); ray {}",
                    s.label,
                    show(&want),
                    show(&got),
                    bits(ray)
                );
            }
        }
    }
    for (s, t) in subjects.iter().zip(&tallies) {
        if t.nearest > 0 {
            eprintln!(
                "{id} {}: {} nearest mismatches, {} of them ties at equal t",
                s.label, t.nearest, t.ties
            );
        }
    }
    Ok((want_tally, tallies))
}

/// Worlds for the subjects `(label, root class lines, nested class)`:
/// `defs(nested)` gives the object definitions.
fn subjects(
    b: &mut Bench,
    list: &[(&str, String, &str)],
    children: &[String],
    defs: impl Fn(&str) -> String,
) -> Result<Vec<Subject>> {
    list.iter()
        .map(|(label, root, nested)| {
            Ok(Subject {
                label: label.to_string(),
                world: b.scene(&world_toml(&defs(nested), root, children))?,
            })
        })
        .collect()
}

/// A grid density that gives `res` cells along the longest axis over `n`
/// primitives (the plugin takes ⌈density·∛n⌉; a hair under `res` so that
/// rounding cannot make it `res + 1`).
fn density_for(res: u32, n: usize) -> f64 {
    (res as f64 - 0.01) / (n as f64).cbrt()
}

/// Non-degenerate triangles of a mesh (the aggregates leave the others out).
fn live_tris(m: &Mesh) -> usize {
    (0..m.tris.len())
        .filter(|&i| !rtk_kernel::geom::is_degenerate(&tri_of(m, i)))
        .count()
}

/// Axis-aligned quad: corner `lo`, spans `(du, dv)` along axes `u`, `v`.
fn push_quad(m: &mut Mesh, lo: DVec3, u: usize, v: usize, du: f64, dv: f64) {
    let n = m.verts.len() as u32;
    let mut eu = DVec3::ZERO;
    eu[u] = du;
    let mut ev = DVec3::ZERO;
    ev[v] = dv;
    for p in [lo, lo + eu, lo + eu + ev, lo + ev] {
        m.verts.push(p.as_vec3().to_array());
    }
    m.tris.push([n, n + 1, n + 2]);
    m.tris.push([n, n + 2, n + 3]);
}

/// A1: the unit box \[0,1\]³ with triangles lying in the planes x, y, z =
/// k/4 (every one a cell or split plane of the structures: the grid of 8³,
/// the octree's centre splits, the kd-tree's planes at box faces), its 12
/// faces, and spheres whose boxes touch those planes. Rays start on the
/// planes, edges and corners, or outside, and run parallel to the axes with
/// ±0 in the other components, or along face and space diagonals. The
/// naive slab test returns NaN (0·∞) here and culls the box.
fn axis_parallel_rays_agree_with_the_list(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(20_000, 300_000);
    let mut rng = RngState::seeded(0xA1);
    let lattice = plane_lattice(&mut rng);
    b.write_obj("a1-lattice.obj", &lattice)?;
    b.write_obj(
        "a1-cube.obj",
        &box_mesh(DVec3::splat(0.5), DVec3::splat(0.5)),
    )?;
    let spheres = [
        (Vec3::splat(0.5), 0.25),
        (Vec3::new(0.25, 0.25, 0.75), 0.25),
        (Vec3::new(0.75, 0.25, 0.25), 0.125),
        (Vec3::new(0.5, 0.75, 0.5), 0.25),
    ];
    let mut defs = mesh_def("lattice", "a1-lattice.obj") + &mesh_def("cube", "a1-cube.obj");
    let mut children = vec!["\"lattice\"".to_string(), "\"cube\"".to_string()];
    for (i, (c, r)) in spheres.iter().enumerate() {
        defs += &sphere_def(&format!("s{i}"), *c, *r);
        children.push(format!("\"s{i}\""));
    }
    let prims = live_tris(&lattice) + 12 + spheres.len();
    let oracle = b.scene(&world_toml(&defs, &class("list", ""), &children))?;
    let grid8 = format!("density = {}\n", num(density_for(8, prims)));
    let list = [
        ("bvh", class("bvh", ""), ""),
        ("grid", class("grid", ""), ""),
        ("grid 8^3", class("grid", &grid8), ""),
        ("octree", class("octree", "max_leaf = 2\n"), ""),
        ("kdtree", class("kdtree", "max_leaf = 1\n"), ""),
        ("slabs", class("slabs", "max_leaf = 1\n"), ""),
        ("raycls", class("raycls", "max_candidates = 2\n"), ""),
    ];
    let subjects = subjects(b, &list, &children, |_| defs.clone())?;
    let rays = axis_parallel_rays(&mut rng, n);
    let (want, got) = compare("A1", &oracle, &subjects, &rays)?;
    let mut lines = Vec::new();
    for (s, t) in subjects.iter().zip(&got) {
        lines.push(Line::count(
            format!("{}, {n} rays", s.label),
            "false misses",
            t.false_misses,
        ));
        lines.push(Line::count(
            format!("{}, {n} rays", s.label),
            "nearest/any-hit mismatches",
            t.nearest + t.any_hit,
        ));
    }
    let nonfinite = want.nonfinite + got.iter().map(|t| t.nonfinite).sum::<u64>();
    lines.push(Line::count("all, list included", "non-finite t", nonfinite));
    Ok(lines)
}

/// A1's triangles: random unit quads of the planes x, y, z = k/4 within
/// the unit box (every one a cell or split plane of the structures).
fn plane_lattice(rng: &mut RngState) -> Mesh {
    let mut lattice = Mesh {
        verts: vec![],
        tris: vec![],
    };
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for k in 0..=4 {
            for i in 0..4 {
                for j in 0..4 {
                    if rng.next_f64() < 0.3 {
                        let mut lo = DVec3::ZERO;
                        lo[axis] = k as f64 / 4.0;
                        lo[u] = i as f64 / 4.0;
                        lo[v] = j as f64 / 4.0;
                        push_quad(&mut lattice, lo, u, v, 0.25, 0.25);
                    }
                }
            }
        }
    }
    lattice
}

/// A1's `n` rays: from the lattice's points, ±0.5 outside, or random,
/// parallel to an axis with ±0 in the other components, or (every fourth)
/// along face and space diagonals.
fn axis_parallel_rays(rng: &mut RngState, n: usize) -> Vec<Ray> {
    let coord = |rng: &mut RngState| match rng.next_u32() % 9 {
        k @ 0..=4 => k as f32 / 4.0,
        5 => rng.next_f32(),
        6 => -0.5,
        7 => 1.5,
        _ => -0.0,
    };
    let mut rays = Vec::with_capacity(n);
    for k in 0..n {
        let o = Vec3::new(coord(rng), coord(rng), coord(rng));
        let mut d = Vec3::new(signed_zero(rng), signed_zero(rng), signed_zero(rng));
        if k % 4 != 3 {
            let a = (rng.next_u32() % 3) as usize;
            d[a] = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
        } else {
            // Face and space diagonals through the lattice's points.
            while d.cmpeq(Vec3::ZERO).all() {
                for a in 0..3 {
                    d[a] = [0.0, -0.0, 1.0, -1.0][(rng.next_u32() % 4) as usize];
                }
            }
        }
        let t_max = if k % 8 == 0 {
            rng.range_f32(0.1, 2.0)
        } else {
            f32::INFINITY
        };
        rays.push(ray_to(o, d, t_max));
    }
    rays
}

/// A2: triangles each lying in a coordinate plane (so their boxes are
/// flat), at |c| = 1, 1e3, 1e5, and rays aimed within 1e-7 (barycentric) of
/// their edges. Rounding of the slab distances makes t0 exceed t1 by an ulp
/// for such boxes and culls them (Ize 2013). Measured twice: the kernel's
/// slab test on each triangle's own tight box (the catalogue's metric), and
/// every aggregate against `list`.
fn flat_boxes_far_away_lose_no_hits(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(10_000, 200_000);
    let tris = 300;
    let mut rng = RngState::seeded(0xA2);
    let mut lines = Vec::new();
    for &dist in &[1.0, 1e3, 1e5] {
        let c = unit_vector(&mut rng) * dist;
        let m = flat_triangles(&mut rng, c, tris);
        b.write_obj("a2-flat.obj", &m)?;
        let defs = mesh_def("flat", "a2-flat.obj");
        let children = vec!["\"flat\"".to_string()];
        let oracle = b.scene(&world_toml(&defs, &class("list", ""), &children))?;
        let list = [
            ("bvh", class("bvh", ""), ""),
            ("grid", class("grid", ""), ""),
            ("octree", class("octree", ""), ""),
            ("kdtree", class("kdtree", ""), ""),
            ("slabs", class("slabs", ""), ""),
            ("raycls", class("raycls", ""), ""),
        ];
        let subjects = subjects(b, &list, &children, |_| defs.clone())?;
        let (rays, slab_misses) = edge_rays_and_slab_misses(&mut rng, &m, n);
        let (_, got) = compare("A2", &oracle, &subjects, &rays)?;
        let setup = format!("|c| {}, {n} edge rays", mag(dist));
        lines.push(Line::count(&setup, "tight-box false misses", slab_misses));
        lines.push(Line::count(
            format!("|c| {}, {} aggregates", mag(dist), list.len()),
            "false misses vs list",
            got.iter().map(|t| t.false_misses).sum(),
        ));
        lines.push(Line::count(
            format!("|c| {}, {} aggregates", mag(dist), list.len()),
            "nearest/any-hit mismatches",
            got.iter().map(|t| t.nearest + t.any_hit).sum(),
        ));
    }
    Ok(lines)
}

/// A2's `tris` triangles about `c`, each in a coordinate plane (so that its
/// box is flat).
fn flat_triangles(rng: &mut RngState, c: DVec3, tris: usize) -> Mesh {
    let mut m = Mesh {
        verts: vec![],
        tris: vec![],
    };
    for i in 0..tris {
        let axis = i % 3;
        let anchor = c + DVec3::new(
            16.0 * rng.next_f64() - 8.0,
            16.0 * rng.next_f64() - 8.0,
            16.0 * rng.next_f64() - 8.0,
        );
        let k = m.verts.len() as u32;
        for _ in 0..3 {
            let mut p = anchor;
            for a in 0..3 {
                if a != axis {
                    p[a] += 3.0 * rng.next_f64();
                }
            }
            m.verts.push(p.as_vec3().to_array());
        }
        m.tris.push([k, k + 1, k + 2]);
    }
    m
}

/// A2's `n` rays aimed within 1e-7 (barycentric) of the edges of `m`'s
/// triangles, and how many of those that hit their triangle the kernel's
/// slab test on its tight box culls.
fn edge_rays_and_slab_misses(rng: &mut RngState, m: &Mesh, n: usize) -> (Vec<Ray>, u64) {
    let mut rays = Vec::with_capacity(n);
    let mut slab_misses = 0u64;
    for _ in 0..n {
        let i = (rng.next_u32() as usize) % m.tris.len();
        let v = tri_of(m, i);
        let p = bary(&v, near_edge(rng, 1e-7));
        let o = (p + unit_vector(rng) * (1.0 + 4.0 * rng.next_f64())).as_vec3();
        let d = (p - o.as_dvec3()).normalize().as_vec3();
        let ray = ray32(o, d);
        let (oa, da) = (o.to_array(), d.to_array());
        if intersect_triangle(oa, da, v, 0.0, f32::INFINITY).is_some() {
            let bx = Bounds3::EMPTY
                .include(v[0].into())
                .include(v[1].into())
                .include(v[2].into());
            let pre = RayBoxPrecomp::new(&ray);
            if pre.intersect(&bx, 0.0, f32::INFINITY).is_none() {
                if slab_misses == 0 {
                    eprintln!("A2 tight box culls its hit triangle: ray {}", bits(&ray));
                }
                slab_misses += 1;
            }
        }
        rays.push(ray);
    }
    (rays, slab_misses)
}

/// A random soup of triangles about `[-8, 8]³`, overlapping, with a repeated
/// triangle (a tie within the mesh) and a degenerate one every 50.
fn soup(rng: &mut RngState, n: usize) -> Mesh {
    let mut m = Mesh {
        verts: vec![],
        tris: vec![],
    };
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    for t in 0..n {
        let c = DVec3::new(u(-8.0, 8.0), u(-8.0, 8.0), u(-8.0, 8.0));
        let k = m.verts.len() as u32;
        for _ in 0..3 {
            let p = c + DVec3::new(u(-1.5, 1.5), u(-1.5, 1.5), u(-1.5, 1.5));
            m.verts.push(p.as_vec3().to_array());
        }
        m.tris.push([k, k + 1, k + 2]);
        if t % 50 == 0 {
            m.tris.push([k, k + 1, k + 2]);
            m.tris.push([k, k, k + 1]);
        }
    }
    m
}

/// 8×8 unit quads in the plane y = 0 on integer coordinates: every edge
/// shared, every vertex on the planes of integer cells.
fn plane_grid() -> Mesh {
    let mut m = Mesh {
        verts: vec![],
        tris: vec![],
    };
    for j in 0..=8 {
        for i in 0..=8 {
            m.verts.push([i as f32 - 4.0, 0.0, j as f32 - 4.0]);
        }
    }
    for j in 0..8u32 {
        for i in 0..8u32 {
            let a = j * 9 + i;
            m.tris.push([a, a + 1, a + 10]);
            m.tris.push([a, a + 10, a + 9]);
        }
    }
    m
}

/// A3: the master oracle. Random overlapping triangles (with repeated and
/// degenerate ones), coplanar quads sharing edges, the same plane twice (ties
/// between children), a closed box, spheres (one listed three times),
/// transformed instances, and a nested cluster of another class; for each
/// aggregate at the root, random rays plus the adversarial sets of A1, A2
/// and T1, and rays at the thrice-held plane from close by and at grazing
/// angles: ties whose computed t lies furthest from its box's entry (t is
/// a weighted sum of the vertices' distances, which cancel when t is small
/// next to the triangle). Nearest and any-hit
/// answers must equal `list`'s; the primitive
/// tests per ray, against `list`'s, guard the structures' purpose.
fn aggregates_match_the_list_on_random_scenes(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(8_000, 40_000);
    let mut rng = RngState::seeded(0xA3);
    let (soup_m, base, children) = master_scene(b, &mut rng)?;
    let defs = |nested: &str| {
        format!(
            "{base}[objects.cluster]\nclass = \"{nested}\"\nchildren = [\"s1\", \"s2\", \"plane\", \
             {{ object = \"small\", transform = [{{ translate = [1.0, 2.0, 3.0] }}] }}]\n"
        )
    };
    let oracle = b.scene(&world_toml(&defs("list"), &class("list", ""), &children))?;
    let list = [
        ("bvh(grid)", class("bvh", ""), "grid"),
        ("grid(kdtree)", class("grid", ""), "kdtree"),
        ("octree(bvh)", class("octree", ""), "bvh"),
        ("kdtree(octree)", class("kdtree", ""), "octree"),
        ("slabs(bvh)", class("slabs", ""), "bvh"),
        ("bvh(slabs)", class("bvh", ""), "slabs"),
        // Nearly every A3 ray is its own: split cells on their first
        // visit (by default a cell waits for a second ray), so that the
        // prim-test ratio measures raycls's culling.
        ("raycls(bvh)", class("raycls", "min_visits = 1\n"), "bvh"),
        ("bvh(raycls)", class("bvh", ""), "raycls"),
    ];
    let subjects = subjects(b, &list, &children, defs)?;
    let mut rays = Vec::with_capacity(n);
    for k in 0..n {
        rays.push(master_ray(&mut rng, k, &soup_m));
    }
    let (want, got) = compare("A3", &oracle, &subjects, &rays)?;
    let mut lines = Vec::new();
    for (s, t) in subjects.iter().zip(&got) {
        let setup = format!("{}, {n} rays", s.label);
        lines.push(Line::count(&setup, "nearest mismatches", t.nearest));
        lines.push(Line::count(&setup, "any-hit mismatches", t.any_hit));
        lines.push(Line::new(
            setup,
            "prim tests/ray vs list",
            t.prim_tests as f64 / want.prim_tests.max(1) as f64,
            Target::AtMost(0.1),
        ));
    }
    let nonfinite = want.nonfinite + got.iter().map(|t| t.nonfinite).sum::<u64>();
    lines.push(Line::count("all, list included", "non-finite t", nonfinite));
    Ok(lines)
}

/// A3's scene, but for the nested cluster: the soup (returned, for the
/// rays aimed at its edges), the plane twice, the box, random spheres (one
/// listed three times) and transformed instances; the definitions and the
/// root's children.
fn master_scene(b: &mut Bench, rng: &mut RngState) -> Result<(Mesh, String, Vec<String>)> {
    let (n_soup, n_sph) = (b.n(2_000, 20_000), b.n(100, 500));
    let soup_m = soup(rng, n_soup);
    b.write_obj("a3-soup.obj", &soup_m)?;
    b.write_obj("a3-small.obj", &soup(rng, 100))?;
    b.write_obj("a3-plane.obj", &plane_grid())?;
    b.write_obj("a3-box.obj", &box_mesh(DVec3::ZERO, DVec3::ONE))?;
    let mut base = mesh_def("soup", "a3-soup.obj")
        + &mesh_def("plane", "a3-plane.obj")
        + &mesh_def("plane2", "a3-plane.obj")
        + &mesh_def("cube", "a3-box.obj")
        + &mesh_def("small", "a3-small.obj");
    let mut children: Vec<String> = ["soup", "plane", "plane2", "cube"]
        .iter()
        .map(|s| format!("\"{s}\""))
        .collect();
    for i in 0..n_sph {
        let c = Vec3::new(
            rng.range_f32(-8.0, 8.0),
            rng.range_f32(-8.0, 8.0),
            rng.range_f32(-8.0, 8.0),
        );
        base += &sphere_def(&format!("s{i}"), c, rng.range_f32(0.1, 1.5));
        children.push(format!("\"s{i}\""));
    }
    children.push("\"s3\"".into());
    children.push("\"s3\"".into());
    children.push(
        "{ object = \"cube\", transform = [{ scale = 0.5 }, { rotate_y = 30.0 }, \
         { translate = [3.0, 1.0, -2.0] }] }"
            .into(),
    );
    children.push("{ object = \"s5\", transform = [{ translate = [0.0, 0.0, 4.0] }] }".into());
    children.push("\"cluster\"".into());
    Ok((soup_m, base, children))
}

/// A3's ray `k`: a random one, or by `k mod 10` one of the adversarial sets
/// of A1, A2 and T1, or one at the thrice-held plane.
fn master_ray(rng: &mut RngState, k: usize, soup_m: &Mesh) -> Ray {
    let box_points = [
        Vec3::splat(-1.0),
        Vec3::new(1.0, 0.3, -0.2),
        Vec3::new(0.0, 1.0, 0.5),
        Vec3::new(1.0, 1.0, -1.0),
    ];
    let mut o = Vec3::new(
        rng.range_f32(-12.0, 12.0),
        rng.range_f32(-12.0, 12.0),
        rng.range_f32(-12.0, 12.0),
    );
    let mut d = unit_vector(rng).as_vec3();
    let axis = |rng: &mut RngState| {
        let mut d = Vec3::new(0.0, -0.0, 0.0);
        d[(rng.next_u32() % 3) as usize] = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
        d
    };
    match k % 10 {
        // A1: axis-parallel with ±0, from anywhere and from integer points.
        3 => d = axis(rng),
        4 => {
            o = o.round();
            d = axis(rng);
        }
        // In the plane of the coplanar quads, grazing.
        5 => {
            o.y = 0.0;
            d.y = if k % 20 == 5 { 0.0 } else { -0.0 };
        }
        // From a corner, an edge or a face of the box.
        6 => o = box_points[(rng.next_u32() % 4) as usize],
        7 => (o, d) = at_a_plane_grid_edge(rng, k),
        9 => (o, d) = at_the_plane_grazing(rng, k),
        // A2: within 1e-7 of a soup triangle's edge.
        8 => {
            let v = tri_of(soup_m, (rng.next_u32() as usize) % soup_m.tris.len());
            let p = bary(&v, near_edge(rng, 1e-7));
            o = (p + unit_vector(rng) * (1.0 + 4.0 * rng.next_f64())).as_vec3();
            d = (p - o.as_dvec3()).normalize().as_vec3();
        }
        _ => {}
    }
    if d.cmpeq(Vec3::ZERO).all() {
        d = Vec3::Z;
    }
    let t_max = if k.is_multiple_of(7) {
        rng.range_f32(0.5, 10.0)
    } else {
        f32::INFINITY
    };
    ray_to(o, d, t_max)
}

/// T1's rays: aimed at a shared edge of the plane grid (along x, or a
/// quad's diagonal); the origin and direction.
fn at_a_plane_grid_edge(rng: &mut RngState, k: usize) -> (Vec3, Vec3) {
    let (i, j, s) = (
        (rng.next_u32() % 8) as f64 - 4.0,
        (rng.next_u32() % 8) as f64 - 4.0,
        rng.next_f64(),
    );
    let p = if k % 20 == 7 {
        DVec3::new(i + s, 0.0, j)
    } else {
        DVec3::new(i + s, 0.0, j + s)
    };
    let o = (p + unit_vector(rng) * (1.0 + 4.0 * rng.next_f64())).as_vec3();
    (o, (p - o.as_dvec3()).normalize().as_vec3())
}

/// Ties: at the plane (three children hold its triangles) from close by
/// and at grazing angles, where a triangle's t is furthest off its box's
/// entry; the origin and direction.
fn at_the_plane_grazing(rng: &mut RngState, k: usize) -> (Vec3, Vec3) {
    let p = DVec3::new(8.0 * rng.next_f64() - 4.0, 0.0, 8.0 * rng.next_f64() - 4.0);
    let elevation = 10f64.powf(-3.0 + 2.0 * rng.next_f64());
    let phi = std::f64::consts::TAU * rng.next_f64();
    let up = if k % 20 == 9 { 1.0 } else { -1.0 };
    let w = DVec3::new(phi.cos(), up * elevation.tan(), phi.sin()).normalize();
    let dist = 10f64.powf(-2.0 + 2.5 * rng.next_f64());
    let o = (p + w * dist).as_vec3();
    (o, (p - o.as_dvec3()).normalize().as_vec3())
}

/// A4: a 64³ grid of unit cells over [0, 64]³ (two small corner triangles
/// fix the bounds), with random triangles, quads on integer planes, spheres
/// whose boxes end on cell faces, and boxes 1e-7 thick straddling cell
/// planes. Rays start on cell faces, pass exactly through lattice corners
/// (integer origins and small-integer directions, so the corner is hit
/// exactly), have one or two ±0 components, or start on the grid's boundary
/// (t = 0 at entry). A DDA crosses at most 3·64 − 2 cells.
fn dda_corner_cases_agree_with_the_list(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(12_000, 150_000);
    let mut rng = RngState::seeded(0xA4);
    let (m, thin) = dda_cells(&mut rng);
    b.write_obj("a4-cells.obj", &m)?;
    let mut defs = mesh_def("cells", "a4-cells.obj");
    let mut children = vec!["\"cells\"".to_string()];
    for i in 0..100 {
        // Centres on half-integers, radius ½: boxes end on cell faces.
        let c = Vec3::new(
            (rng.next_u32() % 62) as f32 + 1.5,
            (rng.next_u32() % 62) as f32 + 1.5,
            (rng.next_u32() % 62) as f32 + 1.5,
        );
        defs += &sphere_def(&format!("s{i}"), c, 0.5);
        children.push(format!("\"s{i}\""));
    }
    let prims = live_tris(&m) + 100;
    let oracle = b.scene(&world_toml(&defs, &class("list", ""), &children))?;
    let grid = format!("density = {}\n", num(density_for(64, prims)));
    let list = [
        ("grid 64^3", class("grid", &grid), ""),
        ("octree", class("octree", ""), ""),
        ("kdtree", class("kdtree", ""), ""),
        ("bvh", class("bvh", ""), ""),
        ("slabs", class("slabs", ""), ""),
        ("raycls", class("raycls", ""), ""),
    ];
    let subjects = subjects(b, &list, &children, |_| defs.clone())?;
    let mut rays = Vec::with_capacity(n);
    for k in 0..n {
        rays.push(dda_ray(&mut rng, k, &thin));
    }
    let (want, got) = compare("A4", &oracle, &subjects, &rays)?;
    let mut lines = Vec::new();
    for (s, t) in subjects.iter().zip(&got) {
        lines.push(Line::count(
            format!("{}, {n} rays", s.label),
            "nearest/any-hit mismatches",
            t.nearest + t.any_hit,
        ));
    }
    lines.push(Line::new(
        format!("grid 64^3, {n} rays"),
        "max cells visited per ray",
        got[0].max_nodes as f64,
        Target::AtMost(3.0 * 64.0 - 2.0),
    ));
    let nonfinite = want.nonfinite + got.iter().map(|t| t.nonfinite).sum::<u64>();
    lines.push(Line::count("all, list included", "non-finite t", nonfinite));
    Ok(lines)
}

/// A4's boxes 1e-7 thick straddling cell planes: (centre, half sizes).
type ThinBoxes = [(DVec3, DVec3); 3];

/// A4's mesh over exactly [0, 64]³: two corner triangles fixing the
/// bounds, random triangles, quads on integer planes, and the thin boxes
/// (returned too, for the rays aimed at them).
fn dda_cells(rng: &mut RngState) -> (Mesh, ThinBoxes) {
    let mut m = Mesh {
        verts: vec![],
        tris: vec![],
    };
    let u = |rng: &mut RngState, lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    // The corners fix the bounds at exactly [0, 64]³.
    for (p, s) in [(0.0f32, 0.5f32), (64.0, -0.5)] {
        let k = m.verts.len() as u32;
        m.verts.extend([[p, p, p], [p + s, p, p], [p, p + s, p]]);
        m.tris.push([k, k + 1, k + 2]);
    }
    for _ in 0..1500 {
        let c = DVec3::new(u(rng, 2.0, 62.0), u(rng, 2.0, 62.0), u(rng, 2.0, 62.0));
        let k = m.verts.len() as u32;
        for _ in 0..3 {
            let p = c + DVec3::new(u(rng, -1.5, 1.5), u(rng, -1.5, 1.5), u(rng, -1.5, 1.5));
            m.verts.push(p.as_vec3().to_array());
        }
        m.tris.push([k, k + 1, k + 2]);
    }
    for _ in 0..300 {
        let axis = (rng.next_u32() % 3) as usize;
        let (a, bb) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut lo = DVec3::ZERO;
        lo[axis] = (rng.next_u32() % 65) as f64;
        lo[a] = (rng.next_u32() % 62) as f64;
        lo[bb] = (rng.next_u32() % 62) as f64;
        push_quad(
            &mut m,
            lo,
            a,
            bb,
            (1 + rng.next_u32() % 2) as f64,
            (1 + rng.next_u32() % 2) as f64,
        );
    }
    // 1e-7 thick boxes straddling the planes x = 1, y = 2 and z = 1 (near
    // the origin, where 1e-7 is an ulp or so).
    let thin = [
        (DVec3::new(1.0, 10.0, 10.0), DVec3::new(5e-8, 4.0, 4.0)),
        (DVec3::new(20.0, 2.0, 20.0), DVec3::new(4.0, 5e-8, 4.0)),
        (DVec3::new(30.0, 30.0, 1.0), DVec3::new(4.0, 4.0, 5e-8)),
    ];
    for (c, h) in thin {
        let t = box_mesh(c, h);
        let k = m.verts.len() as u32;
        m.verts.extend(t.verts);
        m.tris.extend(t.tris.iter().map(|t| t.map(|i| i + k)));
    }
    (m, thin)
}

/// +0 or −0, at random.
fn signed_zero(rng: &mut RngState) -> f32 {
    if rng.next_u32() & 1 == 0 {
        0.0
    } else {
        -0.0
    }
}

/// A4's ray `k`: a random one, or by `k mod 8` one of the DDA's corner
/// cases.
fn dda_ray(rng: &mut RngState, k: usize, thin: &ThinBoxes) -> Ray {
    let mut o = Vec3::new(
        rng.range_f32(-4.0, 68.0),
        rng.range_f32(-4.0, 68.0),
        rng.range_f32(-4.0, 68.0),
    );
    let mut d = unit_vector(rng).as_vec3();
    match k % 8 {
        // On a cell face.
        1 => o[(rng.next_u32() % 3) as usize] = (rng.next_u32() % 65) as f32,
        2 => through_lattice_corner(rng, &mut o, &mut d),
        // Entering at the grid's corner (0, 0, 0).
        3 => {
            d = Vec3::new(
                (1 + rng.next_u32() % 3) as f32,
                (1 + rng.next_u32() % 3) as f32,
                (1 + rng.next_u32() % 3) as f32,
            );
            o = -d * (1 + rng.next_u32() % 4) as f32;
        }
        4 => with_zero_components(rng, k, &mut o, &mut d),
        5 => from_the_boundary(rng, k, &mut o, &mut d),
        6 => at_a_thin_box(rng, k, thin, &mut o, &mut d),
        _ => {}
    }
    if d.cmpeq(Vec3::ZERO).all() {
        d = Vec3::X;
    }
    let t_max = if k.is_multiple_of(9) {
        rng.range_f32(1.0, 40.0)
    } else {
        f32::INFINITY
    };
    ray_to(o, d, t_max)
}

/// Exactly through a lattice corner: o = corner − j·d with a
/// small-integer direction, all exact (`d` is replaced unless zero).
fn through_lattice_corner(rng: &mut RngState, o: &mut Vec3, d: &mut Vec3) {
    let small = |rng: &mut RngState| (rng.next_u32() % 7) as f32 - 3.0;
    while d.cmpeq(Vec3::ZERO).all() {
        *d = Vec3::new(small(rng), small(rng), small(rng));
    }
    let corner = Vec3::new(
        (rng.next_u32() % 65) as f32,
        (rng.next_u32() % 65) as f32,
        (rng.next_u32() % 65) as f32,
    );
    *o = corner - *d * (1 + rng.next_u32() % 8) as f32;
}

/// One or two ±0 components, from integer or random origins.
fn with_zero_components(rng: &mut RngState, k: usize, o: &mut Vec3, d: &mut Vec3) {
    if k % 16 == 4 {
        *o = o.round();
    }
    let keep = (rng.next_u32() % 3) as usize;
    for a in 0..3 {
        if a != keep && (a + k / 8) % 3 != keep {
            d[a] = signed_zero(rng);
        }
    }
    if k % 24 == 4 {
        d[(keep + 1) % 3] = signed_zero(rng);
    }
}

/// t = 0 at entry: the origin on the grid's boundary, inwards.
fn from_the_boundary(rng: &mut RngState, k: usize, o: &mut Vec3, d: &mut Vec3) {
    let a = (rng.next_u32() % 3) as usize;
    *o = Vec3::new(
        rng.range_f32(0.0, 64.0),
        rng.range_f32(0.0, 64.0),
        rng.range_f32(0.0, 64.0),
    );
    if rng.next_u32() & 1 == 0 {
        o[a] = 0.0;
        d[a] = d[a].abs();
    } else {
        o[a] = 64.0;
        d[a] = -d[a].abs();
    }
    if k % 40 == 5 {
        *o = Vec3::ZERO;
        *d = d.abs();
    }
}

/// Through and along the thin boxes.
fn at_a_thin_box(rng: &mut RngState, k: usize, thin: &ThinBoxes, o: &mut Vec3, d: &mut Vec3) {
    let (c, h) = thin[(rng.next_u32() % 3) as usize];
    let a = (0..3).find(|&a| h[a] < 1.0).unwrap_or(0);
    let mut p = c.as_vec3();
    for q in 0..3 {
        if q != a {
            p[q] += rng.range_f32(-3.0, 3.0);
        }
    }
    if k % 16 == 6 {
        // Across the plane.
        *o = p;
        o[a] -= 2.0;
        *d = Vec3::ZERO;
        d[a] = 1.0;
    } else {
        // In the plane itself, along it.
        *o = p;
        d[a] = signed_zero(rng);
        o[(a + 1) % 3] -= 5.0;
        d[(a + 1) % 3] = d[(a + 1) % 3].abs().max(0.1);
    }
}

/// A5: an outer aggregate over [0, 100]³ (for the grid 32³ cells) holding a
/// nested aggregate of 1000 spheres (r = ½) over [20, 80]³, about 19³ outer
/// cells, and small spheres beside it in the same region; rays from (−10,
/// 50, 50). The nested object returns hits lying in later cells: the outer
/// structure must keep them and still find a small sphere in between, and a
/// mailbox must not then skip the nested object for good. With a nested
/// kd-tree (which draws one query id per entry) the entries per ray are
/// counted: the mailbox allows at most one.
fn nested_aggregates_keep_out_of_cell_hits(b: &mut Bench) -> Result<Vec<Line>> {
    let n = b.n(4_000, 60_000);
    let mut rng = RngState::seeded(0xA5);
    let (defs, inner, children) = nested_scene(b, &mut rng)?;
    let prims = 1 + 60 + 2;
    let defs = |nested: &str| {
        format!(
            "{defs}[objects.cluster]\nclass = \"{nested}\"\nchildren = [{}]\n",
            inner.join(", ")
        )
    };
    let oracle = b.scene(&world_toml(&defs("list"), &class("list", ""), &children))?;
    let grid = class(
        "grid",
        &format!("density = {}\n", num(density_for(32, prims))),
    );
    let list = [
        ("grid 32^3(bvh)", grid.clone(), "bvh"),
        ("octree(bvh)", class("octree", "max_leaf = 2\n"), "bvh"),
        ("kdtree(bvh)", class("kdtree", "max_leaf = 1\n"), "bvh"),
        ("bvh(bvh)", class("bvh", "max_leaf = 1\n"), "bvh"),
        ("grid 32^3(kdtree)", grid, "kdtree"),
        ("slabs(bvh)", class("slabs", "max_leaf = 1\n"), "bvh"),
        (
            "raycls(bvh)",
            class("raycls", "max_candidates = 2\n"),
            "bvh",
        ),
    ];
    let subjects = subjects(b, &list, &children, defs)?;
    let rays = rays_from_beside_the_cluster(&mut rng, n);
    let (_, got) = compare("A5", &oracle, &subjects, &rays)?;
    let mut lines = Vec::new();
    for (s, t) in subjects.iter().zip(&got) {
        lines.push(Line::count(
            format!("{}, {n} rays", s.label),
            "nearest/any-hit mismatches",
            t.nearest + t.any_hit,
        ));
    }
    // The outer grid draws one query id per query; the rest are the nested
    // kd-tree's entries.
    let k = &got[4];
    lines.push(Line::new(
        format!("grid 32^3(kdtree), {n} rays"),
        "max nested entries per ray",
        k.max_queries.saturating_sub(1) as f64,
        Target::AtMost(1.0),
    ));
    lines.push(Line::new(
        format!("grid 32^3(kdtree), {n} rays"),
        "mean nested entries per ray",
        (k.queries as f64 - n as f64) / n as f64,
        Target::AtMost(1.0),
    ));
    Ok(lines)
}

/// A5's scene, but for the nested cluster: the definitions, the cluster's
/// 1000 spheres over [20, 80]³, and the root's children (the cluster, small
/// spheres beside it, two triangles fixing the bounds at [0, 100]³).
fn nested_scene(b: &mut Bench, rng: &mut RngState) -> Result<(String, Vec<String>, Vec<String>)> {
    let mut defs = String::new();
    let mut inner = Vec::new();
    for i in 0..1000 {
        let c = Vec3::new(
            rng.range_f32(20.5, 79.5),
            rng.range_f32(20.5, 79.5),
            rng.range_f32(20.5, 79.5),
        );
        defs += &sphere_def(&format!("b{i}"), c, 0.5);
        inner.push(format!("\"b{i}\""));
    }
    let mut children = vec!["\"cluster\"".to_string()];
    for i in 0..60 {
        let c = Vec3::new(
            rng.range_f32(15.0, 85.0),
            rng.range_f32(15.0, 85.0),
            rng.range_f32(15.0, 85.0),
        );
        defs += &sphere_def(&format!("s{i}"), c, rng.range_f32(0.1, 0.4));
        children.push(format!("\"s{i}\""));
    }
    // Two small triangles fix the outer bounds at exactly [0, 100]³.
    let marks = Mesh {
        verts: vec![
            [0.0, 0.0, 0.0],
            [0.5, 0.0, 0.0],
            [0.0, 0.5, 0.0],
            [100.0, 100.0, 100.0],
            [99.5, 100.0, 100.0],
            [100.0, 99.5, 100.0],
        ],
        tris: vec![[0, 1, 2], [3, 4, 5]],
    };
    b.write_obj("a5-marks.obj", &marks)?;
    defs += &mesh_def("marks", "a5-marks.obj");
    children.push("\"marks\"".into());
    Ok((defs, inner, children))
}

/// A5's rays, from (−10, 50, 50): a quarter in random directions, the
/// rest aimed into the cluster's region.
fn rays_from_beside_the_cluster(rng: &mut RngState, n: usize) -> Vec<Ray> {
    let o = Vec3::new(-10.0, 50.0, 50.0);
    let mut rays = Vec::with_capacity(n);
    for k in 0..n {
        let d = if k % 4 == 0 {
            unit_vector(rng).as_vec3()
        } else {
            let p = DVec3::new(
                20.0 + 60.0 * rng.next_f64(),
                20.0 + 60.0 * rng.next_f64(),
                20.0 + 60.0 * rng.next_f64(),
            );
            (p - o.as_dvec3()).normalize().as_vec3()
        };
        let t_max = if k % 7 == 0 {
            rng.range_f32(30.0, 90.0)
        } else {
            f32::INFINITY
        };
        rays.push(ray_to(o, d, t_max));
    }
    rays
}
