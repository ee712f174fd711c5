#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::{abs_mat3, gamma, placed_point_error};
use rtk_kernel::glam::{DQuat, DVec3, Mat3, Quat, Vec3};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::xform::{AxisAngle, Scale};
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    keyframes: Vec<Key>,
}

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Key {
    time: f64,
    #[serde(default)]
    translate: [f64; 3],
    rotate: Option<AxisAngle>,
    scale: Option<Scale>,
}

/// One pose, in f32 once placed (the translation absorbed the renderer's
/// origin in f64).
#[derive(Clone, Copy)]
struct Pose {
    time: f32,
    t: Vec3,
    r: Quat,
    s: Vec3,
}

/// The transform at one time: object to parent, and back.
struct At {
    m: Mat3,
    t: Vec3,
    inv: Mat3,
    inv_t: Vec3,
}

struct Motion {
    keys: Vec<Pose>,
    child: Option<Child>,
    child_bounds: Bounds3,
}

/// Largest scale ratio accepted between axes or keyframes, as the transform
/// steps' condition limit (docs/numerics.md X2).
const MAX_CONDITION: f64 = 1e7;

impl Plugin for Motion {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        if p.keyframes.is_empty() {
            return Err(PluginError::key("keyframes", "give at least one keyframe"));
        }
        let origin = DVec3::from(env.origin);
        let mut keys = Vec::with_capacity(p.keyframes.len());
        let mut last = f64::NEG_INFINITY;
        for (i, k) in p.keyframes.iter().enumerate() {
            let key = |name: &str| format!("keyframes[{i}].{name}");
            if !(0.0..=1.0).contains(&k.time) || k.time <= last {
                return Err(PluginError::key(
                    key("time"),
                    format!("must lie in [0, 1] and increase, got {}", k.time),
                ));
            }
            last = k.time;
            params::finite(&key("translate"), &k.translate.map(|x| x as f32))?;
            if k.translate.iter().any(|x| x.abs() > 1e12) {
                return Err(PluginError::key(key("translate"), "beyond ±1e12"));
            }
            let s = match k.scale {
                None => DVec3::ONE,
                Some(Scale::Uniform(s)) => DVec3::splat(s),
                Some(Scale::Axes(a)) => DVec3::from(a),
            };
            if !(s.min_element() > 0.0 && s.is_finite())
                || s.max_element() / s.min_element() > MAX_CONDITION
            {
                return Err(PluginError::key(
                    key("scale"),
                    "must be positive and finite, within a ratio of 1e7 between axes",
                ));
            }
            // As an instance's transform (docs/scene-format.md, Numbers): a
            // child scaled beyond this overflows f32 or vanishes.
            if s.max_element() > 1e12 || s.min_element() < 1e-12 {
                return Err(PluginError::key(
                    key("scale"),
                    format!(
                        "scales by {:.1e}, outside the 1e-12 to 1e12 rtk handles (docs/numerics.md rule 1)",
                        if s.max_element() > 1e12 { s.max_element() } else { s.min_element() }
                    ),
                ));
            }
            let r = match &k.rotate {
                None => DQuat::IDENTITY,
                Some(a) => {
                    let axis = DVec3::from(a.axis);
                    if !(axis.length() > 0.0 && axis.is_finite() && a.angle.is_finite()) {
                        return Err(PluginError::key(
                            key("rotate"),
                            "needs a non-zero finite axis and a finite angle",
                        ));
                    }
                    DQuat::from_axis_angle(axis.normalize(), a.angle.to_radians())
                }
            };
            keys.push(Pose {
                time: k.time as f32,
                t: (DVec3::from(k.translate) - origin).as_vec3(),
                r: r.as_quat(),
                s: s.as_vec3(),
            });
        }
        Ok(Motion {
            keys,
            child: None,
            child_bounds: Bounds3::EMPTY,
        })
    }
}

