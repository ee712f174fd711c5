//! `__NAME__`: a light, here a point light (intensity falling off as 1/d²).
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    position: [f64; 3],
    #[serde(default = "one")]
    intensity: [f32; 3],
}

fn one() -> [f32; 3] {
    [1.0; 3]
}

struct Lamp {
    pos: Vec3,
    intensity: Color,
}

impl Plugin for Lamp {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        Ok(Lamp {
            // World positions go through env.position (camera-relative rendering).
            pos: env.position("position", p.position)?,
            intensity: params::color("intensity", p.intensity)?,
        })
    }
}

impl Light for Lamp {
    fn sample_li(
        &self,
        _ctx: &mut TraceCtx,
        p: Vec3,
        _u: [f32; 2],
        _time: f32,
    ) -> Option<LightSample> {
        let d = self.pos - p;
        let d2 = d.length_squared();
        if !(d2 > 0.0) {
            return None;
        }
        let dist = d2.sqrt();
        Some(LightSample {
            wi: (d / dist).into(),
            dist,
            li: self.intensity.scale(1.0 / d2),
            pdf: 1.0,
        })
    }
}

// `doc` is shown by `rtk plugins`: the crate needs its README.md.
rtk_kernel::export_light!(Lamp, class = "__NAME__", doc = include_str!("../README.md"));
