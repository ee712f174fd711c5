#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::{DMat4, Vec3};
use rtk_kernel::sdk::texture::{Texture, TextureParam};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "identity")]
    to_world: [f64; 16],
    #[serde(default)]
    fov: Option<f64>,
    #[serde(default = "axis_x")]
    fov_axis: String,
    #[serde(default = "white")]
    irradiance: TextureParam,
    #[serde(default = "one")]
    scale: f32,
}

fn identity() -> [f64; 16] {
    DMat4::IDENTITY.transpose().to_cols_array()
}
fn axis_x() -> String {
    "x".into()
}
fn white() -> TextureParam {
    TextureParam::constant([1.0; 3])
}
fn one() -> f32 {
    1.0
}

struct Projector {
    /// The light's position (renderer space).
    pos: Vec3,
    /// The optical axis, to_world · (0, 0, 1) (not renormalised, as
    /// Mitsuba's).
    axis: Vec3,
    /// World to the projector's frame (linear part; positions relative to `pos`).
    to_local: [Vec3; 3],
    /// cot(fov_x / 2) and the image's aspect w / h.
    cot: f32,
    aspect: f32,
    irradiance: Texture,
    /// π · scale (Mitsuba's normalisation).
    weight: f32,
}

/// The horizontal field of view, as Mitsuba's `parse_fov` for `fov` along
/// `axis` on an image of aspect `aspect`.
fn fov_x(fov: f64, axis: &str, aspect: f64) -> Result<f64, PluginError> {
    let axis = match axis {
        "smaller" if aspect > 1.0 => "y",
        "smaller" => "x",
        "larger" if aspect > 1.0 => "x",
        "larger" => "y",
        a => a,
    };
    let half = (0.5 * fov.to_radians()).tan();
    let x = match axis {
        "x" => fov,
        "y" => 2.0 * (half * aspect).atan().to_degrees(),
        "diagonal" => {
            2.0 * (half / (1.0 + 1.0 / (aspect * aspect)).sqrt())
                .atan()
                .to_degrees()
        }
        other => {
            return Err(PluginError::key(
                "fov_axis",
                format!("`{other}`: use x, y, diagonal, smaller or larger"),
            ))
        }
    };
    if !(x > 0.0 && x < 180.0) {
        return Err(PluginError::key(
            "fov",
            format!("the horizontal field of view is {x}°: it must lie in (0, 180)"),
        ));
    }
    Ok(x)
}

impl Plugin for Projector {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        if !p.to_world.iter().all(|x| x.is_finite()) {
            return Err(PluginError::key("to_world", "must be finite numbers"));
        }
        let m = DMat4::from_cols_array(&p.to_world).transpose();
        if m.row(3) != rtk_kernel::glam::DVec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(PluginError::key("to_world", "the last row must be 0 0 0 1"));
        }
        let det = m.determinant();
        if !(det.abs() > 1e-12) {
            return Err(PluginError::key("to_world", "singular"));
        }
        let inv = m.inverse();
        let origin = m.w_axis.truncate();
        let pos = env.position("to_world", [origin.x, origin.y, origin.z])?;
        let axis = m.z_axis.truncate().as_vec3();
        let to_local = [inv.row(0), inv.row(1), inv.row(2)].map(|r| r.truncate().as_vec3());
        let irradiance = p.irradiance.color("irradiance", env)?;
        let aspect = irradiance.size().map_or(1.0, |(w, h)| w as f64 / h as f64);
        let fx = match p.fov {
            Some(f) => fov_x(f, &p.fov_axis, aspect)?,
            // Mitsuba's default: a 50 mm lens on 35 mm film, on the diagonal.
            None => {
                let d = 2.0
                    * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / 100.0)
                        .atan()
                        .to_degrees();
                fov_x(d, "diagonal", aspect)?
            }
        };
        if !(p.scale >= 0.0 && p.scale.is_finite()) {
            return Err(PluginError::key("scale", "must be finite and ≥ 0"));
        }
        Ok(Projector {
            pos,
            axis,
            to_local,
            cot: (1.0 / (0.5 * fx.to_radians()).tan()) as f32,
            aspect: aspect as f32,
            irradiance,
            weight: std::f32::consts::PI * p.scale,
        })
    }
}

impl Light for Projector {
    fn sample_li(
        &self,
        _ctx: &mut TraceCtx,
        p: Vec3,
        _u: [f32; 2],
        _time: f32,
    ) -> Option<LightSample> {
        let rel = p - self.pos;
        let [x, y, z] = self.to_local.map(|r| r.dot(rel));
        if !(z > 0.0) {
            return None;
        }
        let u = 0.5 - 0.5 * x * self.cot / z;
        let v = 0.5 - 0.5 * self.aspect * y * self.cot / z;
        if !((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)) {
            return None;
        }
        let d2 = rel.length_squared();
        let dist = d2.sqrt();
        let to_light = -rel / dist;
        let cos = self.axis.dot(-to_light);
        if !(cos > 0.0) {
            return None;
        }
        let li = self
            .irradiance
            .eval([u, v])
            .scale(self.weight / (z * z * cos));
        Some(LightSample {
            wi: to_light.into(),
            dist,
            li,
            pdf: 1.0,
        })
    }
}

rtk_kernel::export_light!(
    Projector,
    class = "projector",
    doc = include_str!("../README.md")
);
