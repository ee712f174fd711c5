//! Analytic shapes: a root finder and a surface; the [`Object`] bookkeeping
//! written once.
//!
//! A single analytic primitive (a sphere, a disk, a quadric, a torus, a
//! polygon) is two functions of a ray: where it first meets the shape, and
//! what the surface is there. Everything else an [`Object`] does for such a
//! shape is the same for all of them — count the test in the context's
//! stats, write the one-primitive hit record, read `t` and `uv` back from it
//! when the hit is shaded — and was written out in every plugin. An
//! [`AnalyticShape`] writes only the two functions and its box; the blanket
//! `impl<T: AnalyticShape> Object for T` here does the rest.
//!
//! # Why the interface is shaped so
//! As ripgrep's `grep-matcher` asks a regex engine for two methods and
//! derives the rest, the trait asks for what only the shape knows and
//! defaults the rest:
//!
//! - **Required**: [`nearest_root`](AnalyticShape::nearest_root),
//!   [`surface`](AnalyticShape::surface) and
//!   [`bounds`](AnalyticShape::bounds).
//! - **Defaulted, where a shape may do better**:
//!   [`any_root`](AnalyticShape::any_root) (the shadow query: "the nearest
//!   root exists"; a shape that can answer without finding which root is
//!   nearest overrides it) and [`in_interior`](AnalyticShape::in_interior)
//!   ([`Interior::NONE`]; a closed shape answers).
//!
//! The methods take no [`TraceCtx`] and no hit-stack `level`: a shape is a
//! pure function of the ray, and the context (stats) and the record belong
//! to the adapter, so a shape cannot count itself twice or write a record
//! another aggregate would misread. Its two words of its own travel as a
//! [`Root`]: what `nearest_root` returns is what `surface` is handed back,
//! through the hit record's `t` and `uv`.
//!
//! Why a blanket impl: both traits live in this crate, so coherence allows
//! it, and a plugin's type then *is* an [`Object`]: the export macro and the
//! capabilities ([`SampleSurface`](crate::SampleSurface),
//! [`BoundingVolumes`](crate::BoundingVolumes)) take it as they take any
//! object. The price is that a type implements one trait or the other: a
//! shape that needs `prepare`, children or the context implements [`Object`]
//! itself.
//!
//! # What a shape must guarantee
//! - `nearest_root` returns a root only if `ray.accepts(root.t)`
//!   (`t_min < t < t_max`, finite: docs/numerics.md rule 2), and the
//!   nearest such root, so aggregates narrowing `t_max` find the same hit;
//!   `any_root` agrees with it (true exactly when a root exists).
//! - `surface` fills at least the position with its error bound (`p`,
//!   `p_err`: rule 6) and unit normals (`ng`, `ns`), sets their bits in
//!   `out.filled`, and fills the other fields `mask` asks for when it can
//!   (setting their bits too).
//! - After `create` the shape is immutable and may be queried from many
//!   threads at once (hence [`Plugin`]'s `Send + Sync`).

use crate::{Object, Plugin};
use glam::Vec3;
use rtk_abi::*;
use rtk_geom::Disk;

/// A root of a ray against an analytic shape: the ray parameter and the
/// primitive's two words of its own, kept in the hit record (`hit.uv`)
/// until the hit is shaded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Root {
    /// Ray parameter of the hit; `ray.accepts(t)` holds.
    pub t: f32,
    /// What the root finder learnt that the surface wants back (surface
    /// parameters found on the way); `[0, 0]` when it needs none.
    pub uv: [f32; 2],
}

impl Root {
    /// A root at `t` with no words of its own.
    #[inline]
    pub const fn at(t: f32) -> Self {
        Root { t, uv: [0.0, 0.0] }
    }
}

/// A single analytic primitive, given as its root finder, its surface and
/// its box; an [`Object`] through the blanket impl (see the [module
/// documentation](crate::analytic) for the contract).
pub trait AnalyticShape: Plugin {
    /// Box over `[time0, time1]` in the shape's own space.
    fn bounds(&self, time0: f32, time1: f32) -> Bounds3;

    /// The nearest root in the ray's open interval `(t_min, t_max)`, if any.
    fn nearest_root(&self, ray: &Ray) -> Option<Root>;

