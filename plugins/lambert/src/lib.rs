#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod bump;
#[cfg(test)]
mod bump_tests;

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{cosine_hemisphere, cosine_lobe_sample, cosine_pdf, same_side};
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
    #[serde(default)]
    bump_map: Option<TextureParam>,
    #[serde(default = "one")]
    bump_scale: f32,
}

fn one() -> f32 {
    1.0
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
    /// A height field over uv that tilts the shading normal.
    bump: Option<bump::Bump>,
}

impl Plugin for Lambert {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        Ok(Lambert {
            albedo: p.albedo.reflectance("albedo", env)?,
            le: params::color("emission", p.emission)?,
            two_sided: p.two_sided,
            bump: match p.bump_map {
                Some(t) => Some(bump::Bump::new(
                    t.build("bump_map", env, params::color)?,
                    p.bump_scale,
                )?),
                None => None,
            },
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

    /// The bumped normal for `wo`, if there is a bump map and the hit has
    /// tangents. Two-sided, the surface is first turned to face `wo`.
    fn tilted(&self, g: &LocalGeom, wo: Vec3) -> Option<bump::Tilted> {
        let b = self.bump.as_ref()?;
        if self.two_sided && g.ns.v().dot(wo) < 0.0 {
            let mut front = *g;
            front.ns = (-g.ns.v()).into();
            front.ng = (-g.ng.v()).into();
            return b.tilt(&front, wo);
        }
        b.tilt(g, wo)
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
        if let Some(t) = self.tilted(g, wo) {
            // The lobe about n′, f·cos expressed against the untilted
            // normal the integrator's cosine uses.
            if !t.admits(wo, wi) {
                return Color::BLACK;
            }
            let k = wi.dot(t.n) / wi.dot(g.ns.v()).abs() * t.shadowing(wi);
            return self.f(g).scale(if k.is_finite() { k } else { 0.0 });
        }
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
        if lobes & lobe::DIFFUSE == 0 || lobes & lobe::REFLECTION == 0 {
            return None;
        }
        if let Some(t) = self.tilted(g, wo) {
            let wi = cosine_hemisphere(t.n, u);
            let pdf = wi.dot(t.n) * FRAC_1_PI;
            if !(t.admits(wo, wi) && pdf > 0.0) {
                return None;
            }
            return Some(BsdfSample {
                wi: wi.into(),
                weight: self.albedo.at(g).scale(t.shadowing(wi)),
                pdf,
                lobe: lobe::DIFFUSE | lobe::REFLECTION,
                eta: 1.0,
            });
        }
        if self.behind(g, wo) {
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
        if lobes & ours != ours {
            return Some(0.0);
        }
        if let Some(t) = self.tilted(g, wo) {
            return Some(if t.admits(wo, wi) {
                wi.dot(t.n) * FRAC_1_PI
            } else {
                0.0
            });
        }
        Some(if !self.behind(g, wo) {
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
