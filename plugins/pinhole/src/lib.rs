#![doc = include_str!("../README.md")]
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
    #[serde(default)]
    keyframes: Vec<Key>,
    #[serde(default)]
    near_clip: f32,
    #[serde(default = "no_far_clip")]
    far_clip: f32,
}

fn no_far_clip() -> f32 {
    f32::INFINITY
}

/// A pose of a moving camera.
#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Key {
    time: f32,
    eye: [f64; 3],
    look_at: [f64; 3],
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

/// The camera at one pose: eye, and the film's axes scaled to the field of
/// view.
#[derive(Clone, Copy)]
struct Frame {
    time: f32,
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

struct Pinhole {
    /// One pose, or the keyframes in time order (the camera moves over the
    /// shutter: `--frame` animations, camera motion blur).
    frames: Vec<Frame>,
    /// Depths along the view direction between which the camera sees:
    /// clipping planes (Mitsuba's `near_clip`, `far_clip`).
    clip: [f32; 2],
}

impl Pinhole {
    /// The pose at `time`: between keyframes, the eye and the axes are
    /// interpolated linearly (the axes stay close to orthogonal for the
    /// small turns between frames; the direction is renormalised anyway).
    #[inline]
    fn frame(&self, time: f32) -> Frame {
        let k = &self.frames;
        let i = k.partition_point(|f| f.time <= time);
        if i == 0 || k.len() == 1 {
            return k[0];
        }
        if i == k.len() {
            return k[k.len() - 1];
        }
        let (a, b) = (k[i - 1], k[i]);
        let f = ((time - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
        Frame {
            time,
            eye: a.eye.lerp(b.eye, f),
            forward: a.forward.lerp(b.forward, f),
            right: a.right.lerp(b.right, f),
            up: a.up.lerp(b.up, f),
        }
    }
}

impl Plugin for Pinhole {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let frame = |time: f32, eye, look_at| -> Result<Frame, PluginError> {
            let f = ViewFrame::new(env, eye, look_at, p.up, p.fov_y)?;
            Ok(Frame {
                time,
                eye: f.eye,
                forward: f.forward,
                right: f.right * f.tan_half * f.aspect,
                up: f.up * f.tan_half,
            })
        };
        if !(p.near_clip >= 0.0 && p.near_clip.is_finite()) {
            return Err(PluginError::key("near_clip", "must be finite and ≥ 0"));
        }
        if !(p.far_clip > p.near_clip) {
            return Err(PluginError::key("far_clip", "must exceed near_clip"));
        }
        let clip = [p.near_clip, p.far_clip];
        if p.keyframes.is_empty() {
            return Ok(Pinhole {
                frames: vec![frame(0.0, p.eye, p.look_at)?],
                clip,
            });
        }
        let mut frames = Vec::with_capacity(p.keyframes.len());
        let mut last = f32::NEG_INFINITY;
        for (i, k) in p.keyframes.iter().enumerate() {
            if !((0.0..=1.0).contains(&k.time) && k.time > last) {
                return Err(PluginError::key(
                    format!("keyframes[{i}].time"),
                    format!("must lie in [0, 1] and increase, got {}", k.time),
                ));
            }
            last = k.time;
            frames.push(frame(k.time, k.eye, k.look_at).map_err(|e| PluginError {
                key: format!("keyframes[{i}].{}", e.key),
                message: e.message,
            })?);
        }
        Ok(Pinhole { frames, clip })
    }
}

impl Camera for Pinhole {
    fn generate_ray(&self, _ctx: &mut TraceCtx, s: &CameraSample) -> Option<CameraRay> {
        let sx = 2.0 * s.film[0] - 1.0;
        let sy = 1.0 - 2.0 * s.film[1];
        let f = self.frame(s.time);
        let dir = (f.forward + f.right * sx + f.up * sy).normalize();
        let mut ray = Ray::new(f.eye, dir);
        ray.time = s.time;
        if self.clip != [0.0, f32::INFINITY] {
            // Depth along the view axis is t·cos, cos = dir · forward.
            let cos = dir.dot(f.forward.normalize());
            ray.t_min = self.clip[0] / cos;
            ray.t_max = self.clip[1] / cos;
        }
        Some(CameraRay { ray, weight: 1.0 })
    }
}

rtk_kernel::export_camera!(
    Pinhole,
    class = "pinhole",
    doc = include_str!("../README.md")
);
