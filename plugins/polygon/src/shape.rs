//! The polygon's geometric core, generic over [`Real`]: the plugin runs it
//! in f32, the tests run the same code in f64 as the reference.

use rtk_kernel::geom::vec::*;
use rtk_kernel::geom::{gamma, Real};

/// The plane of a loop of points, in f64: Newell's normal (unit; its
/// direction follows the right-hand rule on the loop's order) and the
/// centroid of the points. `None` when the loop encloses no area.
pub fn plane64(pts: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let mut n = [0.0f64; 3];
    let m = pts.len();
    let mut c = [0.0f64; 3];
    for i in 0..m {
        let a = pts[i];
        let b = pts[(i + 1) % m];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
        for k in 0..3 {
            c[k] += a[k] / m as f64;
        }
    }
    let len = norm64(n);
    // Zero area, relative to the points' spread (twice the area is |n|).
    let spread = pts
        .iter()
        .map(|p| norm64(sub(*p, c)))
        .fold(0.0f64, f64::max);
    if !(len > 1e-10 * spread * spread) {
        return None;
    }
    Some((n.map(|x| x / len), c))
}

/// A planar polygon with holes: the outer loop and the holes' loops, all
/// tested together by the even-odd rule.
#[derive(Clone, Debug)]
pub struct Polygon<R> {
    /// Every loop's vertices, one loop after the other.
    pub pts: Vec<V<R>>,
    /// (first, count) of each loop in `pts`; the outer loop first.
    pub loops: Vec<(usize, usize)>,
    /// Unit normal of the plane.
    pub n: V<R>,
    /// A point of the plane (the outer loop's centroid).
    pub c: V<R>,
}

/// A hit point on the surface and what `local_geom` needs of it.
#[derive(Clone, Copy, Debug)]
pub struct Surface<R> {
    /// The point, reprojected onto the plane.
    pub p: V<R>,
    /// Per-component bound on its distance from the exact plane.
    pub p_err: V<R>,
    /// The point relative to the plane's point `c` (in the plane).
    pub q: V<R>,
}

impl<R: Real> Polygon<R> {
    /// From loops in f64 (the outer loop first) and the plane `plane64`
    /// gave for the outer loop.
    pub fn new(loops: &[Vec<[f64; 3]>], n: [f64; 3], c: [f64; 3]) -> Self {
        let mut pts = Vec::new();
        let mut idx = Vec::new();
        for l in loops {
            idx.push((pts.len(), l.len()));
            pts.extend(l.iter().map(|p| cvt::<R>(*p)));
        }
        Polygon {
            pts,
            loops: idx,
            n: cvt(n),
            c: cvt(c),
        }
    }

    /// Nearest hit of `o + t d` in `(t_min, t_max)`, if any.
    ///
    /// t comes from the plane: `n·(c − o) / n·d` (refused, like the disk's,
    /// when the origin lies on the plane within [`Polygon::origin_band`]).
    /// Whether the ray passes inside is decided **in ray space**, as the
    /// watertight triangle test does: every vertex is translated by −o and
    /// sheared along d (the permutation puts d's dominant axis last), so the
    /// ray is the point (0, 0), and the even-odd crossing rule counts the
    /// edges crossing the +X half-line. Crossings are half-open: an edge
    /// counts when exactly one end has Y > 0 (so a vertex on the line counts
    /// once) and its crossing point X = e/(Yb − Ya), e = Xa·Yb − Xb·Ya, is
    /// ≥ 0 (decided by signs, no division). Two polygons sharing an edge
    /// compute that edge's (X, Y) and e from identical operands, e exactly
    /// negated when the edge runs the other way, so both reach the same
    /// decision for it: a ray at the shared edge hits exactly one of the two
    /// when they tile a plane, never neither.
    pub fn intersect(&self, o: V<R>, d: V<R>, t_min: R, t_max: R) -> Option<R> {
        let n = self.n;
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
        if self.inside(o, d) {
            Some(t)
        } else {
            None
        }
    }

