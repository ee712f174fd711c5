#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod shape;
use rtk_kernel::geom::vec;

use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use shape::Torus;
use std::f32::consts::TAU;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    center: [f64; 3],
    #[serde(default = "up")]
    axis: [f32; 3],
    #[serde(default = "one")]
    major_radius: f32,
    #[serde(default = "quarter")]
    minor_radius: f32,
}

fn one() -> f32 {
    1.0
}

fn quarter() -> f32 {
    0.25
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

struct TorusObject {
    /// Bounding sphere (`inq_bounds`).
    sphere: BoundSphere,
    torus: Torus<f32>,
    bounds: Bounds3,
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

impl Plugin for TorusObject {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let c = env.position("center", p.center)?;
        params::direction("axis", p.axis)?;
        let big = length("major_radius", p.major_radius)?;
        let small = length("minor_radius", p.minor_radius)?;
        if small >= big {
            return Err(PluginError::key(
                "minor_radius",
                format!(
                    "must be less than major_radius ({big}) for a ring torus, got {small} \
                     (horn and spindle tori are not supported)"
                ),
            ));
        }
        let c64 = c.to_array().map(f64::from);
        let axis = p.axis.map(f64::from);
        let w = vec::frame64(axis)[2];
        let e = vec::circle_extent(w, big as f64).map(|x| x + small as f64);
        let (lo, hi) = vec::f32_box(
            std::array::from_fn(|i| c64[i] - e[i]),
            std::array::from_fn(|i| c64[i] + e[i]),
        );
        let sphere = BoundSphere::from_f64(c64, (big + small) as f64, 1e-6 * (big + small) as f64);
        Ok(TorusObject {
            sphere,
            torus: Torus::new(c64, axis, big as f64, small as f64),
            bounds: Bounds3::new(Vec3::from(lo), Vec3::from(hi)),
        })
    }
}

impl AnalyticShape for TorusObject {
    /// Inside the tube: (ρ − R)² + z² < r² in the torus's frame, in f64.
    fn in_interior(&self, p: Vec3, _time: f32) -> Interior {
        Interior::from_bool(self.torus.contains(p.to_array()))
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn nearest_root(&self, ray: &Ray) -> Option<Root> {
        self.torus
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
            .torus
            .surface(ray.origin.to_array(), ray.dir.to_array(), root.t);
        let n = Vec3::from(s.n).normalize_or(Vec3::from(self.torus.frame[0]));
        out.p = Vec3::from(s.p).into();
        out.p_err = Vec3::from(s.p_err).into();
        out.ng = n.into();
        out.ns = n.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            // u = phi / 2pi around the axis, v = theta / 2pi around the tube
            // (theta = 0 on the outer equator, increasing towards +axis).
            let [x, y, z] = s.local;
            let [fu, fv, fw] = self.torus.frame.map(Vec3::from);
            let (big, small) = (self.torus.big, self.torus.small);
            let rho = (x * x + y * y).sqrt();
            let phi = y.atan2(x).rem_euclid(TAU);
            let theta = z.atan2(rho - big).rem_euclid(TAU);
            out.uv = [phi / TAU, theta / TAU];
            let (cp, sp) = (phi.cos(), phi.sin());
            let (ct, st) = (theta.cos(), theta.sin());
            out.dpdu = ((fv * cp - fu * sp) * (TAU * rho)).into();
            out.dpdv = ((-(fu * cp + fv * sp) * st + fw * ct) * (TAU * small)).into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

/// A sphere around the shape, and slabs cutting its box with the sphere's
/// tangent planes.
impl BoundingVolumes for TorusObject {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.sphere)
    }
    fn slabs(&self, _t0: f32, _t1: f32) -> Option<SlabBounds> {
        Some(SlabBounds::from_box(&self.bounds).intersect(&SlabBounds::around_sphere(&self.sphere)))
    }
}

rtk_kernel::export_object!(
    TorusObject,
    class = "torus",
    doc = include_str!("../README.md"),
    capabilities = [BoundingVolumes]
);
