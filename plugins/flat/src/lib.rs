#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "white")]
    color: [f32; 3],
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

struct Flat {
    color: Color,
}

impl Plugin for Flat {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(Flat {
            color: params::color("color", p.color)?,
        })
    }
}

impl Shader for Flat {
    fn lobes(&self) -> u32 {
        0
    }

    /// As a material, it reflects nothing.
    fn eval(&self, _ctx: &mut TraceCtx, _g: &LocalGeom, _wo: glam::Vec3, _wi: glam::Vec3) -> Color {
        Color::BLACK
    }
}

impl Shade for Flat {
    fn shade(&self, _ctx: &mut TraceCtx, _scene: &Scene, _ray: &Ray, _geom: &LocalGeom) -> Color {
        self.color
    }
}

rtk_kernel::export_shader!(
    Flat,
    class = "flat",
    doc = include_str!("../README.md"),
    capabilities = [Shade]
);
