//! The look-at frame every perspective camera starts from, read and checked
//! once here so `pinhole`, `thinlens` and third-party cameras agree on its
//! conventions and its errors.

use super::{Env, PluginError};
use crate::params;
use glam::{DVec3, Vec3};

/// A camera's position and orthonormal frame, with its field of view.
#[derive(Clone, Copy, Debug)]
pub struct ViewFrame {
    /// The eye, in the renderer's space (`Env::position`).
    pub eye: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit image-right: `forward × up`.
    pub right: Vec3,
    /// Unit image-up: `right × forward`.
    pub up: Vec3,
    /// tan(fov_y / 2): the half-height of the image at unit distance.
    pub tan_half: f32,
    /// Image width over height.
    pub aspect: f32,
    /// |look_at − eye|, in f64.
    pub look_distance: f64,
}

impl ViewFrame {
    /// From the `eye`, `look_at`, `up` and `fov_y` parameters (errors name
    /// them). The view direction is taken from the unrounded f64 points:
    /// far from the origin their f32 roundings would tilt it.
    pub fn new(
        env: &Env,
        eye: [f64; 3],
        look_at: [f64; 3],
        up: [f32; 3],
        fov_y: f32,
    ) -> Result<ViewFrame, PluginError> {
        let eye_r = env.position("eye", eye)?;
        env.position("look_at", look_at)?;
        let look = DVec3::from(look_at) - DVec3::from(eye);
        let up = params::point("up", up)?;
        if !(fov_y > 0.0 && fov_y < 180.0) {
            return Err(PluginError::key(
                "fov_y",
                format!("must be between 0 and 180 degrees, got {fov_y}"),
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
        Ok(ViewFrame {
            eye: eye_r,
            forward,
            right,
            up: right.cross(forward),
            tan_half: (fov_y.to_radians() * 0.5).tan(),
            aspect: env.image_width.max(1) as f32 / env.image_height.max(1) as f32,
            look_distance: look.length(),
        })
    }
}
