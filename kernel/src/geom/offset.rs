//! Spawning rays from surfaces: offset past the error bound along the
//! geometric normal (pbrt-v4 `OffsetRayOrigin`), never a scene epsilon.

use crate::abi::{LocalGeom, Ray};
use glam::Vec3;

/// Move `p` past its error box `p_err` along the geometric normal `n`, to the
/// side `w` points to, then round each component away from `p`.
#[inline]
pub fn offset_ray_origin(p: Vec3, p_err: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_err);
    let mut offset = n * d;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = po[i].next_up();
        } else if offset[i] < 0.0 {
            po[i] = po[i].next_down();
        }
    }
    po
}

/// A ray leaving the surface at `g` in direction `dir`, one generation deeper.
#[inline]
pub fn spawn_ray(g: &LocalGeom, dir: Vec3, parent: &Ray) -> Ray {
    let o = offset_ray_origin(g.p.v(), g.p_err.v(), g.ng.v(), dir);
    Ray {
        origin: o.into(),
        dir: dir.into(),
        t_min: 0.0,
        t_max: f32::INFINITY,
        time: parent.time,
        generation: parent.generation + 1,
    }
}

/// Fraction of the segment a point-to-point shadow ray stops short of its end
/// (pbrt's ShadowEpsilon), so that the target surface is not reported.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// A shadow ray from the surface at `g` towards the point `to` (unnormalised
/// direction, `t_max = 1 - SHADOW_EPSILON`).
#[inline]
pub fn spawn_ray_to(g: &LocalGeom, to: Vec3, parent: &Ray) -> Ray {
    let o = offset_ray_origin(g.p.v(), g.p_err.v(), g.ng.v(), to - g.p.v());
    Ray {
        origin: o.into(),
        dir: (to - o).into(),
        t_min: 0.0,
        t_max: 1.0 - SHADOW_EPSILON,
        time: parent.time,
        generation: parent.generation + 1,
    }
}
