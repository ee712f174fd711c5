//! Ray/sphere intersection in the formulation of Haines, Günther and
//! Akenine-Möller (Ray Tracing Gems ch. 7): the discriminant from
//! `r² − |f − (f·d)d/|d|²|²` and the stable root `q`, which stays accurate when
//! the sphere is far away or tiny compared with the distance (docs/numerics.md Q1, Q2).

use super::{gamma, max_of, Real};

/// Both roots of a ray/sphere intersection, in ascending order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereHit<R> {
    /// Near root.
    pub t0: R,
    /// Far root.
    pub t1: R,
    /// A bound on the absolute error of either root: roots whose magnitude is
    /// below it are indistinguishable from the origin lying on the surface.
    pub t_err: R,
}

#[inline]
fn dot<R: Real>(a: [R; 3], b: [R; 3]) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Intersect the ray `o + t d` (any length `d`) with the sphere `(c, r)`.
/// Returns both roots (which may be negative), or `None` when the ray misses.
#[inline]
pub fn intersect_sphere<R: Real>(c: [R; 3], r: R, o: [R; 3], d: [R; 3]) -> Option<SphereHit<R>> {
    let f = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
    let a = dot(d, d);
    if !(a > R::ZERO) {
        return None;
    }
    let b_half = -dot(f, d); // b' = -(f·d)
    let c_coef = dot(f, f) - r * r;
    // |f - (f·d / a) d|² computed directly: no cancellation of b² against 4ac.
    let s = (-b_half) / a;
    let l = [f[0] - s * d[0], f[1] - s * d[1], f[2] - s * d[2]];
    let disc = a * (r * r - dot(l, l));
    if !(disc >= R::ZERO) {
        return None;
    }
    let q = b_half + b_half.signum1() * disc.sqrt();
    let (mut t0, mut t1) = if q == R::ZERO {
        // Origin at the centre's projection with zero discriminant: tangent at t = 0.
        (R::ZERO, R::ZERO)
    } else {
        (c_coef / q, q / a)
    };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if !(t0.is_finite() && t1.is_finite()) {
        return None;
    }
    // Each root carries a few roundings relative to the larger one's scale;
    // |f|/|d| bounds the distance scale of the problem.
    let scale = max_of(max_of(t0.abs(), t1.abs()), (dot(f, f) / a).sqrt());
    let t_err = gamma::<R>(7) * scale;
    Some(SphereHit { t0, t1, t_err })
}

/// The nearest root accepted by `(t_min, t_max)`, skipping roots within the
/// error band around 0 (the origin lies on the surface there, pbrt-v4's
/// "t lower bound ≤ 0" rule).
#[inline]
pub fn nearest_root<R: Real>(h: &SphereHit<R>, t_min: R, t_max: R) -> Option<R> {
    [h.t0, h.t1]
        .into_iter()
        .find(|&t| t > t_min && t < t_max && t > h.t_err && t.is_finite())
}

/// The hit point `o + t d` reprojected onto the sphere, and its error bound
/// (per component): `γ₅|p − c|` for the reprojection plus one rounding of the
/// sum with the centre.
#[inline]
pub fn sphere_point_and_error<R: Real>(
    c: [R; 3],
    r: R,
    o: [R; 3],
    d: [R; 3],
    t: R,
) -> ([R; 3], [R; 3]) {
    let mut pl = [
        o[0] + t * d[0] - c[0],
        o[1] + t * d[1] - c[1],
        o[2] + t * d[2] - c[2],
    ];
    let len = dot(pl, pl).sqrt();
    if len > R::ZERO {
        let k = r / len;
        pl = [pl[0] * k, pl[1] * k, pl[2] * k];
    }
    let p = [pl[0] + c[0], pl[1] + c[1], pl[2] + c[2]];
    let g5 = gamma::<R>(5);
    let g1 = gamma::<R>(1);
    let err = std::array::from_fn(|i| g5 * pl[i].abs() + g1 * p[i].abs());
    (p, err)
}

/// An f64 bound rounded up to f32.
#[inline]
fn up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// [`intersect_sphere`] on f32 inputs, evaluated in f64 and rounded once:
/// what the `sphere` plugin uses.
///
/// Why: in f32 even the RTG-7 form loses the far sphere: `f − s·d` rounds at
/// the scale of the distance, and `|f|² − r²` cancels for a huge sphere seen
/// from near its surface (a 1e6 ground 3 units below the camera: t off by
/// 0.5 %), so silhouettes of spheres 1e5–1e6 radii away, and tiny spheres,
/// classify differently from the f64 reference (numerics.md Q1–Q3, X2).
/// The inputs convert exactly, so this is the f64 reference itself, and a
/// scalar f64 evaluation costs about what the f32 one does (BENCHMARKS.md).
/// The band of [`nearest_root`] becomes the f64 one, a few f64 ulps, so an
/// origin just above a huge sphere still sees it.
#[inline]
pub fn intersect_sphere_in_f64(
    c: [f32; 3],
    r: f32,
    o: [f32; 3],
    d: [f32; 3],
) -> Option<SphereHit<f32>> {
    let w = |a: [f32; 3]| a.map(f64::from);
    let h = intersect_sphere::<f64>(w(c), r as f64, w(o), w(d))?;
    let (t0, t1) = (h.t0 as f32, h.t1 as f32);
    (t0.is_finite() && t1.is_finite()).then_some(SphereHit {
        t0,
        t1,
        t_err: up(h.t_err),
    })
}

