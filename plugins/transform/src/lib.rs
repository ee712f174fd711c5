#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::{abs_mat3, gamma, placed_point_error};
use rtk_kernel::glam::{Affine3A, DAffine3, DVec3, Mat3, Vec3};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::xform::{self, Step};
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    matrix: Option<Vec<f64>>,
    steps: Option<Vec<Step>>,
}

struct Transform {
    /// Object to parent.
    m: Affine3A,
    /// Parent to object.
    inv: Affine3A,
    /// Normals: (M⁻¹)ᵀ.
    normal: Mat3,
    /// |M| for error propagation.
    abs_m: Mat3,
    /// |M⁻¹| and |M⁻¹'s translation|: the error of taking a spawned ray's
    /// origin back into the child's space.
    abs_inv: Mat3,
    abs_inv_t: Vec3,
    flips: bool,
    child: Option<Child>,
    /// The child's box over the shutter interval, in its own space.
    child_bounds: Bounds3,
    /// The placed child's sphere and slabs (`inq_bounds`), from its hull
    /// points mapped in f64.
    sphere: BoundSphere,
    slabs: SlabBounds,
}

fn to_f32(m: &DAffine3) -> Affine3A {
    Affine3A::from_mat3_translation(m.matrix3.as_mat3(), m.translation.as_vec3())
}

impl Plugin for Transform {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let key = if p.matrix.is_some() {
            "matrix"
        } else {
            "steps"
        };
        let m = match (p.matrix, p.steps) {
            (Some(m), None) => {
                let a = xform::matrix_from_rows("matrix", &m)?;
                xform::check("matrix", &a)?;
                a
            }
            (None, Some(s)) => xform::compose("steps", &s)?,
            _ => return Err(PluginError::msg("give exactly one of `matrix` and `steps`")),
        };
        // Rule 1's coordinate limit, as instance transforms have it.
        if m.translation.abs().max_element() > 1e12 {
            return Err(PluginError::key(
                key,
                format!(
                    "moves the child by {:e}, beyond the ±1e12 rtk handles (docs/numerics.md rule 1)",
                    m.translation.abs().max_element()
                ),
            ));
        }
        // Placed in the renderer's space (docs/numerics.md X3): the shell
        // creates this object's child unshifted, so the matrix absorbs the
        // world origin, in f64.
        let origin = DVec3::from(env.origin);
        Self::from_transform(DAffine3::from_translation(-origin) * m, env)
    }
}

impl FromTransform for Transform {
    /// The shell's instance transforms: composed and checked already.
    fn from_transform(m: DAffine3, _env: &Env) -> Result<Self, PluginError> {
        let inv = m.inverse();
        let normal = inv.matrix3.transpose();
        let abs = m.matrix3.as_mat3();
        let abs_inv = inv.matrix3.as_mat3();
        Ok(Transform {
            m: to_f32(&m),
            inv: to_f32(&inv),
            normal: normal.as_mat3(),
            abs_m: abs_mat3(abs),
            abs_inv: abs_mat3(abs_inv),
            abs_inv_t: inv.translation.as_vec3().abs(),
            flips: m.matrix3.determinant() < 0.0,
            child: None,
            child_bounds: Bounds3::EMPTY,
            sphere: BoundSphere::EMPTY,
            slabs: SlabBounds::EMPTY,
        })
    }
}

