//! The torus's geometric core, generic over [`Real`]: the plugin runs it in
//! f32, the tests run the same code in f64 as the reference.
//!
//! # The quartic, solved robustly
//! In the torus's frame (centre at 0, axis z) a point p is on the surface
//! when F(p) = (|p|² + R² − r²)² − 4R²(x² + y²) = 0. F factors as
//! G(p)·H(p) with G = (ρ − R)² + z² − r² (ρ = √(x² + y²): the squared
//! distance from the core circle minus r²) and H = (ρ + R)² + z² − r² > 0 for
//! a ring torus (r < R), so F and G have the same sign everywhere.
//!
//! 1. **Shift and scale.** The ray's origin is moved to the point of the ray
//!    closest to the centre (t = s), the direction is made unit, and lengths
//!    are divided by S = R + r. Along the ray, p(τ) = g + τe with |g| < 1 if
//!    the ray meets the bounding sphere at all, which bounds the search to
//!    |τ| ≤ √(1 − |g|²) and keeps every coefficient of F(τ) of order 1:
//!    no overflow for R = 1e12, no underflow for R = 1e-12, and no
//!    cancellation growing with the origin's distance.
//! 2. **Isolate the roots by the derivatives** (Yuksel, "High-Performance
//!    Polynomial Root Finding for Graphics", HPG 2022): the roots of F'' (a
//!    quadratic, closed form) split the interval where F' is monotonic; the
//!    roots of F' found there split it where F is monotonic, so each piece
//!    holds at most one root of F, bracketed by a sign change.
//! 3. **Decide and refine on G, not F.** The signs at the piece ends, and
//!    the safeguarded Newton/bisection (Numerical Recipes' rtsafe) inside a
//!    bracket, use G evaluated from the geometry: its rounding is of the
//!    order of ε·S per unit of distance, like a sphere's, where F's expanded
//!    coefficients lose a factor of about R/r near the tube.
//! 4. **The origin is a piece end**, its sign computed from the unshifted
//!    origin, so a ray leaving the surface (offset past the hit's error
//!    bound) starts on the right side; an origin within the error bound of
//!    the surface drops the root at the origin.
//!
//! Closed forms (Ferrari) cancel badly near double roots and are no cheaper;
//! the derivative cascade finds every root in order, so the nearest root in
//! (t_min, t_max) is the first one found.

use rtk_kernel::geom::vec::*;
use rtk_kernel::geom::{gamma, Real};

/// A ring torus: centre `c`, axis `frame[2]`, major radius `big`, minor
/// radius `small` < `big`.
#[derive(Clone, Copy, Debug)]
pub struct Torus<R> {
    /// Centre.
    pub c: V<R>,
    /// Frame: u, v span the equatorial plane, w = the axis (unit).
    pub frame: [V<R>; 3],
    /// Major radius R (centre to the tube's core circle).
    pub big: R,
    /// Minor radius r (of the tube).
    pub small: R,
    /// Bounding-sphere radius R + r: the unit of the normalised quartic.
    pub s: R,
    /// R / S.
    rn: R,
    /// r / S.
    sn: R,
}

/// A hit point on the surface and what `local_geom` needs of it.
#[derive(Clone, Copy, Debug)]
pub struct Surface<R> {
    /// The point, reprojected onto the surface.
    pub p: V<R>,
    /// Per-component bound on its distance from the exact surface.
    pub p_err: V<R>,
    /// Outward unit normal (away from the core circle).
    pub n: V<R>,
    /// Local coordinates (x, y, z) of the reprojected point.
    pub local: V<R>,
}

/// G = (ρ − R)² + z² − r² at `p` (normalised units) and its derivative
/// along the unit `e`.
#[inline]
fn g_and_slope<R: Real>(p: V<R>, e: V<R>, rn: R, sn: R) -> (R, R) {
    let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
    let dr = rho - rn;
    let g = dr * dr + p[2] * p[2] - sn * sn;
    let drho = if rho > R::ZERO {
        (p[0] * e[0] + p[1] * e[1]) / rho
    } else {
        R::ZERO
    };
    let two = R::ONE + R::ONE;
    (g, two * (dr * drho + p[2] * e[2]))
}

