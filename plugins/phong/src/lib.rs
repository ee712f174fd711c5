#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{
    cosine_lobe_sample, fresnel_dielectric, reflect, reflect_at, refract_at, same_side,
};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::{FRAC_1_PI, PI};

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "half")]
    diffuse: [f32; 3],
    #[serde(default)]
    specular: [f32; 3],
    #[serde(default = "shiny")]
    shininess: f32,
    #[serde(default)]
    mirror: [f32; 3],
    #[serde(default)]
    transmission: [f32; 3],
    #[serde(default = "glass")]
    ior: f32,
}

fn half() -> [f32; 3] {
    [0.5; 3]
}
fn shiny() -> f32 {
    32.0
}
fn glass() -> f32 {
    1.5
}

struct Phong {
    kd: Color,
    ks: Color,
    n: f32,
    kr: Color,
    kt: Color,
    ior: f32,
}

impl Phong {
    /// Diffuse plus normalised Phong lobe, for wo and wi on the same side.
    fn brdf(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        if !same_side(g, wo, wi) {
            return Color::BLACK;
        }
        let n = g.ns.v();
        let n = if n.dot(wo) < 0.0 { -n } else { n };
        let mut f = self.kd.scale(FRAC_1_PI);
        if !self.ks.is_black() {
            let cos_a = reflect(wo, n).dot(wi).max(0.0);
            f = f.plus(
                self.ks
                    .scale((self.n + 2.0) / (2.0 * PI) * cos_a.powf(self.n)),
            );
        }
        f
    }
}

impl Plugin for Phong {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(p.shininess.is_finite() && p.shininess >= 0.0) {
            return Err(PluginError::key("shininess", "must be a number >= 0"));
        }
        if !(p.ior.is_finite() && p.ior > 0.0) {
            return Err(PluginError::key("ior", "must be a positive number"));
        }
        Ok(Phong {
            kd: params::color("diffuse", p.diffuse)?,
            ks: params::color("specular", p.specular)?,
            n: p.shininess,
            kr: params::color("mirror", p.mirror)?,
            kt: params::color("transmission", p.transmission)?,
            ior: p.ior,
        })
    }
}

/// The side a ray arrives from: the shading normal turned towards `wo`, and
/// the relative index of refraction across the surface (n_t / n_i).
struct Side {
    n: Vec3,
    eta: f32,
}

impl Phong {
    fn side(&self, g: &LocalGeom, wo: Vec3) -> Side {
        let entering = g.ng.v().dot(wo) > 0.0;
        let ns = g.ns.v();
        Side {
            n: if ns.dot(wo) > 0.0 { ns } else { -ns },
            eta: if entering { self.ior } else { 1.0 / self.ior },
        }
    }

    /// The mirror lobe: direction and weight `kr + kt·F`.
    fn mirror_lobe(&self, g: &LocalGeom, s: &Side, wo: Vec3) -> (Vec3, Color) {
        let mut w = self.kr;
        if !self.kt.is_black() {
            w = w.plus(self.kt.scale(fresnel_dielectric(wo.dot(s.n), s.eta)));
        }
        (reflect_at(g, wo, s.n), w)
    }

    /// The refraction lobe: direction and weight `kt·(1 − F)`; none on total
    /// internal reflection or without transmission.
    fn refraction_lobe(&self, g: &LocalGeom, s: &Side, wo: Vec3) -> Option<(Vec3, Color)> {
        if self.kt.is_black() {
            return None;
        }
        let f = fresnel_dielectric(wo.dot(s.n), s.eta);
        refract_at(g, wo, s.n, s.eta).map(|t| (t, self.kt.scale(1.0 - f)))
    }
}

fn delta(wi: Vec3, weight: Color, side: u32) -> Option<BsdfSample> {
    (!weight.is_black()).then(|| BsdfSample {
        wi: wi.into(),
        weight,
        pdf: 1.0,
        lobe: lobe::SPECULAR | side,
        eta: 1.0,
    })
}

impl Shader for Phong {
    fn lobes(&self) -> u32 {
        let mut l = lobe::DIFFUSE | lobe::GLOSSY | lobe::REFLECTION;
        if !(self.kr.is_black() && self.kt.is_black()) {
            l |= lobe::SPECULAR; // the mirror direction (kr, and kt·F)
        }
        if !self.kt.is_black() {
            l |= lobe::TRANSMISSION;
        }
        l
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        self.brdf(g, wo, wi)
    }

    /// Specular requests get a delta lobe: transmission when `lobes` allows
    /// it, else reflection; otherwise the diffuse and glossy terms are
    /// sampled together by their cosine lobe.
    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        if lobes & lobe::SPECULAR != 0 && !(self.kr.is_black() && self.kt.is_black()) {
            let side = self.side(g, wo);
            if lobes & lobe::TRANSMISSION != 0 {
                if let Some((t, w)) = self.refraction_lobe(g, &side, wo) {
                    return delta(t, w, lobe::TRANSMISSION);
                }
            }
            if lobes & lobe::REFLECTION != 0 {
                let (r, w) = self.mirror_lobe(g, &side, wo);
                return delta(r, w, lobe::REFLECTION);
            }
            return None;
        }
        if lobes & (lobe::DIFFUSE | lobe::GLOSSY) == 0 || lobes & lobe::REFLECTION == 0 {
            return None;
        }
        let bits = lobe::DIFFUSE | lobe::GLOSSY | lobe::REFLECTION;
        cosine_lobe_sample(g, wo, u, bits, |wi| self.brdf(g, wo, wi))
    }
}

rtk_kernel::export_shader!(Phong, class = "phong", doc = include_str!("../README.md"));
