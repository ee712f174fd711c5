#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod tables;

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::microfacet::Normals;
use rtk_kernel::sdk::shading::{cosine_hemisphere, fresnel_dielectric};
use rtk_kernel::sdk::texture::{Texture, TextureParam};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::FRAC_1_PI;
use tables::RES;

/// The parameter table: Mitsuba 3's `roughplastic` names and defaults, but
/// for the distribution (rtk's default is GGX, Mitsuba's Beckmann; `rtk
/// import` writes it, and turns named indices into numbers).
#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "ggx")]
    distribution: String,
    #[serde(default = "rough")]
    alpha: f32,
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

fn ggx() -> String {
    "ggx".into()
}
fn rough() -> f32 {
    0.1
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

/// Range of `alpha`, as `roughconductor`'s: below 1e-3 f32 densities
/// (up to ~1/α²) resolve the lobe poorly.
const ALPHA_MIN: f32 = 1e-3;
const ALPHA_MAX: f32 = 1.0;

const GLOSSY: u32 = lobe::GLOSSY | lobe::REFLECTION;
const DIFFUSE: u32 = lobe::DIFFUSE | lobe::REFLECTION;

struct RoughPlastic {
    normals: Normals,
    /// int_ior / ext_ior.
    eta: f32,
    diffuse: Texture,
    specular: Color,
    nonlinear: bool,
    /// T(μ), the interface's transmittance at the tabulated cosines.
    transmittance: [f32; RES],
    /// The interface's reflectance seen from the diffuse base.
    internal: f32,
    /// How much sampling favours the specular lobe before the Fresnel
    /// split: mean specular / (mean diffuse + mean specular), Mitsuba's.
    specular_weight: f32,
}

impl Plugin for RoughPlastic {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        if !(p.alpha >= ALPHA_MIN && p.alpha <= ALPHA_MAX) {
            return Err(PluginError::key(
                "alpha",
                format!("must be a number in [0.001, 1], got {}", p.alpha),
            ));
        }
        for (key, v) in [("int_ior", p.int_ior), ("ext_ior", p.ext_ior)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(PluginError::key(key, format!("must be positive, got {v}")));
            }
        }
        if p.int_ior == p.ext_ior {
            return Err(PluginError::key(
                "int_ior",
                "must differ from ext_ior: an index-matched coat has no interface",
            ));
        }
        let normals = Normals::named(&p.distribution, p.alpha).ok_or_else(|| {
            PluginError::key(
                "distribution",
                format!("`{}`: use \"ggx\" or \"beckmann\"", p.distribution),
            )
        })?;
        let eta = p.int_ior / p.ext_ior;
        let diffuse = p
            .diffuse_reflectance
            .reflectance("diffuse_reflectance", env)?;
        let specular = params::reflectance("specular_reflectance", p.specular_reflectance)?;
        let (d_mean, s_mean) = (
            mean(&diffuse),
            specular.to_array().iter().sum::<f32>() / 3.0,
        );
        Ok(RoughPlastic {
            normals,
            eta,
            diffuse,
            specular,
            nonlinear: p.nonlinear,
            transmittance: tables::transmittance(normals, eta),
            internal: tables::internal_reflectance(normals, eta),
            specular_weight: s_mean / (d_mean + s_mean).max(1e-6),
        })
    }
}

/// A texture's mean colour, averaged over channels: for a constant its
/// value, for an image its texels, else ½ (it only steers sampling).
fn mean(t: &Texture) -> f32 {
    if let Some(c) = t.as_constant() {
        return c.to_array().iter().sum::<f32>() / 3.0;
    }
    match t.texels() {
        Some((_, _, px)) if !px.is_empty() => {
            px.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / (3.0 * px.len() as f32)
        }
        _ => 0.5,
    }
}

/// Orthonormal frame about the shading normal (one-sided: not turned).
struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    fn new(g: &LocalGeom) -> Frame {
        let n = g.ns.v();
        let (t, b) = n.any_orthonormal_pair();
        Frame { t, b, n }
    }
    #[inline]
    fn local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }
    #[inline]
    fn world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

impl RoughPlastic {
    /// The specular lobe's f / specular, local, both cosines positive:
    /// F(wo·h) D(h) G1(wo, h) G1(wi, h) / (4 cos θo cos θi).
    fn glossy(&self, lo: Vec3, li: Vec3) -> f32 {
        let h = (lo + li).normalize_or_zero();
        let g = self.normals.g1(lo, h) * self.normals.g1(li, h);
        let f =
            fresnel_dielectric(lo.dot(h), self.eta) * self.normals.d(h) * g / (4.0 * lo.z * li.z);
        if f.is_finite() {
            f
        } else {
            0.0
        }
    }

