//! `__NAME__`: a camera, here a pinhole built on the kernel's `ViewFrame`
//! (which reads the eye as a world position and checks the parameters).
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::camera::ViewFrame;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "default_eye")]
    eye: [f64; 3],
    #[serde(default)]
    look_at: [f64; 3],
    #[serde(default = "default_up")]
    up: [f32; 3],
    #[serde(default = "default_fov")]
    fov_y: f32,
}

fn default_eye() -> [f64; 3] {
    [0.0, 0.0, 5.0]
}
fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov() -> f32 {
    40.0
}

struct Cam {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

impl Plugin for Cam {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let f = ViewFrame::new(env, p.eye, p.look_at, p.up, p.fov_y)?;
        Ok(Cam {
            eye: f.eye,
            forward: f.forward,
            right: f.right * f.tan_half * f.aspect,
            up: f.up * f.tan_half,
        })
    }
}

impl Camera for Cam {
    /// `s.film` is in [0, 1]², (0, 0) at the top left; returns the ray and its weight.
    fn generate_ray(&self, _ctx: &mut TraceCtx, s: &CameraSample) -> Option<CameraRay> {
        let sx = 2.0 * s.film[0] - 1.0;
        let sy = 1.0 - 2.0 * s.film[1];
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        let mut ray = Ray::new(self.eye, dir);
        ray.time = s.time;
        Some(CameraRay { ray, weight: 1.0 })
    }
}

// `doc` is shown by `rtk plugins`: the crate needs its README.md.
rtk_kernel::export_camera!(Cam, class = "__NAME__", doc = include_str!("../README.md"));
