//! The cone's geometric core, generic over [`Real`]: the plugin runs it in
//! f32, the tests run the same code in f64 as the reference.

use rtk_kernel::geom::vec::*;
use rtk_kernel::geom::{gamma, max_of, Real};

/// A finite open cone: in the frame at the apex with w along the axis,
/// x² + y² = (k z)², 0 ≤ z ≤ h, k = r / h (no base cap).
#[derive(Clone, Copy, Debug)]
pub struct Cone<R> {
    /// Apex.
    pub apex: V<R>,
    /// Frame: u, v across, w from the apex towards the base (unit).
    pub frame: [V<R>; 3],
    /// Height.
    pub h: R,
    /// r / h.
    pub k: R,
    /// √(1 + k²): distance in the meridian plane per unit of ρ − k z.
    pub sec: R,
}

/// A hit point on the surface and what `local_geom` needs of it.
#[derive(Clone, Copy, Debug)]
pub struct Surface<R> {
    /// The point, reprojected onto the surface.
    pub p: V<R>,
    /// Per-component bound on its distance from the exact surface.
    pub p_err: V<R>,
    /// Outward unit normal (away from the axis and towards the apex).
    pub n: V<R>,
    /// Local coordinates (x, y, z) of the reprojected point.
    pub local: V<R>,
}

impl<R: Real> Cone<R> {
    /// From parameters in f64: `axis` goes from the apex to the base's
    /// centre, its length the height; `r` is the base radius.
    pub fn new(apex: [f64; 3], axis: [f64; 3], r: f64) -> Self {
        let f = frame64(axis);
        let h = norm64(axis);
        let k = r / h;
        Cone {
            apex: cvt(apex),
            frame: [cvt(f[0]), cvt(f[1]), cvt(f[2])],
            h: R::from_f64(h),
            k: R::from_f64(k),
            sec: R::from_f64((1.0 + k * k).sqrt()),
        }
    }

    /// Nearest hit of `o + t d` in `(t_min, t_max)`, if any.
    ///
    /// The quadric A t² + 2B t + C = 0 with A = D²xy − k²D²z,
    /// B = X·Dxy − k²XzDz, C = X²xy − k²X²z (X, D: origin and direction in
    /// the frame). As Ray Tracing Gems ch. 7 does for the sphere, the
    /// discriminant B² − AC, which does not depend on where along the ray the
    /// origin sits, is computed at the point of the ray closest to the middle
    /// of the axis, where its terms are of the cone's size and do not cancel
    /// catastrophically when the origin is far away; the roots are the
    /// stable pair C/q and q/A, q = −(B + sign(B)√disc). A ray parallel to a
    /// generatrix (A = 0) keeps its one finite root C/q. Roots within
    /// γ₇·max(|t₀|, |t₁|, |X|/|D|) of 0 are skipped, and when the origin lies
    /// within [`Cone::origin_band`] of the surface the root at the origin
    /// (C/q) is dropped. The double cone is cut to 0 ≤ z ≤ h.
    #[inline]
    pub fn intersect(&self, o: V<R>, d: V<R>, t_min: R, t_max: R) -> Option<R> {
        let k2 = self.k * self.k;
        let f = sub(o, self.apex);
        let x = to_local(&self.frame, f);
        let dl = to_local(&self.frame, d);
        let dd = dot(dl, dl);
        if !(dd > R::ZERO) {
            return None;
        }
        let a = dl[0] * dl[0] + dl[1] * dl[1] - k2 * dl[2] * dl[2];
        let b = x[0] * dl[0] + x[1] * dl[1] - k2 * x[2] * dl[2];
        let rho2 = x[0] * x[0] + x[1] * x[1];
        let kz2 = k2 * x[2] * x[2];
        let c = rho2 - kz2;
        // The point of the ray closest to the middle of the axis.
        let half = self.h * R::from_f64(0.5);
        let ts = -(x[0] * dl[0] + x[1] * dl[1] + (x[2] - half) * dl[2]) / dd;
        let s = add(x, scale(dl, ts));
        let bs = s[0] * dl[0] + s[1] * dl[1] - k2 * s[2] * dl[2];
        let cs = s[0] * s[0] + s[1] * s[1] - k2 * s[2] * s[2];
        let disc = bs * bs - a * cs;
        if !(disc >= R::ZERO) {
            return None;
        }
        let q = -(b + b.signum1() * disc.sqrt());
        let (near, far) = if q == R::ZERO {
            (R::ZERO, R::ZERO)
        } else {
            (c / q, q / a)
        };
        let scale_t = (dot(f, f) / dd).sqrt();
        let mut t_err = gamma::<R>(7) * scale_t;
        for t in [near, far] {
            if t.is_finite() {
                t_err = max_of(t_err, gamma::<R>(7) * t.abs());
            }
        }
        let on_surface =
            c.abs() <= (rho2.sqrt() + (kz2).sqrt()) * self.sec * self.origin_band(o, f, x[2]);
        let (t0, t1) = if on_surface {
            (far, far)
        } else if near < far {
            (near, far)
        } else {
            (far, near)
        };
        for t in [t0, t1] {
            if t > t_min && t < t_max && t > t_err && t.is_finite() {
                let z = x[2] + t * dl[2];
                if z >= R::ZERO && z <= self.h {
                    return Some(t);
                }
            }
        }
        None
    }

