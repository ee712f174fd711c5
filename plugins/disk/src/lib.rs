#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::vec;

use rtk_kernel::geom::Disk;
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::f32::consts::TAU;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    center: [f64; 3],
    #[serde(default = "up")]
    normal: [f32; 3],
    #[serde(default = "one")]
    radius: f32,
    #[serde(default)]
    inner_radius: f32,
}

fn one() -> f32 {
    1.0
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

struct DiskObject {
    /// Bounding sphere (`inq_bounds`).
    sphere: BoundSphere,
    disk: Disk<f32>,
    bounds: Bounds3,
}

/// A radius: finite, positive, within what f32 handles.
fn radius(key: &str, r: f32) -> Result<f32, PluginError> {
    if !r.is_finite() || r <= 0.0 {
        return Err(PluginError::key(
            key,
            format!("must be a positive number, got {r}"),
        ));
    }
    if !(f32::MIN_POSITIVE..=params::MAX_COORDINATE).contains(&r) {
        return Err(PluginError::key(
            key,
            format!("{r:e} is outside the range f32 handles (1.2e-38 to 1e12)"),
        ));
    }
    Ok(r)
}

impl Plugin for DiskObject {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let c = env.position("center", p.center)?;
        params::direction("normal", p.normal)?;
        let r = radius("radius", p.radius)?;
        if !p.inner_radius.is_finite() || p.inner_radius < 0.0 || p.inner_radius >= r {
            return Err(PluginError::key(
                "inner_radius",
                format!(
                    "must be at least 0 and less than radius ({r}), got {}",
                    p.inner_radius
                ),
            ));
        }
        let c64 = c.to_array().map(f64::from);
        let n64 = p.normal.map(f64::from);
        let disk = Disk::new(c64, n64, r as f64, p.inner_radius as f64);
        let e = vec::circle_extent(vec::frame64(n64)[2], r as f64);
        let (lo, hi) = vec::f32_box(
            std::array::from_fn(|i| c64[i] - e[i]),
            std::array::from_fn(|i| c64[i] + e[i]),
        );
        Ok(DiskObject {
            sphere: BoundSphere::from_f64(c64, r as f64, 1e-6 * r as f64),
            disk,
            bounds: Bounds3::new(Vec3::from(lo), Vec3::from(hi)),
        })
    }
}

impl AnalyticShape for DiskObject {
    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn nearest_root(&self, ray: &Ray) -> Option<Root> {
        self.disk
            .intersect(
                ray.origin.to_array(),
                ray.dir.to_array(),
                ray.t_min,
                ray.t_max,
            )
            .map(Root::at)
    }

    fn surface(&self, ray: &Ray, root: Root, mask: u32, out: &mut LocalGeom) {
        let s = self
            .disk
            .surface(ray.origin.to_array(), ray.dir.to_array(), root.t);
        let [fu, fv, fw] = self.disk.frame.map(Vec3::from);
        out.p = Vec3::from(s.p).into();
        out.p_err = Vec3::from(s.p_err).into();
        out.ng = fw.into();
        out.ns = fw.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            // u = phi / 2pi around the normal from the frame's u axis,
            // v = (radius - rho) / (radius - inner_radius), as pbrt's disk.
            let [x, y] = s.xy;
            let rho = (x * x + y * y).sqrt();
            let (r, ri) = (self.disk.r, self.disk.ri);
            let phi = y.atan2(x).rem_euclid(TAU);
            out.uv = [phi / TAU, ((r - rho) / (r - ri)).clamp(0.0, 1.0)];
            let (dpdu, dpdv) = if rho > 0.0 {
                let radial = (fu * x + fv * y) / rho;
                ((fv * x - fu * y) * TAU, -radial * (r - ri))
            } else {
                (fv * (TAU * r), -fu * (r - ri))
            };
            out.dpdu = dpdu.into();
            out.dpdv = dpdv.into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

/// A sphere around the disk (its rim), and slabs cutting its box with the
/// sphere's tangent planes.
impl BoundingVolumes for DiskObject {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.sphere)
    }
    fn slabs(&self, _t0: f32, _t1: f32) -> Option<SlabBounds> {
        Some(SlabBounds::from_box(&self.bounds).intersect(&SlabBounds::around_sphere(&self.sphere)))
    }
}

rtk_kernel::export_object!(
    DiskObject,
    class = "disk",
    doc = include_str!("../README.md"),
    capabilities = [BoundingVolumes]
);