    /// Local geometry at an accepted root (rebuilt from the hit record):
    /// position, error bound and unit normals always, the rest as `mask`
    /// asks, each said in `out.filled`.
    fn surface(&self, ray: &Ray, root: Root, mask: u32, out: &mut LocalGeom);

    /// Any root in `(t_min, t_max)`: the shadow query. Override it when
    /// existence is cheaper than the nearest root.
    #[inline]
    fn any_root(&self, ray: &Ray) -> bool {
        self.nearest_root(ray).is_some()
    }

    /// Is `p` inside the shape at `time`? As [`Object::in_interior`]: the
    /// default, [`Interior::NONE`], says the shape has no interior.
    #[inline]
    fn in_interior(&self, p: Vec3, time: f32) -> Interior {
        let _ = (p, time);
        Interior::NONE
    }
}

/// The bookkeeping, once: one primitive test counted per query, the
/// primitive's record (id 0: a single primitive has no ties to break), and
/// the surface asked at the recorded `t` and `uv`.
impl<T: AnalyticShape> Object for T {
    #[inline]
    fn bounds(&self, time0: f32, time1: f32) -> Bounds3 {
        AnalyticShape::bounds(self, time0, time1)
    }

    #[inline]
    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        ctx.stats.prim_tests += 1;
        match self.nearest_root(ray) {
            Some(root) => {
                debug_assert!(ray.accepts(root.t), "a root outside the ray's interval");
                hit.record_leaf(level, root.t, 0, root.uv);
                true
            }
            None => false,
        }
    }

    #[inline]
    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, _level: u32) -> bool {
        ctx.stats.prim_tests += 1;
        self.any_root(ray)
    }

    #[inline]
    fn local_geom(
        &self,
        _ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        _level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let root = Root {
            t: hit.t,
            uv: hit.uv,
        };
        self.surface(ray, root, mask, out);
    }

    #[inline]
    fn in_interior(&self, _ctx: &mut TraceCtx, p: Vec3, time: f32) -> Interior {
        AnalyticShape::in_interior(self, p, time)
    }
}

// ---- Closing a surface with disks (closed cylinders and cones)

/// The nearest of a surface's own root and the disks closing it (caps:
/// part `k + 1` for `caps[k]`, in `uv[0]`; a cap wins only when strictly
/// nearer, so a tie at the rim goes to the surface, part 0). How a closed
/// cylinder or cone finds its hits.
pub fn nearest_with_caps(caps: &[Disk<f32>], wall: Option<Root>, ray: &Ray) -> Option<Root> {
    let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
    let mut best = wall;
    for (k, cap) in caps.iter().enumerate() {
        let limit = best.map_or(ray.t_max, |b| b.t);
        if let Some(t) = cap.intersect(o, d, ray.t_min, limit) {
            best = Some(Root {
                t,
                uv: [(k + 1) as f32, 0.0],
            });
        }
    }
    best
}

/// The surface at a cap hit: the point in the cap's plane with its error
/// bound, the cap's normal, uv = (angle / 2π, distance from the centre /
/// radius).
pub fn cap_surface(cap: &Disk<f32>, ray: &Ray, t: f32, mask: u32, out: &mut LocalGeom) {
    let s = cap.surface(ray.origin.to_array(), ray.dir.to_array(), t);
    let n = Vec3::from(cap.n());
    out.p = Vec3::from(s.p).into();
    out.p_err = Vec3::from(s.p_err).into();
    out.ng = n.into();
    out.ns = n.into();
    out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
    if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
        let [x, y] = s.xy;
        let rho = (x * x + y * y).sqrt();
        let phi = y.atan2(x).rem_euclid(std::f32::consts::TAU);
        out.uv = [phi / std::f32::consts::TAU, (rho / cap.r).clamp(0.0, 1.0)];
        let [fu, fv, _] = cap.frame.map(Vec3::from);
        let radial = if rho > 0.0 {
            (fu * x + fv * y) / rho
        } else {
            fu
        };
        out.dpdu = ((fv * x - fu * y) * std::f32::consts::TAU).into();
        out.dpdv = (radial * cap.r).into();
        out.filled |= geom_mask::UV | geom_mask::TANGENTS;
    }
}
