//! The conservative, NaN-ordered ray/box slab test (numerics.md A1, A2).

use crate::abi::{Bounds3, Ray};
use crate::geom::gamma;

/// Per-ray data for box tests, computed once per ray and reused for every node.
#[derive(Clone, Copy, Debug)]
pub struct RayBoxPrecomp {
    origin: [f32; 3],
    inv_dir: [f32; 3],
}

/// The parametric interval where a ray overlaps a box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlabHit {
    /// Entry.
    pub t0: f32,
    /// Exit.
    pub t1: f32,
}

impl RayBoxPrecomp {
    /// Precompute for a ray. A zero direction component gives an infinite
    /// reciprocal; the test below keeps the old bound whenever `0 * inf`
    /// produces NaN, so an origin lying in a slab plane counts as inside.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        Self {
            origin: ray.origin.to_array(),
            inv_dir: [1.0 / ray.dir.x, 1.0 / ray.dir.y, 1.0 / ray.dir.z],
        }
    }

    /// Overlap of `(t_min, t_max)` with the box, or `None`. Conservative:
    /// the far distance is widened by `1 + 2γ₃` (Ize 2013, pbrt-v4), and the
    /// comparisons are written so a NaN keeps the previous bound.
    #[inline]
    pub fn intersect(&self, b: &Bounds3, t_min: f32, t_max: f32) -> Option<SlabHit> {
        let lo = b.min.to_array();
        let hi = b.max.to_array();
        let mut t0 = t_min;
        let mut t1 = t_max;
        let widen = 1.0 + 2.0 * gamma::<f32>(3);
        for a in 0..3 {
            let mut tn = (lo[a] - self.origin[a]) * self.inv_dir[a];
            let mut tf = (hi[a] - self.origin[a]) * self.inv_dir[a];
            // Order by the sign of the reciprocal, not by comparing: with an
            // origin in the slab plane one of the two is NaN (0 * inf).
            if self.inv_dir[a].is_sign_negative() {
                std::mem::swap(&mut tn, &mut tf);
            }
            tf *= widen;
            // NaN-ordered: a NaN compares false and leaves the bound alone.
            if tn > t0 {
                t0 = tn;
            }
            if tf < t1 {
                t1 = tf;
            }
            if t0 > t1 {
                return None;
            }
        }
        Some(SlabHit { t0, t1 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn unit() -> Bounds3 {
        Bounds3::new(Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn origin_on_face_parallel_ray_hits() {
        // numerics.md A1: d = (0,0,1) from the x = 0 face, the x = 1 face and the x = y = 1 edge.
        for o in [
            Vec3::new(0.0, 0.5, -1.0),
            Vec3::new(1.0, 0.5, -1.0),
            Vec3::new(1.0, 1.0, -1.0),
        ] {
            let r = Ray::new(o, Vec3::Z);
            assert!(
                RayBoxPrecomp::new(&r)
                    .intersect(&unit(), 0.0, f32::INFINITY)
                    .is_some(),
                "{o}"
            );
            let r = Ray::new(o, Vec3::new(-0.0, 0.0, 1.0));
            assert!(RayBoxPrecomp::new(&r)
                .intersect(&unit(), 0.0, f32::INFINITY)
                .is_some());
        }
    }

    #[test]
    fn misses_and_interval() {
        let r = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let h = RayBoxPrecomp::new(&r)
            .intersect(&unit(), 0.0, f32::INFINITY)
            .unwrap();
        assert!((h.t0 - 1.0).abs() < 1e-6 && (h.t1 - 2.0).abs() < 1e-5);
        assert!(RayBoxPrecomp::new(&r)
            .intersect(&unit(), 0.0, 0.5)
            .is_none());
        let r = Ray::new(Vec3::new(-1.0, 2.0, 0.5), Vec3::X);
        assert!(RayBoxPrecomp::new(&r)
            .intersect(&unit(), 0.0, f32::INFINITY)
            .is_none());
    }

    #[test]
    fn flat_box_far_from_origin_is_not_culled() {
        // numerics.md A2: a flat box at |c| = 1e5 hit by rays aimed at it.
        let c = 1e5f32;
        let b = Bounds3::new(Vec3::new(c, c, c), Vec3::new(c + 1.0, c + 1.0, c));
        let mut misses = 0;
        for i in 0..1000 {
            let u = i as f32 / 1000.0;
            let target = Vec3::new(c + u, c + 0.37, c);
            let o = target + Vec3::new(3.0, -2.0, 5.0);
            let r = Ray::new(o, (target - o).normalize());
            if RayBoxPrecomp::new(&r)
                .intersect(&b, 0.0, f32::INFINITY)
                .is_none()
            {
                misses += 1;
            }
        }
        assert_eq!(misses, 0);
    }
}
