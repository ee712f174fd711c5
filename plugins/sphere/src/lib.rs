#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::{intersect_sphere_in_f64, nearest_root, sphere_point_in_f64};
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    center: [f64; 3],
    #[serde(default = "one")]
    radius: f32,
}

fn one() -> f32 {
    1.0
}

struct Sphere {
    c: Vec3,
    r: f32,
}

impl Plugin for Sphere {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let center = env.position("center", p.center)?;
        if !p.radius.is_finite() || p.radius <= 0.0 {
            return Err(PluginError::key(
                "radius",
                format!("must be a positive number, got {}", p.radius),
            ));
        }
        if p.radius < f32::MIN_POSITIVE || p.radius > 1e12 {
            return Err(PluginError::key(
                "radius",
                format!(
                    "{:e} is outside the range f32 handles (1.2e-38 to 1e12)",
                    p.radius
                ),
            ));
        }
        Ok(Sphere {
            c: center,
            r: p.radius,
        })
    }
}

impl AnalyticShape for Sphere {
    /// Inside when nearer the centre than the radius (f64: exact for every
    /// point farther from the surface than the rounding of its inputs).
    fn in_interior(&self, p: Vec3, _time: f32) -> Interior {
        let d2 = (p.as_dvec3() - self.c.as_dvec3()).length_squared();
        Interior::from_bool(d2 < (self.r as f64) * (self.r as f64))
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        Bounds3::new(self.c - Vec3::splat(self.r), self.c + Vec3::splat(self.r))
    }

    fn nearest_root(&self, ray: &Ray) -> Option<Root> {
        let h = intersect_sphere_in_f64(
            self.c.to_array(),
            self.r,
            ray.origin.to_array(),
            ray.dir.to_array(),
        )?;
        nearest_root(&h, ray.t_min, ray.t_max).map(Root::at)
    }

    fn surface(&self, ray: &Ray, root: Root, mask: u32, out: &mut LocalGeom) {
        let (p, err) = sphere_point_in_f64(
            self.c.to_array(),
            self.r,
            ray.origin.to_array(),
            ray.dir.to_array(),
            root.t,
        );
        let p = Vec3::from(p);
        let n = ((p - self.c) / self.r).normalize_or(Vec3::Z);
        out.p = p.into();
        out.p_err = Vec3::from(err).into();
        out.ng = n.into();
        out.ns = n.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            // u = phi / 2pi around +y, v = theta / pi from +y.
            let phi = n.z.atan2(n.x).rem_euclid(std::f32::consts::TAU);
            let theta = n.y.clamp(-1.0, 1.0).acos();
            out.uv = [phi / std::f32::consts::TAU, theta / std::f32::consts::PI];
            let dpdu = Vec3::new(-n.z, 0.0, n.x) * (std::f32::consts::TAU * self.r);
            let dpdu = if dpdu.length_squared() > 0.0 {
                dpdu
            } else {
                n.any_orthonormal_vector()
            };
            let dpdv = n.cross(dpdu).normalize_or(Vec3::X) * (std::f32::consts::PI * self.r);
            out.dpdu = dpdu.into();
            out.dpdv = dpdv.into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

impl SampleSurface for Sphere {
    fn area(&self) -> f32 {
        4.0 * std::f32::consts::PI * self.r * self.r
    }

    fn sample_point(&self, u: [f32; 2]) -> Option<(Vec3, Vec3)> {
        let n = rtk_kernel::sdk::shading::uniform_sphere(u);
        Some((self.c + self.r * n, n))
    }
}

/// The sphere bounds itself exactly; its slabs are its tangent planes.
impl BoundingVolumes for Sphere {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.volume())
    }
    fn slabs(&self, _t0: f32, _t1: f32) -> Option<SlabBounds> {
        Some(SlabBounds::around_sphere(&self.volume()))
    }
}

impl Sphere {
    fn volume(&self) -> BoundSphere {
        BoundSphere::from_f64(self.c.as_dvec3().to_array(), self.r as f64, 0.0)
    }
}

rtk_kernel::export_object!(
    Sphere,
    class = "sphere",
    doc = include_str!("../README.md"),
    capabilities = [SampleSurface, BoundingVolumes]
);
