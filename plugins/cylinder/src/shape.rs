//! The cylinder's geometric core, generic over [`Real`]: the plugin runs it
//! in f32, the tests run the same code in f64 as the reference.

use rtk_kernel::geom::vec::*;
use rtk_kernel::geom::{gamma, max_of, Real};

/// A finite open cylinder: the points at distance `r` from the segment
/// `base + z w`, 0 ≤ z ≤ h (no caps).
#[derive(Clone, Copy, Debug)]
pub struct Cylinder<R> {
    /// Centre of the bottom circle.
    pub base: V<R>,
    /// Frame: u, v across, w along the axis (unit).
    pub frame: [V<R>; 3],
    /// Height.
    pub h: R,
    /// Radius.
    pub r: R,
}

/// A hit point on the surface and what `local_geom` needs of it.
#[derive(Clone, Copy, Debug)]
pub struct Surface<R> {
    /// The point, reprojected onto the surface.
    pub p: V<R>,
    /// Per-component bound on its distance from the exact surface.
    pub p_err: V<R>,
    /// Outward unit normal.
    pub n: V<R>,
    /// Local coordinates (x, y, z) of the reprojected point (x² + y² = r²).
    pub local: V<R>,
}

impl<R: Real> Cylinder<R> {
    /// From parameters in f64: `axis` is the direction from the bottom to
    /// the top circle's centre, its length the height.
    pub fn new(base: [f64; 3], axis: [f64; 3], r: f64) -> Self {
        let f = frame64(axis);
        Cylinder {
            base: cvt(base),
            frame: [cvt(f[0]), cvt(f[1]), cvt(f[2])],
            h: R::from_f64(norm64(axis)),
            r: R::from_f64(r),
        }
    }

    /// Nearest hit of `o + t d` in `(t_min, t_max)`, if any.
    ///
    /// In the cylinder's frame the lateral surface is x² + y² = r², a circle
    /// problem in 2D, solved as Ray Tracing Gems ch. 7 solves the sphere:
    /// the discriminant from r² − |l|², l the point of the 2D line closest
    /// to the axis, and the stable roots c/q and q/a. Then 0 ≤ z ≤ h.
    ///
    /// Origins on the surface: a root within γ₇·max(|t₀|, |t₁|, |f|/|d_xy|)
    /// of 0 is skipped (as the sphere does), and when the origin lies within
    /// [`Cylinder::origin_band`] of the surface, the root nearest 0 (c/q, the
    /// origin itself) is dropped outright, whatever the angle of the ray.
    #[inline]
    pub fn intersect(&self, o: V<R>, d: V<R>, t_min: R, t_max: R) -> Option<R> {
        let f = sub(o, self.base);
        let fl = to_local(&self.frame, f);
        let dl = to_local(&self.frame, d);
        let a = dl[0] * dl[0] + dl[1] * dl[1];
        if !(a > R::ZERO) {
            return None; // parallel to the axis: never crosses the wall
        }
        let b_half = -(fl[0] * dl[0] + fl[1] * dl[1]);
        let rho2 = fl[0] * fl[0] + fl[1] * fl[1];
        let r2 = self.r * self.r;
        let c = rho2 - r2;
        let s = (-b_half) / a;
        let l = [fl[0] - s * dl[0], fl[1] - s * dl[1]];
        let disc = a * (r2 - (l[0] * l[0] + l[1] * l[1]));
        if !(disc >= R::ZERO) {
            return None;
        }
        let q = b_half + b_half.signum1() * disc.sqrt();
        let (near, far) = if q == R::ZERO {
            (R::ZERO, R::ZERO)
        } else {
            (c / q, q / a)
        };
        let fd = abs3(f) / a.sqrt();
        let t_err = gamma::<R>(7) * max_of(max_of(near.abs(), far.abs()), fd);
        let on_surface = c.abs() <= (rho2.sqrt() + self.r) * self.origin_band(o, f, fl[2]);
        let (t0, t1) = if on_surface {
            (far, far)
        } else if near < far {
            (near, far)
        } else {
            (far, near)
        };
        for t in [t0, t1] {
            if t > t_min && t < t_max && t > t_err && t.is_finite() {
                let z = fl[2] + t * dl[2];
                if z >= R::ZERO && z <= self.h {
                    return Some(t);
                }
            }
        }
        None
    }

