#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod shape;
use rtk_kernel::geom::vec;

use rtk_kernel::geom::Disk;
use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::analytic::{cap_surface, nearest_with_caps};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use shape::Cone;
use std::f32::consts::TAU;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "apex")]
    apex: [f64; 3],
    #[serde(default = "down")]
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

fn apex() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

fn down() -> [f32; 3] {
    [0.0, -1.0, 0.0]
}

struct ConeObject {
    /// Bounding sphere (`inq_bounds`): around the apex and the base rim.
    sphere: BoundSphere,
    cone: Cone<f32>,
    bounds: Bounds3,
    /// The base disk when `caps` closes the cone (part 1 of a hit; the
    /// wall is part 0), outward.
    caps: Option<[Disk<f32>; 1]>,
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

impl Plugin for ConeObject {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let apex = env.position("apex", p.apex)?;
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
        let a64 = apex.to_array().map(f64::from);
        let base: [f64; 3] = std::array::from_fn(|i| a64[i] + axis[i]);
        let e = vec::circle_extent(vec::frame64(axis)[2], r as f64);
        let (lo, hi) = vec::f32_box(
            std::array::from_fn(|i| a64[i].min(base[i] - e[i])),
            std::array::from_fn(|i| a64[i].max(base[i] + e[i])),
        );
        // The apex and the rim are at most sqrt((h/2)² + r²) from the
        // axis's midpoint (when r >= h/2 the rim is farther; else the apex).
        let mid: [f64; 3] = std::array::from_fn(|i| a64[i] + 0.5 * axis[i]);
        let reach = ((r as f64).powi(2) + (0.5 * h).powi(2)).sqrt();
        let w = vec::frame64(axis)[2];
        let caps = p.caps.then(|| [Disk::new(base, w, r as f64, 0.0)]);
        Ok(ConeObject {
            sphere: BoundSphere::from_f64(mid, reach, 1e-6 * reach),
            cone: Cone::new(a64, axis, r as f64),
            bounds: Bounds3::new(Vec3::from(lo), Vec3::from(hi)),
            caps,
        })
    }
}

impl AnalyticShape for ConeObject {
    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn nearest_root(&self, ray: &Ray) -> Option<Root> {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let wall = self
            .cone
            .intersect(o, d, ray.t_min, ray.t_max)
            .map(Root::at);
        match &self.caps {
            Some(caps) => nearest_with_caps(caps, wall, ray),
            None => wall,
        }
    }

    /// Inside a closed cone: between the apex and the base's plane, nearer
    /// the axis than the cone's radius there, in f64. An open one has no
    /// interior.
    fn in_interior(&self, p: Vec3, _time: f32) -> Interior {
        if self.caps.is_none() {
            return Interior::NONE;
        }
        let a = Vec3::from(self.cone.apex).as_dvec3();
        let w = Vec3::from(self.cone.frame[2]).as_dvec3();
        let f = p.as_dvec3() - a;
        let z = f.dot(w);
        let rho2 = f.length_squared() - z * z;
        let (h, k) = (self.cone.h as f64, self.cone.k as f64);
        Interior::from_bool(z > 0.0 && z < h && rho2 < (k * z) * (k * z))
    }

    fn surface(&self, ray: &Ray, root: Root, mask: u32, out: &mut LocalGeom) {
        if let (Some(caps), 1) = (&self.caps, root.uv[0] as usize) {
            return cap_surface(&caps[0], ray, root.t, mask, out);
        }
        let s = self
            .cone
            .surface(ray.origin.to_array(), ray.dir.to_array(), root.t);
        let n = Vec3::from(s.n).normalize_or(Vec3::from(self.cone.frame[0]));
        out.p = Vec3::from(s.p).into();
        out.p_err = Vec3::from(s.p_err).into();
        out.ng = n.into();
        out.ns = n.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            // u = phi / 2pi around the axis, v = z / height: 0 at the apex,
            // 1 on the rim. dpdu x dpdv points outwards.
            let [x, y, z] = s.local;
            let [fu, fv, fw] = self.cone.frame.map(Vec3::from);
            let (h, k) = (self.cone.h, self.cone.k);
            let rho = (x * x + y * y).sqrt();
            let phi = y.atan2(x).rem_euclid(TAU);
            out.uv = [phi / TAU, (z / h).clamp(0.0, 1.0)];
            let (c, sn) = if rho > 0.0 {
                (x / rho, y / rho)
            } else {
                (1.0, 0.0)
            };
            let dpdu = (fv * x - fu * y) * TAU;
            // At the apex dpdu vanishes: use the direction of increasing phi.
            let dpdu = if dpdu.length_squared() > 0.0 {
                dpdu
            } else {
                fv * c - fu * sn
            };
            out.dpdu = dpdu.into();
            out.dpdv = (((fu * c + fv * sn) * k + fw) * h).into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

/// A sphere around the cone, and slabs cutting its box with the sphere's
/// tangent planes.
impl BoundingVolumes for ConeObject {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.sphere)
    }
    fn slabs(&self, _t0: f32, _t1: f32) -> Option<SlabBounds> {
        Some(SlabBounds::from_box(&self.bounds).intersect(&SlabBounds::around_sphere(&self.sphere)))
    }
}

rtk_kernel::export_object!(
    ConeObject,
    class = "cone",
    doc = include_str!("../README.md"),
    capabilities = [BoundingVolumes]
);
