#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::camera::ViewFrame;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::FRAC_PI_4;

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
    aperture_radius: f32,
    #[serde(default)]
    focus_distance: Option<f64>,
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

struct ThinLens {
    eye: Vec3,
    forward: Vec3,
    /// Film x axis, scaled to the half-width of the image at unit distance.
    right: Vec3,
    /// Film y axis, scaled to the half-height at unit distance.
    up: Vec3,
    /// Lens x axis (unit right times the aperture radius).
    lens_x: Vec3,
    /// Lens y axis (unit up times the aperture radius).
    lens_y: Vec3,
    /// Lens offsets divided by the focus distance: the direction towards the
    /// focus point from a lens point `eye + o` is `d − o / focus_distance`.
    tilt_x: Vec3,
    tilt_y: Vec3,
    /// A zero aperture: the pinhole's rays, bit for bit.
    pinhole: bool,
}

impl Plugin for ThinLens {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let f = ViewFrame::new(env, p.eye, p.look_at, p.up, p.fov_y)?;
        let (eye, forward, right, up) = (f.eye, f.forward, f.right, f.up);
        if !(p.aperture_radius >= 0.0 && p.aperture_radius.is_finite()) {
            return Err(PluginError::key(
                "aperture_radius",
                format!("must be a finite number ≥ 0, got {}", p.aperture_radius),
            ));
        }
        let focus = match p.focus_distance {
            Some(f) if !(f > 0.0 && f.is_finite() && (f as f32).is_normal()) => {
                return Err(PluginError::key(
                    "focus_distance",
                    format!("must be a finite number > 0, got {f}"),
                ));
            }
            Some(f) => f,
            None => f.look_distance,
        };
        let (tan_half, aspect) = (f.tan_half, f.aspect);
        let r = p.aperture_radius;
        let inv_focus = (1.0 / focus) as f32;
        Ok(ThinLens {
            eye,
            forward,
            right: right * tan_half * aspect,
            up: up * tan_half,
            lens_x: right * r,
            lens_y: up * r,
            tilt_x: right * (r * inv_focus),
            tilt_y: up * (r * inv_focus),
            pinhole: r == 0.0,
        })
    }
}

/// Shirley and Chiu's concentric map of `u` ∈ [0, 1)² onto the unit disk
/// (area-preserving, low distortion, so stratified samples stay stratified).
#[inline]
fn concentric_disk(u: [f32; 2]) -> (f32, f32) {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, theta) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, 2.0 * FRAC_PI_4 - FRAC_PI_4 * (a / b))
    };
    let (s, c) = theta.sin_cos();
    (r * c, r * s)
}

impl Camera for ThinLens {
    fn generate_ray(&self, _ctx: &mut TraceCtx, s: &CameraSample) -> Option<CameraRay> {
        let sx = 2.0 * s.film[0] - 1.0;
        let sy = 1.0 - 2.0 * s.film[1];
        // The pinhole's direction: its point at distance `focus_distance`
        // along the view (d·forward = 1) is on the plane of focus.
        let d = self.forward + self.right * sx + self.up * sy;
        let mut ray = if self.pinhole {
            Ray::new(self.eye, d.normalize())
        } else {
            let (lx, ly) = concentric_disk(s.lens);
            let origin = self.eye + self.lens_x * lx + self.lens_y * ly;
            // focus point − origin = focus_distance · (d − offset / focus_distance).
            let dir = (d - self.tilt_x * lx - self.tilt_y * ly).normalize();
            Ray::new(origin, dir)
        };
        ray.time = s.time;
        Some(CameraRay { ray, weight: 1.0 })
    }
}