    /// How close to the surface (a distance) an origin must be to count as
    /// lying on it: the error bound a hit point of this cylinder would have
    /// there (see [`Cylinder::surface`]: Σ|nᵢ|·p_errᵢ ≤ γ₂|o|₁ + γ₁₅(r + |z|)
    /// for a unit radial normal, |z| clamped to the height), plus the
    /// rounding of the local coordinates x, y, γ₆|f|₁ (f = o − base).
    #[inline]
    fn origin_band(&self, o: V<R>, f: V<R>, z: R) -> R {
        let z = if z.abs() < self.h { z.abs() } else { self.h };
        gamma::<R>(2) * abs1(o) + gamma::<R>(6) * abs1(f) + gamma::<R>(20) * (self.r + z)
    }

    /// The hit point at `t`, reprojected onto the surface (x, y scaled to the
    /// radius), with its error bound γ₁₀(r + |z|) + γ₂|pᵢ|: the projection,
    /// the frame's rounding and the local-to-world sum, then the one addition
    /// of `base`.
    #[inline]
    pub fn surface(&self, o: V<R>, d: V<R>, t: R) -> Surface<R> {
        let f = sub(o, self.base);
        let pl = add(to_local(&self.frame, f), scale(to_local(&self.frame, d), t));
        let rho = (pl[0] * pl[0] + pl[1] * pl[1]).sqrt();
        let (x, y) = if rho > R::ZERO {
            (pl[0] * (self.r / rho), pl[1] * (self.r / rho))
        } else {
            (self.r, R::ZERO)
        };
        let z = pl[2];
        let local = [x, y, z];
        let p = add(self.base, to_world(&self.frame, local));
        let k = gamma::<R>(10) * (self.r + z.abs());
        let g2 = gamma::<R>(2);
        let p_err = std::array::from_fn(|i| k + g2 * p[i].abs());
        let n = to_world(&self.frame, [x / self.r, y / self.r, R::ZERO]);
        Surface { p, p_err, n, local }
    }
}

#[inline]
fn abs1<R: Real>(a: V<R>) -> R {
    a[0].abs() + a[1].abs() + a[2].abs()
}

