#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{cosine_lobe_sample, cosine_pdf, same_side};
use rtk_kernel::sdk::texture::{Texture, TextureParam};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::FRAC_1_PI;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "half")]
    albedo: TextureParam,
    #[serde(default)]
    emission: [f32; 3],
    #[serde(default = "yes")]
    two_sided: bool,
}

fn yes() -> bool {
    true
}

fn half() -> TextureParam {
    TextureParam::constant([0.5; 3])
}

struct Lambert {
    /// The albedo, a constant colour or a texture over uv.
    albedo: Texture,
    /// Radiance emitted on the front side (black: it does not emit).
    le: Color,
    /// Reflects on both sides; false: only where both directions lie on
    /// the side the shading normal faces (Mitsuba's `diffuse`).
    two_sided: bool,
}

impl Plugin for Lambert {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        Ok(Lambert {
            albedo: p.albedo.reflectance("albedo", env)?,
            le: params::color("emission", p.emission)?,
            two_sided: p.two_sided,
        })
    }
}

impl Lambert {
    /// The BRDF at the hit: albedo / π.
    #[inline]
    fn f(&self, g: &LocalGeom) -> Color {
        self.albedo.at(g).scale(FRAC_1_PI)
    }

    /// Does a one-sided lambert see `w` from its back (the side the
    /// shading normal does not face)? Then it reflects nothing.
    #[inline]
    fn behind(&self, g: &LocalGeom, w: Vec3) -> bool {
        !self.two_sided && !(g.ns.v().dot(w) > 0.0)
    }
}

impl Shader for Lambert {
    fn lobes(&self) -> u32 {
        let emits = if self.le.is_black() {
            0
        } else {
            lobe::EMISSION
        };
        lobe::DIFFUSE | lobe::REFLECTION | emits
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        // Reflection only: both directions on the same side of the surface.
        if same_side(g, wo, wi) && !self.behind(g, wo) {
            self.f(g)
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
        if lobes & lobe::DIFFUSE == 0 || lobes & lobe::REFLECTION == 0 || self.behind(g, wo) {
            return None;
        }
        cosine_lobe_sample(g, wo, u, lobe::DIFFUSE | lobe::REFLECTION, |_| self.f(g))
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
        Some(if lobes & ours == ours && !self.behind(g, wo) {
            cosine_pdf(g, wo, wi)
        } else {
            0.0
        })
    }

    /// Front side only: the side the geometric normal faces.
    fn emitted(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3) -> Color {
        if g.ng.v().dot(wo) > 0.0 {
            self.le
        } else {
            Color::BLACK
        }
    }
}

rtk_kernel::export_shader!(
    Lambert,
    class = "lambert",
    doc = include_str!("../README.md")
);
