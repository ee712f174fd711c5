//! Small vector helpers on `[R; 3]` over [`Real`], so that one shape routine
//! instantiates for f32 (the plugin) and f64 (its reference), and the f64
//! set-up that analytic shapes share: orthonormal frames and f32 bounds
//! rounded outwards.
//!
//! Why arrays rather than glam: glam has no vector generic over the float
//! type, and the f64 reference must run the very same code as the f32 path.

use super::Real;

/// A 3-vector of `R`.
pub type V<R> = [R; 3];

/// a · b.
#[inline]
pub fn dot<R: Real>(a: V<R>, b: V<R>) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a − b.
#[inline]
pub fn sub<R: Real>(a: V<R>, b: V<R>) -> V<R> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// a + b.
#[inline]
pub fn add<R: Real>(a: V<R>, b: V<R>) -> V<R> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// k·a.
#[inline]
pub fn scale<R: Real>(a: V<R>, k: R) -> V<R> {
    [a[0] * k, a[1] * k, a[2] * k]
}

/// Σ|aᵢbᵢ|: the magnitude a dot product's rounding error is relative to.
#[inline]
pub fn abs_dot<R: Real>(a: V<R>, b: V<R>) -> R {
    (a[0] * b[0]).abs() + (a[1] * b[1]).abs() + (a[2] * b[2]).abs()
}

/// Local coordinates of `a` in the frame (u, v, w).
#[inline]
pub fn to_local<R: Real>(f: &[V<R>; 3], a: V<R>) -> V<R> {
    [dot(f[0], a), dot(f[1], a), dot(f[2], a)]
}

/// World vector of local coordinates `l` in the frame (u, v, w).
#[inline]
pub fn to_world<R: Real>(f: &[V<R>; 3], l: V<R>) -> V<R> {
    std::array::from_fn(|i| f[0][i] * l[0] + f[1][i] * l[1] + f[2][i] * l[2])
}

/// a × b in f64.
#[inline]
pub fn cross64(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// |a| in f64.
#[inline]
pub fn norm64(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// A right-handed orthonormal frame (u, v, w) with w = `axis` / |axis|,
/// computed in f64 (then rounded once to `R`): u × v = w.
pub fn frame64(axis: [f64; 3]) -> [[f64; 3]; 3] {
    let l = norm64(axis);
    let w = axis.map(|c| c / l);
    // Cross with the coordinate axis least aligned with w.
    let i = (0..3)
        .min_by(|&a, &b| w[a].abs().total_cmp(&w[b].abs()))
        .unwrap_or(0);
    let mut e = [0.0; 3];
    e[i] = 1.0;
    let u = cross64(e, w);
    let lu = norm64(u);
    let u = u.map(|c| c / lu);
    let v = cross64(w, u);
    [u, v, w]
}

/// Round an f64 vector to `R`.
#[inline]
pub fn cvt<R: Real>(a: [f64; 3]) -> V<R> {
    a.map(R::from_f64)
}

/// Half the extent, along each world axis, of a circle of radius `r` in the
/// plane normal to the unit vector `w`: r·√(1 − wᵢ²).
pub fn circle_extent(w: [f64; 3], r: f64) -> [f64; 3] {
    w.map(|c| r * (1.0 - c * c).max(0.0).sqrt())
}

/// A box around `[lo, hi]` (computed in f64) rounded outwards to f32, with a
/// relative margin for the rounding of the stored f32 parameters.
pub fn f32_box(lo: [f64; 3], hi: [f64; 3]) -> ([f32; 3], [f32; 3]) {
    let m = lo
        .iter()
        .chain(hi.iter())
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    let pad = m * 4.0 * f32::EPSILON as f64;
    let down = |x: f64| {
        let f = (x - pad) as f32;
        if (f as f64) > x - pad {
            f.next_down()
        } else {
            f
        }
    };
    let up = |x: f64| {
        let f = (x + pad) as f32;
        if (f as f64) < x + pad {
            f.next_up()
        } else {
            f
        }
    };
    (lo.map(down), hi.map(up))
}
