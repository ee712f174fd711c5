#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::microfacet::Normals;
use rtk_kernel::sdk::shading::fresnel_dielectric;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

/// The parameter table (Mitsuba 3's `roughdielectric` with its two indices
/// as one ratio, as rtk's `dielectric` takes it).
#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "ggx")]
    distribution: String,
    #[serde(default = "rough")]
    alpha: f32,
    #[serde(default = "glass")]
    eta: f32,
    #[serde(default = "white")]
    reflectance: [f32; 3],
    #[serde(default = "white")]
    transmittance: [f32; 3],
    #[serde(default)]
    scale_radiance: bool,
}

fn ggx() -> String {
    "ggx".into()
}
fn rough() -> f32 {
    0.1
}
fn glass() -> f32 {
    1.5
}
fn white() -> [f32; 3] {
    [1.0; 3]
}

const REFLECT: u32 = lobe::GLOSSY | lobe::REFLECTION;
const TRANSMIT: u32 = lobe::GLOSSY | lobe::TRANSMISSION;

struct RoughDielectric {
    normals: Normals,
    /// Inside over outside (outside: the side the shading normal faces).
    eta: f32,
    kr: Color,
    kt: Color,
    scale_radiance: bool,
}

impl Plugin for RoughDielectric {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(p.alpha >= 1e-3 && p.alpha <= 1.0) {
            return Err(PluginError::key(
                "alpha",
                format!("must be a number in [0.001, 1], got {}", p.alpha),
            ));
        }
        if !(p.eta.is_finite() && p.eta > 0.0 && p.eta != 1.0) {
            return Err(PluginError::key(
                "eta",
                format!("must be a positive number other than 1, got {}", p.eta),
            ));
        }
        let normals = Normals::named(&p.distribution, p.alpha).ok_or_else(|| {
            PluginError::key(
                "distribution",
                format!("`{}`: use \"ggx\" or \"beckmann\"", p.distribution),
            )
        })?;
        Ok(RoughDielectric {
            normals,
            eta: p.eta,
            kr: params::reflectance("reflectance", p.reflectance)?,
            kt: params::reflectance("transmittance", p.transmittance)?,
            scale_radiance: p.scale_radiance,
        })
    }
}

/// Mitsuba's `fresnel` for a signed cosine: from below, the inverse index.
#[inline]
fn fresnel(cos: f32, eta: f32) -> f32 {
    if cos >= 0.0 {
        fresnel_dielectric(cos, eta)
    } else {
        fresnel_dielectric(-cos, 1.0 / eta)
    }
}

/// Orthonormal frame about the shading normal (not turned: which side the
/// light is on says whether it enters).
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
    fn local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }
    fn world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// A pair of local directions and what the lobes need of them.
struct Pair {
    /// Both on one side: a reflection.
    reflect: bool,
    /// The relative index for light arriving along `lo`'s side.
    eta: f32,
    /// The generalised half vector, in the upper hemisphere.
    m: Vec3,
}

impl RoughDielectric {
    fn pair(&self, lo: Vec3, li: Vec3) -> Option<Pair> {
        if lo.z == 0.0 || li.z == 0.0 {
            return None;
        }
        let reflect = lo.z * li.z > 0.0;
        let eta = if lo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let m = (lo + li * if reflect { 1.0 } else { eta }).normalize_or_zero();
        let m = if m.z < 0.0 { -m } else { m };
        (m != Vec3::ZERO).then_some(Pair { reflect, eta, m })
    }

    /// f(lo, li) (cosine not included), Mitsuba's `eval` over |cos θi|.
    fn f(&self, lo: Vec3, li: Vec3) -> Color {
        let Some(Pair { reflect, eta, m }) = self.pair(lo, li) else {
            return Color::BLACK;
        };
        let d = self.normals.d(m);
        let g = self.normals.g1(lo, m) * self.normals.g1(li, m);
        let f = fresnel(lo.dot(m), self.eta);
        let (om, im) = (lo.dot(m), li.dot(m));
        let (value, tint) = if reflect {
            (f * d * g / (4.0 * lo.z.abs()), self.kr)
        } else {
            let scale = if self.scale_radiance {
                1.0 / (eta * eta)
            } else {
                1.0
            };
            let v = scale * (1.0 - f) * d * g * eta * eta * om * im
                / (lo.z * (om + eta * im) * (om + eta * im));
            (v.abs(), self.kt)
        };
        let v = value / li.z.abs();
        if v.is_finite() {
            tint.scale(v)
        } else {
            Color::BLACK
        }
    }

