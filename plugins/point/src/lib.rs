#![doc = include_str!("../README.md")]
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

struct Point {
    pos: Vec3,
    intensity: Color,
}

impl Plugin for Point {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        Ok(Point {
            pos: env.position("position", p.position)?,
            intensity: params::color("intensity", p.intensity)?,
        })
    }
}

impl Light for Point {
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

rtk_kernel::export_light!(Point, class = "point", doc = include_str!("../README.md"));
