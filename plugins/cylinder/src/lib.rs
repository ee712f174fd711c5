#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod shape;
use rtk_kernel::geom::vec;

use rtk_kernel::geom::Disk;
use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::analytic::{cap_surface, nearest_with_caps};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use shape::Cylinder;
use std::f32::consts::TAU;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    base: [f64; 3],
    #[serde(default = "up")]
    axis: [f32; 3],
    #[serde(default)]
    height: Option<f32>,
    #[serde(default = "one")]
    radius: f32,
    #[serde(default)]
    caps: bool,
}

fn one() -> f32 {
    1.0
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

struct CylinderObject {
    /// Bounding sphere (`inq_bounds`).
    sphere: BoundSphere,
    cyl: Cylinder<f32>,
    bounds: Bounds3,
    /// The bottom and top disks when `caps` closes the cylinder (parts 1
    /// and 2 of a hit; the wall is part 0), outward.
    caps: Option<[Disk<f32>; 2]>,
}

/// A length: finite, positive, within what f32 handles.
fn length(key: &str, r: f32) -> Result<f32, PluginError> {
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

impl Plugin for CylinderObject {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let base = env.position("base", p.base)?;
        params::direction("axis", p.axis)?;
        let r = length("radius", p.radius)?;
        let axis = p.axis.map(f64::from);
        let len = vec::norm64(axis);
        let h = match p.height {
            Some(h) => length("height", h)? as f64,
            None => length("axis", len as f32).map_err(|e| {
                PluginError::key("axis", format!("its length is the height: {}", e.message))
            })? as f64,
        };
        let axis = axis.map(|c| c / len * h);
        let b64 = base.to_array().map(f64::from);
        let top: [f64; 3] = std::array::from_fn(|i| b64[i] + axis[i]);
        let e = vec::circle_extent(vec::frame64(axis)[2], r as f64);
        let (lo, hi) = vec::f32_box(
            std::array::from_fn(|i| b64[i].min(top[i]) - e[i]),
            std::array::from_fn(|i| b64[i].max(top[i]) + e[i]),
        );
        let mid: [f64; 3] = std::array::from_fn(|i| b64[i] + 0.5 * axis[i]);
        let reach = ((r as f64).powi(2) + (0.5 * h).powi(2)).sqrt();
        let sphere = BoundSphere::from_f64(mid, reach, 1e-6 * reach);
        let w = vec::frame64(axis)[2];
        let caps = p.caps.then(|| {
            [
                Disk::new(b64, w.map(|c| -c), r as f64, 0.0),
                Disk::new(top, w, r as f64, 0.0),
            ]
        });
        Ok(CylinderObject {
            sphere,
            cyl: Cylinder::new(b64, axis, r as f64),
            bounds: Bounds3::new(Vec3::from(lo), Vec3::from(hi)),
            caps,
        })
    }
}

impl AnalyticShape for CylinderObject {
    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn nearest_root(&self, ray: &Ray) -> Option<Root> {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let wall = self.cyl.intersect(o, d, ray.t_min, ray.t_max).map(Root::at);
        match &self.caps {
            Some(caps) => nearest_with_caps(caps, wall, ray),
            None => wall,
        }
    }

    /// Inside a closed cylinder: between the caps' planes and nearer the
    /// axis than the radius, in f64. An open one has no interior.
    fn in_interior(&self, p: Vec3, _time: f32) -> Interior {
        if self.caps.is_none() {
            return Interior::NONE;
        }
        let b = Vec3::from(self.cyl.base).as_dvec3();
        let w = Vec3::from(self.cyl.frame[2]).as_dvec3();
        let f = p.as_dvec3() - b;
        let z = f.dot(w);
        let rho2 = f.length_squared() - z * z;
        let (h, r) = (self.cyl.h as f64, self.cyl.r as f64);
        Interior::from_bool(z > 0.0 && z < h && rho2 < r * r)
    }

    fn surface(&self, ray: &Ray, root: Root, mask: u32, out: &mut LocalGeom) {
        if let (Some(caps), part @ 1..=2) = (&self.caps, root.uv[0] as usize) {
            return cap_surface(&caps[part - 1], ray, root.t, mask, out);
        }
        let s = self
            .cyl
            .surface(ray.origin.to_array(), ray.dir.to_array(), root.t);
        let n = Vec3::from(s.n).normalize_or(Vec3::from(self.cyl.frame[0]));
        out.p = Vec3::from(s.p).into();
        out.p_err = Vec3::from(s.p_err).into();
        out.ng = n.into();
        out.ns = n.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            // u = phi / 2pi around the axis, v = z / height (pbrt's cylinder).
            let [x, y, z] = s.local;
            let [fu, fv, fw] = self.cyl.frame.map(Vec3::from);
            let phi = y.atan2(x).rem_euclid(TAU);
            out.uv = [phi / TAU, (z / self.cyl.h).clamp(0.0, 1.0)];
            out.dpdu = ((fv * x - fu * y) * TAU).into();
            out.dpdv = (fw * self.cyl.h).into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

/// A sphere around the shape, and slabs cutting its box with the sphere's
/// tangent planes.
impl BoundingVolumes for CylinderObject {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.sphere)
    }
    fn slabs(&self, _t0: f32, _t1: f32) -> Option<SlabBounds> {
        Some(SlabBounds::from_box(&self.bounds).intersect(&SlabBounds::around_sphere(&self.sphere)))
    }
}

rtk_kernel::export_object!(
    CylinderObject,
    class = "cylinder",
    doc = include_str!("../README.md"),
    capabilities = [BoundingVolumes]
);
