//! `interior-parity`: the paper's fifth operation checked against the
//! first. A closed object's `in_interior(p)` must agree with the parity of
//! `intersect` along a ray from `p` (odd: inside) for every point farther
//! from the surface than the hits' position error bounds; nearer points may
//! be answered either way.
//!
//! How "far from every surface" is judged without knowing the surface: the
//! nearest hit along 14 probe directions (the axes and the diagonals) must
//! be farther than 4 times the largest position error bound of those hits.
//! That bounds the distance from above, not below, so a point could still lie
//! nearer a surface the probes miss; for random points that is as unlikely
//! as landing within rounding of the surface itself.
//!
//! Objects with children are checked over closed children that do not
//! overlap (spheres on a lattice), where the union the aggregate answers and
//! the parity a ray counts agree.

use super::object::{def, world, Shape};
use super::{Check, Cx, Params};
use crate::stress::Probe;
use anyhow::Result;
use rtk_kernel::abi::{Interior, Ray, TraceCtx};
use rtk_kernel::glam::Vec3;
use rtk_shell::World;

/// The probe directions of the distance test: the axes and the diagonals.
fn probes() -> [Vec3; 14] {
    let d = 1.0 / 3f32.sqrt();
    [
        Vec3::X,
        -Vec3::X,
        Vec3::Y,
        -Vec3::Y,
        Vec3::Z,
        -Vec3::Z,
        Vec3::new(d, d, d),
        Vec3::new(d, d, -d),
        Vec3::new(d, -d, d),
        Vec3::new(d, -d, -d),
        Vec3::new(-d, d, d),
        Vec3::new(-d, d, -d),
        Vec3::new(-d, -d, d),
        Vec3::new(-d, -d, -d),
    ]
}

/// The world the check runs on: the class alone, or over closed children
/// that do not overlap.
fn scene(cx: &Cx, shape: Shape) -> String {
    let n = match shape {
        Shape::Primitive => 0,
        Shape::Fixed(k) => k,
        Shape::Aggregate => 5,
    };
    let mut defs = String::new();
    let mut kids = Vec::new();
    for i in 0..n {
        let c = [3.0 * i as f64, 0.7 * i as f64, -0.4 * i as f64];
        defs += &format!(
            "[objects.s{i}]\nclass = \"sphere\"\ncenter = [{}, {}, {}]\nradius = {}\n",
            c[0],
            c[1],
            c[2],
            1.0 + 0.1 * i as f64
        );
        kids.push(format!("\"s{i}\""));
    }
    if n == 0 {
        defs = def("p", &cx.class, &cx.params, &[]);
        kids.push("\"p\"".into());
        return world(&defs, "list", &Params::default(), &kids);
    }
    world(&defs, &cx.class, &cx.params, &kids)
}

/// How many times the ray crosses the surface: the hits one after another.
fn crossings(probe: &mut Probe, mut ray: Ray) -> Result<u32> {
    let mut n = 0;
    while n < 10_000 {
        match probe.nearest(&ray)? {
            Some(h) => {
                n += 1;
                ray.t_min = h.t;
            }
            None => break,
        }
    }
    Ok(n)
}

/// Whether `p` is farther than 4 position error bounds from the surface
/// along every probe direction.
fn far_from_surface(probe: &mut Probe, p: Vec3) -> Result<bool> {
    for d in probes() {
        let r = Ray::new(p, d);
        if let Some(h) = probe.nearest(&r)? {
            let g = probe.geom(&r, &h)?;
            let err = g.p_err.v().abs().max_element().max(f32::EPSILON * h.t);
            if !(h.t > 4.0 * err) {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

/// The check, over `n` random points in the world's box grown by a tenth.
pub(crate) fn check(cx: &mut Cx, shape: Shape, n: usize) -> Result<Check> {
    let w: World = cx.bench.scene(&scene(cx, shape))?;
    let b = w.bounds;
    let (lo, hi) = (b.min.v(), b.max.v());
    let pad = (hi - lo) * 0.1 + Vec3::splat(1e-3);
    let (lo, hi) = (lo - pad, hi + pad);
    let mut probe = Probe::new(&w);
    let mut ctx = TraceCtx::new(0, 1, 0);
    let (mut answered, mut compared, mut bad) = (0u64, 0u64, (0u64, String::new()));
    for _ in 0..n {
        let u = Vec3::new(cx.rng.next_f32(), cx.rng.next_f32(), cx.rng.next_f32());
        let p = lo + (hi - lo) * u;
        let a = w.root.in_interior(&mut ctx, p, 0.0);
        if let Some((c, m)) = ctx.failure() {
            return Ok(Check::new(
                "interior-parity",
                false,
                format!("plugin `{c}` {m}"),
            ));
        }
        if a == Interior::NONE {
            continue;
        }
        answered += 1;
        if !far_from_surface(&mut probe, p)? {
            continue;
        }
        compared += 1;
        let d = rtk_kernel::sdk::shading::uniform_sphere([cx.rng.next_f32(), cx.rng.next_f32()]);
        let odd = crossings(&mut probe, Ray::new(p, d))? % 2 == 1;
        if odd != a.is_inside() {
            super::note(&mut bad, || {
                format!(
                    "at {:?}: in_interior says {}, but a ray along {:?} crosses the surface an {} number of times",
                    p.to_array(),
                    if a.is_inside() { "inside" } else { "outside" },
                    d.to_array(),
                    if odd { "odd" } else { "even" }
                )
            });
        }
    }
    Ok(if answered == 0 {
        Check::pass(
            "interior-parity",
            "the class answers that it has no interior (an open or flat surface)",
        )
    } else {
        Check::held(
            "interior-parity",
            &bad,
            compared,
            "points far from the surface",
        )
    })
}