    /// The density with which `sample` returns `li` among `lobes`.
    fn density(&self, lo: Vec3, li: Vec3, lobes: (bool, bool)) -> f32 {
        let Some(Pair { reflect, eta, m }) = self.pair(lo, li) else {
            return 0.0;
        };
        let (want_r, want_t) = lobes;
        if !((want_r && reflect) || (want_t && !reflect)) {
            return 0.0;
        }
        let (om, im) = (lo.dot(m), li.dot(m));
        if !(om * lo.z > 0.0 && im * li.z > 0.0) {
            return 0.0;
        }
        let dwh = if reflect {
            1.0 / (4.0 * im)
        } else {
            eta * eta * im / ((om + eta * im) * (om + eta * im))
        };
        let up = if lo.z < 0.0 { -lo } else { lo };
        let mut p = self.normals.pdf(up, m) * dwh.abs();
        if want_r && want_t {
            let f = fresnel(om, self.eta);
            p *= if reflect { f } else { 1.0 - f };
        }
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// Mitsuba's `refract(wi, m, cos_theta_t, eta_ti)` of `lo` across the
    /// facet `m`; `None` on total internal reflection.
    fn refract(&self, lo: Vec3, m: Vec3) -> Option<(Vec3, f32)> {
        let c = lo.dot(m);
        let eta_it = if c >= 0.0 { self.eta } else { 1.0 / self.eta };
        let eta_ti = 1.0 / eta_it;
        let cos_t2 = 1.0 - (1.0 - c * c) * eta_ti * eta_ti;
        if !(cos_t2 > 0.0) {
            return None;
        }
        let cos_t = if c >= 0.0 {
            -cos_t2.sqrt()
        } else {
            cos_t2.sqrt()
        };
        Some((m * (c * eta_ti + cos_t) - lo * eta_ti, eta_it))
    }
}

fn wanted(lobes: u32) -> (bool, bool) {
    (lobes & REFLECT == REFLECT, lobes & TRANSMIT == TRANSMIT)
}

impl Shader for RoughDielectric {
    fn lobes(&self) -> u32 {
        REFLECT | TRANSMIT
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        let fr = Frame::new(g);
        self.f(fr.local(wo), fr.local(wi))
    }

    /// A normal from the distribution (seen from `wo`'s side) for `u`, then
    /// reflection with probability F, else refraction.
    fn sample(
        &self,
        ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        let (want_r, want_t) = wanted(lobes);
        if !(want_r || want_t) {
            return None;
        }
        let fr = Frame::new(g);
        let lo = fr.local(wo);
        if lo.z == 0.0 {
            return None;
        }
        let up = if lo.z < 0.0 { -lo } else { lo };
        let m = self.normals.sample(up, u);
        let fm = fresnel(lo.dot(m), self.eta);
        // The lobe is chosen by the facet's Fresnel term, so after the
        // facet: a third number, from the context's stream.
        let reflect = match (want_r, want_t) {
            (true, true) => ctx.rng.next_f32() < fm,
            (r, _) => r,
        };
        let (li, eta) = if reflect {
            (2.0 * lo.dot(m) * m - lo, 1.0)
        } else {
            self.refract(lo, m)?
        };
        let wi = fr.world(li).normalize();
        let li = fr.local(wi);
        // A reflection that dips below, or a refraction that stays above,
        // leaves the lobe it was drawn for: no sample (its mass is lost).
        if (li.z * lo.z > 0.0) != reflect {
            return None;
        }
        let pdf = self.density(lo, li, (want_r, want_t));
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.f(lo, li).scale(li.z.abs() / pdf);
        if !weight.is_finite() || weight.is_black() {
            return None;
        }
        Some(BsdfSample {
            wi: wi.into(),
            weight,
            pdf,
            lobe: if reflect { REFLECT } else { TRANSMIT },
            eta,
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
        let fr = Frame::new(g);
        Some(self.density(fr.local(wo), fr.local(wi), wanted(lobes)))
    }
}

rtk_kernel::export_shader!(
    RoughDielectric,
    class = "roughdielectric",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests;
