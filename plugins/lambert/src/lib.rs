#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod bump;
#[cfg(test)]
mod tests;

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
    #[serde(default)]
    opacity: Option<TextureParam>,
    #[serde(default)]
    normal_map: Option<TextureParam>,
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
    /// A height field or a normal map that tilts the shading normal.
    bump: Option<bump::Tilt>,
    /// Where below 1, light passes through (a cut-out leaf).
    opacity: Option<Texture>,
}

impl Plugin for Lambert {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        Ok(Lambert {
            albedo: p.albedo.reflectance("albedo", env)?,
            le: params::color("emission", p.emission)?,
            two_sided: p.two_sided,
            bump: match (p.bump_map, p.normal_map) {
                (Some(_), Some(_)) => {
                    return Err(PluginError::key(
                        "normal_map",
                        "a surface takes a bump_map or a normal_map, not both",
                    ))
                }
                (Some(t), None) => Some(bump::Tilt::Bump(bump::Bump::new(
                    t.build("bump_map", env, params::color)?,
                    p.bump_scale,
                )?)),
                (None, Some(t)) => Some(bump::Tilt::Normals(bump::NormalMap::new(
                    t.reflectance("normal_map", env)?,
                ))),
                (None, None) => None,
            },
            opacity: match p.opacity {
                Some(t) => Some(t.reflectance("opacity", env)?),
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

/// The diffuse lobe itself (bumped or not), before any opacity.
impl Lambert {
    fn lobe_eval(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
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

    fn lobe_sample(&self, g: &LocalGeom, wo: Vec3, u: [f32; 2]) -> Option<BsdfSample> {
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
                lobe: DIFFUSE,
                eta: 1.0,
            });
        }
        if self.behind(g, wo) {
            return None;
        }
        cosine_lobe_sample(g, wo, u, DIFFUSE, |_| self.f(g))
    }

    fn lobe_pdf(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> f32 {
        if let Some(t) = self.tilted(g, wo) {
            return if t.admits(wo, wi) {
                wi.dot(t.n) * FRAC_1_PI
            } else {
                0.0
            };
        }
        if !self.behind(g, wo) {
            cosine_pdf(g, wo, wi)
        } else {
            0.0
        }
    }

    /// The surface's opacity at the hit (1 without an opacity map), and
    /// whether the pass-through and the diffuse lobes are asked for.
    fn opacity(&self, g: &LocalGeom, lobes: u32) -> (f32, bool, bool) {
        let diffuse = lobes & DIFFUSE == DIFFUSE;
        let Some(o) = &self.opacity else {
            return (1.0, false, diffuse);
        };
        let null = lobes & NULL == NULL;
        let a = match (null, diffuse) {
            (true, true) => {
                let c = o.at(g).to_array();
                (0..3)
                    .map(|k| c[k] * LUMINANCE[k])
                    .sum::<f32>()
                    .clamp(0.0, 1.0)
            }
            (true, false) => 0.0,
            _ => 1.0,
        };
        (a, null, diffuse)
    }
}

/// The diffuse lobe.
const DIFFUSE: u32 = lobe::DIFFUSE | lobe::REFLECTION;
/// Passing through where the opacity map is below 1: straight on, as if
/// the surface were not there (Mitsuba's `mask`, its null lobe).
const NULL: u32 = lobe::SPECULAR | lobe::TRANSMISSION;
/// Mitsuba's luminance weights: an opacity map's value is its luminance.
const LUMINANCE: [f32; 3] = [0.212671, 0.715160, 0.072169];

impl Shader for Lambert {
    fn lobes(&self) -> u32 {
        let emits = if self.le.is_black() {
            0
        } else {
            lobe::EMISSION
        };
        let through = if self.opacity.is_some() { NULL } else { 0 };
        DIFFUSE | emits | through
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        let (a, _, _) = self.opacity(g, lobe::ALL);
        self.lobe_eval(g, wo, wi).scale(a)
    }

    /// With an opacity map: through with probability 1 − α (weight 1),
    /// else the diffuse lobe with `u[0]` stretched back to [0, 1).
    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        let (a, null, diffuse) = self.opacity(g, lobes);
        if !(u[0] < a) {
            return null.then_some(BsdfSample {
                wi: (-wo).into(),
                weight: Color::splat(1.0),
                pdf: 1.0 - a,
                lobe: NULL,
                eta: 1.0,
            });
        }
        if !diffuse {
            return None;
        }
        let mut s = self.lobe_sample(g, wo, [(u[0] / a).min(1.0 - f32::EPSILON), u[1]])?;
        s.pdf *= a;
        Some(s)
    }

    fn pdf(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        wi: Vec3,
        lobes: u32,
    ) -> Option<f32> {
        let (a, _, diffuse) = self.opacity(g, lobes);
        Some(if diffuse {
            a * self.lobe_pdf(g, wo, wi)
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
