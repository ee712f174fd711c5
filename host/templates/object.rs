//! `__NAME__`: a primitive object, here a sphere intersected with the
//! kernel's robust routines (RTG ch. 7 in f64, error-bounded hit point).
#![forbid(unsafe_code)]

use rtk_kernel::geom::{intersect_sphere_in_f64, nearest_root, sphere_point_in_f64};
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    center: [f64; 3],
    #[serde(default = "one")]
    radius: f32,
}

fn one() -> f32 {
    1.0
}

struct Prim {
    c: Vec3,
    r: f32,
}

impl Prim {
    #[inline]
    fn root(&self, ray: &Ray) -> Option<f32> {
        let h = intersect_sphere_in_f64(
            self.c.to_array(),
            self.r,
            ray.origin.to_array(),
            ray.dir.to_array(),
        )?;
        nearest_root(&h, ray.t_min, ray.t_max)
    }
}

impl Plugin for Prim {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        // World positions go through env.position (camera-relative rendering).
        let c = env.position("center", p.center)?;
        if !(p.radius > 0.0 && p.radius <= 1e12) {
            return Err(PluginError::key(
                "radius",
                format!("must be a positive number up to 1e12, got {}", p.radius),
            ));
        }
        Ok(Prim { c, r: p.radius })
    }
}

impl Object for Prim {
    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        Bounds3::new(self.c - Vec3::splat(self.r), self.c + Vec3::splat(self.r))
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        ctx.stats.prim_tests += 1;
        match self.root(ray) {
            Some(t) => {
                hit.record_leaf(level, t, 0, [0.0, 0.0]);
                true
            }
            None => false,
        }
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, _level: u32) -> bool {
        ctx.stats.prim_tests += 1;
        self.root(ray).is_some()
    }

    fn local_geom(
        &self,
        _ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        _level: u32,
        _mask: u32,
        out: &mut LocalGeom,
    ) {
        let (p, err) = sphere_point_in_f64(
            self.c.to_array(),
            self.r,
            ray.origin.to_array(),
            ray.dir.to_array(),
            hit.t,
        );
        let p = Vec3::from(p);
        let n = ((p - self.c) / self.r).normalize_or(Vec3::Z);
        out.p = p.into();
        out.p_err = Vec3::from(err).into();
        out.ng = n.into();
        out.ns = n.into();
        // Position and normals only; an integrator asking for uv or
        // tangents sees they were not filled.
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
    }
}

// `doc` is shown by `rtk plugins`: the crate needs its README.md.
rtk_kernel::export_object!(Prim, class = "__NAME__", doc = include_str!("../README.md"));