    /// The even-odd crossing test of the ray through `o` along `d` against
    /// every loop, in ray space (see [`Polygon::intersect`]).
    #[inline]
    pub fn inside(&self, o: V<R>, d: V<R>) -> bool {
        let ad = [d[0].abs(), d[1].abs(), d[2].abs()];
        let kz = if ad[0] > ad[1] {
            if ad[0] > ad[2] {
                0
            } else {
                2
            }
        } else if ad[1] > ad[2] {
            1
        } else {
            2
        };
        if !(ad[kz] > R::ZERO) {
            return false;
        }
        let kx = (kz + 1) % 3;
        let ky = (kz + 2) % 3;
        let sx = d[kx] / d[kz];
        let sy = d[ky] / d[kz];
        let proj = |v: V<R>| {
            let rx = v[kx] - o[kx];
            let ry = v[ky] - o[ky];
            let rz = v[kz] - o[kz];
            (rx - sx * rz, ry - sy * rz)
        };
        let mut odd = false;
        for &(first, count) in &self.loops {
            let mut a = proj(self.pts[first + count - 1]);
            for i in 0..count {
                let b = proj(self.pts[first + i]);
                let (a_up, b_up) = (a.1 > R::ZERO, b.1 > R::ZERO);
                if a_up != b_up {
                    let e = a.0 * b.1 - b.0 * a.1;
                    // X = e / (Yb − Ya) ≥ 0, with Yb > Ya exactly when b is up.
                    let crosses = if b_up { e >= R::ZERO } else { e <= R::ZERO };
                    if crosses {
                        odd = !odd;
                    }
                }
                a = b;
            }
        }
        odd
    }

    /// How close to the plane an origin must be to count as lying on it (the
    /// disk's rule): the rounding bound of n·(c − o), γ₅Σ|nᵢwᵢ|, plus the
    /// error bound a hit point would have at `o`, Σ|nᵢ|(γ₈|w|₁ + γ₂|oᵢ|).
    #[inline]
    fn origin_band(&self, o: V<R>, w: V<R>) -> R {
        let n = self.n;
        let wl = w[0].abs() + w[1].abs() + w[2].abs();
        let g8w = gamma::<R>(8) * wl;
        let g2 = gamma::<R>(2);
        gamma::<R>(5) * abs_dot(n, w)
            + n[0].abs() * (g8w + g2 * o[0].abs())
            + n[1].abs() * (g8w + g2 * o[1].abs())
            + n[2].abs() * (g8w + g2 * o[2].abs())
    }

