//! One bicubic Bézier patch, intersected directly: a box over its control
//! points, g×g sub-patch boxes (the exact control points of each sub-patch,
//! so each box bounds its piece of surface), and Newton's method on the ray
//! written as two planes, started at the centre of each sub-patch whose box
//! the ray crosses. Everything here is f64, on the f32 control points.

pub type V3 = [f64; 3];

#[inline]
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
#[inline]
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
#[inline]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline]
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
#[inline]
fn lerp(a: V3, b: V3, t: f64) -> V3 {
    add(a, scale(sub(b, a), t))
}

/// Cubic Bernstein basis and its derivative at t.
#[inline]
fn bernstein(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    (
        [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t],
        [
            -3.0 * s * s,
            3.0 * s * s - 6.0 * s * t,
            6.0 * s * t - 3.0 * t * t,
            3.0 * t * t,
        ],
    )
}

/// Control points of the piece [a, b] of a cubic Bézier curve (de Casteljau).
fn segment(c: [V3; 4], a: f64, b: f64) -> [V3; 4] {
    // Left part [0, b].
    let split_left = |c: [V3; 4], t: f64| -> [V3; 4] {
        let p01 = lerp(c[0], c[1], t);
        let p12 = lerp(c[1], c[2], t);
        let p23 = lerp(c[2], c[3], t);
        let q0 = lerp(p01, p12, t);
        let q1 = lerp(p12, p23, t);
        [c[0], p01, q0, lerp(q0, q1, t)]
    };
    let split_right = |c: [V3; 4], t: f64| -> [V3; 4] {
        let p01 = lerp(c[0], c[1], t);
        let p12 = lerp(c[1], c[2], t);
        let p23 = lerp(c[2], c[3], t);
        let q0 = lerp(p01, p12, t);
        let q1 = lerp(p12, p23, t);
        [lerp(q0, q1, t), q1, p23, c[3]]
    };
    let left = if b < 1.0 { split_left(c, b) } else { c };
    if a > 0.0 {
        split_right(left, a / b)
    } else {
        left
    }
}

/// An axis-aligned box in f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Box3 {
    pub lo: V3,
    pub hi: V3,
}

impl Box3 {
    fn of(points: &[V3], pad: f64) -> Box3 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Box3 {
            lo: lo.map(|x| x - pad),
            hi: hi.map(|x| x + pad),
        }
    }

    /// Entry and exit parameters of the ray in the box, clipped to
    /// [t0, t1]; `None` if it misses. An axis the ray is parallel to
    /// (d = 0, 1/d = ±∞) only checks that the origin lies within the slab.
    #[inline]
    fn clip(&self, o: V3, inv: V3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        let (mut a, mut b) = (t0, t1);
        for k in 0..3 {
            if inv[k].is_infinite() {
                if o[k] < self.lo[k] || o[k] > self.hi[k] {
                    return None;
                }
                continue;
            }
            let n = (self.lo[k] - o[k]) * inv[k];
            let f = (self.hi[k] - o[k]) * inv[k];
            let (n, f) = if n <= f { (n, f) } else { (f, n) };
            a = a.max(n);
            b = b.min(f);
        }
        (a <= b).then_some((a, b))
    }
}

/// Surface point and first derivatives.
#[derive(Clone, Copy, Debug)]
pub struct Eval {
    pub p: V3,
    pub du: V3,
    pub dv: V3,
}

/// Parameter slack at patch boundaries: a hit with u or v within this of
/// [0, 1] counts, so adjacent patches overlap by a hair at their shared
/// edges instead of leaving a crack where Newton's answer rounds outward.
pub const PARAM_SLACK: f64 = 1e-7;

/// Newton stops when the point is this close to the ray (relative to the
/// larger of the patch's and the ray origin's coordinates).
pub const TOL: f64 = 1e-12;
/// Roots closer than this (relative, as `TOL`) to the origin are refused.
pub const SELF_DIST: f64 = 1e-11;
/// The absolute part of the hit point's error bound (relative, as `TOL`).
pub const RESID: f64 = 4e-11;

/// A hit on one patch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchHit {
    pub t: f64,
    pub u: f64,
    pub v: f64,
}

#[derive(Clone, Debug)]
pub struct Patch {
    /// Control points, row-major: cp[4 i + j] weighs B_i(u) B_j(v).
    pub cp: [V3; 16],
    /// Box of the control points (contains the patch).
    pub bounds: Box3,
    /// g×g sub-patch boxes, sub-patch (a, b) at index a·g + b covering
    /// u ∈ [a/g, (a+1)/g], v ∈ [b/g, (b+1)/g].
    sub: Vec<Box3>,
    g: usize,
    /// Largest |coordinate| of the control points: the scale of rounding.
    pub scale: f64,
}