/// Numerical Recipes' rtsafe: the root of `f` in `[a, b]` where `f(a)` and
/// `f(b)` have opposite signs (`a_neg`: f(a) < 0), Newton steps kept inside
/// the bracket, bisection when a step would leave it or converges slowly.
#[inline]
fn rtsafe<R: Real>(a: R, b: R, a_neg: bool, f: impl Fn(R) -> (R, R)) -> R {
    let half = R::from_f64(0.5);
    // xl: the end where f < 0.
    let (mut xl, mut xh) = if a_neg { (a, b) } else { (b, a) };
    let mut x = (a + b) * half;
    let mut dx_old = (b - a).abs();
    let mut dx = dx_old;
    let (mut fx, mut dfx) = f(x);
    let tol = R::UNIT_ROUNDOFF * R::from_f64(4.0);
    for _ in 0..100 {
        let newton_ok = ((x - xh) * dfx - fx) * ((x - xl) * dfx - fx) < R::ZERO
            && (fx + fx).abs() <= (dx_old * dfx).abs();
        if newton_ok {
            dx_old = dx;
            dx = fx / dfx;
            let prev = x;
            x = x - dx;
            if prev == x {
                return x;
            }
        } else {
            dx_old = dx;
            dx = (xh - xl) * half;
            x = xl + dx;
            if x == xl {
                return x;
            }
        }
        if dx.abs() < tol {
            return x;
        }
        let (nf, nd) = f(x);
        fx = nf;
        dfx = nd;
        if fx == R::ZERO {
            return x;
        }
        if fx < R::ZERO {
            xl = x;
        } else {
            xh = x;
        }
    }
    x
}

/// The ray in the normalised frame (step 1 of the module documentation):
/// p(τ) = g + τe, τ = (t − s)·k, searched over `lo..hi`.
struct Normalised<R> {
    /// o − c.
    f: V<R>,
    /// o − c in the torus's frame.
    fl: V<R>,
    /// The unit direction, in the torus's frame.
    e: V<R>,
    /// The ray's point closest to the centre, in units of S.
    g: V<R>,
    /// |g|².
    g2: R,
    /// The `t` of that point.
    s: R,
    /// τ per unit of `t`: L/S.
    k: R,
    /// L, the length of the direction.
    l: R,
    /// 1/S.
    inv_s: R,
    /// The interval of τ searched: `(t_min, t_max)` clipped to the search
    /// sphere.
    lo: R,
    hi: R,
    /// The interval starts at `t_min`, not at the sphere.
    from_origin: bool,
}

impl<R: Real> Normalised<R> {
    /// G and its slope at τ = `x`.
    #[inline]
    fn g_at(&self, x: R, rn: R, sn: R) -> (R, R) {
        g_and_slope(add(self.g, scale(self.e, x)), self.e, rn, sn)
    }
}

/// The normalised quartic F(τ) = τ⁴ + c3τ³ + c2τ² + c1τ + c0 along the ray,
/// through what its derivatives need (step 2 uses only those).
struct Quartic<R> {
    /// g·e: the roots of F'' are −β ± √(β² − c2/6).
    beta: R,
    c3: R,
    c2: R,
    c1: R,
}

impl<R: Real> Quartic<R> {
    #[inline]
    fn new(ray: &Normalised<R>, rn: R, sn: R) -> Self {
        let (g, e) = (ray.g, ray.e);
        let four = R::from_f64(4.0);
        let two = R::from_f64(2.0);
        let beta = dot(g, e);
        let alpha = ray.g2 + rn * rn - sn * sn;
        let r4 = four * rn * rn;
        let exy2 = e[0] * e[0] + e[1] * e[1];
        let gexy = g[0] * e[0] + g[1] * e[1];
        Quartic {
            beta,
            c3: four * beta,
            c2: four * beta * beta + two * alpha - r4 * exy2,
            c1: four * alpha * beta - two * r4 * gexy,
        }
    }

    /// F'(τ) = 4τ³ + 3c3τ² + 2c2τ + c1 and F''(τ) = 12τ² + 6c3τ + 2c2.
    #[inline]
    fn d1(&self, x: R) -> (R, R) {
        let (c3, c2, c1) = (self.c3, self.c2, self.c1);
        let (four, two) = (R::from_f64(4.0), R::from_f64(2.0));
        let v = ((four * x + R::from_f64(3.0) * c3) * x + two * c2) * x + c1;
        let dv = (R::from_f64(12.0) * x + R::from_f64(6.0) * c3) * x + two * c2;
        (v, dv)
    }