rtk_kernel::export_camera!(
    ThinLens,
    class = "thinlens",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_disk_covers_the_disk_uniformly() {
        let mut rng = RngState::seeded(5);
        let n = 200_000;
        let (mut inner, mut mean) = (0u32, (0.0f64, 0.0f64));
        for _ in 0..n {
            let (x, y) = concentric_disk([rng.next_f32(), rng.next_f32()]);
            let r2 = x * x + y * y;
            assert!(r2 <= 1.0 + 1e-5, "{x} {y}");
            if r2 < 0.25 {
                inner += 1;
            }
            mean.0 += x as f64 / n as f64;
            mean.1 += y as f64 / n as f64;
        }
        // A quarter of the area lies within radius 1/2.
        let frac = inner as f64 / n as f64;
        assert!((frac - 0.25).abs() < 0.005, "{frac}");
        assert!(mean.0.abs() < 0.005 && mean.1.abs() < 0.005, "{mean:?}");
        assert_eq!(concentric_disk([0.5, 0.5]), (0.0, 0.0));
    }

    fn camera(aperture: f32, focus: Option<f64>) -> ThinLens {
        let env = Env {
            scene_dir: ".",
            name: "cameras.c",
            image_width: 64,
            image_height: 64,
            origin: [0.0; 3],
            arrays: Default::default(),
        };
        let p = Params {
            eye: [0.0, 0.0, 5.0],
            look_at: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y: 40.0,
            aperture_radius: aperture,
            focus_distance: focus,
        };
        ThinLens::create(p, &env).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Every ray through one film point meets the others on the plane of
    /// focus, and starts on the lens disk.
    #[test]
    fn rays_of_one_film_point_meet_on_the_focus_plane() {
        for focus in [None, Some(2.0), Some(11.0)] {
            let c = camera(0.5, focus);
            let f = focus.unwrap_or(5.0) as f32;
            let mut rng = RngState::seeded(9);
            for _ in 0..100 {
                let film = [rng.next_f32(), rng.next_f32()];
                let mut ctx = TraceCtx::new(0, 1, 0);
                let CameraRay { ray: r0, weight: w } = c
                    .generate_ray(
                        &mut ctx,
                        &CameraSample {
                            film,
                            lens: [0.5, 0.5],
                            time: 0.25,
                        },
                    )
                    .expect("a ray");
                assert_eq!(w, 1.0);
                assert_eq!(r0.time, 0.25);
                let at = |r: &Ray| {
                    let t = (5.0 - f - r.origin.z) / r.dir.z; // plane z = 5 − f
                    r.origin.v() + r.dir.v() * t
                };
                let p0 = at(&r0);
                for _ in 0..10 {
                    let r = c
                        .generate_ray(
                            &mut ctx,
                            &CameraSample {
                                film,
                                lens: [rng.next_f32(), rng.next_f32()],
                                time: 0.0,
                            },
                        )
                        .expect("a ray")
                        .ray;
                    assert!((r.dir.v().length() - 1.0).abs() < 1e-6);
                    let o = r.origin.v() - Vec3::new(0.0, 0.0, 5.0);
                    assert!(o.z == 0.0 && o.length() <= 0.5 + 1e-6, "{o}");
                    assert!((at(&r) - p0).length() < 1e-4 * f, "{} {}", at(&r), p0);
                }
            }
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        let env = Env {
            scene_dir: ".",
            name: "cameras.c",
            image_width: 4,
            image_height: 4,
            origin: [0.0; 3],
            arrays: Default::default(),
        };
        let p = |a: f32, f: Option<f64>| Params {
            eye: [0.0, 0.0, 5.0],
            look_at: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            fov_y: 40.0,
            aperture_radius: a,
            focus_distance: f,
        };
        let key = |r: Result<ThinLens, PluginError>| r.err().map(|e| e.key);
        assert_eq!(
            key(ThinLens::create(p(-1.0, None), &env)).as_deref(),
            Some("aperture_radius")
        );
        assert_eq!(
            key(ThinLens::create(p(f32::NAN, None), &env)).as_deref(),
            Some("aperture_radius")
        );
        assert_eq!(
            key(ThinLens::create(p(0.1, Some(0.0)), &env)).as_deref(),
            Some("focus_distance")
        );
        assert_eq!(
            key(ThinLens::create(p(0.1, Some(-2.0)), &env)).as_deref(),
            Some("focus_distance")
        );
        assert!(ThinLens::create(p(0.0, Some(3.0)), &env).is_ok());
    }
}