    /// How close to the surface (a distance) an origin must be to count as
    /// lying on it: the error bound a hit point would have there (see
    /// [`Cone::surface`]; Σ|nᵢ| ≤ √3, |z| clamped to the height), plus the
    /// rounding of the local coordinates, γ₆|f|₁ (f = o − apex).
    #[inline]
    fn origin_band(&self, o: V<R>, f: V<R>, z: R) -> R {
        let z = if z.abs() < self.h { z.abs() } else { self.h };
        gamma::<R>(2) * abs1(o) + gamma::<R>(6) * abs1(f) + gamma::<R>(24) * (self.k * z + z)
    }

    /// The hit point at `t`, reprojected onto the surface (onto the
    /// generatrix in its meridian plane), with its error bound
    /// γ₁₂(ρ + z) + γ₂|pᵢ|: the projection, the frame's rounding and the
    /// local-to-world sum, then the one addition of the apex.
    #[inline]
    pub fn surface(&self, o: V<R>, d: V<R>, t: R) -> Surface<R> {
        let f = sub(o, self.apex);
        let pl = add(to_local(&self.frame, f), scale(to_local(&self.frame, d), t));
        let rho = (pl[0] * pl[0] + pl[1] * pl[1]).sqrt();
        // Foot of the perpendicular on the line ρ = k z, z ≥ 0.
        let w = (rho * self.k + pl[2]) / (self.sec * self.sec);
        let w = max_of(w, R::ZERO);
        let (rho_s, z) = (self.k * w, w);
        let (x, y) = if rho > R::ZERO {
            (pl[0] * (rho_s / rho), pl[1] * (rho_s / rho))
        } else {
            (rho_s, R::ZERO)
        };
        let local = [x, y, z];
        let p = add(self.apex, to_world(&self.frame, local));
        let kk = gamma::<R>(12) * (rho_s + z);
        let g2 = gamma::<R>(2);
        let p_err = std::array::from_fn(|i| kk + g2 * p[i].abs());
        let nl = if rho_s > R::ZERO {
            [
                x / (rho_s * self.sec),
                y / (rho_s * self.sec),
                -self.k / self.sec,
            ]
        } else {
            [R::ZERO, R::ZERO, -R::ONE]
        };
        let n = to_world(&self.frame, nl);
        Surface { p, p_err, n, local }
    }
}

