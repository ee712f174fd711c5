//! The watertight ray/triangle test of Woop, Benthin and Wald (JCGT 2013), in
//! pbrt-v4's form: shear the triangle into ray space, compute the edge
//! functions with one rounding less, and accept on consistent signs. Two
//! rechecks in f64 keep it watertight where f32 cannot decide
//! (docs/numerics.md T1–T4):
//! - an edge function that is exactly zero in f32 (the ray runs along an
//!   edge or through a vertex) is recomputed in f64 (pbrt-v4);
//! - a hit whose `t` lies within its own error bound of the origin is
//!   rechecked in f64 instead of being rejected, which pbrt does and which
//!   opens rare holes at vertices with nearly edge-on fans (docs/numerics.md rule 4).

use super::{gamma, Real};

/// A triangle hit: `t` and the barycentrics of the three vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit<R> {
    /// Ray parameter.
    pub t: R,
    /// Barycentric weights of p0, p1, p2 (sum to 1).
    pub b: [R; 3],
}

#[inline]
fn sub<R: Real>(a: [R; 3], b: [R; 3]) -> [R; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn cross<R: Real>(a: [R; 3], b: [R; 3]) -> [R; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn mx<R: Real>(a: R, b: R) -> R {
    if b > a {
        b
    } else {
        a
    }
}

/// Result of the core test: a hit, no hit, or "f32 cannot decide".
enum Core<R> {
    /// A hit and the bound on its t's error.
    Hit(TriHit<R>, R),
    Miss,
    /// Inside the triangle, at a t that came out ≤ 0 but within its error
    /// bound of 0: the plane may lie just ahead of the origin.
    Near(TriHit<R>),
}

/// What the test computes from the ray alone: the axis permutation that
/// makes the direction's largest component z, and the shear that maps the
/// direction to +z. Computed once per ray ([`RayShear::new`]) when many
/// triangles are tested against one ray; the per-triangle work is the same
/// arithmetic on the same values, so the results are bit-identical.
#[derive(Clone, Copy, Debug)]
pub struct RayShear<R> {
    o: [R; 3],
    k: [usize; 3],
    s: [R; 3],
    /// The permuted direction's z is zero (a zero direction): nothing is hit.
    flat: bool,
}

impl<R: Real> RayShear<R> {
    /// The shear of the ray `o + t·d`.
    #[inline]
    pub fn new(o: [R; 3], d: [R; 3]) -> Self {
        // Permute so that the ray's largest direction component is z.
        let ad = [d[0].abs(), d[1].abs(), d[2].abs()];
        // Selects, not branches: an incoherent ray's dominant axis is a coin
        // toss the branch predictor loses.
        use std::hint::select_unpredictable as pick;
        let x_over_y = ad[0] > ad[1];
        let (k01, a01) = (pick(x_over_y, 0, 1), pick(x_over_y, ad[0], ad[1]));
        let kz = pick(a01 > ad[2], k01, 2);
        let kx = pick(kz == 2, 0, kz + 1);
        let ky = pick(kx == 2, 0, kx + 1);
        let dp = [d[kx], d[ky], d[kz]];
        let flat = dp[2] == R::ZERO;
        RayShear {
            o,
            k: [kx, ky, kz],
            s: [-dp[0] / dp[2], -dp[1] / dp[2], R::ONE / dp[2]],
            flat,
        }
    }
}

impl<R: Copy> RayShear<R> {
    /// The origin, the axis permutation (x, y, z of the sheared space) and
    /// the shear: for a SIMD version of the same test.
    #[inline]
    pub fn parts(&self) -> ([R; 3], [usize; 3], [R; 3]) {
        (self.o, self.k, self.s)
    }
}

/// Is the triangle degenerate (zero area in this precision)? Such triangles
/// are never hit (T3); an aggregate may leave them out of its structure.
#[inline]
pub fn is_degenerate<R: Real>(p: &[[R; 3]; 3]) -> bool {
    let n = cross(sub(p[2], p[0]), sub(p[1], p[0]));
    !(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > R::ZERO)
}

#[inline]
fn core<R: Real>(
    o: [R; 3],
    d: [R; 3],
    p: [[R; 3]; 3],
    t_max: R,
    exact_zeros_in_f64: bool,
) -> Core<R> {
    if is_degenerate(&p) {
        return Core::Miss;
    }
    core_sheared(&RayShear::new(o, d), p, t_max, exact_zeros_in_f64)
}

/// The per-triangle part of the test, for a non-degenerate triangle.
#[inline]
fn core_sheared<R: Real>(
    r: &RayShear<R>,
    p: [[R; 3]; 3],
    t_max: R,
    exact_zeros_in_f64: bool,
) -> Core<R> {
    let o = r.o;
    let [kx, ky, kz] = r.k;
    let mut t = [sub(p[0], o), sub(p[1], o), sub(p[2], o)];
    for v in t.iter_mut() {
        *v = [v[kx], v[ky], v[kz]];
    }
    if r.flat {
        return Core::Miss;
    }
    let [sx, sy, sz] = r.s;
    for v in t.iter_mut() {
        v[0] = v[0] + sx * v[2];
        v[1] = v[1] + sy * v[2];
    } // Plain products, not FMA-based differences: without a target FMA,
      // `mul_add` is a library call (BENCHMARKS.md, "Watertight test"). They stay
      // watertight: a shared edge's function is computed from the same operands
      // in both triangles and comes out exactly negated; an exact zero goes to f64.
    let mut e0 = t[1][0] * t[2][1] - t[1][1] * t[2][0];
    let mut e1 = t[2][0] * t[0][1] - t[2][1] * t[0][0];
    let mut e2 = t[0][0] * t[1][1] - t[0][1] * t[1][0];
    if exact_zeros_in_f64 && (e0 == R::ZERO || e1 == R::ZERO || e2 == R::ZERO) {
        // pbrt-v4: redo the edge functions in f64 from the same sheared
        // f32 coordinates. Products of f32s are exact in f64, so each sign
        // is exact, and a shared edge still comes out exactly negated in
        // the neighbour: the decision stays watertight (T2-T4).
        let w =
            |a: R, b: R, c: R, d: R| R::from_f64(a.to_f64() * b.to_f64() - c.to_f64() * d.to_f64());
        e0 = w(t[1][0], t[2][1], t[1][1], t[2][0]);
        e1 = w(t[2][0], t[0][1], t[2][1], t[0][0]);
        e2 = w(t[0][0], t[1][1], t[0][1], t[1][0]);
    }
    if (e0 < R::ZERO || e1 < R::ZERO || e2 < R::ZERO)
        && (e0 > R::ZERO || e1 > R::ZERO || e2 > R::ZERO)
    {
        return Core::Miss;
    }
    let det = e0 + e1 + e2;
    if det == R::ZERO {
        return Core::Miss;
    }
    for v in t.iter_mut() {
        v[2] = v[2] * sz;
    }
    let ts = e0 * t[0][2] + e1 * t[1][2] + e2 * t[2][2];
    // pbrt-v4's bound on the error of t, in the scaled form (times |det|).
    let ts_err = || {
        let max_zt = mx(mx(t[0][2].abs(), t[1][2].abs()), t[2][2].abs());
        let max_xt = mx(mx(t[0][0].abs(), t[1][0].abs()), t[2][0].abs());
        let max_yt = mx(mx(t[0][1].abs(), t[1][1].abs()), t[2][1].abs());
        let dz = gamma::<R>(3) * max_zt;
        let dx = gamma::<R>(5) * (max_xt + max_zt);
        let dy = gamma::<R>(5) * (max_yt + max_zt);
        let two = R::ONE + R::ONE;
        let three = two + R::ONE;
        let de = two * (gamma::<R>(2) * max_xt * max_yt + dy * max_xt + dx * max_yt);
        let max_e = mx(mx(e0.abs(), e1.abs()), e2.abs());
        three * (gamma::<R>(3) * max_e * max_zt + de * max_zt + dz * max_e)
    };
    let inv = R::ONE / det;
    let hit = || TriHit {
        t: ts * inv,
        b: [e0 * inv, e1 * inv, e2 * inv],
    };
    // Compare in scaled form (no division yet); NaN-false throughout. A t
    // on the wrong side of 0 by less than its error is not a miss yet (the
    // rare path: the ray's line crosses the triangle behind the origin).
    let ahead = if det < R::ZERO {
        ts < R::ZERO
    } else {
        ts > R::ZERO
    };
    if !ahead {
        return if ts.abs() <= ts_err() {
            Core::Near(hit())
        } else {
            Core::Miss
        };
    }
    // Widened by more than the rounding of t = ts / det and of t_max · det,
    // so no hit whose computed t is below t_max is lost here (the callers
    // test t < t_max exactly): otherwise which of two hits an ulp apart is
    // nearest would depend on the order they are tested in.
    // A t within its error of 0 is not decided here either: the f64 t the
    // caller resolves (`resolve_t`) may still be below t_max.
    let bound = t_max * det * (R::ONE + gamma::<R>(4));
    if det < R::ZERO && !(ts >= bound) || det > R::ZERO && !(ts <= bound) {
        return if ts.abs() <= ts_err() {
            Core::Near(hit())
        } else {
            Core::Miss
        };
    }
    Core::Hit(hit(), ts_err() * inv.abs())
}

/// The f64 oracle: the same test in f64 on the (exactly converted) inputs.
pub fn intersect_triangle_f64(
    o: [f64; 3],
    d: [f64; 3],
    p: [[f64; 3]; 3],
    t_min: f64,
    t_max: f64,
) -> Option<TriHit<f64>> {
    match core(o, d, p, t_max, false) {
        Core::Hit(h, _) if h.t > t_min && h.t < t_max && h.t.is_finite() => Some(h),
        _ => None,
    }
}

/// The `t` of a hit whose inside/outside f32 has decided but whose `t` f32
/// cannot tell from 0 (rule 4): the plane's `t` in f64, and where even that
/// is within its bound of 0, the exact orientation (`hit_just_ahead`). Only
/// `t` is rechecked: the classification stays the f32 one, which the
/// triangle's neighbours share, so the mesh stays watertight.
#[cold]
fn resolve_t(o: [f32; 3], d: [f32; 3], p: [[f32; 3]; 3], t_min: f32, t_max: f32) -> Option<f32> {
    if let Some(k) = (0..3).find(|&k| p[0][k] == p[1][k] && p[1][k] == p[2][k]) {
        return axis_plane_t(o[k], d[k], p[0][k]).filter(|&t| t > t_min && t < t_max);
    }
    let w = |a: [f32; 3]| a.map(|x| x as f64);
    let (t64, dt64) = plane_t(w(o), w(d), p.map(w))?;
    let t = if t64 > dt64 {
        t64 as f32
    } else if t64 >= -dt64 && t_min <= 0.0 {
        hit_just_ahead(o, d, p)?
    } else {
        return None;
    };
    (t > t_min && t < t_max && t.is_finite()).then_some(t)
}

/// `t` at the plane `x_k = c` of an axis-aligned triangle (a wall or a
/// floor: all three vertices share coordinate k), whose sign is exact:
/// `c − o_k` in f64 is correctly rounded, so it is 0 only when the origin
/// lies in the plane (no hit, rule 4), and its sign is the true one. This
/// is what [`hit_just_ahead`] decides with an exact orientation test, for
/// the commonest case at a fraction of the cost: every ray leaving a floor
/// at y = 0 starts a denormal above it (rule 7's last ulp) and meets the
/// floor's other triangle at t ≈ 1e-45 (the Cornell box spent a fifth of
/// its time in the general test before this).
#[inline]
fn axis_plane_t(o: f32, d: f32, c: f32) -> Option<f32> {
    let t = (c as f64 - o as f64) / d as f64;
    // Positive by the exact sign, whatever the rounding to f32 made of it.
    (t > 0.0 && t.is_finite()).then(|| (t as f32).max(f32::from_bits(1)))
}

/// The ray's `t` at the triangle's plane and its error bound, computed as
/// the watertight test does (shear, edge functions, scaled `t`), in f64.
fn plane_t(o: [f64; 3], d: [f64; 3], p: [[f64; 3]; 3]) -> Option<(f64, f64)> {
    let r = RayShear::new(o, d);
    if r.flat {
        return None;
    }
    let [kx, ky, kz] = r.k;
    let mut t = [sub(p[0], o), sub(p[1], o), sub(p[2], o)];
    for v in t.iter_mut() {
        *v = [v[kx], v[ky], v[kz]];
    }
    let [sx, sy, sz] = r.s;
    for v in t.iter_mut() {
        v[0] += sx * v[2];
        v[1] += sy * v[2];
    }
    let e0 = t[1][0] * t[2][1] - t[1][1] * t[2][0];
    let e1 = t[2][0] * t[0][1] - t[2][1] * t[0][0];
    let e2 = t[0][0] * t[1][1] - t[0][1] * t[1][0];
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    for v in t.iter_mut() {
        v[2] *= sz;
    }
    let ts = e0 * t[0][2] + e1 * t[1][2] + e2 * t[2][2];
    let inv = 1.0 / det;
    let max_zt = mx(mx(t[0][2].abs(), t[1][2].abs()), t[2][2].abs());
    let max_xt = mx(mx(t[0][0].abs(), t[1][0].abs()), t[2][0].abs());
    let max_yt = mx(mx(t[0][1].abs(), t[1][1].abs()), t[2][1].abs());
    let dz = gamma::<f64>(3) * max_zt;
    let dx = gamma::<f64>(5) * (max_xt + max_zt);
    let dy = gamma::<f64>(5) * (max_yt + max_zt);
    let de = 2.0 * (gamma::<f64>(2) * max_xt * max_yt + dy * max_xt + dx * max_yt);
    let max_e = mx(mx(e0.abs(), e1.abs()), e2.abs());
    let dt = 3.0 * (gamma::<f64>(3) * max_e * max_zt + de * max_zt + dz * max_e) * inv.abs();
    Some((ts * inv, dt))
}

/// The `t` of a ray whose hit inside the triangle is too close to its origin
/// for f64 to resolve: positive, when the origin lies strictly on the side
/// of the plane the ray leaves from (Shewchuk's exact `orient3d`, via the
/// `robust` crate); `None` when it lies in the plane or behind it.
///
/// Why: a camera one denormal above a floor, looking down at a shallow
/// angle, meets the floor at t ≈ 1e-45, and the t bounds (f32 and f64
/// alike) scale with the triangle's coordinates, not with t: without an
/// exact test the floor vanishes from part of the image. The exact sign
/// keeps rule 4's other half: an origin exactly in the plane never hits.
#[cold]
fn hit_just_ahead(o: [f32; 3], d: [f32; 3], p: [[f32; 3]; 3]) -> Option<f32> {
    let c = |a: [f32; 3]| robust::Coord3D {
        x: a[0] as f64,
        y: a[1] as f64,
        z: a[2] as f64,
    };
    // orient3d(a, b, c, o) = (a − o)·n with n = (b − a) × (c − a).
    let side = robust::orient3d(c(p[0]), c(p[1]), c(p[2]), c(o));
    let w = |a: [f32; 3]| a.map(|x| x as f64);
    let (a, b, cc, o, d) = (w(p[0]), w(p[1]), w(p[2]), w(o), w(d));
    let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let e2 = [cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let nd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    if !(side * nd > 0.0) {
        return None;
    }
    let ao = [a[0] - o[0], a[1] - o[1], a[2] - o[2]];
    let t = (n[0] * ao[0] + n[1] * ao[1] + n[2] * ao[2]) / nd;
    // Positive by the exact test, whatever rounding made of it.
    Some((t as f32).max(f32::from_bits(1)))
}

/// Watertight ray/triangle intersection in f32 with f64 rechecks. Accepts
/// `t_min < t < t_max`, finite.
#[inline]
pub fn intersect_triangle(
    o: [f32; 3],
    d: [f32; 3],
    p: [[f32; 3]; 3],
    t_min: f32,
    t_max: f32,
) -> Option<TriHit<f32>> {
    if is_degenerate(&p) {
        return None;
    }
    intersect_triangle_sheared(&RayShear::new(o, d), d, p, t_min, t_max)
}

/// [`intersect_triangle`] with the ray's shear computed once for many
/// triangles (`d` is the ray's direction, for the f64 recheck). The triangle
/// must not be degenerate ([`is_degenerate`]): those are never hit.
#[inline]
pub fn intersect_triangle_sheared(
    r: &RayShear<f32>,
    d: [f32; 3],
    p: [[f32; 3]; 3],
    t_min: f32,
    t_max: f32,
) -> Option<TriHit<f32>> {
    let o = r.o;
    match core_sheared(r, p, t_max, true) {
        Core::Miss => None,
        Core::Near(h) => resolve_t(o, d, p, t_min, t_max).map(|t| TriHit { t, b: h.b }),
        // A t within its error of 0 is replaced by resolve_t's, which is then
        // the one tested against [t_min, t_max].
        Core::Hit(h, dt) if h.t <= dt => {
            resolve_t(o, d, p, t_min, t_max).map(|t| TriHit { t, b: h.b })
        }
        Core::Hit(h, _) => (h.t > t_min && h.t < t_max && h.t.is_finite()).then_some(h),
    }
}

/// The hit point reconstructed from barycentrics relative to the first vertex,
/// `p₀ + b₁(p₁ − p₀) + b₂(p₂ − p₀)`, and its error bound
/// `γ₃(|b₁e₁| + |b₂e₂|) + γ₁|p|` (docs/numerics.md rule 3).
///
/// Why relative to `p₀` rather than pbrt's `Σ bᵢpᵢ` with bound `γ₇ Σ|bᵢpᵢ|`:
/// far from the origin the edges are small next to the coordinates, so the
/// bound is about half as wide; and where all three vertices share a
/// coordinate (faces of boxes, floors, walls) that coordinate is exact and
/// its error is zero, so the point stays on the near side of a neighbouring
/// face. Rounding is monotone, so on such a face the point never leaves the
/// half-spaces of the faces around it, which is what keeps reflected rays
/// inside a closed box (numerics.md S5). Errors in the barycentrics move the
/// point along the plane, not off it, as in pbrt.
#[inline]
pub fn triangle_point_and_error(p: [[f32; 3]; 3], b: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let mut out = [0.0f32; 3];
    let mut err = [0.0f32; 3];
    for i in 0..3 {
        let e1 = p[1][i] - p[0][i];
        let e2 = p[2][i] - p[0][i];
        if e1 == 0.0 && e2 == 0.0 {
            // Equal f32 coordinates subtract to an exact zero: the sum is p₀.
            out[i] = p[0][i];
            continue;
        }
        let (d1, d2) = (b[1] * e1, b[2] * e2);
        out[i] = p[0][i] + (d1 + d2);
        err[i] = gamma::<f32>(3) * (d1.abs() + d2.abs()) + gamma::<f32>(1) * out[i].abs();
    }
    (out, err)
}

/// [`triangle_point_and_error`], with the point moved into the triangle until
/// it is twice its error bound from every edge (or to the centroid of a
/// triangle too small for that).
///
/// Why: a point within its error of an edge may lie outside the neighbouring
/// face's half-space, and a ray reflected from there towards that face starts
/// behind it, misses it, and leaves a closed mirror box (the house of mirrors,
/// docs/numerics.md S5). The normal offset cannot help: it clears only the
/// face being left. Moving the point along the face, away from the edge, puts
/// it strictly inside the wedge the two faces enclose, whatever the arriving
/// direction; the move is a few ulps along the surface, far below anything a
/// shader can see. Spawned rays start here; shading keeps the barycentrics.
#[inline]
pub fn triangle_point_inset(p: [[f32; 3]; 3], b: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let (q, err) = triangle_point_and_error(p, b);
    // The L1 length bounds the error box's diagonal.
    let m = 2.0 * (err[0] + err[1] + err[2]);
    let v = p.map(glam::Vec3::from);
    let area2 = (v[1] - v[0]).cross(v[2] - v[0]).length();
    if m == 0.0 || !(area2 > 0.0 && area2.is_finite()) {
        return (q, err);
    }
    // Distance to the edge opposite vertex k is b_k times that edge's height.
    let edge = [
        (v[2] - v[1]).length(),
        (v[0] - v[2]).length(),
        (v[1] - v[0]).length(),
    ];
    let floor = edge.map(|e| m * e / area2);
    if (0..3).all(|k| b[k] >= floor[k]) {
        return (q, err);
    }
    let spare = 1.0 - (floor[0] + floor[1] + floor[2]);
    let b = if spare > 0.0 {
        let above = std::array::from_fn::<f32, 3, _>(|k| (b[k] - floor[k]).max(0.0));
        let total = above[0] + above[1] + above[2];
        std::array::from_fn(|k| floor[k] + above[k] * (spare / total))
    } else {
        [1.0 / 3.0; 3]
    };
    triangle_point_and_error(p, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simple_hit_and_barycentrics() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let h =
            intersect_triangle([0.25, 0.25, 1.0], [0.0, 0.0, -1.0], p, 0.0, f32::INFINITY).unwrap();
        assert_eq!(h.t, 1.0);
        assert!((h.b[1] - 0.25).abs() < 1e-7 && (h.b[2] - 0.25).abs() < 1e-7);
        assert!(intersect_triangle([0.25, 0.25, 1.0], [0.0, 0.0, -1.0], p, 0.0, 1.0).is_none());
        assert!(
            intersect_triangle([0.75, 0.75, 1.0], [0.0, 0.0, -1.0], p, 0.0, f32::INFINITY)
                .is_none()
        );
    }

    /// An origin exactly in the triangle's plane (zero error bound, so no
    /// offset) must never hit the triangle, whatever the direction.
    #[test]
    fn origin_in_plane_never_self_hits() {
        let p = [[-6.0, 0.0, -6.0], [-6.0, 0.0, 6.0], [6.0, 0.0, 6.0]];
        let mut s = rtk_abi::RngState::seeded(3);
        for _ in 0..100_000 {
            let o = [
                (s.next_f64() * 8.0 - 6.0) as f32,
                0.0,
                (s.next_f64() * 8.0 - 2.0) as f32,
            ];
            let target = [4.0f32, 6.0, 4.0];
            let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
            assert!(intersect_triangle(o, d, p, 0.0, 1.0).is_none(), "{o:?}");
        }
    }

    #[test]
    fn degenerate_never_hit() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(
            intersect_triangle([0.5, 0.0, 1.0], [0.0, 0.0, -1.0], p, 0.0, f32::INFINITY).is_none()
        );
    }

    /// docs/numerics.md T1: rays aimed at the shared diagonal of a quad, at several
    /// scales and offsets: none may pass between the two triangles.
    #[test]
    fn shared_edge_is_watertight() {
        let mut s = rtk_abi::RngState::seeded(11);
        for &(scale, off) in &[(1e-3f64, 0.0f64), (1.0, 0.0), (1e3, 1e3), (1.0, 1e5)] {
            let q = |x: f64, y: f64| {
                [
                    (x * scale + off) as f32,
                    (y * scale + off * 0.5) as f32,
                    (off * 0.25) as f32,
                ]
            };
            let (v0, v1, v2, v3) = (q(-1.0, -1.0), q(1.0, -1.0), q(1.0, 1.0), q(-1.0, 1.0));
            let (ta, tb) = ([v0, v1, v2], [v0, v2, v3]);
            let mut leaks = 0;
            for _ in 0..20_000 {
                let u = s.next_f64();
                let target: Vec<f64> = (0..3)
                    .map(|i| v0[i] as f64 + u * (v2[i] as f64 - v0[i] as f64))
                    .collect();
                let h = 0.5 + 2.5 * s.next_f64();
                let o = [
                    (target[0] + (s.next_f64() - 0.5) * scale) as f32,
                    (target[1] + (s.next_f64() - 0.5) * scale) as f32,
                    (target[2] + h * scale) as f32,
                ];
                let d64: Vec<f64> = (0..3).map(|i| target[i] - o[i] as f64).collect();
                let l = (d64[0] * d64[0] + d64[1] * d64[1] + d64[2] * d64[2]).sqrt();
                let d = [
                    (d64[0] / l) as f32,
                    (d64[1] / l) as f32,
                    (d64[2] / l) as f32,
                ];
                let a = intersect_triangle(o, d, ta, 0.0, f32::INFINITY).is_some();
                let b = intersect_triangle(o, d, tb, 0.0, f32::INFINITY).is_some();
                if !a && !b {
                    leaks += 1;
                }
            }
            assert_eq!(leaks, 0, "scale {scale} offset {off}");
        }
    }

    /// docs/numerics.md T2 (pbrt-v4's `Triangle.Watertight` recipe): a 16x16 UV
    /// sphere with vertex radii jittered in [1, 6] and exactly shared poles
    /// and seam; rays from inside the r = 0.5 ball aimed exactly at vertices
    /// and at random, with the mesh at |c| = 0, 1e3 and 1e5 — every ray must
    /// hit some triangle.
    #[test]
    fn closed_mesh_has_no_leaks() {
        let (nt, np) = (16usize, 16usize);
        let mut s = rtk_abi::RngState::seeded(17);
        for &c in &[0.0f64, 1e3, 1e5] {
            let mut verts: Vec<[f64; 3]> = vec![
                [0.0, 0.0, 1.0 + 5.0 * s.next_f64()],
                [0.0, 0.0, -(1.0 + 5.0 * s.next_f64())],
            ];
            for i in 1..nt {
                let th = std::f64::consts::PI * i as f64 / nt as f64;
                for j in 0..np {
                    let ph = std::f64::consts::TAU * j as f64 / np as f64;
                    let r = 1.0 + 5.0 * s.next_f64();
                    verts.push([
                        r * th.sin() * ph.cos(),
                        r * th.sin() * ph.sin(),
                        r * th.cos(),
                    ]);
                }
            }
            let idx = |i: usize, j: usize| 2 + (i - 1) * np + (j % np);
            let mut tris = Vec::new();
            for j in 0..np {
                tris.push([0, idx(1, j), idx(1, j + 1)]);
                tris.push([1, idx(nt - 1, j + 1), idx(nt - 1, j)]);
                for i in 1..nt - 1 {
                    tris.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                    tris.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
                }
            }
            let v32: Vec<[f32; 3]> = verts
                .iter()
                .map(|v| {
                    [
                        (v[0] + c) as f32,
                        (v[1] + c * 0.5) as f32,
                        (v[2] - c * 0.25) as f32,
                    ]
                })
                .collect();
            let mut leaks = 0;
            for k in 0..40_000 {
                let o64 = loop {
                    let p = [s.next_f64() - 0.5, s.next_f64() - 0.5, s.next_f64() - 0.5];
                    if p.iter().map(|x| x * x).sum::<f64>() < 0.25 {
                        break p;
                    }
                };
                let o = [
                    (o64[0] + c) as f32,
                    (o64[1] + c * 0.5) as f32,
                    (o64[2] - c * 0.25) as f32,
                ];
                let target: [f64; 3] = if k % 2 == 0 {
                    let v = v32[(s.next_f64() * v32.len() as f64) as usize % v32.len()];
                    [v[0] as f64, v[1] as f64, v[2] as f64]
                } else {
                    [
                        o[0] as f64 + s.next_f64() - 0.5,
                        o[1] as f64 + s.next_f64() - 0.5,
                        o[2] as f64 + s.next_f64() - 0.5,
                    ]
                };
                let d64 = [
                    target[0] - o[0] as f64,
                    target[1] - o[1] as f64,
                    target[2] - o[2] as f64,
                ];
                let l = (d64[0] * d64[0] + d64[1] * d64[1] + d64[2] * d64[2]).sqrt();
                let d = d64.map(|x| (x / l) as f32);
                let hit = tris.iter().any(|t: &[usize; 3]| {
                    intersect_triangle(o, d, [v32[t[0]], v32[t[1]], v32[t[2]]], 0.0, f32::INFINITY)
                        .is_some()
                });
                if !hit {
                    leaks += 1;
                }
            }
            assert_eq!(leaks, 0, "leaks at |c| = {c}");
        }
    }

    /// An origin one denormal above a floor sees the floor in every
    /// direction that goes down, however shallow, and one denormal below it
    /// never does (f32 and f64 alike cannot tell t ≈ 1e-45 from 0: the exact
    /// orientation decides). Issue 8: 4 % of such pixels used to miss.
    #[test]
    fn origin_a_denormal_above_a_floor_sees_it() {
        let floor = [
            [
                [-10.0f32, 0.0, -10.0],
                [10.0, 0.0, 10.0],
                [10.0, 0.0, -10.0],
            ],
            [
                [-10.0f32, 0.0, -10.0],
                [-10.0, 0.0, 10.0],
                [10.0, 0.0, 10.0],
            ],
        ];
        let mut s = rtk_abi::RngState::seeded(17);
        let (mut above_missed, mut below_hit) = (0, 0);
        for _ in 0..50_000 {
            let (x, z) = (s.range_f32(-5.0, 5.0), s.range_f32(-5.0, 5.0));
            // Down at any angle, shallow ones included.
            let d = [
                s.range_f32(-1.0, 1.0),
                -(10f32.powf(s.range_f32(-4.0, 0.0))),
                s.range_f32(-1.0, 1.0),
            ];
            let hits = |y: f32| {
                floor
                    .iter()
                    .filter(|t| intersect_triangle([x, y, z], d, **t, 0.0, f32::INFINITY).is_some())
                    .count()
            };
            if hits(f32::from_bits(1)) == 0 {
                above_missed += 1;
            }
            if hits(-f32::from_bits(1)) > 0 || hits(0.0) > 0 {
                below_hit += 1;
            }
        }
        assert_eq!((above_missed, below_hit), (0, 0));
    }

    /// docs/numerics.md T4: huge coordinates never give a non-finite t.
    #[test]
    fn huge_coordinates_never_non_finite() {
        for e in 7..31 {
            let s = 10f32.powi(e);
            let p = [[-s, -s, 0.0], [s, -s, 0.0], [0.0, s, 0.0]];
            if let Some(h) =
                intersect_triangle([0.0, 0.0, s], [0.0, 0.0, -1.0], p, 0.0, f32::INFINITY)
            {
                assert!(h.t.is_finite(), "s = {s}");
            }
        }
    }

    /// The inset point stays on the plane within its bound and ends up
    /// farther from every edge than its error box reaches, even for hits
    /// exactly on an edge or a vertex.
    #[test]
    fn inset_point_clears_every_edge() {
        use glam::DVec3;
        let mut s = rtk_abi::RngState::seeded(9);
        let mut checked = 0;
        for &c in &[0.0, 1e3, 1e5] {
            for _ in 0..5_000 {
                let p: [[f32; 3]; 3] = std::array::from_fn(|_| {
                    std::array::from_fn(|_| (c + s.next_f64() * 4.0 - 2.0) as f32)
                });
                // Barycentrics on an edge, at a vertex, or anywhere.
                let mut b1 = s.next_f64() as f32;
                let mut b2 = (s.next_f64() as f32) * (1.0 - b1);
                match s.next_f64() {
                    x if x < 0.3 => b2 = 0.0,
                    x if x < 0.4 => (b1, b2) = (0.0, 0.0),
                    x if x < 0.6 => b2 = 1.0 - b1,
                    _ => {}
                }
                let (q, e) = triangle_point_inset(p, [1.0 - b1 - b2, b1, b2]);
                let v = p.map(|x| DVec3::from(x.map(f64::from)));
                let n = (v[1] - v[0]).cross(v[2] - v[0]);
                if n.length() < 1e-3 {
                    continue;
                }
                let n = n.normalize();
                let q = DVec3::from(q.map(f64::from));
                let e = DVec3::from(e.map(f64::from));
                let reach = e.x + e.y + e.z;
                // Too small to clear its edges by twice its error: the centroid.
                let perimeter: f64 = (0..3).map(|k| (v[(k + 1) % 3] - v[k]).length()).sum();
                if 2.0 * reach * perimeter >= (v[1] - v[0]).cross(v[2] - v[0]).length() {
                    continue;
                }
                assert!(((q - v[0]).dot(n)).abs() <= n.abs().dot(e), "off the plane");
                for k in 0..3 {
                    let (a, b) = (v[(k + 1) % 3], v[(k + 2) % 3]);
                    // Signed distance into the triangle from edge a-b.
                    let inward = n.cross(b - a).normalize();
                    let d = (q - a).dot(inward);
                    assert!(d > reach, "edge {k}: {d} <= {reach} at |c| = {c}");
                }
                checked += 1;
            }
        }
        assert!(checked > 12_000, "only {checked} triangles checked");
    }

    #[test]
    fn point_error_bounds_hold_against_f64() {
        let mut s = rtk_abi::RngState::seeded(5);
        for _ in 0..10_000 {
            let c = 1e3;
            let p: [[f32; 3]; 3] =
                std::array::from_fn(|_| std::array::from_fn(|_| (c + s.next_f64() * 10.0) as f32));
            let b0 = s.next_f64() as f32 * 0.5;
            let b1 = s.next_f64() as f32 * 0.5;
            let b = [1.0 - b0 - b1, b0, b1];
            let (q, e) = triangle_point_and_error(p, b);
            for i in 0..3 {
                // The plane point the barycentrics name: b₀ is implied by b₁, b₂.
                let v0 = p[0][i] as f64;
                let exact =
                    v0 + b[1] as f64 * (p[1][i] as f64 - v0) + b[2] as f64 * (p[2][i] as f64 - v0);
                assert!((q[i] as f64 - exact).abs() <= e[i] as f64);
            }
        }
    }

    /// A hit counts when t < t_max, for the t the test reports: with t_max
    /// one ulp above a hit's t the hit is still found, with the same t, and
    /// with t_max at that t it is not. (The scaled compare `ts <= t_max·det`
    /// once rounded the other way and lost such hits: `list` then kept a
    /// child's hit an ulp farther than a later child's, and `raycls`, which
    /// tests them in another order, did not — on a bunny at scale 1e6.)
    #[test]
    fn hit_found_iff_its_t_is_below_t_max() {
        let mut s = rtk_abi::RngState::seeded(11);
        let mut hits = 0;
        for _ in 0..200_000 {
            let mut r = |k: f64| (s.next_f64() * 2.0 - 1.0) * k;
            let p: [[f32; 3]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| r(1.0) as f32));
            let far = 10f64.powf(r(7.0).abs());
            let o: [f32; 3] = std::array::from_fn(|_| (r(1.0) * far) as f32);
            let aim: [f64; 3] = std::array::from_fn(|_| r(0.3));
            let scale = (0.5 + s.next_f64()) / far.max(1.0);
            let d: [f32; 3] = std::array::from_fn(|i| ((aim[i] - o[i] as f64) * scale) as f32);
            let Some(h) = intersect_triangle(o, d, p, 0.0, f32::INFINITY) else {
                continue;
            };
            hits += 1;
            let again = intersect_triangle(o, d, p, 0.0, h.t.next_up());
            assert_eq!(again.map(|a| a.t), Some(h.t), "{o:?} {d:?} {p:?}");
            assert!(intersect_triangle(o, d, p, 0.0, h.t).is_none());
        }
        assert!(hits > 10_000, "{hits}");
    }
}