    /// The ends of the pieces of `[lo, hi]` where F is monotonic, in
    /// order, and how many: the roots of F'' split it where F' is
    /// monotonic, and the roots of F' found in those pieces split it again.
    #[inline]
    fn monotonic_pieces(&self, lo: R, hi: R) -> ([R; 6], usize) {
        let beta = self.beta;
        // Roots of F'' (6τ² + 3c3τ + c2 = 0, i.e. τ = −β ± √(β² − c2/6)).
        let mut cuts2 = [lo; 4];
        let mut n2 = 1;
        let disc2 = beta * beta - self.c2 / R::from_f64(6.0);
        if disc2 > R::ZERO {
            let sq = disc2.sqrt();
            for x in [-beta - sq, -beta + sq] {
                if x > lo && x < hi {
                    cuts2[n2] = x;
                    n2 += 1;
                }
            }
        }
        cuts2[n2] = hi;
        n2 += 1;
        // Roots of F' between them: where F is monotonic.
        let d1 = |x: R| self.d1(x);
        let mut cuts1 = [lo; 6];
        let mut n1 = 1;
        let mut pa = d1(cuts2[0]).0;
        for i in 1..n2 {
            let pb = d1(cuts2[i]).0;
            if (pa < R::ZERO) != (pb < R::ZERO) && pa != R::ZERO && pb != R::ZERO {
                let x = rtsafe(cuts2[i - 1], cuts2[i], pa < R::ZERO, d1);
                if x > cuts1[n1 - 1] && x < hi {
                    cuts1[n1] = x;
                    n1 += 1;
                }
            }
            pa = pb;
        }
        cuts1[n1] = hi;
        n1 += 1;
        (cuts1, n1)
    }
}

impl<R: Real> Torus<R> {
    /// From parameters in f64.
    pub fn new(c: [f64; 3], axis: [f64; 3], big: f64, small: f64) -> Self {
        let f = frame64(axis);
        let s = big + small;
        Torus {
            c: cvt(c),
            frame: [cvt(f[0]), cvt(f[1]), cvt(f[2])],
            big: R::from_f64(big),
            small: R::from_f64(small),
            s: R::from_f64(s),
            rn: R::from_f64(big / s),
            sn: R::from_f64(small / s),
        }
    }

