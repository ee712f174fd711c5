#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::uniform_sphere;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "one")]
    radiance: [f32; 3],
}

fn one() -> [f32; 3] {
    [1.0; 3]
}

struct Constant {
    radiance: Color,
}

/// Density of a direction uniform over the sphere.
const UNIFORM_PDF: f32 = 1.0 / (4.0 * std::f32::consts::PI);

impl Plugin for Constant {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(Constant {
            radiance: params::color("radiance", p.radiance)?,
        })
    }
}

impl Light for Constant {
    fn sample_li(
        &self,
        _ctx: &mut TraceCtx,
        _p: Vec3,
        u: [f32; 2],
        _time: f32,
    ) -> Option<LightSample> {
        Some(LightSample {
            wi: uniform_sphere(u).into(),
            dist: f32::INFINITY,
            li: self.radiance,
            pdf: UNIFORM_PDF,
        })
    }
}

impl Environment for Constant {
    fn le(&self, _ctx: &mut TraceCtx, _dir: Vec3) -> Color {
        self.radiance
    }

    fn pdf_li(&self, _ctx: &mut TraceCtx, _p: Vec3, _wi: Vec3) -> f32 {
        UNIFORM_PDF
    }
}

rtk_kernel::export_light!(
    Constant,
    class = "constant",
    doc = include_str!("../README.md"),
    capabilities = [Environment]
);
