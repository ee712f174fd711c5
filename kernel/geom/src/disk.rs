//! A disk or an annulus in a plane, generic over [`Real`]: the `disk`
//! plugin and the caps of closed cylinders and cones run it in f32, the
//! tests run the same code in f64 as the reference.

use crate::vec::*;
use crate::{gamma, Real};

/// A disk (or an annulus) of centre `c` in the plane through `c` normal to `n`.
#[derive(Clone, Copy, Debug)]
pub struct Disk<R> {
    /// Centre.
    pub c: V<R>,
    /// Frame: u, v span the plane, w = the unit normal.
    pub frame: [V<R>; 3],
    /// Outer radius.
    pub r: R,
    /// Inner radius (0 for a full disk).
    pub ri: R,
}

/// A hit point on the surface and what `local_geom` needs of it.
#[derive(Clone, Copy, Debug)]
pub struct DiskSurface<R> {
    /// The point, reprojected onto the plane.
    pub p: V<R>,
    /// Per-component bound on its distance from the exact plane.
    pub p_err: V<R>,
    /// In-plane coordinates (x, y) of the point relative to the centre.
    pub xy: [R; 2],
}

impl<R: Real> Disk<R> {
    /// From parameters in f64 (the frame is computed in f64 and rounded once).
    pub fn new(c: [f64; 3], normal: [f64; 3], r: f64, ri: f64) -> Self {
        let f = frame64(normal);
        Disk {
            c: cvt(c),
            frame: [cvt(f[0]), cvt(f[1]), cvt(f[2])],
            r: R::from_f64(r),
            ri: R::from_f64(ri),
        }
    }

    /// The unit normal.
    #[inline]
    pub fn n(&self) -> V<R> {
        self.frame[2]
    }

    /// Nearest hit of `o + t d` in `(t_min, t_max)`, if any.
    ///
    /// `t = n·(c − o) / n·d`. The numerator is the signed distance of the
    /// origin from the plane (|n| = 1); when its magnitude is within
    /// its origin band (`origin_band`), the origin lies on the plane as far as f32 can
    /// tell, and the hit is refused (no self-hit). The
    /// radial test uses `q = t d − (c − o)` projected into the plane, and is
    /// closed at both radii: a disk of radius r and an annulus of inner
    /// radius r sharing its centre and normal compute the same ρ², so a ray
    /// between them hits one or both, never neither.
    #[inline]
    pub fn intersect(&self, o: V<R>, d: V<R>, t_min: R, t_max: R) -> Option<R> {
        let n = self.n();
        let w = sub(self.c, o);
        let num = dot(n, w);
        let den = dot(n, d);
        let t = num / den;
        if !(t > t_min && t < t_max && t.is_finite()) {
            return None;
        }
        if !(num.abs() > self.origin_band(o, w)) {
            return None;
        }
        let q = sub(scale(d, t), w);
        let qn = dot(q, n);
        let qp = sub(q, scale(n, qn));
        let rho2 = dot(qp, qp);
        if rho2 <= self.r * self.r && rho2 >= self.ri * self.ri {
            Some(t)
        } else {
            None
        }
    }

    /// How close to the plane an origin must be to count as lying on it:
    /// the rounding bound of `n·(c − o)`, γ₅Σ|nᵢwᵢ| (w = c − o), plus the
    /// error bound a hit point of this disk would have at `o`
    /// (Σ|nᵢ|(γ₈|w| + γ₂|oᵢ|), see [`Disk::surface`], with |w|₁ ≥ |w|).
    /// So a ray leaving a hit point, offset or not, never re-hits the disk.
    #[inline]
    fn origin_band(&self, o: V<R>, w: V<R>) -> R {
        let n = self.n();
        let wl = w[0].abs() + w[1].abs() + w[2].abs();
        let g8w = gamma::<R>(8) * wl;
        let g2 = gamma::<R>(2);
        gamma::<R>(5) * abs_dot(n, w)
            + n[0].abs() * (g8w + g2 * o[0].abs())
            + n[1].abs() * (g8w + g2 * o[1].abs())
            + n[2].abs() * (g8w + g2 * o[2].abs())
    }