#[inline]
fn abs1<R: Real>(a: V<R>) -> R {
    a[0].abs() + a[1].abs() + a[2].abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::geom::offset_ray_origin;
    use rtk_kernel::glam::Vec3;
    use rtk_kernel::RngState;

    fn pair(apex: [f32; 3], axis: [f32; 3], r: f32) -> (Cone<f32>, Cone<f64>) {
        let b = apex.map(f64::from);
        let a = axis.map(f64::from);
        (Cone::new(b, a, r as f64), Cone::new(b, a, r as f64))
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

    /// Signed distance of a point from the exact (f64) infinite cone.
    fn surf_dist(g: &Cone<f64>, p: [f64; 3]) -> f64 {
        let l = to_local(&g.frame, sub(p, g.apex));
        ((l[0] * l[0] + l[1] * l[1]).sqrt() - g.k * l[2]) / g.sec
    }

    const CASES: [([f32; 3], [f32; 3], f32); 4] = [
        ([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], 1.0),
        ([0.5, -0.25, 1.0], [0.3, 1.7, -0.6], 0.3),
        ([1e3, -2e3, 5e2], [3.0, 1.0, -2.0], 2.0),
        ([1e2, 1e2, 0.0], [0.0, 0.0, 2e-2], 1e-2),
    ];

    #[test]
    fn head_on_and_open_base() {
        // Apex at y = 1, base of radius 1 at y = 0.
        let (f, _) = pair([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], 1.0);
        let inf = f32::INFINITY;
        // Horizontal ray at y = 0.5: the cone's radius there is 0.5.
        assert_eq!(
            f.intersect([0.0, 0.5, 5.0], [0.0, 0.0, -1.0], 0.0, inf),
            Some(4.5)
        );
        // From inside to the far wall.
        assert_eq!(
            f.intersect([0.0, 0.5, 0.0], [0.0, 0.0, -1.0], 0.0, inf),
            Some(0.5)
        );
        // Above the apex (the other nappe is cut away), and below the base.
        assert!(f
            .intersect([0.0, 1.5, 5.0], [0.0, 0.0, -1.0], 0.0, inf)
            .is_none());
        assert!(f
            .intersect([0.0, -0.1, 5.0], [0.0, 0.0, -1.0], 0.0, inf)
            .is_none());
        // Up through the open base along the axis: the apex (a double root).
        let t = f.intersect([0.0, -1.0, 0.0], [0.0, 1.0, 0.0], 0.0, inf);
        assert!(t.is_none() || (t.unwrap() - 2.0).abs() < 1e-5, "{t:?}");
        // Up through the base, off axis: the inside of the wall.
        let t = f
            .intersect([0.25, -1.0, 0.0], [0.0, 1.0, 0.0], 0.0, inf)
            .unwrap();
        assert!((t - 1.75).abs() < 1e-6, "{t}");
    }

    /// A ray parallel to a generatrix (A = 0): one root, on the opposite side.
    #[test]
    fn parallel_to_a_generatrix() {
        // Apex at the origin, axis +z, k = 1: generatrix direction (1, 0, 1).
        let (f, g) = pair([0.0, 0.0, 0.0], [0.0, 0.0, 2.0], 2.0);
        let o = [-0.5f32, 0.0, 0.0];
        let d = [1.0f32, 0.0, 1.0];
        // x = -0.5 + t, z = t: |x| = z at t = 0.25.
        let a = f.intersect(o, d, 0.0, f32::INFINITY).unwrap();
        let b = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY).unwrap();
        assert!(
            (a - 0.25).abs() < 1e-6 && (b - 0.25).abs() < 1e-12,
            "{a} {b}"
        );
    }

    /// Random rays from a box around the cone aimed near it: f32 against
    /// f64. Mismatches only near the silhouettes, the rim or the apex; t and
    /// the normal agree.
    #[test]
    fn f32_matches_f64_on_random_rays() {
        let mut rng = RngState::seeded(31);
        for (apex, axis, r) in CASES {
            let (f, g) = pair(apex, axis, r);
            let size = r.max(g.h as f32);
            let mid: [f32; 3] = std::array::from_fn(|i| apex[i] + 0.5 * axis[i]);
            let (mut hits, mut band, mut worst_t, mut worst_n, mut worst_abs) =
                (0, 0, 0.0f64, 0.0f64, 0.0f64);
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
                        let rel = (a as f64 - b).abs() / b;
                        let sg = g.surface(f64v(o), f64v(d), b);
                        let dl = to_local(&g.frame, f64v(d));
                        let cos = dot(dl, to_local(&g.frame, sg.n)).abs() / norm64(dl);
                        let dist = b * norm64(dl);
                        // Every hit: the distance error over the problem's scale
                        // and the conditioning 1/|cos θ| of a root.
                        let scale = norm64(sub(f64v(o), g.apex)) + size as f64;
                        worst_abs = worst_abs.max((a as f64 - b).abs() * norm64(dl) * cos / scale);
                        if cos > 0.05 && dist > 0.1 * size as f64 {
                            worst_t = worst_t.max(rel);
                        }
                        let sf = f.surface(o, d, a);
                        let dp = norm64(sub(f64v(sf.p), sg.p));
                        let dn = norm64(sub(f64v(sf.n), sg.n));
                        let rho = (sg.local[0].powi(2) + sg.local[1].powi(2)).sqrt();
                        // |Δp| over the local radius of curvature explains Δn.
                        worst_n = worst_n.max(dn / (dp / rho.max(1e-30) + 1e-6));
                    }
                    (None, None) => {}
                    (a, b) => {
                        let tt = b.unwrap_or_else(|| a.map_or(0.0, f64::from));
                        let s = g.surface(f64v(o), f64v(d), tt);
                        let z = s.local[2];
                        let dl = to_local(&g.frame, f64v(d));
                        let nl = to_local(&g.frame, s.n);
                        let graze = dot(dl, nl).abs() / norm64(dl);
                        let rim = (z - g.h).abs() / g.h;
                        let apex_near = z / g.h;
                        let at_origin = tt * norm64(f64v(d)) < 1e-5 * norm64(f64v(o));
                        assert!(
                            graze < 1e-3 || rim < 1e-5 || apex_near < 1e-3 || at_origin,
                            "mismatch off the band: f32 {a:?} f64 {b:?}, cos {graze:e}, z/h {apex_near:e}"
                        );
                        band += 1;
                    }
                }
            }
            println!(
                "cone r {r} at {apex:?}: {hits} hits of {total}, {band} band mismatches, \
                 max rel t err {worst_t:e} (|cos| > 0.05, t|d| > size / 10), \
                 max |dt||d||cos| / (|o - apex| + size) {worst_abs:e}, max normal err / (|dp|/rho + 1e-6) {worst_n:e}"
            );
            assert!(hits > total / 20, "{hits}");
            assert!(band * 500 < total, "{band}");
            assert!(worst_t < 1e-5, "{worst_t}");
            assert!(worst_abs < 1e-5, "{worst_abs}");
            assert!(worst_n < 4.0, "{worst_n}");
        }
    }

    /// Hit points lie within their bound of the exact surface; rays spawned
    /// off them never re-hit short (see the cylinder's test of the same name).
    #[test]
    fn origins_on_the_surface() {
        let mut rng = RngState::seeded(8);
        for (apex, axis, r) in CASES {
            let (f, g) = pair(apex, axis, r);
            let size = r.max(g.h as f32);
            let mid: [f32; 3] = std::array::from_fn(|i| apex[i] + 0.5 * axis[i]);
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
                let dist = surf_dist(&g, f64v(s.p));
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
            println!(
                "cone r {r} at {apex:?}: {pts} points within bound, {rays} rays, {short} self-hits"
            );
            assert!(pts > 500);
            assert_eq!(short, 0);
        }
    }

    /// Rays tangent to the wall (across a meridian plane), offset from the
    /// tangent by ±1e-3 of the local radius: f32 and f64 agree outside a
    /// relative band of 1e-5.
    #[test]
    fn grazing_rays() {
        let (f, g) = pair([0.0, 2.0, 0.0], [0.0, -2.0, 0.0], 1.0);
        let mut mism = 0;
        let n = 4000;
        for i in 0..n {
            let e = (i as f32 / n as f32 - 0.5) * 2e-3;
            // At y = 1 the radius is 0.5; the tangent line x = 0.5, y = 1 runs along z.
            let o = [0.5 * (1.0 + e), 1.0, -5.0];
            let d = [0.0, 0.0, 1.0];
            let a = f.intersect(o, d, 0.0, f32::INFINITY).is_some();
            let b = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY).is_some();
            if a != b {
                assert!(e.abs() < 1e-5, "mismatch at {e:e}");
                mism += 1;
            }
            if e != 0.0 {
                assert_eq!(b, e < 0.0, "f64 at {e:e}");
            }
        }
        println!("grazing: {mism} mismatches of {n}");
    }
}
