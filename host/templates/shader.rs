//! `__NAME__`: a shader, here an ideal diffuse reflector (BRDF albedo / π)
//! answering the material queries eval, sample and pdf.
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{cosine_lobe_sample, cosine_pdf, same_side};
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

struct Diffuse {
    /// albedo / π
    f: Color,
}

impl Plugin for Diffuse {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(Diffuse {
            f: params::reflectance("albedo", p.albedo)?.scale(FRAC_1_PI),
        })
    }
}

impl Shader for Diffuse {
    fn lobes(&self) -> u32 {
        lobe::DIFFUSE | lobe::REFLECTION
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        if same_side(g, wo, wi) {
            self.f
        } else {
            Color::BLACK
        }
    }

    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        if lobes & lobe::DIFFUSE == 0 || lobes & lobe::REFLECTION == 0 {
            return None;
        }
        cosine_lobe_sample(g, wo, u, lobe::DIFFUSE | lobe::REFLECTION, |_| self.f)
    }

    fn pdf(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        wi: Vec3,
        lobes: u32,
    ) -> Option<f32> {
        let ours = lobe::DIFFUSE | lobe::REFLECTION;
        Some(if lobes & ours == ours {
            cosine_pdf(g, wo, wi)
        } else {
            0.0
        })
    }
}

// `doc` is shown by `rtk plugins`: the crate needs its README.md.
rtk_kernel::export_shader!(Diffuse, class = "__NAME__", doc = include_str!("../README.md"));