    /// The hit point at `t`, reprojected onto the plane, with the bound
    /// γ₈|q| + γ₂|pᵢ| (q = p − c), as the disk's.
    #[inline]
    pub fn surface(&self, o: V<R>, d: V<R>, t: R) -> Surface<R> {
        let n = self.n;
        let w = sub(self.c, o);
        let q = sub(scale(d, t), w);
        let qp = sub(q, scale(n, dot(q, n)));
        let p = add(self.c, qp);
        let ql = dot(qp, qp).sqrt();
        let g8 = gamma::<R>(8);
        let g2 = gamma::<R>(2);
        let p_err = std::array::from_fn(|i| g8 * ql + g2 * p[i].abs());
        Surface { p, p_err, q: qp }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::geom::offset_ray_origin;
    use rtk_kernel::glam::Vec3;
    use rtk_kernel::RngState;

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

    /// Map 2D loops onto the plane through `origin` spanned by `ex`, `ey`,
    /// rounded to f32 (as a scene file would give them).
    fn place(
        loops2: &[Vec<[f64; 2]>],
        origin: [f64; 3],
        ex: [f64; 3],
        ey: [f64; 3],
    ) -> Vec<Vec<[f32; 3]>> {
        loops2
            .iter()
            .map(|l| {
                l.iter()
                    .map(|p| {
                        std::array::from_fn(|k| (origin[k] + p[0] * ex[k] + p[1] * ey[k]) as f32)
                    })
                    .collect()
            })
            .collect()
    }

    fn pair(loops: &[Vec<[f32; 3]>]) -> (Polygon<f32>, Polygon<f64>) {
        let l64: Vec<Vec<[f64; 3]>> = loops
            .iter()
            .map(|l| l.iter().map(|p| f64v(*p)).collect())
            .collect();
        let (n, c) = plane64(&l64[0]).expect("a plane");
        // The reference runs on the plane the plugin holds (rounded to f32).
        let (n32, c32) = (n.map(|x| x as f32 as f64), c.map(|x| x as f32 as f64));
        (Polygon::new(&l64, n, c), Polygon::new(&l64, n32, c32))
    }

    /// Independent point-in-polygon in 2D by the winding number (even-odd
    /// over loops), and the distance to the nearest edge.
    fn pip2(loops2: &[Vec<[f64; 2]>], p: [f64; 2]) -> (bool, f64) {
        let mut inside = false;
        let mut dmin = f64::INFINITY;
        for l in loops2 {
            let m = l.len();
            let mut wind = 0.0;
            for i in 0..m {
                let a = [l[i][0] - p[0], l[i][1] - p[1]];
                let b = [l[(i + 1) % m][0] - p[0], l[(i + 1) % m][1] - p[1]];
                wind += (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1]);
                let e = [b[0] - a[0], b[1] - a[1]];
                let s =
                    (-(a[0] * e[0] + a[1] * e[1]) / (e[0] * e[0] + e[1] * e[1])).clamp(0.0, 1.0);
                dmin = dmin.min((a[0] + s * e[0]).hypot(a[1] + s * e[1]));
            }
            if (wind / std::f64::consts::TAU).round() as i64 % 2 != 0 {
                inside = !inside;
            }
        }
        (inside, dmin)
    }

    /// A non-convex outer loop (a "C" with a notch) and a square hole.
    fn c_with_hole() -> Vec<Vec<[f64; 2]>> {
        vec![
            vec![
                [0.0, 0.0],
                [4.0, 0.0],
                [4.0, 1.0],
                [1.0, 1.0],
                [1.0, 3.0],
                [4.0, 3.0],
                [4.0, 4.0],
                [0.0, 4.0],
            ],
            vec![[0.25, 3.25], [0.75, 3.25], [0.75, 3.75], [0.25, 3.75]],
        ]
    }

    fn tilted_frame() -> ([f64; 3], [f64; 3]) {
        let ex = [0.6, 0.0, -0.8];
        let ey0 = [0.3, 0.9, 0.2];
        let k = ey0[0] * ex[0] + ey0[1] * ex[1] + ey0[2] * ex[2];
        let ey = std::array::from_fn(|i| ey0[i] - k * ex[i]);
        let l = norm64(ey);
        (ex, ey.map(|x| x / l))
    }

    #[test]
    fn plane_and_winding() {
        let sq = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        let (n, c) = plane64(&sq).unwrap();
        assert_eq!(n, [0.0, 0.0, 1.0]); // counter-clockwise seen from +z
        assert_eq!(c, [0.5, 0.5, 0.0]);
        let line = vec![[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]];
        assert!(plane64(&line).is_none());
        let loops: Vec<Vec<[f64; 3]>> = vec![sq];
        let p = Polygon::<f32>::new(&loops, n, c);
        let inf = f32::INFINITY;
        assert_eq!(
            p.intersect([0.5, 0.5, 2.0], [0.0, 0.0, -1.0], 0.0, inf),
            Some(2.0)
        );
        assert_eq!(
            p.intersect([0.5, 0.5, -2.0], [0.0, 0.0, 1.0], 0.0, inf),
            Some(2.0)
        );
        assert!(p
            .intersect([1.5, 0.5, 2.0], [0.0, 0.0, -1.0], 0.0, inf)
            .is_none());
        assert!(p
            .intersect([0.5, 0.5, 2.0], [0.0, 0.0, -1.0], 0.0, 2.0)
            .is_none());
        assert!(p
            .intersect([0.5, 0.5, 0.0], [1.0, 0.0, 0.0], 0.0, inf)
            .is_none());
    }