    /// The hit point at `t`, reprojected onto the plane, and its error bound:
    /// γ₈|q| for the projection (q = p − c) plus γ₂|pᵢ| for adding the centre.
    #[inline]
    pub fn surface(&self, o: V<R>, d: V<R>, t: R) -> DiskSurface<R> {
        let n = self.n();
        let w = sub(self.c, o);
        let q = sub(scale(d, t), w);
        let qn = dot(q, n);
        let qp = sub(q, scale(n, qn));
        let p = add(self.c, qp);
        let ql = dot(qp, qp).sqrt();
        let g8 = gamma::<R>(8);
        let g2 = gamma::<R>(2);
        let p_err = std::array::from_fn(|i| g8 * ql + g2 * p[i].abs());
        DiskSurface {
            p,
            p_err,
            xy: [dot(qp, self.frame[0]), dot(qp, self.frame[1])],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::offset_ray_origin;
    use glam::Vec3;
    use rtk_abi::RngState;

    fn pair(c: [f32; 3], n: [f32; 3], r: f32, ri: f32) -> (Disk<f32>, Disk<f64>) {
        let c = c.map(f64::from);
        let n = n.map(f64::from);
        (
            Disk::new(c, n, r as f64, ri as f64),
            Disk::new(c, n, r as f64, ri as f64),
        )
    }

    fn unit(v: [f32; 3]) -> [f32; 3] {
        Vec3::from(v).normalize().to_array()
    }

    /// A random unit direction.
    fn sphere_dir(rng: &mut RngState) -> [f32; 3] {
        loop {
            let v = [
                rng.range_f32(-1.0, 1.0),
                rng.range_f32(-1.0, 1.0),
                rng.range_f32(-1.0, 1.0),
            ];
            let l = Vec3::from(v).length();
            if l > 0.1 && l <= 1.0 {
                return unit(v);
            }
        }
    }

    fn f64v(a: [f32; 3]) -> [f64; 3] {
        a.map(f64::from)
    }

    /// Distance of the f64 point `p` from the f64 disk's plane, in f64.
    fn plane_dist(d: &Disk<f64>, p: [f64; 3]) -> f64 {
        dot(d.n(), sub(p, d.c)).abs()
    }

    #[test]
    fn head_on_and_annulus() {
        let (f, _) = pair([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0, 0.5);
        let t = f.intersect([0.75, 0.0, 5.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY);
        assert_eq!(t, Some(5.0));
        // Through the hole, outside the rim.
        assert!(f
            .intersect([0.25, 0.0, 5.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY)
            .is_none());
        assert!(f
            .intersect([1.25, 0.0, 5.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY)
            .is_none());
        // Hit exactly at t_max or t_min is refused (open interval).
        assert!(f
            .intersect([0.75, 0.0, 5.0], [0.0, 0.0, -1.0], 0.0, 5.0)
            .is_none());
        assert!(f
            .intersect([0.75, 0.0, 5.0], [0.0, 0.0, -1.0], 5.0, 9.0)
            .is_none());
        // Parallel ray: never a hit, never a NaN accepted.
        assert!(f
            .intersect([0.75, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, f32::INFINITY)
            .is_none());
    }

    /// Random rays from a sphere around a tilted disk far from the origin:
    /// f32 against the f64 instance. Mismatches must lie within a thin band
    /// around the rims (relative 1e-5 of the radius); t agrees to 1e-5 for
    /// well-conditioned rays (condition number of num/den below 4), and within 8ε times the condition number of
    /// num/den for every ray (grazing rays included).
    #[test]
    fn f32_matches_f64_on_random_rays() {
        let mut rng = RngState::seeded(11);
        for &(c, r) in &[([0.0f32, 0.0, 0.0], 1.0f32), ([1e3, -2e3, 5e2], 3.0)] {
            let n = unit([0.3, 0.8, -0.5]);
            let (f, g) = pair(c, n, r, 0.4 * r);
            let (mut hits, mut band, mut worst_t, mut worst_plain) = (0, 0, 0.0f64, 0.0f64);
            let total = 50_000;
            for _ in 0..total {
                let o = std::array::from_fn(|i| c[i] + 4.0 * r * rng.range_f32(-1.0, 1.0));
                let target: [f32; 3] =
                    std::array::from_fn(|i| c[i] + 1.2 * r * rng.range_f32(-1.0, 1.0));
                let d = sub(target, o);
                let hf = f.intersect(o, d, 0.0, f32::INFINITY);
                let hg = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY);
                match (hf, hg) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        // Relative error over the condition number of
                        // t = num / den: Σ|nᵢwᵢ|/|num| + Σ|nᵢdᵢ|/|den|.
                        let (n, w) = (g.n(), sub(g.c, f64v(o)));
                        let cond = abs_dot(n, w) / dot(n, w).abs()
                            + abs_dot(n, f64v(d)) / dot(n, f64v(d)).abs();
                        let rel = (a as f64 - b).abs() / b;
                        worst_t = worst_t.max(rel / cond);
                        if cond < 4.0 {
                            worst_plain = worst_plain.max(rel);
                        }
                    }
                    (None, None) => {}
                    (a, b) => {
                        // Must be a rim graze: the hit point lies within
                        // 1e-5 r of one of the radii.
                        let tt = b.unwrap_or_else(|| a.map_or(0.0, f64::from));
                        let s = g.surface(f64v(o), f64v(d), tt);
                        let rho = (s.xy[0] * s.xy[0] + s.xy[1] * s.xy[1]).sqrt();
                        let near = (rho - r as f64).abs().min((rho - 0.4 * r as f64).abs());
                        assert!(
                            near < 1e-5 * r as f64,
                            "mismatch off the rims: rho {rho}, f32 {a:?}, f64 {b:?}"
                        );
                        band += 1;
                    }
                }
            }
            println!(
                "disk at {c:?}: {hits} hits of {total}, {band} rim mismatches, \
                 max rel t err {worst_plain:e} (condition < 4), max rel t err / condition {worst_t:e}"
            );
            assert!(hits > total / 10);
            assert!(band * 1000 < total, "{band}");
            assert!(worst_plain < 1e-5, "{worst_plain}");
            assert!(worst_t < 8.0 * f32::EPSILON as f64, "{worst_t}");
        }
    }

    /// Reprojected hit points lie within their bound of the exact plane; and
    /// rays spawned off them (outwards and through) never re-hit the disk.
    #[test]
    fn points_within_bound_and_no_self_hits() {
        let mut rng = RngState::seeded(5);
        for &(c, r) in &[
            ([0.0f32, 0.0, 0.0], 1.0f32),
            ([1e3, -2e3, 5e2], 3.0),
            ([1e5, 0.0, 0.0], 1e3),
            ([0.0, 0.0, 0.0], 1e-3),
        ] {
            let n = unit([0.3, 0.8, -0.5]);
            let (f, g) = pair(c, n, r, 0.0);
            let (mut checked, mut rehits) = (0, 0);
            for _ in 0..20_000 {
                let o = std::array::from_fn(|i| c[i] + 4.0 * r * rng.range_f32(-1.0, 1.0));
                let target: [f32; 3] = std::array::from_fn(|i| c[i] + r * rng.range_f32(-0.7, 0.7));
                let d = sub(target, o);
                let Some(t) = f.intersect(o, d, 0.0, f32::INFINITY) else {
                    continue;
                };
                let s = f.surface(o, d, t);
                let dist = plane_dist(&g, f64v(s.p));
                let bound = abs_dot(f64v(f.n()), f64v(s.p_err));
                assert!(dist <= bound, "off plane by {dist:e} > {bound:e}");
                checked += 1;
                // Spawn: both sides, random directions, origin on the surface
                // offset as the renderer does, and also exactly the point.
                for _ in 0..4 {
                    let w = sphere_dir(&mut rng);
                    let po = offset_ray_origin(
                        Vec3::from(s.p),
                        Vec3::from(s.p_err),
                        Vec3::from(f.n()),
                        Vec3::from(w),
                    );
                    for origin in [po.to_array(), s.p] {
                        if f.intersect(origin, w, 0.0, f32::INFINITY).is_some() {
                            rehits += 1;
                        }
                    }
                }
            }
            println!("disk r {r} at {c:?}: {checked} points within bound, {rehits} self-hits");
            assert!(checked > 1000);
            assert_eq!(rehits, 0);
        }
    }

    /// Grazing rays (almost in the plane) agree with f64 away from the rim,
    /// and a ray exactly in the plane is a miss.
    #[test]
    fn grazing_rays() {
        let (f, g) = pair([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0, 0.0);
        let mut mism = 0;
        for i in 0..2000 {
            let eps = 1e-6f32 * (1.0 + i as f32);
            let o = [-5.0f32, 5.0 * eps, 0.1];
            let d = [1.0f32, -eps, 0.0];
            let a = f.intersect(o, d, 0.0, f32::INFINITY).is_some();
            let b = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY).is_some();
            if a != b {
                mism += 1;
            }
            assert!(b, "the f64 reference should hit");
        }
        assert_eq!(mism, 0);
        assert!(f
            .intersect([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, f32::INFINITY)
            .is_none());
    }

    /// A disk of radius 1 and an annulus 1..2 with the same centre and normal:
    /// rays aimed at the shared circle hit at least one of them.
    #[test]
    fn disk_and_annulus_leave_no_gap() {
        let c = [3.0f32, -1.0, 2.0];
        let n = unit([0.2, 0.9, 0.4]);
        let (inner, _) = pair(c, n, 1.0, 0.0);
        let (outer, _) = pair(c, n, 2.0, 1.0);
        let fr = inner.frame;
        let mut rng = RngState::seeded(9);
        for _ in 0..50_000 {
            let a = rng.range_f32(0.0, std::f32::consts::TAU);
            let target: [f32; 3] =
                std::array::from_fn(|i| c[i] + a.cos() * fr[0][i] + a.sin() * fr[1][i]);
            let o =
                std::array::from_fn(|i| target[i] + 5.0 * rng.range_f32(-1.0, 1.0) + 10.0 * n[i]);
            let d = sub(target, o);
            let hit = inner.intersect(o, d, 0.0, f32::INFINITY).is_some()
                || outer.intersect(o, d, 0.0, f32::INFINITY).is_some();
            assert!(hit, "gap at {target:?} from {o:?}");
        }
    }
}