    /// The diffuse base seen through the interface: ρ / (1 − ρ_int) ·
    /// T(θo) T(θi) / (π η²), with ρ_int = Fint (linear) or ρ·Fint.
    fn base(&self, g: &LocalGeom, lo: Vec3, li: Vec3) -> Color {
        let rho = self.diffuse.at(g);
        let k = tables::lookup(&self.transmittance, lo.z)
            * tables::lookup(&self.transmittance, li.z)
            * FRAC_1_PI
            / (self.eta * self.eta);
        let fi = self.internal;
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

    /// The probability of sampling the specular lobe at cosine `cos_o`,
    /// given the lobes asked for (`None`: neither).
    fn p_glossy(&self, cos_o: f32, lobes: u32) -> Option<f32> {
        match (lobes & GLOSSY == GLOSSY, lobes & DIFFUSE == DIFFUSE) {
            (false, false) => None,
            (true, false) => Some(1.0),
            (false, true) => Some(0.0),
            (true, true) => {
                let t = tables::lookup(&self.transmittance, cos_o);
                let s = (1.0 - t) * self.specular_weight;
                let d = t * (1.0 - self.specular_weight);
                Some(if s + d > 0.0 { s / (s + d) } else { 1.0 })
            }
        }
    }

    /// The mixture's density of `li` given `lo` (local, both above).
    fn density(&self, lo: Vec3, li: Vec3, p_glossy: f32) -> f32 {
        let h = (lo + li).normalize_or_zero();
        let spec = self.normals.pdf(lo, h) / (4.0 * lo.dot(h));
        let spec = if spec.is_finite() && spec > 0.0 {
            spec
        } else {
            0.0
        };
        let p = p_glossy * spec + (1.0 - p_glossy) * li.z * FRAC_1_PI;
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// Local `wo`, `wi` if both are above the shading normal.
    fn above(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Option<(Frame, Vec3, Vec3)> {
        let fr = Frame::new(g);
        let (lo, li) = (fr.local(wo), fr.local(wi));
        (lo.z > 0.0 && li.z > 0.0).then_some((fr, lo, li))
    }

    fn f(&self, g: &LocalGeom, lo: Vec3, li: Vec3) -> Color {
        self.specular
            .scale(self.glossy(lo, li))
            .plus(self.base(g, lo, li))
    }
}

impl Shader for RoughPlastic {
    fn lobes(&self) -> u32 {
        GLOSSY | DIFFUSE
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        match self.above(g, wo, wi) {
            Some((_, lo, li)) => self.f(g, lo, li),
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
        let fr = Frame::new(g);
        let lo = fr.local(wo);
        if !(lo.z > 0.0) {
            return None;
        }
        let ps = self.p_glossy(lo.z, lobes)?;
        // u[0] chooses the lobe and is stretched back to [0, 1).
        let (li, lobe) = if u[0] < ps {
            let m = self.normals.sample(lo, [u[0] / ps, u[1]]);
            (2.0 * lo.dot(m) * m - lo, GLOSSY)
        } else {
            let u0 = ((u[0] - ps) / (1.0 - ps)).min(1.0 - f32::EPSILON);
            (cosine_hemisphere(Vec3::Z, [u0, u[1]]), DIFFUSE)
        };
        if !(li.z > 0.0) {
            return None;
        }
        let wi = fr.world(li).normalize();
        let li = fr.local(wi);
        let pdf = self.density(lo, li, ps);
        if !(pdf > 0.0 && li.z > 0.0) {
            return None;
        }
        let f = match lobe {
            GLOSSY if ps == 1.0 => self.specular.scale(self.glossy(lo, li)),
            DIFFUSE if ps == 0.0 => self.base(g, lo, li),
            _ => self.f(g, lo, li),
        };
        Some(BsdfSample {
            wi: wi.into(),
            weight: f.scale(li.z / pdf),
            pdf,
            lobe,
            eta: 1.0,
        })
    }

    fn pdf(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        wi: Vec3,
        lobes: u32,
    ) -> Option<f32> {
        let Some((_, lo, li)) = self.above(g, wo, wi) else {
            return Some(0.0);
        };
        Some(match self.p_glossy(lo.z, lobes) {
            Some(ps) => self.density(lo, li, ps),
            None => 0.0,
        })
    }
}

rtk_kernel::export_shader!(
    RoughPlastic,
    class = "roughplastic",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests;
