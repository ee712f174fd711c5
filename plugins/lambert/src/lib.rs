#![doc = include_str!("../README.md")]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{cosine_pdf, cosine_sample, direct_light};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::FRAC_1_PI;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "half")]
    albedo: [f32; 3],
}

fn half() -> [f32; 3] {
    [0.5; 3]
}

struct Lambert {
    f: Color,
}

impl Lambert {
    /// The BRDF where wo and wi are on the same side of the surface.
    fn brdf(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        let n = g.ns.v();
        if n.dot(wo) * n.dot(wi) > 0.0 {
            self.f
        } else {
            Color::BLACK
        }
    }
}

impl Shader for Lambert {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        check_finite("albedo", &p.albedo)?;
        if p.albedo.iter().any(|&c| !(0.0..=1.0).contains(&c)) {
            return Err(PluginError::key("albedo", "components must be in [0, 1]"));
        }
        Ok(Lambert {
            f: Color::from_array(p.albedo).scale(FRAC_1_PI),
        })
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        self.brdf(g, wo, wi)
    }

    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
    ) -> Option<BsdfSample> {
        let (wi, pdf) = cosine_sample(g, wo, u)?;
        Some(BsdfSample {
            wi: wi.into(),
            f: self.f,
            pdf,
            flags: bsdf_flags::REFLECTION,
        })
    }

    fn pdf(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> f32 {
        cosine_pdf(g, wo, wi)
    }

    const SHADES: bool = true;
    fn shade(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray, g: &LocalGeom) -> Color {
        let wo = -ray.dir.v().normalize();
        direct_light(ctx, scene, ray, g, |_, wi| self.brdf(g, wo, wi))
    }
}

rtk_kernel::export_shader!(
    Lambert,
    class = "lambert",
    doc = include_str!("../README.md")
);