impl Patch {
    /// A patch from 16 control points; `g` sub-patches a side (≥ 1).
    pub fn new(cp: [V3; 16], g: usize) -> Patch {
        let g = g.max(1);
        let scale = cp
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f64, |m, x| m.max(x.abs()));
        // f64 de Casteljau rounds at ~1e-16 of the scale: pad well past it.
        let pad = scale * 1e-12;
        let mut sub = Vec::with_capacity(g * g);
        for a in 0..g {
            let (u0, u1) = (a as f64 / g as f64, (a + 1) as f64 / g as f64);
            // Rows restricted to [u0, u1] (each column of 4 along u).
            let mut rows = [[0.0; 3]; 16];
            for j in 0..4 {
                let col = [cp[j], cp[4 + j], cp[8 + j], cp[12 + j]];
                let s = segment(col, u0, u1);
                for i in 0..4 {
                    rows[4 * i + j] = s[i];
                }
            }
            for b in 0..g {
                let (v0, v1) = (b as f64 / g as f64, (b + 1) as f64 / g as f64);
                let mut pts = [[0.0; 3]; 16];
                for i in 0..4 {
                    let row = [
                        rows[4 * i],
                        rows[4 * i + 1],
                        rows[4 * i + 2],
                        rows[4 * i + 3],
                    ];
                    let s = segment(row, v0, v1);
                    pts[4 * i..4 * i + 4].copy_from_slice(&s);
                }
                sub.push(Box3::of(&pts, pad));
            }
        }
        Patch {
            cp,
            bounds: Box3::of(&cp, 0.0),
            sub,
            g,
            scale,
        }
    }

    /// P(u, v), ∂P/∂u, ∂P/∂v.
    pub fn eval(&self, u: f64, v: f64) -> Eval {
        let (bu, dbu) = bernstein(u);
        let (bv, dbv) = bernstein(v);
        let mut e = Eval {
            p: [0.0; 3],
            du: [0.0; 3],
            dv: [0.0; 3],
        };
        for i in 0..4 {
            for j in 0..4 {
                let c = self.cp[4 * i + j];
                let (w, wu, wv) = (bu[i] * bv[j], dbu[i] * bv[j], bu[i] * dbv[j]);
                for (k, ck) in c.iter().enumerate() {
                    e.p[k] += w * ck;
                    e.du[k] += wu * ck;
                    e.dv[k] += wv * ck;
                }
            }
        }
        e
    }

    /// The unit normal ∂P/∂u × ∂P/∂v at (u, v). Where that vanishes (a
    /// collapsed edge: the teapot's lid top and bottom centre, where one
    /// derivative is zero), the normal is the limit approached from inside
    /// the patch: the cross product a small step towards the patch's
    /// centre, then a larger one; `None` only for a patch degenerate
    /// everywhere near (u, v) (a curve or a point).
    pub fn normal(&self, u: f64, v: f64) -> Option<V3> {
        for step in [0.0, 1e-6, 1e-4, 1e-2] {
            let (uu, vv) = (u + (0.5 - u) * step, v + (0.5 - v) * step);
            let e = self.eval(uu, vv);
            let n = cross(e.du, e.dv);
            let l = norm(n);
            // A derivative below 1e-9 of the patch's size is rounding noise
            // (a collapsed edge), and so is their cross product's direction.
            let size = norm(sub(self.bounds.hi, self.bounds.lo));
            let (lu, lv) = (norm(e.du), norm(e.dv));
            let ok = lu > 1e-9 * size && lv > 1e-9 * size && l > 1e-12 * lu * lv;
            if ok && l.is_finite() {
                return Some(scale(n, 1.0 / l));
            }
        }
        None
    }

    /// Nearest hit with t in (t_min, t_max), t·|d| beyond `SELF_DIST` of the
    /// scale (a root closer to the origin is the surface the ray leaves).
    pub fn intersect(&self, o: V3, d: V3, t_min: f64, t_max: f64) -> Option<PatchHit> {
        let inv = d.map(|x| 1.0 / x);
        self.bounds.clip(o, inv, t_min.max(0.0), t_max)?;
        let dl = norm(d);
        if !(dl > 0.0) || !dl.is_finite() {
            return None;
        }
        let w = scale(d, 1.0 / dl);
        // Two planes through the ray: n1, n2 ⟂ d.
        let a = if w[0].abs() > 0.9 {
            [0.0, 1.0, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let n1 = {
            let c = cross(w, a);
            scale(c, 1.0 / norm(c))
        };
        let n2 = cross(w, n1);
        // Distances off the ray are trusted to ~1e-15 of the larger of the
        // patch's and the origin's coordinates: converge to well inside
        // f32's resolution, well outside f64 noise.
        let omax = o.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let big = self.scale.max(omax).max(f64::MIN_POSITIVE);
        let tol = TOL * big;
        // A root this close to the origin is the surface the ray starts on
        // (f64 noise); a spawned ray starts at least `RESID`·scale away
        // (`point_error`), four times farther.
        let self_dist = SELF_DIST * big;
        let mut best: Option<PatchHit> = None;
        let g = self.g as f64;
        for (k, b) in self.sub.iter().enumerate() {
            let limit = best.map_or(t_max, |h| h.t);
            let Some((near, _)) = b.clip(o, inv, t_min.max(0.0), limit) else {
                continue;
            };
            if best.is_some_and(|h| near > h.t) {
                continue;
            }
            let (su, sv) = ((k / self.g) as f64, (k % self.g) as f64);
            let start = ((su + 0.5) / g, (sv + 0.5) / g);
            if let Some(h) = self.newton(o, w, dl, n1, n2, start, tol) {
                let inside = (-PARAM_SLACK..=1.0 + PARAM_SLACK).contains(&h.u)
                    && (-PARAM_SLACK..=1.0 + PARAM_SLACK).contains(&h.v);
                if inside
                    && h.t > t_min
                    && h.t < t_max
                    && h.t.is_finite()
                    && h.t * dl > self_dist
                    && best.is_none_or(|b| h.t < b.t)
                {
                    best = Some(h);
                }
            }
        }
        best
    }

    /// Newton's method on (n1·(P − o), n2·(P − o)) = 0 from `start`.
    #[allow(clippy::too_many_arguments)]
    fn newton(
        &self,
        o: V3,
        w: V3,
        dl: f64,
        n1: V3,
        n2: V3,
        start: (f64, f64),
        tol: f64,
    ) -> Option<PatchHit> {
        let (mut u, mut v) = start;
        for _ in 0..24 {
            let e = self.eval(u, v);
            let r = sub(e.p, o);
            let (f1, f2) = (dot(n1, r), dot(n2, r));
            let (a, b, c, dd) = (dot(n1, e.du), dot(n1, e.dv), dot(n2, e.du), dot(n2, e.dv));
            let det = a * dd - b * c;
            let converged = f1.abs().max(f2.abs()) <= tol;

            if converged {
                return Some(PatchHit {
                    t: dot(r, w) / dl,
                    u,
                    v,
                });
            }
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let du = (dd * f1 - b * f2) / det;
            let dv = (a * f2 - c * f1) / det;
            // Damp wild steps (near a silhouette) to half the patch.
            let m = du.abs().max(dv.abs());
            let k = if m > 0.5 { 0.5 / m } else { 1.0 };
            u -= du * k;
            v -= dv * k;
            if !(-0.5..=1.5).contains(&u) || !(-0.5..=1.5).contains(&v) {
                return None;
            }
        }
        None
    }

    /// Polish a hit for `local_geom`: Newton from the stored (u, v) on the
    /// same ray; returns (u, v) (the stored ones if Newton does not improve).
    pub fn refine(&self, o: V3, d: V3, u: f64, v: f64) -> (f64, f64) {
        let dl = norm(d);
        if !(dl > 0.0) || !dl.is_finite() {
            return (u, v);
        }
        let w = scale(d, 1.0 / dl);
        let a = if w[0].abs() > 0.9 {
            [0.0, 1.0, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let n1 = {
            let c = cross(w, a);
            scale(c, 1.0 / norm(c))
        };
        let n2 = cross(w, n1);
        let omax = o.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let tol = TOL * self.scale.max(omax).max(f64::MIN_POSITIVE);
        match self.newton(o, w, dl, n1, n2, (u, v), tol) {
            Some(h) if (h.u - u).abs() < 1e-3 && (h.v - v).abs() < 1e-3 => (h.u, h.v),
            _ => (u, v),
        }
    }

    /// Absolute error bound (per component) of P(u, v) rounded to f32: two
    /// f32 ulps of |p|, plus `RESID` of the patch's scale (covering f64
    /// evaluation noise, ~1e-15, and Newton's residual, `TOL`), plus what
    /// the parameters' own rounding moves the point by.
    pub fn point_error(&self, e: &Eval) -> V3 {
        let pmax = e.p.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let resid = RESID * self.scale.max(pmax);
        let dpar = 1e-15 * (norm(e.du) + norm(e.dv));
        std::array::from_fn(|k| 2.0 * f32::EPSILON as f64 * e.p[k].abs() + resid + dpar)
    }
}
