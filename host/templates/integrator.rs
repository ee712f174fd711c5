//! `__NAME__`: an integrator, here the shading normal as a colour (the
//! smallest one that traces the scene).
#![forbid(unsafe_code)]

use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {}

struct Integ;

impl Plugin for Integ {
    type Params = Params;

    fn create(_p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(Integ)
    }
}

impl Integrator for Integ {
    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray) -> Color {
        let mut hit = Hit::new();
        if !scene.intersect(ctx, ray, ray_kind::TRACED, &mut hit) {
            return scene.background(ctx, ray);
        }
        // Ask only for what is used.
        let g = scene.local_geom(ctx, ray, &hit, geom_mask::SHADING_NORMAL);
        let n = g.ns.v();
        Color::new(0.5 * (n.x + 1.0), 0.5 * (n.y + 1.0), 0.5 * (n.z + 1.0))
    }
}

// `doc` is shown by `rtk plugins`: the crate needs its README.md.
rtk_kernel::export_integrator!(Integ, class = "__NAME__", doc = include_str!("../README.md"));