/// [`sphere_point_and_error`] evaluated in f64 and rounded once: the point
/// is on the sphere to f64 precision, so its bound is its own rounding to
/// f32 (about an ulp of |p|), not an ulp of the centre's distance — a point
/// on a 1e6 sphere near the world's origin is as exact as the origin allows.
#[inline]
pub fn sphere_point_in_f64(
    c: [f32; 3],
    r: f32,
    o: [f32; 3],
    d: [f32; 3],
    t: f32,
) -> ([f32; 3], [f32; 3]) {
    let w = |a: [f32; 3]| a.map(f64::from);
    let (p, e) = sphere_point_and_error::<f64>(w(c), r as f64, w(o), w(d), t as f64);
    let pf = p.map(|x| x as f32);
    let delta = std::array::from_fn::<f64, 3, _>(|i| (pf[i] as f64 - p[i]).abs());
    // Rounding moves the point along the surface too, and a sphere curves
    // away from its tangent plane by |δ|²/2r: on a tiny sphere that can
    // exceed the normal part of δ (numerics.md Q3's ant).
    let curve = (delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]) / (r as f64);
    let err = std::array::from_fn(|i| up(e[i] + delta[i] + curve));
    (pf, err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_sphere_head_on() {
        let h =
            intersect_sphere([0.0f32, 0.0, 0.0], 1.0, [0.0, 0.0, -5.0], [0.0, 0.0, 1.0]).unwrap();
        assert_eq!((h.t0, h.t1), (4.0, 6.0));
        assert_eq!(nearest_root(&h, 0.0, f32::INFINITY), Some(4.0));
        assert_eq!(nearest_root(&h, 4.0, f32::INFINITY), Some(6.0));
        assert_eq!(nearest_root(&h, 0.0, 4.0), None);
    }

    #[test]
    fn unnormalised_direction_keeps_parameterisation() {
        let h =
            intersect_sphere([0.0f32, 0.0, 0.0], 1.0, [0.0, 0.0, -5.0], [0.0, 0.0, 2.0]).unwrap();
        assert_eq!((h.t0, h.t1), (2.0, 3.0));
    }

    /// docs/numerics.md Q1: a unit sphere at distance 1e4 — hit/miss classification
    /// against the f64 evaluation of the same formula on the same f32 inputs.
    #[test]
    fn far_sphere_classification_matches_f64() {
        let mut seed = rtk_abi::RngState::seeded(7);
        let dist = 1e4f32;
        let c = [dist * 0.6, dist * 0.0, dist * 0.8];
        let mut mismatch = 0;
        let n = 20_000;
        for _ in 0..n {
            let (a, b) = (seed.next_f64() * 2.0 - 1.0, seed.next_f64() * 2.0 - 1.0);
            let target = [c[0] + 1.5 * a as f32, c[1] + 1.5 * b as f32, c[2]];
            let len =
                (target[0] * target[0] + target[1] * target[1] + target[2] * target[2]).sqrt();
            let d = [target[0] / len, target[1] / len, target[2] / len];
            let f = intersect_sphere(c, 1.0f32, [0.0; 3], d).is_some();
            let dd = d.map(|x| x as f64);
            let g = intersect_sphere(c.map(|x| x as f64), 1.0f64, [0.0; 3], dd).is_some();
            if f != g {
                mismatch += 1;
            }
        }
        // docs/numerics.md: RTG-7 measured 8.5e-5 at 1e4 (textbook: 54 %).
        assert!(
            (mismatch as f64) / (n as f64) < 1e-3,
            "mismatch {mismatch}/{n}"
        );
    }

    #[test]
    fn reprojected_point_is_within_its_error_bound_of_f64() {
        let mut seed = rtk_abi::RngState::seeded(3);
        for _ in 0..10_000 {
            let c = [1e3f32, -2e3, 5e2];
            let o = [0.0f32, 0.0, 0.0];
            let t = [
                c[0] + (seed.next_f64() as f32 - 0.5),
                c[1] + (seed.next_f64() as f32 - 0.5),
                c[2],
            ];
            let l = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
            let d = [t[0] / l, t[1] / l, t[2] / l];
            let Some(h) = intersect_sphere(c, 1.0f32, o, d) else {
                continue;
            };
            let Some(tt) = nearest_root(&h, 0.0, f32::INFINITY) else {
                continue;
            };
            let (p, err) = sphere_point_and_error(c, 1.0f32, o, d, tt);
            // The reprojected f32 point must lie on the sphere within its bound.
            let pl: Vec<f64> = (0..3).map(|i| p[i] as f64 - c[i] as f64).collect();
            let dist = (pl[0] * pl[0] + pl[1] * pl[1] + pl[2] * pl[2]).sqrt();
            let e = (err[0] as f64).hypot(err[1] as f64).hypot(err[2] as f64);
            assert!(
                (dist - 1.0).abs() <= e,
                "off surface by {} > {}",
                (dist - 1.0).abs(),
                e
            );
        }
    }
}