#[inline]
fn abs3<R: Real>(a: V<R>) -> R {
    dot(a, a).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::geom::offset_ray_origin;
    use rtk_kernel::glam::Vec3;
    use rtk_kernel::RngState;

    fn pair(base: [f32; 3], axis: [f32; 3], r: f32) -> (Cylinder<f32>, Cylinder<f64>) {
        let b = base.map(f64::from);
        let a = axis.map(f64::from);
        (Cylinder::new(b, a, r as f64), Cylinder::new(b, a, r as f64))
    }

    fn f64v(a: [f32; 3]) -> [f64; 3] {
        a.map(f64::from)
    }

    fn sphere_dir(rng: &mut RngState) -> [f32; 3] {
        loop {
            let v = [
                rng.range_f32(-1.0, 1.0),
                rng.range_f32(-1.0, 1.0),
                rng.range_f32(-1.0, 1.0),
            ];
            let l = Vec3::from(v).length();
            if l > 0.1 && l <= 1.0 {
                return (Vec3::from(v) / l).to_array();
            }
        }
    }

    /// Distance of a point from the exact (f64) lateral surface, and its z.
    fn surf_dist(g: &Cylinder<f64>, p: [f64; 3]) -> (f64, f64) {
        let l = to_local(&g.frame, sub(p, g.base));
        ((l[0] * l[0] + l[1] * l[1]).sqrt() - g.r, l[2])
    }

    const CASES: [([f32; 3], [f32; 3], f32); 4] = [
        ([0.0, 0.0, 0.0], [0.0, 2.0, 0.0], 1.0),
        ([0.5, -0.25, 1.0], [0.3, 1.7, -0.6], 0.5),
        ([1e3, -2e3, 5e2], [3.0, 1.0, -2.0], 1.0),
        ([1e2, 1e2, 0.0], [0.0, 0.0, 2e-2], 1e-2),
    ];

    #[test]
    fn head_on_and_open_ends() {
        let (f, _) = pair([0.0, 0.0, 0.0], [0.0, 2.0, 0.0], 1.0);
        let inf = f32::INFINITY;
        assert_eq!(
            f.intersect([0.0, 1.0, 5.0], [0.0, 0.0, -1.0], 0.0, inf),
            Some(4.0)
        );
        // From inside: the far wall.
        assert_eq!(
            f.intersect([0.0, 1.0, 0.0], [0.0, 0.0, -1.0], 0.0, inf),
            Some(1.0)
        );
        // Above the top, missing the height range; along the axis: no wall.
        assert!(f
            .intersect([0.0, 3.0, 5.0], [0.0, 0.0, -1.0], 0.0, inf)
            .is_none());
        assert!(f
            .intersect([0.0, 5.0, 0.0], [0.0, -1.0, 0.0], 0.0, inf)
            .is_none());
        // Down through the open top, onto the inside of the wall.
        assert_eq!(
            f.intersect([0.0, 3.0, 0.0], [0.0, -1.0, 0.5], 0.0, inf),
            Some(2.0)
        );
        // Open interval at t_max.
        assert!(f
            .intersect([0.0, 1.0, 5.0], [0.0, 0.0, -1.0], 0.0, 4.0)
            .is_none());
    }

    /// Random rays from a box around the cylinder aimed near it: f32 against
    /// f64. Mismatches only near the silhouettes or the rims; t and the
    /// normal agree.
    #[test]
    fn f32_matches_f64_on_random_rays() {
        let mut rng = RngState::seeded(21);
        for (base, axis, r) in CASES {
            let (f, g) = pair(base, axis, r);
            let h = g.h as f32;
            let size = r.max(h);
            let mid: [f32; 3] = std::array::from_fn(|i| base[i] + 0.5 * axis[i]);
            let (mut hits, mut band, mut worst_t, mut worst_n) = (0, 0, 0.0f64, 0.0f64);
            let total = 40_000;
            for _ in 0..total {
                let o: [f32; 3] =
                    std::array::from_fn(|i| mid[i] + 3.0 * size * rng.range_f32(-1.0, 1.0));
                let tg: [f32; 3] =
                    std::array::from_fn(|i| mid[i] + 0.8 * size * rng.range_f32(-1.0, 1.0));
                let d = sub(tg, o);
                let hf = f.intersect(o, d, 0.0, f32::INFINITY);
                let hg = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY);
                match (hf, hg) {
                    (Some(a), Some(b)) if (a as f64 - b).abs() <= 1e-4 * b => {
                        hits += 1;
                        worst_t = worst_t.max((a as f64 - b).abs() / b);
                        // The normal error, over what the distance between
                        // the two hit points explains (|Δp|/r) plus 1e-6.
                        let (sf, sg) = (f.surface(o, d, a), g.surface(f64v(o), f64v(d), b));
                        let dp = norm64(sub(f64v(sf.p), sg.p));
                        let dn = norm64(sub(f64v(sf.n), sg.n));
                        worst_n = worst_n.max(dn / (dp / g.r + 1e-6));
                    }
                    (None, None) => {}
                    (a, b) => {
                        // A different answer: a silhouette graze (discriminant
                        // near 0) or a rim (z near 0 or h) in f64.
                        let tt = b.unwrap_or_else(|| a.map_or(0.0, f64::from));
                        let s = g.surface(f64v(o), f64v(d), tt);
                        let z = s.local[2];
                        let dl = to_local(&g.frame, f64v(d));
                        let graze =
                            (dl[0] * s.local[0] + dl[1] * s.local[1]).abs() / (g.r * norm64(dl));
                        let rim = z.abs().min((z - g.h).abs()) / g.h;
                        // Or within the origin's own precision of the origin.
                        let at_origin = tt * norm64(f64v(d)) < 1e-5 * norm64(f64v(o));
                        assert!(
                            graze < 1e-3 || rim < 1e-5 || at_origin,
                            "mismatch off the band: f32 {a:?} f64 {b:?}, cos {graze:e}, rim {rim:e}"
                        );
                        band += 1;
                    }
                }
            }
            println!(
                "cylinder r {r} at {base:?}: {hits} hits of {total}, {band} band mismatches, \
                 max rel t err {worst_t:e}, max normal err / (|dp|/r + 1e-6) {worst_n:e}"
            );
            assert!(hits > total / 20, "{hits}");
            assert!(band * 500 < total, "{band}");
            assert!(worst_t < 1e-5, "{worst_t}");
            assert!(worst_n < 2.0, "{worst_n}");
        }
    }

    /// Hit points lie within their bound of the exact surface. Rays spawned
    /// off them as the renderer does (offset along the normal) never re-hit
    /// short: outward rays never hit the convex outside again, and inward
    /// rays reach at least half the f64 chord. Rays from the raw point (no
    /// offset) behave the same away from tangency (|cos θ| > 1e-2).
    #[test]
    fn origins_on_the_surface() {
        let mut rng = RngState::seeded(4);
        for (base, axis, r) in CASES {
            let (f, g) = pair(base, axis, r);
            let size = r.max(g.h as f32);
            let mid: [f32; 3] = std::array::from_fn(|i| base[i] + 0.5 * axis[i]);
            let (mut pts, mut short, mut rays) = (0, 0, 0);
            for _ in 0..5_000 {
                let o: [f32; 3] =
                    std::array::from_fn(|i| mid[i] + 3.0 * size * rng.range_f32(-1.0, 1.0));
                let tg: [f32; 3] =
                    std::array::from_fn(|i| mid[i] + 0.5 * size * rng.range_f32(-1.0, 1.0));
                let d = sub(tg, o);
                let Some(t) = f.intersect(o, d, 0.0, f32::INFINITY) else {
                    continue;
                };
                let s = f.surface(o, d, t);
                let (dist, _) = surf_dist(&g, f64v(s.p));
                let bound = abs_dot(f64v(s.n), f64v(s.p_err));
                assert!(dist.abs() <= bound, "off surface by {dist:e} > {bound:e}");
                pts += 1;
                for _ in 0..8 {
                    let w = sphere_dir(&mut rng);
                    let cos = dot(w, s.n);
                    let po = offset_ray_origin(
                        Vec3::from(s.p),
                        Vec3::from(s.p_err),
                        Vec3::from(s.n),
                        Vec3::from(w),
                    )
                    .to_array();
                    let origins: &[[f32; 3]] = if cos.abs() > 1e-2 { &[po, s.p] } else { &[po] };
                    for &org in origins {
                        rays += 1;
                        let hf = f.intersect(org, w, 0.0, f32::INFINITY);
                        let hg = g.intersect(f64v(org), f64v(w), 0.0, f64::INFINITY);
                        let bad = match (hf, hg) {
                            (Some(a), Some(b)) => (a as f64) < 0.5 * b,
                            (Some(_), None) => true,
                            _ => false,
                        };
                        if bad {
                            short += 1;
                            println!(
                                "short: cos {cos:e} f32 {hf:?} f64 {hg:?} raw {}",
                                org == s.p
                            );
                        }
                    }
                }
            }
            println!("cylinder r {r} at {base:?}: {pts} points within bound, {rays} rays, {short} self-hits");
            assert!(pts > 500);
            assert_eq!(short, 0);
        }
    }

    /// Grazing rays tangent to the wall, and rays skimming the rims: f32 and
    /// f64 agree outside a relative band of 1e-5 around the tangent.
    #[test]
    fn grazing_rays() {
        let (f, g) = pair([0.0, 0.0, 0.0], [0.0, 2.0, 0.0], 1.0);
        let mut mism = 0;
        let n = 4000;
        for i in 0..n {
            // Offsets from the tangent line x = 1, from -1e-3 to 1e-3.
            let e = (i as f32 / n as f32 - 0.5) * 2e-3;
            let o = [1.0 + e, 1.0, -5.0];
            let d = [0.0, 0.0, 1.0];
            let a = f.intersect(o, d, 0.0, f32::INFINITY).is_some();
            let b = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY).is_some();
            if a != b {
                assert!(e.abs() < 1e-5, "mismatch at {e:e}");
                mism += 1;
            }
            assert_eq!(b, e <= 0.0, "f64 at {e:e}");
        }
        println!("grazing: {mism} mismatches of {n}");
        // A ray along the axis inside, and one along the wall: no hit.
        assert!(f
            .intersect([0.0, -1.0, 0.0], [0.0, 1.0, 0.0], 0.0, f32::INFINITY)
            .is_none());
        assert!(f
            .intersect([1.0, -1.0, 0.0], [0.0, 1.0, 0.0], 0.0, f32::INFINITY)
            .is_none());
    }
}
