#![doc = include_str!("../README.md")]

use rtk_kernel::geom::spawn_ray;
use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{
    cosine_pdf, cosine_sample, direct_light, fresnel_dielectric, reflect, refract,
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
        let n = g.ns.v();
        if n.dot(wo) * n.dot(wi) <= 0.0 {
            return Color::BLACK;
        }
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

fn color(key: &str, c: [f32; 3]) -> Result<Color, PluginError> {
    check_finite(key, &c)?;
    if c.iter().any(|&v| v < 0.0) {
        return Err(PluginError::key(key, "components must not be negative"));
    }
    Ok(Color::from_array(c))
}

impl Shader for Phong {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(p.shininess.is_finite() && p.shininess >= 0.0) {
            return Err(PluginError::key("shininess", "must be a number >= 0"));
        }
        if !(p.ior.is_finite() && p.ior > 0.0) {
            return Err(PluginError::key("ior", "must be a positive number"));
        }
        Ok(Phong {
            kd: color("diffuse", p.diffuse)?,
            ks: color("specular", p.specular)?,
            n: p.shininess,
            kr: color("mirror", p.mirror)?,
            kt: color("transmission", p.transmission)?,
            ior: p.ior,
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
            f: self.brdf(g, wo, wi),
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
        let mut l = if self.kd.is_black() && self.ks.is_black() {
            Color::BLACK
        } else {
            direct_light(ctx, scene, ray, g, |_, wi| self.brdf(g, wo, wi))
        };
        if self.kr.is_black() && self.kt.is_black() {
            return l;
        }
        // Work on the side the ray arrives from.
        let ng = g.ng.v();
        let entering = ng.dot(wo) > 0.0;
        let n = if g.ns.v().dot(wo) > 0.0 {
            g.ns.v()
        } else {
            -g.ns.v()
        };
        let r_dir = reflect(wo, n);
        let mut reflect_weight = self.kr;
        if !self.kt.is_black() {
            let eta = if entering { self.ior } else { 1.0 / self.ior };
            let f = fresnel_dielectric(wo.dot(n), eta);
            reflect_weight = reflect_weight.plus(self.kt.scale(f));
            if let Some(t_dir) = refract(wo, n, eta) {
                let t = spawn_ray(g, t_dir, ray);
                l = l.plus(self.kt.scale(1.0 - f).times(scene.trace(
                    ctx,
                    &t,
                    ray_kind::REFRACTION,
                )));
            }
        }
        if !reflect_weight.is_black() {
            let r = spawn_ray(g, r_dir, ray);
            l = l.plus(reflect_weight.times(scene.trace(ctx, &r, ray_kind::REFLECTION)));
        }
        l
    }
}

rtk_kernel::export_shader!(Phong, class = "phong", doc = include_str!("../README.md"));