    /// Whether `p` lies inside the tube, decided in f64 on the distance form
    /// (ρ − R)² + z² < r² (ρ, z: cylindrical coordinates about the axis).
    pub fn contains(&self, p: V<R>) -> bool {
        let d = |x: V<R>| [x[0].to_f64(), x[1].to_f64(), x[2].to_f64()];
        let (c, w) = (d(self.c), d(self.frame[2]));
        let f = [d(p)[0] - c[0], d(p)[1] - c[1], d(p)[2] - c[2]];
        let z = f[0] * w[0] + f[1] * w[1] + f[2] * w[2];
        let rho = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - z * z)
            .max(0.0)
            .sqrt();
        let (big, small) = (self.big.to_f64(), self.small.to_f64());
        (rho - big) * (rho - big) + z * z < small * small
    }

    /// Nearest hit of `o + t d` in `(t_min, t_max)`, if any (see the module
    /// documentation for the method).
    pub fn intersect(&self, o: V<R>, d: V<R>, t_min: R, t_max: R) -> Option<R> {
        let ray = self.normalise(o, d, t_min, t_max)?;
        let quartic = Quartic::new(&ray, self.rn, self.sn);
        let (cuts, n) = quartic.monotonic_pieces(ray.lo, ray.hi);
        let (g_lo, origin_on_surface) = self.g_at_start(o, &ray, t_min);
        self.first_root(&ray, &cuts[..n], g_lo, origin_on_surface, t_min, t_max)
    }

    /// Step 1: the ray shifted to its point closest to the centre, made
    /// unit and scaled by 1/S, with the τ interval to search; `None` when
    /// it misses the bounding sphere or the interval is empty.
    #[inline]
    fn normalise(&self, o: V<R>, d: V<R>, t_min: R, t_max: R) -> Option<Normalised<R>> {
        let one = R::ONE;
        let f = sub(o, self.c);
        let fl = to_local(&self.frame, f);
        let dl = to_local(&self.frame, d);
        let l2 = dot(dl, dl);
        if !(l2 > R::ZERO) {
            return None;
        }
        let l = l2.sqrt();
        let e = scale(dl, one / l);
        let s = -dot(fl, dl) / l2; // t of the point closest to the centre
        let inv_s = one / self.s;
        let g = scale(add(fl, scale(dl, s)), inv_s);
        let g2 = dot(g, g);
        let pad = gamma::<R>(8);
        if !(g2 < one + pad) {
            return None; // misses the bounding sphere
        }
        // Search a sphere 1/8 larger: the bounding sphere touches the torus
        // along its outer equator, and a root there must not sit at the end
        // of the interval, where G's sign is a coin toss.
        let w = (R::from_f64(1.125 * 1.125) - g2).sqrt();
        // τ = (t − s)·L/S; the accepted interval, clipped to the sphere.
        let k = l * inv_s;
        let tau_of = |t: R| (t - s) * k;
        let tau0 = tau_of(t_min);
        let mut lo = -w;
        let from_origin = tau0 > lo;
        if from_origin {
            lo = tau0;
        }
        let hi_t = tau_of(t_max);
        let hi = if hi_t < w { hi_t } else { w };
        if !(lo < hi) {
            return None;
        }
        Some(Normalised {
            f,
            fl,
            e,
            g,
            g2,
            s,
            k,
            l,
            inv_s,
            lo,
            hi,
            from_origin,
        })
    }

    /// G at the start of the interval, and whether the ray starts on the
    /// surface (step 4): from the unshifted origin's own coordinates when
    /// the interval starts there, so a ray leaving the surface starts on
    /// the right side.
    #[inline]
    fn g_at_start(&self, o: V<R>, ray: &Normalised<R>, t_min: R) -> (R, bool) {
        let (rn, sn) = (self.rn, self.sn);
        if !ray.from_origin {
            return (ray.g_at(ray.lo, rn, sn).0, false);
        }
        if t_min != R::ZERO {
            // The interval starts at a point of the ray (`t_min`, where a
            // query for "the next hit after t" starts, as CSG asks): a root
            // there was the last hit, and must not be found again a few
            // ulps later. Its band adds the rounding of o + t_min·d.
            let band =
                self.origin_band(o, ray.f) + gamma::<R>(3) * t_min.abs() * ray.l * abs1(ray.e);
            let start = scale(add(ray.fl, scale(ray.e, ray.l * t_min)), ray.inv_s);
            let on = self.on_surface(start, ray.e, band * ray.inv_s).1;
            return (ray.g_at(ray.lo, rn, sn).0, on);
        }
        let band = self.origin_band(o, ray.f) * ray.inv_s;
        self.on_surface(scale(ray.fl, ray.inv_s), ray.e, band)
    }

    /// G at the normalised point `po` (direction `e`), and whether `po`
    /// lies on the surface within the normalised error band `band`:
    /// |G| = |D − r|(D + r), D the distance from the core circle.
    fn on_surface(&self, po: V<R>, e: V<R>, band: R) -> (R, bool) {
        let (rn, sn) = (self.rn, self.sn);
        let gv = g_and_slope(po, e, rn, sn).0;
        let rho = (po[0] * po[0] + po[1] * po[1]).sqrt();
        let dr = rho - rn;
        let dcore = (dr * dr + po[2] * po[2]).sqrt();
        (gv, gv.abs() <= (dcore + sn) * band)
    }

    /// Step 3: the first piece (ends `cuts`) where G changes sign, its root
    /// refined on G and returned as `t` if it lies in `(t_min, t_max)` and
    /// beyond the error of `t` at the origin; a root exactly at a piece end
    /// is taken too. `g_lo`: G at the first end; `origin_on_surface`: the
    /// first piece starts on the surface, whose root there is dropped.
    #[inline]
    fn first_root(
        &self,
        ray: &Normalised<R>,
        cuts: &[R],
        g_lo: R,
        origin_on_surface: bool,
        t_min: R,
        t_max: R,
    ) -> Option<R> {
        let (rn, sn) = (self.rn, self.sn);
        let at = |x: R| ray.g_at(x, rn, sn);
        let t_err = gamma::<R>(8) * (ray.s.abs() + self.s / ray.l);
        let accept = |t: R| t > t_min && t < t_max && t > t_err && t.is_finite();
        let mut ga = g_lo;
        for i in 1..cuts.len() {
            let gb = at(cuts[i]).0;
            let skip = i == 1 && origin_on_surface;
            if !skip && (ga < R::ZERO) != (gb < R::ZERO) && gb != R::ZERO {
                let x = if ga == R::ZERO {
                    cuts[i - 1]
                } else {
                    rtsafe(cuts[i - 1], cuts[i], ga < R::ZERO, at)
                };
                let t = ray.s + x / ray.k;
                if accept(t) {
                    return Some(t);
                }
            } else if gb == R::ZERO {
                // A root exactly at a piece end: take it (not at the origin).
                let t = ray.s + cuts[i] / ray.k;
                if accept(t) {
                    return Some(t);
                }
            }
            ga = gb;
        }
        None
    }

    /// How close to the surface (a distance) an origin must be to count as
    /// lying on it: the error bound a hit point would have there (see
    /// [`Torus::surface`]; Σ|nᵢ| ≤ √3), plus the rounding of the local
    /// coordinates, γ₆|f|₁ (f = o − c).
    #[inline]
    fn origin_band(&self, o: V<R>, f: V<R>) -> R {
        gamma::<R>(2) * abs1(o) + gamma::<R>(6) * abs1(f) + gamma::<R>(24) * self.s
    }

    /// The hit point at `t`, reprojected onto the surface (along the line
    /// from the nearest point of the core circle), with its error bound
    /// γ₁₂·(R + r) + γ₂|pᵢ|: the projection, the frame's rounding and the
    /// local-to-world sum, then the one addition of the centre.
    pub fn surface(&self, o: V<R>, d: V<R>, t: R) -> Surface<R> {
        let f = sub(o, self.c);
        let pl = add(to_local(&self.frame, f), scale(to_local(&self.frame, d), t));
        let rho = (pl[0] * pl[0] + pl[1] * pl[1]).sqrt();
        // Nearest point of the core circle (any, on the axis).
        let (cx, cy) = if rho > R::ZERO {
            (pl[0] * (self.big / rho), pl[1] * (self.big / rho))
        } else {
            (self.big, R::ZERO)
        };
        let v = [pl[0] - cx, pl[1] - cy, pl[2]];
        let vl = dot(v, v).sqrt();
        let nl = if vl > R::ZERO {
            scale(v, R::ONE / vl)
        } else {
            [cx / self.big, cy / self.big, R::ZERO]
        };
        let local = [
            cx + self.small * nl[0],
            cy + self.small * nl[1],
            self.small * nl[2],
        ];
        let p = add(self.c, to_world(&self.frame, local));
        let kk = gamma::<R>(12) * self.s;
        let g2 = gamma::<R>(2);
        let p_err = std::array::from_fn(|i| kk + g2 * p[i].abs());
        Surface {
            p,
            p_err,
            n: to_world(&self.frame, nl),
            local,
        }
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

    fn pair(c: [f32; 3], axis: [f32; 3], big: f32, small: f32) -> (Torus<f32>, Torus<f64>) {
        let c = c.map(f64::from);
        let a = axis.map(f64::from);
        (
            Torus::new(c, a, big as f64, small as f64),
            Torus::new(c, a, big as f64, small as f64),
        )
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

    /// Signed distance of a point from the exact (f64) torus.
    fn surf_dist(g: &Torus<f64>, p: [f64; 3]) -> f64 {
        let l = to_local(&g.frame, sub(p, g.c));
        let rho = (l[0] * l[0] + l[1] * l[1]).sqrt();
        ((rho - g.big).hypot(l[2])) - g.small
    }

    /// The exact nearest hit, by brute force in f64: sample the signed
    /// distance densely along the ray inside the bounding sphere and bisect
    /// the sign changes. An independent check of the f64 solver.
    fn brute_force(g: &Torus<f64>, o: [f64; 3], d: [f64; 3]) -> Option<f64> {
        let n = 20_000;
        let ld = norm64(d);
        let f = sub(o, g.c);
        let s = -dot(f, d) / (ld * ld);
        let h = g.s / ld * 1.001;
        let (a, b) = ((s - h).max(0.0), s + h);
        if a >= b {
            return None;
        }
        let at = |t: f64| surf_dist(g, add(o, scale(d, t)));
        let mut prev = (a, at(a));
        for i in 1..=n {
            let t = a + (b - a) * i as f64 / n as f64;
            let v = at(t);
            if (v < 0.0) != (prev.1 < 0.0) {
                let (mut x0, mut x1) = (prev.0, t);
                for _ in 0..60 {
                    let m = 0.5 * (x0 + x1);
                    if (at(m) < 0.0) == (prev.1 < 0.0) {
                        x0 = m;
                    } else {
                        x1 = m;
                    }
                }
                if x0 > 0.0 {
                    return Some(0.5 * (x0 + x1));
                }
            }
            prev = (t, v);
        }
        None
    }

    const CASES: [([f32; 3], [f32; 3], f32, f32); 4] = [
        ([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0, 0.25),
        ([0.5, -0.25, 1.0], [0.3, 1.7, -0.6], 1.0, 0.5),
        ([1e3, -2e3, 5e2], [3.0, 1.0, -2.0], 2.0, 0.1),
        ([1e2, 1e2, 0.0], [0.0, 0.0, 1.0], 1e-2, 2e-3),
    ];

    #[test]
    fn head_on_hole_and_axis() {
        let (f, _) = pair([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0, 0.25);
        let inf = f32::INFINITY;
        // Along the equator's diameter from outside: outer wall at 5 - 1.25.
        let t = f
            .intersect([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], 0.0, inf)
            .unwrap();
        assert!((t - 3.75).abs() < 1e-6, "{t}");
        // From inside the tube: its inner wall (x = 0.75), then nothing closer.
        let t = f
            .intersect([0.0, 0.0, 1.0], [0.0, 0.0, -1.0], 0.0, inf)
            .unwrap();
        assert!((t - 0.25).abs() < 1e-6, "{t}");
        // From the hole's centre, outwards: the inner equator at 0.75.
        let t = f
            .intersect([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, inf)
            .unwrap();
        assert!((t - 0.75).abs() < 1e-6, "{t}");
        // Along the axis, through the hole: never a hit.
        assert!(f
            .intersect([0.0, 5.0, 0.0], [0.0, -1.0, 0.0], 0.0, inf)
            .is_none());
        assert!(f
            .intersect([0.0, -5.0, 0.0], [0.0, 1.0, 0.0], 0.0, inf)
            .is_none());
        // Through the hole, slanted, missing the tube.
        assert!(f
            .intersect([0.2, 5.0, 0.1], [0.1, -10.0, 0.2], 0.0, inf)
            .is_none());
        // Over the top of the tube (y = 0.3 > r) and just touching below it.
        assert!(f
            .intersect([-5.0, 0.3, 0.0], [1.0, 0.0, 0.0], 0.0, inf)
            .is_none());
        let t = f
            .intersect([-5.0, 0.2, 0.0], [1.0, 0.0, 0.0], 0.0, inf)
            .unwrap();
        let x = -1.0 - (0.25f32 * 0.25 - 0.2 * 0.2).sqrt();
        assert!((t - (x + 5.0)).abs() < 1e-5, "{t}");
        // Open interval at t_max.
        assert!(f
            .intersect([0.0, 0.0, 5.0], [0.0, 0.0, -1.0], 0.0, 3.75)
            .is_none());
    }

    /// Rays through the hole at random angles and offsets, and along the
    /// axis from far away: the f32 routine agrees with the f64 one and with
    /// a brute-force f64 search.
    #[test]
    fn hole_and_axis_rays() {
        let (f, g) = pair([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0, 0.3);
        let mut rng = RngState::seeded(77);
        let (mut through, mut band) = (0, 0);
        for i in 0..5_000 {
            // From above, aimed at a point of the hole (radius < 0.7).
            let a = rng.range_f32(0.0, std::f32::consts::TAU);
            let rr = 0.69 * rng.next_f32().sqrt();
            let target = [rr * a.cos(), rr * a.sin(), 0.0];
            // Steep rays from far above, and slanted ones from close by
            // (some of which clip the inside of the tube).
            let z = if i % 2 == 0 {
                rng.range_f32(10.0, 1e4)
            } else {
                rng.range_f32(0.5, 10.0)
            };
            let o = [rng.range_f32(-2.0, 2.0), rng.range_f32(-2.0, 2.0), z];
            let d = sub(target, o);
            let hf = f.intersect(o, d, 0.0, f32::INFINITY);
            let hg = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY);
            let bf = brute_force(&g, f64v(o), f64v(d));
            assert_eq!(hg.is_some(), bf.is_some(), "f64 {hg:?} brute {bf:?}");
            if hf.is_some() != hg.is_some() {
                // Only a graze of the tube.
                let tt = hg.unwrap_or_else(|| hf.map_or(0.0, f64::from));
                let s = g.surface(f64v(o), f64v(d), tt);
                let cos = dot(f64v(d), s.n).abs() / norm64(f64v(d));
                assert!(cos < 2e-3, "f32 {hf:?} f64 {hg:?} from {o:?}");
                band += 1;
            }
            if let (Some(a), Some(b)) = (hg, bf) {
                assert!((a - b).abs() <= 1e-9 * b, "{a} {b}");
            }
            if hf.is_none() {
                through += 1;
            }
        }
        println!("hole: {through} of 5000 rays pass through, {band} grazing mismatches");
        assert!(through > 1000 && through < 5000);
        assert!(band < 5);
        // Along the axis from far away, both directions, and slightly off it.
        for z in [1e1f32, 1e3, 1e6] {
            for dz in [-1.0f32, 1.0] {
                for off in [0.0f32, 1e-3, 0.5] {
                    let o = [off, 0.0, -dz * z];
                    let d = [0.0, 0.0, dz];
                    assert!(f.intersect(o, d, 0.0, f32::INFINITY).is_none());
                }
            }
        }
    }

    /// Random rays aimed near the torus: f32 against f64 (and the f64 solver
    /// against brute force on a subset). Mismatches only near silhouettes
    /// (grazing); t and the normal agree.
    #[test]
    fn f32_matches_f64_on_random_rays() {
        let mut rng = RngState::seeded(41);
        for (c, axis, big, small) in CASES {
            let (f, g) = pair(c, axis, big, small);
            let size = big + small;
            let (mut hits, mut band, mut worst_t, mut worst_abs, mut worst_n) =
                (0, 0, 0.0f64, 0.0f64, 0.0f64);
            let total = 30_000;
            for i in 0..total {
                let o: [f32; 3] =
                    std::array::from_fn(|i| c[i] + 3.0 * size * rng.range_f32(-1.0, 1.0));
                let tg: [f32; 3] = std::array::from_fn(|i| c[i] + size * rng.range_f32(-1.0, 1.0));
                let d = sub(tg, o);
                let hf = f.intersect(o, d, 0.0, f32::INFINITY);
                let hg = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY);
                if i % 20 == 0 && c == CASES[0].0 {
                    let bf = brute_force(&g, f64v(o), f64v(d));
                    match (hg, bf) {
                        (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-6 * b, "{a} {b}"),
                        (None, None) => {}
                        _ => panic!("f64 solver {hg:?} against brute force {bf:?}"),
                    }
                }
                match (hf, hg) {
                    (Some(a), Some(b)) if (a as f64 - b).abs() <= 1e-4 * b => {
                        hits += 1;
                        let sf = f.surface(o, d, a);
                        let sg = g.surface(f64v(o), f64v(d), b);
                        let ld = norm64(f64v(d));
                        let cos = dot(f64v(d), sg.n).abs() / ld;
                        let scale = norm64(sub(f64v(o), g.c)) + size as f64;
                        worst_abs = worst_abs.max((a as f64 - b).abs() * ld * cos / scale);
                        if cos > 0.05 && b * ld > 0.1 * size as f64 {
                            worst_t = worst_t.max((a as f64 - b).abs() / b);
                        }
                        let dp = norm64(sub(f64v(sf.p), sg.p));
                        let dn = norm64(sub(f64v(sf.n), sg.n));
                        worst_n = worst_n.max(dn / (dp / g.small + 1e-6));
                    }
                    (None, None) => {}
                    (a, b) => {
                        let tt = b.unwrap_or_else(|| a.map_or(0.0, f64::from));
                        let s = g.surface(f64v(o), f64v(d), tt);
                        let cos = dot(f64v(d), s.n).abs() / norm64(f64v(d));
                        let at_origin = tt * norm64(f64v(d)) < 1e-5 * norm64(f64v(o));
                        assert!(
                            cos < 2e-3 || at_origin,
                            "mismatch off the band: f32 {a:?} f64 {b:?}, cos {cos:e}, o {o:?} d {d:?}"
                        );
                        band += 1;
                    }
                }
            }
            println!(
                "torus R {big} r {small} at {c:?}: {hits} hits of {total}, {band} band mismatches, \
                 max rel t err {worst_t:e} (|cos| > 0.05, t|d| > size / 10), \
                 max |dt||d||cos| / (|o - c| + size) {worst_abs:e}, \
                 max normal err / (|dp|/r + 1e-6) {worst_n:e}"
            );
            assert!(hits > total / 20, "{hits}");
            assert!(band * 500 < total, "{band}");
            assert!(worst_t < 1e-5, "{worst_t}");
            assert!(worst_abs < 1e-5, "{worst_abs}");
            assert!(worst_n < 4.0, "{worst_n}");
        }
    }

    /// docs/numerics.md Q1 for the torus: camera at the origin, the torus at
    /// distance D, rays over a disk of radius 1.5 (R + r) around its centre.
    /// Hit/miss against f64 on the same f32 inputs, and t.
    #[test]
    fn far_torus_classification_matches_f64() {
        let mut rng = RngState::seeded(17);
        for (dist, limit) in [(10.0f32, 1e-3), (1e4, 1e-3)] {
            let c = [0.6 * dist, 0.0, 0.8 * dist];
            let (f, g) = pair(c, [0.3, 1.0, 0.2], 1.0, 0.25);
            let (mut mism, mut hits, mut worst) = (0, 0, 0.0f64);
            let n = 20_000;
            for _ in 0..n {
                let (a, b) = (rng.range_f32(-1.0, 1.0), rng.range_f32(-1.0, 1.0));
                let target = [c[0] + 1.875 * a, c[1] + 1.875 * b, c[2]];
                let d = Vec3::from(target).normalize().to_array();
                let hf = f.intersect([0.0; 3], d, 0.0, f32::INFINITY);
                let hg = g.intersect([0.0; 3], f64v(d), 0.0, f64::INFINITY);
                match (hf, hg) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        worst = worst.max((a as f64 - b).abs() / b);
                    }
                    (None, None) => {}
                    _ => mism += 1,
                }
            }
            println!(
                "far torus at {dist}: {hits} hits of {n}, {mism} mismatches, max rel t err {worst:e}"
            );
            assert!((mism as f64) < limit * n as f64, "{mism}");
            assert!(hits > n / 10);
        }
    }

    /// Hit points lie within their bound of the exact surface; rays spawned
    /// off them (offset as the renderer does, and from the raw point away
    /// from tangency) never stop short of half the f64 distance.
    #[test]
    fn origins_on_the_surface() {
        let mut rng = RngState::seeded(12);
        for (c, axis, big, small) in CASES {
            let (f, g) = pair(c, axis, big, small);
            let size = big + small;
            let (mut pts, mut short, mut rays) = (0, 0, 0);
            for _ in 0..4_000 {
                let o: [f32; 3] =
                    std::array::from_fn(|i| c[i] + 3.0 * size * rng.range_f32(-1.0, 1.0));
                let tg: [f32; 3] = std::array::from_fn(|i| c[i] + size * rng.range_f32(-1.0, 1.0));
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
                "torus R {big} at {c:?}: {pts} points within bound, {rays} rays, {short} self-hits"
            );
            assert!(pts > 400);
            assert_eq!(short, 0);
        }
    }

    /// Rays tangent to the outer equator and to the top of the tube, offset
    /// by ±1e-3 r: f32 agrees with f64 outside a band of 1e-4 r.
    #[test]
    fn grazing_rays() {
        let (f, g) = pair([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 1.0, 0.25);
        let mut mism = 0;
        let n = 4000;
        for i in 0..n {
            let e = (i as f32 / n as f32 - 0.5) * 2e-3 * 0.25;
            // Tangent to the outer equator at (1.25, 0, 0), along y.
            let rays = [
                ([1.25 + e, -5.0, 0.0], [0.0, 1.0, 0.0]),
                // Over the top of the tube at (1, 0, 0.25), along y.
                ([1.0, -5.0, 0.25 + e], [0.0, 1.0, 0.0]),
            ];
            for (o, d) in rays {
                let a = f.intersect(o, d, 0.0, f32::INFINITY).is_some();
                let b = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY).is_some();
                if a != b {
                    assert!(e.abs() < 0.25e-4, "mismatch at {e:e}");
                    mism += 1;
                }
                if e.abs() > 1e-7 {
                    assert_eq!(b, e < 0.0, "f64 at {e:e} {o:?}");
                }
            }
        }
        println!("grazing: {mism} mismatches of {}", 2 * n);
    }
}
#[cfg(test)]
mod next_hit_tests {
    use super::*;

    /// Asking for the next hit after the last one, as CSG and parity
    /// counts do, never finds the last one again (it did, a few ulps past
    /// `t_min`, before the interval's start was tested for lying on the surface).
    #[test]
    fn the_next_hit_after_a_hit_is_another_one() {
        let t: Torus<f32> = Torus::new([0.0; 3], [0.0, 1.0, 0.0], 1.0, 0.25);
        let o = [0.20824552f32, 0.2485528, 0.84028697];
        let d = [0.6823708f32, -0.20046304, -0.70298266];
        let mut hits = Vec::new();
        let mut t_min = 0.0f32;
        while let Some(x) = t.intersect(o, d, t_min, f32::INFINITY) {
            hits.push(x);
            t_min = x;
            assert!(hits.len() <= 4, "{hits:?}");
        }
        assert!(!t.contains(o));
        assert_eq!(
            hits.len() % 2,
            0,
            "an outside point crosses an even number of times: {hits:?}"
        );
        assert!(hits.windows(2).all(|w| w[1] - w[0] > 1e-3), "{hits:?}");
    }
}
