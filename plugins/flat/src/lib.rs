#![doc = include_str!("../README.md")]

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

impl Shader for Flat {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        check_finite("color", &p.color)?;
        if p.color.iter().any(|&c| c < 0.0) {
            return Err(PluginError::key("color", "components must not be negative"));
        }
        Ok(Flat {
            color: Color::from_array(p.color),
        })
    }

    const SHADES: bool = true;
    fn shade(&self, _ctx: &mut TraceCtx, _scene: &Scene, _ray: &Ray, _geom: &LocalGeom) -> Color {
        self.color
    }
}

rtk_kernel::export_shader!(Flat, class = "flat", doc = include_str!("../README.md"));
