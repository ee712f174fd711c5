#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "down")]
    direction: [f32; 3],
    #[serde(default = "one")]
    irradiance: [f32; 3],
}

fn down() -> [f32; 3] {
    [0.0, -1.0, 0.0]
}
fn one() -> [f32; 3] {
    [1.0; 3]
}

struct Directional {
    to_light: Vec3,
    irradiance: Color,
}

impl Plugin for Directional {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(Directional {
            to_light: -params::direction("direction", p.direction)?,
            irradiance: params::color("irradiance", p.irradiance)?,
        })
    }
}

impl Light for Directional {
    fn sample_li(
        &self,
        _ctx: &mut TraceCtx,
        _p: Vec3,
        _u: [f32; 2],
        _time: f32,
    ) -> Option<LightSample> {
        Some(LightSample {
            wi: self.to_light.into(),
            dist: f32::INFINITY,
            li: self.irradiance,
            pdf: 1.0,
        })
    }
}

rtk_kernel::export_light!(
    Directional,
    class = "directional",
    doc = include_str!("../README.md")
);
