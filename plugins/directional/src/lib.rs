#![doc = include_str!("../README.md")]

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

impl Light for Directional {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        check_finite("direction", &p.direction)?;
        check_finite("irradiance", &p.irradiance)?;
        let d = Vec3::from(p.direction);
        if d.length_squared() == 0.0 {
            return Err(PluginError::key("direction", "must not be zero"));
        }
        if p.irradiance.iter().any(|&c| c < 0.0) {
            return Err(PluginError::key("irradiance", "must not be negative"));
        }
        Ok(Directional {
            to_light: -d.normalize(),
            irradiance: Color::from_array(p.irradiance),
        })
    }

    fn flags(&self) -> u32 {
        light_flags::DELTA_DIRECTION
    }

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
            flags: light_flags::DELTA_DIRECTION,
        })
    }
}

rtk_kernel::export_light!(
    Directional,
    class = "directional",
    doc = include_str!("../README.md")
);