impl Motion {
    /// The pose at `time`: the keyframes around it, interpolated.
    fn pose(&self, time: f32) -> Pose {
        let k = &self.keys;
        let i = k.partition_point(|p| p.time <= time);
        if i == 0 {
            return k[0];
        }
        if i == k.len() {
            return k[k.len() - 1];
        }
        let (a, b) = (k[i - 1], k[i]);
        let f = ((time - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
        Pose {
            time,
            t: a.t.lerp(b.t, f),
            r: a.r.slerp(b.r, f),
            s: a.s.lerp(b.s, f),
        }
    }

    #[inline]
    fn at(&self, time: f32) -> At {
        let p = self.pose(time);
        let rot = Mat3::from_quat(p.r);
        let m = rot * Mat3::from_diagonal(p.s);
        let inv = Mat3::from_diagonal(p.s.recip()) * rot.transpose();
        At {
            m,
            t: p.t,
            inv,
            inv_t: -(inv * p.t),
        }
    }

    #[inline]
    fn to_object(a: &At, ray: &Ray) -> Ray {
        Ray {
            origin: (a.inv * ray.origin.v() + a.inv_t).into(),
            dir: (a.inv * ray.dir.v()).into(),
            ..*ray
        }
    }

    /// The child's box corners placed at `time`.
    fn placed(&self, time: f32) -> Bounds3 {
        let a = self.at(time);
        self.child_bounds
            .corners()
            .into_iter()
            .fold(Bounds3::EMPTY, |b, p| b.include(a.m * p + a.t))
    }
}

impl Object for Motion {
    /// The child's answer at the point taken into its space at `time`.
    fn in_interior(&self, ctx: &mut TraceCtx, p: Vec3, time: f32) -> Interior {
        let Some(c) = &self.child else {
            return Interior::NONE;
        };
        let a = self.at(time);
        c.in_interior(ctx, a.inv * p + a.inv_t, time)
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        if self.child.is_some() {
            return Err(PluginError::key(
                "children",
                "a motion takes exactly one child",
            ));
        }
        self.child = Some(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        let Some(c) = &self.child else {
            return Err(PluginError::key("children", "a motion needs one child"));
        };
        self.child_bounds = c.bounds(0.0, 1.0)?;
        Ok(())
    }

    /// The union of the placed box at 64 steps per keyframe segment within
    /// [t0, t1], each widened by half the farthest any corner can travel in
    /// a step (a point on a path of length L is within L/2 of one of its
    /// ends), so the swept volume is covered however the pose turns.
    fn bounds(&self, t0: f32, t1: f32) -> Bounds3 {
        let b = self.child_bounds;
        if b.is_empty() {
            return b;
        }
        let (t0, t1) = (t0.min(t1), t0.max(t1));
        let mut times = vec![t0, t1];
        times.extend(
            self.keys
                .iter()
                .map(|k| k.time)
                .filter(|&t| t > t0 && t < t1),
        );
        times.sort_by(f32::total_cmp);
        let extent = b.min.v().abs().max(b.max.v().abs()).length();
        let mut out = Bounds3::EMPTY;
        for w in times.windows(2) {
            const STEPS: usize = 64;
            let mut prev: Option<(f32, Pose)> = None;
            for k in 0..=STEPS {
                let t = w[0] + (w[1] - w[0]) * k as f32 / STEPS as f32;
                let p = self.pose(t);
                let placed = self.placed(t);
                let pad = match prev {
                    None => 0.0,
                    Some((_, q)) => {
                        let turn = p.r.angle_between(q.r);
                        let s = p.s.max(q.s).max_element();
                        0.5 * ((p.t - q.t).length()
                            + turn * s * extent
                            + (p.s - q.s).abs().max_element() * extent)
                    }
                };
                let lo = placed.min.v() - Vec3::splat(pad);
                let hi = placed.max.v() + Vec3::splat(pad);
                out = out.union(Bounds3::new(lo, hi));
                prev = Some((t, p));
            }
        }
        // The rounding of the corner transforms, as `transform` widens.
        let g = gamma::<f32>(3);
        let pad = (out.min.v().abs().max(out.max.v().abs())) * g;
        Bounds3::new(out.min.v() - pad, out.max.v() + pad)
    }

    #[inline]
    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some(c) = &self.child else { return false };
        let r = Self::to_object(&self.at(ray.time), ray);
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
        c.occluded(ctx, &Self::to_object(&self.at(ray.time), ray), level + 1)
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
        let a = self.at(ray.time);
        c.local_geom(ctx, &Self::to_object(&a, ray), hit, level + 1, mask, out);
        if out.filled & geom_mask::POSITION != 0 {
            // Rule 8's bound, at this time's matrix.
            let p = out.p.v();
            let q = a.m * p + a.t;
            let e = placed_point_error(
                p,
                out.p_err.v(),
                q,
                a.t,
                abs_mat3(a.m),
                abs_mat3(a.inv),
                a.inv_t.abs(),
            );
            out.p = q.into();
            out.p_err = e.into();
        }
        let normal = a.inv.transpose();
        if out.filled & geom_mask::GEOMETRIC_NORMAL != 0 {
            out.ng = (normal * out.ng.v()).normalize_or(Vec3::Z).into();
        }
        if out.filled & geom_mask::SHADING_NORMAL != 0 {
            out.ns = (normal * out.ns.v()).normalize_or(Vec3::Z).into();
        }
        if out.filled & geom_mask::TANGENTS != 0 {
            out.dpdu = (a.m * out.dpdu.v()).into();
            out.dpdv = (a.m * out.dpdv.v()).into();
        }
    }
}

rtk_kernel::export_object!(Motion, class = "motion", doc = include_str!("../README.md"));
