#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{cosine_hemisphere, fresnel_dielectric, reflect_at};
use rtk_kernel::sdk::texture::{Texture, TextureParam};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::FRAC_1_PI;

/// The parameter table: Mitsuba 3's `plastic` names and defaults (`rtk
/// import` turns named indices into numbers).
#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "polypropylene")]
    int_ior: f32,
    #[serde(default = "air")]
    ext_ior: f32,
    #[serde(default = "half")]
    diffuse_reflectance: TextureParam,
    #[serde(default = "white")]
    specular_reflectance: [f32; 3],
    #[serde(default)]
    nonlinear: bool,
}

fn polypropylene() -> f32 {
    1.49
}
fn air() -> f32 {
    1.000277
}
fn half() -> TextureParam {
    TextureParam::constant([0.5; 3])
}
fn white() -> [f32; 3] {
    [1.0; 3]
}

const MIRROR: u32 = lobe::SPECULAR | lobe::REFLECTION;
const DIFFUSE: u32 = lobe::DIFFUSE | lobe::REFLECTION;

struct Plastic {
    /// int_ior / ext_ior.
    eta: f32,
    diffuse: Texture,
    specular: Color,
    nonlinear: bool,
    /// The coat's hemispherical reflectance seen from inside.
    fdr_int: f32,
    /// Mitsuba's steer towards the mirror: mean specular / (mean diffuse +
    /// mean specular).
    specular_weight: f32,
}

impl Plugin for Plastic {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        for (key, v) in [("int_ior", p.int_ior), ("ext_ior", p.ext_ior)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(PluginError::key(key, format!("must be positive, got {v}")));
            }
        }
        let eta = p.int_ior / p.ext_ior;
        let diffuse = p
            .diffuse_reflectance
            .reflectance("diffuse_reflectance", env)?;
        let specular = params::reflectance("specular_reflectance", p.specular_reflectance)?;
        let d_mean = diffuse
            .as_constant()
            .map_or(0.5, |c| c.to_array().iter().sum::<f32>() / 3.0);
        let s_mean = specular.to_array().iter().sum::<f32>() / 3.0;
        Ok(Plastic {
            eta,
            diffuse,
            specular,
            nonlinear: p.nonlinear,
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
            specular_weight: s_mean / (d_mean + s_mean).max(1e-6),
        })
    }
}

/// The hemispherical average of the dielectric Fresnel reflectance for
/// relative index `eta`, by Mitsuba's fits (`fresnel_diffuse_reflectance`
/// in `include/mitsuba/render/fresnel.h`): Egan and Hilgeman (1973) below
/// 1, d'Eon and Irving (2011) above.
fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881f32];
        c.iter().rev().fold(0.0, |acc, k| acc * inv + k)
    }
}

impl Plastic {
    /// Cosines of `wo` and `wi` with the shading normal, if both are above
    /// it (one-sided, as Mitsuba's).
    fn cosines(g: &LocalGeom, wo: Vec3, wi: Vec3) -> Option<(f32, f32)> {
        let n = g.ns.v();
        let (ci, co) = (n.dot(wo), n.dot(wi));
        (ci > 0.0 && co > 0.0).then_some((ci, co))
    }

    /// The diffuse base through the smooth coat:
    /// ρ / (1 − ρ_int) · (1 − F(θo)) (1 − F(θi)) / (π η²).
    fn base(&self, g: &LocalGeom, cos_o: f32, cos_i: f32) -> Color {
        let rho = self.diffuse.at(g);
        let k = (1.0 - fresnel_dielectric(cos_o, self.eta))
            * (1.0 - fresnel_dielectric(cos_i, self.eta))
            * FRAC_1_PI
            / (self.eta * self.eta);
        let fi = self.fdr_int;
        if self.nonlinear {
            let kept = |r: f32| r / (1.0 - r * fi) * k;
            Color {
                r: kept(rho.r),
                g: kept(rho.g),
                b: kept(rho.b),
                w: kept(rho.w),
            }
        } else {
            rho.scale(k / (1.0 - fi))
        }
    }

    /// The probability of the mirror at viewing cosine `cos_o` for the
    /// lobes asked for (`None`: neither).
    fn p_mirror(&self, cos_o: f32, lobes: u32) -> Option<f32> {
        match (lobes & MIRROR == MIRROR, lobes & DIFFUSE == DIFFUSE) {
            (false, false) => None,
            (true, false) => Some(1.0),
            (false, true) => Some(0.0),
            (true, true) => {
                let f = fresnel_dielectric(cos_o, self.eta);
                let s = f * self.specular_weight;
                let d = (1.0 - f) * (1.0 - self.specular_weight);
                Some(if s + d > 0.0 { s / (s + d) } else { 1.0 })
            }
        }
    }
}

impl Shader for Plastic {
    fn lobes(&self) -> u32 {
        MIRROR | DIFFUSE
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        match Self::cosines(g, wo, wi) {
            Some((co, ci)) => self.base(g, co, ci),
            None => Color::BLACK,
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
        let n = g.ns.v();
        let cos_o = n.dot(wo);
        if !(cos_o > 0.0) {
            return None;
        }
        let pm = self.p_mirror(cos_o, lobes)?;
        if u[0] < pm {
            let f = fresnel_dielectric(cos_o, self.eta);
            return Some(BsdfSample {
                wi: reflect_at(g, wo, n).into(),
                weight: self.specular.scale(f / pm),
                pdf: pm,
                lobe: MIRROR,
                eta: 1.0,
            });
        }
        let u0 = ((u[0] - pm) / (1.0 - pm)).min(1.0 - f32::EPSILON);
        let wi = cosine_hemisphere(n, [u0, u[1]]);
        let cos_i = n.dot(wi);
        let pdf = (1.0 - pm) * cos_i * FRAC_1_PI;
        if !(cos_i > 0.0 && pdf > 0.0) {
            return None;
        }
        Some(BsdfSample {
            wi: wi.into(),
            weight: self.base(g, cos_o, cos_i).scale(cos_i / pdf),
            pdf,
            lobe: DIFFUSE,
            eta: 1.0,
        })
    }

    /// The diffuse lobe's density (the mirror is a delta: 0 elsewhere).
    fn pdf(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        wi: Vec3,
        lobes: u32,
    ) -> Option<f32> {
        let Some((co, ci)) = Self::cosines(g, wo, wi) else {
            return Some(0.0);
        };
        Some(match self.p_mirror(co, lobes) {
            Some(pm) => (1.0 - pm) * ci * FRAC_1_PI,
            None => 0.0,
        })
    }
}

rtk_kernel::export_shader!(
    Plastic,
    class = "plastic",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests;
