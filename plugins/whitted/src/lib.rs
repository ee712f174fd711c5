#![doc = include_str!("../README.md")]

use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "depth")]
    max_depth: u32,
}

fn depth() -> u32 {
    32
}

struct Whitted {
    max_depth: u32,
}

/// What Whitted shading reads: position (spawning rays), both normals.
const MASK: u32 = geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;

impl Integrator for Whitted {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if p.max_depth > 1024 {
            return Err(PluginError::key("max_depth", "must be at most 1024"));
        }
        Ok(Whitted {
            max_depth: p.max_depth,
        })
    }

    fn max_depth(&self) -> u32 {
        self.max_depth
    }

    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray) -> Color {
        if ray.generation > self.max_depth {
            return Color::BLACK;
        }
        let mut hit = Hit::new();
        if !scene.intersect(ctx, ray, ray_kind::TRACED, &mut hit) {
            return scene.background(ray);
        }
        let g = scene.local_geom(ctx, ray, &hit, MASK);
        let wo = -ray.dir.v().normalize();
        scene.emitted(&g, wo).plus(scene.shade(ctx, ray, &g))
    }
}

rtk_kernel::export_integrator!(
    Whitted,
    class = "whitted",
    doc = include_str!("../README.md")
);
