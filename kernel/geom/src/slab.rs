//! The conservative, NaN-ordered ray/box slab test (docs/numerics.md A1, A2).

use crate::{gamma, Real};
use rtk_abi::{Bounds3, Ray};

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

    /// Overlap of `(t_min, t_max)` with the box, or `None`; see [`slab`].
    #[inline]
    pub fn intersect(&self, b: &Bounds3, t_min: f32, t_max: f32) -> Option<SlabHit> {
        slab(
            self.origin,
            self.inv_dir,
            b.min.to_array(),
            b.max.to_array(),
            t_min,
            t_max,
        )
        .map(|(t0, t1)| SlabHit { t0, t1 })
    }
}

/// The slab test in any precision: the overlap of `(t_min, t_max)` with the
/// box `[lo, hi]` for the ray `origin + t d`, given `inv_dir = 1/d`.
/// Conservative: the far distance is widened by `1 + 2γ₄` — Ize 2013
/// (and pbrt-v4) give `1 + 2γ₃` for the three roundings of each distance,
/// but the widening product rounds too: the far side then carries four
/// roundings against the near side's three, and `(1 + γ₃)/(1 − γ₄)`
/// exceeds `1 + 2γ₃` by about an ulp, while `1 + 2γ₄` covers it. Slabs are ordered by the sign of the reciprocal (comparing the
/// two distances fails when one is `0·∞ = NaN`, an origin in the slab's
/// plane), and the comparisons are written so a NaN keeps the previous bound.
#[inline]
pub fn slab<R: Real>(
    origin: [R; 3],
    inv_dir: [R; 3],
    lo: [R; 3],
    hi: [R; 3],
    t_min: R,
    t_max: R,
) -> Option<(R, R)> {
    let mut t0 = t_min;
    let mut t1 = t_max;
    let widen = R::ONE + (R::ONE + R::ONE) * gamma::<R>(4);
    for a in 0..3 {
        let mut tn = (lo[a] - origin[a]) * inv_dir[a];
        let mut tf = (hi[a] - origin[a]) * inv_dir[a];
        if inv_dir[a] < R::ZERO {
            std::mem::swap(&mut tn, &mut tf);
        }
        tf = tf * widen;
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
    Some((t0, t1))
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
        // docs/numerics.md A1: d = (0,0,1) from the x = 0 face, the x = 1 face and the x = y = 1 edge.
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
    fn f32_and_f64_agree_on_random_rays() {
        let mut s = rtk_abi::RngState::seeded(9);
        let mut u = || s.next_f64();
        let (mut n, mut hits) = (0, 0);
        for _ in 0..20_000 {
            let o: [f32; 3] = std::array::from_fn(|_| (u() * 6.0 - 3.0) as f32);
            let d: [f32; 3] = std::array::from_fn(|_| (u() * 2.0 - 1.0) as f32);
            let inv = d.map(|x| 1.0 / x);
            let a = slab(o, inv, [0.0; 3], [1.0; 3], 0.0, f32::INFINITY).is_some();
            let b = slab(
                o.map(f64::from),
                d.map(|x| 1.0 / x as f64),
                [0.0; 3],
                [1.0; 3],
                0.0,
                f64::INFINITY,
            )
            .is_some();
            // f32 may only err on the side of a hit (conservative).
            assert!(a || !b, "f32 missed a box f64 hits: o {o:?} d {d:?}");
            n += (a != b) as u32;
            hits += b as u32;
        }
        assert!(hits > 300 && n < 10, "{hits} {n}");
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
        // docs/numerics.md A2: a flat box at |c| = 1e5 hit by rays aimed at it.
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