    /// A non-convex polygon with a hole, tilted and far from the origin: f32
    /// against f64 and against an independent winding-number test of the
    /// f64 hit point; disagreements only within 1e-5 of an edge.
    #[test]
    fn nonconvex_with_hole_random_rays() {
        let mut rng = RngState::seeded(3);
        let loops2 = c_with_hole();
        let (ex, ey) = tilted_frame();
        for origin in [[0.0, 0.0, 0.0], [1e3, -2e3, 5e2]] {
            let loops = place(&loops2, origin, ex, ey);
            let (f, g) = pair(&loops);
            // The reference's 2D loops: the f32 vertices' plane coordinates.
            let ref2: Vec<Vec<[f64; 2]>> = loops
                .iter()
                .map(|l| {
                    l.iter()
                        .map(|p| {
                            let r = sub(f64v(*p), origin);
                            [dot(r, ex), dot(r, ey)]
                        })
                        .collect()
                })
                .collect();
            // The f32 vertices lie off the plane by up to `dev`; seen along a
            // ray at angle θ to the normal the outline moves by dev·tan θ.
            let dev = loops
                .iter()
                .flatten()
                .map(|p| dot(g.n, sub(f64v(*p), g.c)).abs())
                .fold(0.0f64, f64::max);
            let (mut hits, mut near_edge, mut worst_t) = (0, 0, 0.0f64);
            let total = 40_000;
            for _ in 0..total {
                // Origins on the normal's side (up to 6 units off the plane),
                // either side; targets over the polygon's box and around it.
                let (a, b) = (
                    rng.range_f32(-0.5, 4.5) as f64,
                    rng.range_f32(-0.5, 4.5) as f64,
                );
                let target: [f32; 3] =
                    std::array::from_fn(|k| (origin[k] + a * ex[k] + b * ey[k]) as f32);
                let o: [f32; 3] =
                    std::array::from_fn(|k| target[k] + 6.0 * rng.range_f32(-1.0, 1.0));
                let d = sub(target, o);
                let hf = f.intersect(o, d, 0.0, f32::INFINITY);
                let hg = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY);
                // The f64 hit point's plane coordinates, exactly.
                let tt = dot(g.n, sub(g.c, f64v(o))) / dot(g.n, f64v(d));
                let p = add(f64v(o), scale(f64v(d), tt));
                let rel = sub(p, origin);
                let (inside, dist) = pip2(&ref2, [dot(rel, ex), dot(rel, ey)]);
                let expect = inside && tt > 0.0;
                if hf.is_some() != expect || hg.is_some() != expect {
                    let cos = dot(g.n, f64v(d)).abs() / norm64(f64v(d));
                    let tan = (1.0 - cos * cos).sqrt() / cos;
                    let band = 1e-6 + 2.0 * dev * (1.0 + tan);
                    assert!(
                        dist < band || tt.abs() < 1e-9,
                        "f32 {hf:?} f64 {hg:?} expected {expect} at {dist:e} (band {band:e})"
                    );
                    near_edge += 1;
                }
                if let (Some(a), Some(b)) = (hf, hg) {
                    hits += 1;
                    let cond = abs_dot(g.n, sub(g.c, f64v(o))) / dot(g.n, sub(g.c, f64v(o))).abs()
                        + abs_dot(g.n, f64v(d)) / dot(g.n, f64v(d)).abs();
                    worst_t = worst_t.max((a as f64 - b).abs() / b / cond);
                }
            }
            println!(
                "polygon at {origin:?}: {hits} hits of {total}, {near_edge} disagreements with \
                 the winding number near edges (vertex offset from the plane {dev:e}), \
                 max rel t err / condition {worst_t:e}"
            );
            assert!(hits > total / 5);
            assert!(near_edge * 1000 < total);
            assert!(worst_t < 8.0 * f32::EPSILON as f64);
        }
    }

    /// The textbook test, for comparison only: t from the polygon's own
    /// plane, then the hit point's even-odd crossing test (half-open) in the
    /// projection dropping the normal's dominant axis.
    fn textbook_hit(poly: &Polygon<f32>, o: [f32; 3], d: [f32; 3]) -> bool {
        let t = dot(poly.n, sub(poly.c, o)) / dot(poly.n, d);
        if !(t > 0.0 && t.is_finite()) {
            return false;
        }
        let p = add(o, scale(d, t));
        let an = poly.n.map(f32::abs);
        let k = if an[0] > an[1] && an[0] > an[2] {
            0
        } else if an[1] > an[2] {
            1
        } else {
            2
        };
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let mut odd = false;
        let (first, count) = poly.loops[0];
        for e in 0..count {
            let a = poly.pts[first + e];
            let b = poly.pts[first + (e + 1) % count];
            if (a[j] > p[j]) != (b[j] > p[j]) {
                let x = (b[i] - a[i]) * (p[j] - a[j]) / (b[j] - a[j]) + a[i];
                if p[i] < x {
                    odd = !odd;
                }
            }
        }
        odd
    }

    /// Two non-convex polygons tiling a square along a shared zigzag chain
    /// of edges (tilted, at three scales and offsets): rays aimed exactly at
    /// points of the shared edges, and at the shared vertices, from random
    /// origins on both sides hit one or both, never neither.
    #[test]
    fn shared_edges_never_leak() {
        let mut rng = RngState::seeded(99);
        // From the left side of a 3 x 3 square to its right side.
        let chain = [[0.0, 0.5], [1.3, 1.1], [0.7, 2.2], [2.1, 2.6], [3.0, 2.4]];
        let (ex, ey) = tilted_frame();
        for (scale_, origin) in [
            (1.0, [0.0, 0.0, 0.0]),
            (1e-3, [0.0, 0.0, 0.0]),
            (1.0, [1e3, 1e3, -1e3]),
            (100.0, [1e4, 0.0, 0.0]),
        ] {
            // Upper piece: the chain, then the top corners.
            let mut left: Vec<[f64; 2]> = chain.to_vec();
            left.extend([[3.0, 3.0], [0.0, 3.0]]);
            // Lower piece: the bottom corners, then the chain reversed.
            let mut right: Vec<[f64; 2]> = vec![[0.0, 0.0], [3.0, 0.0]];
            right.extend(chain.iter().rev());
            let sc = |l: Vec<[f64; 2]>| {
                vec![l
                    .into_iter()
                    .map(|p| [p[0] * scale_, p[1] * scale_])
                    .collect::<Vec<_>>()]
            };
            let lp = place(&sc(left), origin, ex, ey);
            let rp = place(&sc(right), origin, ex, ey);
            let (lf, _) = pair(&lp);
            let (rf, _) = pair(&rp);
            // The shared chain's vertices, exactly as both polygons hold them.
            let cv: Vec<[f32; 3]> = lp[0][..chain.len()].to_vec();
            let (mut leaks, mut both, mut n, mut textbook_leaks) = (0, 0, 0, 0);
            for i in 0..80_000 {
                // A point inside a shared edge, or (one ray in 16) a shared
                // vertex inside the square (the chain's ends lie on its border).
                let k = i % (cv.len() - 1);
                let (a, b) = (cv[k], cv[k + 1]);
                let s = if i % 16 == 0 && k > 0 {
                    0.0
                } else {
                    0.001 + 0.998 * rng.next_f32()
                };
                let target: [f32; 3] = std::array::from_fn(|j| a[j] + s * (b[j] - a[j]));
                let nrm: [f32; 3] = lf.n;
                let side = if i % 2 == 0 { 1.0 } else { -1.0 };
                let o: [f32; 3] = std::array::from_fn(|j| {
                    target[j]
                        + scale_ as f32 * (3.0 * rng.range_f32(-1.0, 1.0) + side * 4.0 * nrm[j])
                });
                let d = sub(target, o);
                let hl = lf.intersect(o, d, 0.0, f32::INFINITY).is_some();
                let hr = rf.intersect(o, d, 0.0, f32::INFINITY).is_some();
                // Only count rays that reach the plane (not parallel).
                if dot(nrm, d).abs() > 1e-3 * dot(d, d).sqrt() {
                    n += 1;
                    if !hl && !hr {
                        leaks += 1;
                    }
                    if hl && hr {
                        both += 1;
                    }
                    if !textbook_hit(&lf, o, d) && !textbook_hit(&rf, o, d) {
                        textbook_leaks += 1;
                    }
                }
            }
            println!(
                "shared edges, scale {scale_} at {origin:?}: {n} rays, {leaks} leaks, {both} hit both \
                 (the textbook hit-point test: {textbook_leaks} leaks)"
            );
            assert_eq!(leaks, 0);
        }
    }

    /// Hit points lie within their bound of the plane, and rays leaving them
    /// (offset or from the raw point) never re-hit the polygon.
    #[test]
    fn origins_on_the_surface() {
        let mut rng = RngState::seeded(6);
        let loops2 = c_with_hole();
        let (ex, ey) = tilted_frame();
        for origin in [[0.0, 0.0, 0.0], [1e3, -2e3, 5e2], [1e5, 0.0, 0.0]] {
            let (f, g) = pair(&place(&loops2, origin, ex, ey));
            let (mut pts, mut rehits) = (0, 0);
            for _ in 0..10_000 {
                let (a, b) = (
                    rng.range_f32(0.0, 4.0) as f64,
                    rng.range_f32(0.0, 4.0) as f64,
                );
                let target: [f32; 3] =
                    std::array::from_fn(|k| (origin[k] + a * ex[k] + b * ey[k]) as f32);
                let o: [f32; 3] =
                    std::array::from_fn(|k| target[k] + 6.0 * rng.range_f32(-1.0, 1.0));
                let d = sub(target, o);
                let Some(t) = f.intersect(o, d, 0.0, f32::INFINITY) else {
                    continue;
                };
                let s = f.surface(o, d, t);
                let dist = dot(g.n, sub(f64v(s.p), g.c)).abs();
                let bound = abs_dot(f64v(f.n), f64v(s.p_err));
                assert!(dist <= bound, "off plane by {dist:e} > {bound:e}");
                pts += 1;
                for _ in 0..4 {
                    let w = sphere_dir(&mut rng);
                    let po = offset_ray_origin(
                        Vec3::from(s.p),
                        Vec3::from(s.p_err),
                        Vec3::from(f.n),
                        Vec3::from(w),
                    );
                    for org in [po.to_array(), s.p] {
                        if f.intersect(org, w, 0.0, f32::INFINITY).is_some() {
                            rehits += 1;
                        }
                    }
                }
            }
            println!("polygon at {origin:?}: {pts} points within bound, {rehits} self-hits");
            assert!(pts > 1000);
            assert_eq!(rehits, 0);
        }
    }

    /// Grazing rays (nearly in the plane) agree with f64 away from the edges.
    #[test]
    fn grazing_rays() {
        let loops2 = c_with_hole();
        let loops = place(&loops2, [0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let (f, g) = pair(&loops);
        let mut mism = 0;
        for i in 0..4000 {
            let eps = 1e-6f32 * (1.0 + i as f32);
            // Landing at x = 0.5, y = 2 (the left bar) or y = 0.5 (the bottom bar).
            let y = if i % 2 == 0 { 2.0 } else { 0.5 };
            let o = [-4.5f32, y, 5.0 * eps];
            let d = [1.0f32, 0.0, -eps];
            let a = f.intersect(o, d, 0.0, f32::INFINITY);
            let b = g.intersect(f64v(o), f64v(d), 0.0, f64::INFINITY);
            if a.is_some() != b.is_some() {
                mism += 1;
            }
            assert!(b.is_some(), "the f64 reference should hit");
        }
        assert_eq!(mism, 0);
    }
}
