#![doc = include_str!("../README.md")]

use rtk_kernel::glam::{DVec3, Vec3};
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

struct Pinhole {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

impl Plugin for Pinhole {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let eye = env.position("eye", p.eye)?;
        env.position("look_at", p.look_at)?;
        // The view direction from the unrounded points: far from the
        // origin their f32 roundings would tilt it.
        let look = DVec3::from(p.look_at) - DVec3::from(p.eye);
        let up = params::point("up", p.up)?;
        if !(p.fov_y > 0.0 && p.fov_y < 180.0) {
            return Err(PluginError::key(
                "fov_y",
                format!("must be between 0 and 180 degrees, got {}", p.fov_y),
            ));
        }
        let forward = look.normalize_or_zero().as_vec3();
        if forward == Vec3::ZERO {
            return Err(PluginError::key("look_at", "must differ from eye"));
        }
        let right = forward.cross(up).normalize_or_zero();
        if right == Vec3::ZERO {
            return Err(PluginError::key(
                "up",
                "must not be parallel to the view direction",
            ));
        }
        let up = right.cross(forward);
        let tan_half = (p.fov_y.to_radians() * 0.5).tan();
        let aspect = env.image_width.max(1) as f32 / env.image_height.max(1) as f32;
        Ok(Pinhole {
            eye,
            forward,
            right: right * tan_half * aspect,
            up: up * tan_half,
        })
    }
}

impl Camera for Pinhole {
    fn generate_ray(&self, s: &CameraSample) -> (Ray, f32) {
        let sx = 2.0 * s.film[0] - 1.0;
        let sy = 1.0 - 2.0 * s.film[1];
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        let mut ray = Ray::new(self.eye, dir);
        ray.time = s.time;
        (ray, 1.0)
    }
}

rtk_kernel::export_camera!(
    Pinhole,
    class = "pinhole",
    doc = include_str!("../README.md")
);