impl Object for Transform {
    /// The child's answer at the point taken into its space (with the f32
    /// matrix rays are mapped with, so the answer agrees with `intersect`).
    fn in_interior(&self, ctx: &mut TraceCtx, p: Vec3, time: f32) -> Interior {
        match &self.child {
            Some(c) => c.in_interior(ctx, self.inv.transform_point3(p), time),
            None => Interior::NONE,
        }
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        if self.child.is_some() {
            return Err(PluginError::key(
                "children",
                "a transform takes exactly one child",
            ));
        }
        self.child = Some(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        let Some(c) = &self.child else {
            return Err(PluginError::key("children", "a transform needs one child"));
        };
        self.child_bounds = c.bounds(0.0, 1.0)?;
        // The child's hull points (its box's corners if it offers none),
        // placed in f64; each is within γ₃ of its magnitude of where the f32
        // matrix the rays are mapped with puts it, as the box's corners are.
        let m = DAffine3::from_mat3_translation(
            Mat3::from(self.m.matrix3).as_dmat3(),
            Vec3::from(self.m.translation).as_dvec3(),
        );
        let placed: Vec<[f64; 3]> = c
            .hull_points(0.0, 1.0)?
            .iter()
            .map(|p| m.transform_point3(Vec3::from(*p).as_dvec3()).to_array())
            .collect();
        let reach = placed.iter().flatten().fold(0.0f64, |a, &x| a.max(x.abs()));
        let pad = reach * gamma::<f32>(3) as f64;
        self.sphere = BoundSphere::around_points_f64(&placed, pad);
        self.slabs = SlabBounds::from_points_f64(&placed, pad);
        // The child's own sphere, placed, when that is smaller (a rotated
        // torus or rod): radius times a bound on the matrix's largest
        // singular value, √λmax(LᵀL) ≤ √(Gershgorin row sum), exact for a
        // rotation with uniform scale.
        let cs = c.bound_sphere(0.0, 1.0)?;
        if !cs.is_empty() {
            let l = m.matrix3;
            let a = l.transpose() * l;
            let gersh = (0..3)
                .map(|i| a.row(i).abs().element_sum())
                .fold(0.0f64, f64::max);
            let center = m.transform_point3(Vec3::from(cs.center).as_dvec3());
            let pad = center.abs().max_element() * gamma::<f32>(3) as f64;
            let placed = BoundSphere::from_f64(
                center.to_array(),
                cs.radius as f64 * (gersh * (1.0 + 1e-12)).sqrt(),
                pad,
            );
            if placed.radius < self.sphere.radius {
                self.sphere = placed;
            }
        }
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        let b = self.child_bounds;
        if b.is_empty() {
            return b;
        }
        let mut out = Bounds3::EMPTY;
        for p in b.corners() {
            out = out.include(self.m.transform_point3(p));
        }
        // Widen by the rounding of the corner transforms.
        let g = gamma::<f32>(3);
        let pad = (out.min.v().abs().max(out.max.v().abs())) * g;
        Bounds3::new(out.min.v() - pad, out.max.v() + pad)
    }

    #[inline]
    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some(c) = &self.child else { return false };
        let r = self.to_object(ray);
        if c.intersect(ctx, &r, hit, level + 1) {
            hit.record_child(level, 0);
            true
        } else {
            false
        }
    }

    #[inline]
    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let Some(c) = &self.child else { return false };
        c.occluded(ctx, &self.to_object(ray), level + 1)
    }

    fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let Some(c) = &self.child else { return };
        c.local_geom(ctx, &self.to_object(ray), hit, level + 1, mask, out);
        if out.filled & geom_mask::POSITION != 0 {
            let p = out.p.v();
            let q = self.m.transform_point3(p);
            let t = Vec3::from(self.m.translation);
            let e = placed_point_error(
                p,
                out.p_err.v(),
                q,
                t,
                self.abs_m,
                self.abs_inv,
                self.abs_inv_t,
            );
            out.p = q.into();
            out.p_err = e.into();
        }
        if out.filled & geom_mask::GEOMETRIC_NORMAL != 0 {
            out.ng = (self.normal * out.ng.v()).normalize_or(Vec3::Z).into();
        }
        if out.filled & geom_mask::SHADING_NORMAL != 0 {
            out.ns = (self.normal * out.ns.v()).normalize_or(Vec3::Z).into();
        }
        if out.filled & geom_mask::TANGENTS != 0 {
            out.dpdu = self.m.transform_vector3(out.dpdu.v()).into();
            let v = self.m.transform_vector3(out.dpdv.v());
            out.dpdv = if self.flips { (-v).into() } else { v.into() };
        }
    }
}

impl Transform {
    #[inline]
    fn to_object(&self, ray: &Ray) -> Ray {
        Ray {
            origin: self.inv.transform_point3(ray.origin.v()).into(),
            dir: self.inv.transform_vector3(ray.dir.v()).into(),
            ..*ray
        }
    }
}

/// Volumes of the placed child: a rotated child keeps a tight sphere and
/// slabs where its box would be rotated and re-boxed.
impl BoundingVolumes for Transform {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.sphere)
    }
    fn slabs(&self, t0: f32, t1: f32) -> Option<SlabBounds> {
        Some(
            self.slabs
                .intersect(&SlabBounds::from_box(&self.bounds(t0, t1))),
        )
    }
}

rtk_kernel::export_object!(
    Transform,
    class = "transform",
    doc = include_str!("../README.md"),
    capabilities = [FromTransform, BoundingVolumes]
);
