//! The paper's bounding volumes beyond the box — spheres and Kay–Kajiya
//! slabs — built from points and boxes, and their conservative ray tests.
//!
//! Everything is computed in f64 from f32 inputs and rounded outward to f32,
//! so a volume built here contains its points exactly, and a ray test never
//! rejects a ray that meets the volume (`docs/numerics.md` rule 10: a bound
//! may be loose, never short). The ray tests run in f64: they are meant for
//! volumes around expensive children and for studying what a volume type
//! costs and saves (the `bvh`'s `bound` option), not for the SIMD box path.
//!
//! Sources: T. L. Kay and J. T. Kajiya, "Ray tracing complex scenes",
//! SIGGRAPH 1986 (plane-set volumes, the seven normals); the sphere test is
//! the perpendicular-distance form of Haines, "Precision improvements for
//! ray/sphere intersection", Ray Tracing Gems (2019), which avoids the
//! cancellation of `b² − c` far from the sphere.

#![allow(clippy::needless_range_loop)] // seven slabs indexed in step across arrays

use rtk_abi::{BoundSphere, Bounds3, Float3, Ray, SlabBounds, SLAB_COUNT, SLAB_NORMALS};

/// Round an f64 down to an f32 that is not above it.
#[inline]
pub fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        f.next_down()
    } else {
        f
    }
}

/// Round an f64 up to an f32 that is not below it.
#[inline]
pub fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

fn dvec(p: [f32; 3]) -> [f64; 3] {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

fn d3(p: Float3) -> [f64; 3] {
    [p.x as f64, p.y as f64, p.z as f64]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The eight corners of a box (none for an empty box).
pub fn box_corners(b: &Bounds3) -> Vec<[f32; 3]> {
    if b.min.x > b.max.x || b.min.y > b.max.y || b.min.z > b.max.z {
        return Vec::new();
    }
    (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            ]
        })
        .collect()
}

/// Relative allowance of the f64 ray tests: far above their rounding
/// (a few units of 2⁻⁵³), far below anything an f32 scene resolves.
const REL: f64 = 1e-12;

/// The geometry of [`BoundSphere`]: built from points and boxes in f64 and
/// rounded outward, tested against rays conservatively. (A trait because
/// the type is a plain value of the ABI crate, which holds no geometry.)
pub trait SphereVolume: Sized {
    /// A sphere around `points`, centred on their box's centre (not the
    /// smallest sphere, which Ritter's or Welzl's method would approach; the
    /// box centre is within a factor √3 and costs one pass).
    fn around_points(points: &[[f32; 3]]) -> BoundSphere;

    /// The sphere through a box's corners.
    fn around_box(b: &Bounds3) -> BoundSphere;

    /// A sphere of centre `c` and radius `r` computed in f64 (by a plugin
    /// from its own parameters), widened by `pad` and by the rounding of
    /// the centre to f32.
    fn from_f64(c: [f64; 3], r: f64, pad: f64) -> BoundSphere;

    /// A sphere around points given in f64, each known within `pad` of its
    /// true place along every axis.
    fn around_points_f64(points: &[[f64; 3]], pad: f64) -> BoundSphere;

    /// A sphere containing both.
    fn union(&self, o: &BoundSphere) -> BoundSphere;

    /// Whether `p` is inside (within the rounding of the test).
    fn contains(&self, p: [f32; 3]) -> bool;

    /// Where the ray may be inside: an interval containing the true one,
    /// `None` when the ray's line misses the sphere. The caller compares it
    /// with its `(t_min, t_max)`.
    fn ray_interval(&self, ray: &Ray) -> Option<(f32, f32)>;

    /// [`ray_interval`](Self::ray_interval) with the ray's part computed
    /// once per ray.
    fn interval(&self, r: &SphereRay) -> Option<(f32, f32)>;
}

impl SphereVolume for BoundSphere {
    fn around_points(points: &[[f32; 3]]) -> BoundSphere {
        let mut b = Bounds3::EMPTY;
        for p in points {
            b = b.include((*p).into());
        }
        around_points_from(&b, points)
    }

    fn around_box(b: &Bounds3) -> BoundSphere {
        around_points_from(b, &box_corners(b))
    }

    fn from_f64(c: [f64; 3], r: f64, pad: f64) -> BoundSphere {
        let center = Float3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        let cd = d3(center);
        let moved = [cd[0] - c[0], cd[1] - c[1], cd[2] - c[2]];
        let radius = f32_up((r + pad + dot(moved, moved).sqrt()) * (1.0 + 4.0 * f64::EPSILON));
        BoundSphere { center, radius }
    }

    fn around_points_f64(points: &[[f64; 3]], pad: f64) -> BoundSphere {
        if points.is_empty() {
            return Self::EMPTY;
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in points {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        let c: [f64; 3] = std::array::from_fn(|i| (lo[i] + hi[i]) * 0.5);
        let r2 = points
            .iter()
            .map(|p| {
                let v = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
                dot(v, v)
            })
            .fold(0.0, f64::max);
        Self::from_f64(c, r2.sqrt(), pad * 3f64.sqrt())
    }

    fn union(&self, o: &BoundSphere) -> BoundSphere {
        if o.is_empty() {
            return *self;
        }
        if self.is_empty() {
            return *o;
        }
        let (a, b) = (d3(self.center), d3(o.center));
        let v = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let dist = dot(v, v).sqrt();
        let (ra, rb) = (self.radius as f64, o.radius as f64);
        if dist + rb <= ra {
            return *self;
        }
        if dist + ra <= rb {
            return *o;
        }
        let r = (dist + ra + rb) * 0.5;
        let s = (r - ra) / dist;
        let c = [a[0] + v[0] * s, a[1] + v[1] * s, a[2] + v[2] * s];
        let center = Float3 {
            x: c[0] as f32,
            y: c[1] as f32,
            z: c[2] as f32,
        };
        // The rounded centre moved by at most its rounding: add that.
        let cd = d3(center);
        let moved = [cd[0] - c[0], cd[1] - c[1], cd[2] - c[2]];
        let radius = f32_up((r + dot(moved, moved).sqrt()) * (1.0 + 4.0 * f64::EPSILON));
        BoundSphere { center, radius }
    }

    fn contains(&self, p: [f32; 3]) -> bool {
        let (c, p) = (d3(self.center), dvec(p));
        let v = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        !self.is_empty() && dot(v, v).sqrt() <= self.radius as f64 * (1.0 + REL)
    }

    fn ray_interval(&self, ray: &Ray) -> Option<(f32, f32)> {
        self.interval(&SphereRay::new(ray))
    }

    fn interval(&self, r: &SphereRay) -> Option<(f32, f32)> {
        if self.is_empty() || !(r.dd > 0.0) {
            return None;
        }
        let (o, d, c) = (r.o, r.d, d3(self.center));
        let oc = [c[0] - o[0], c[1] - o[1], c[2] - o[2]];
        let tc = dot(oc, d) * r.inv_dd;
        // Perpendicular offset from the centre to the line (Haines 2019).
        let perp = [oc[0] - tc * d[0], oc[1] - tc * d[1], oc[2] - tc * d[2]];
        let h2 = dot(perp, perp);
        let rad = self.radius as f64;
        let slack = REL * (dot(oc, oc) + rad * rad);
        let disc = rad * rad + slack - h2;
        if disc < 0.0 {
            return None;
        }
        let half = (disc * r.inv_dd).sqrt();
        let pad = REL * (tc.abs() + half);
        Some((f32_down(tc - half - pad), f32_up(tc + half + pad)))
    }
}

fn around_points_from(b: &Bounds3, points: &[[f32; 3]]) -> BoundSphere {
    if points.is_empty() {
        return BoundSphere::EMPTY;
    }
    let c = [
        ((b.min.x as f64 + b.max.x as f64) * 0.5) as f32,
        ((b.min.y as f64 + b.max.y as f64) * 0.5) as f32,
        ((b.min.z as f64 + b.max.z as f64) * 0.5) as f32,
    ];
    let cd = dvec(c);
    let r2 = points
        .iter()
        .map(|p| {
            let d = dvec(*p);
            let v = [d[0] - cd[0], d[1] - cd[1], d[2] - cd[2]];
            dot(v, v)
        })
        .fold(0.0, f64::max);
    BoundSphere {
        center: Float3 {
            x: c[0],
            y: c[1],
            z: c[2],
        },
        // One ulp beyond the f64 root covers its rounding.
        radius: f32_up(r2.sqrt() * (1.0 + 4.0 * f64::EPSILON)),
    }
}

/// A ray's part of the sphere test, in f64.
#[derive(Clone, Copy, Debug)]
pub struct SphereRay {
    o: [f64; 3],
    d: [f64; 3],
    dd: f64,
    inv_dd: f64,
}

impl SphereRay {
    /// For `ray`.
    pub fn new(ray: &Ray) -> Self {
        let d = d3(ray.dir);
        let dd = dot(d, d);
        SphereRay {
            o: d3(ray.origin),
            d,
            dd,
            inv_dd: 1.0 / dd,
        }
    }
}

/// A ray's part of the slab test, per normal: `n·o` and `1 / n·d` in f64
/// (Kay and Kajiya's per-ray precomputation: a volume then costs two
/// multiplications per slab).
#[derive(Clone, Copy, Debug)]
pub struct SlabRay {
    no: [f64; SLAB_COUNT],
    inv: [f64; SLAB_COUNT],
    /// The ray is parallel to the slab's planes (`n·d = 0`).
    parallel: [bool; SLAB_COUNT],
}

impl SlabRay {
    /// For `ray`.
    pub fn new(ray: &Ray) -> Self {
        let (o, d) = (d3(ray.origin), d3(ray.dir));
        let mut r = SlabRay {
            no: [0.0; SLAB_COUNT],
            inv: [0.0; SLAB_COUNT],
            parallel: [false; SLAB_COUNT],
        };
        for k in 0..SLAB_COUNT {
            let n = dvec(SLAB_NORMALS[k]);
            let nd = dot(n, d);
            r.no[k] = dot(n, o);
            r.parallel[k] = nd == 0.0;
            r.inv[k] = if nd == 0.0 { 0.0 } else { 1.0 / nd };
        }
        r
    }
}

/// The geometry of [`SlabBounds`]: built from points and boxes in f64 and
/// rounded outward, tested against rays conservatively. (A trait because
/// the type is a plain value of the ABI crate, which holds no geometry.)
pub trait SlabVolume: Sized {
    /// The slabs of a point set: each point lies inside exactly (the
    /// diagonal sums are formed in f64 and rounded outward).
    fn from_points(points: &[[f32; 3]]) -> SlabBounds;

    /// The slabs of points given in f64, each within `pad` of its true place
    /// along every axis.
    fn from_points_f64(points: &[[f64; 3]], pad: f64) -> SlabBounds;

    /// The slabs of a sphere (tangent planes), outward.
    fn around_sphere(sp: &BoundSphere) -> SlabBounds;

    /// The intersection of two volumes that both contain an object (tighter
    /// than either).
    fn intersect(&self, o: &SlabBounds) -> SlabBounds;

    /// The slabs of a box: its own planes and its corners' diagonals.
    fn from_box(b: &Bounds3) -> SlabBounds;

    /// The smallest slab volume containing both.
    fn union(&self, o: &SlabBounds) -> SlabBounds;

    /// The box of the first three slabs.
    fn aabb(&self) -> Bounds3;

    /// Whether `p` is inside (exactly: the sums are formed in f64).
    fn contains(&self, p: [f32; 3]) -> bool;

    /// An interval containing the part of the ray's line inside the volume,
    /// or `None` when the line misses it.
    fn ray_interval(&self, ray: &Ray) -> Option<(f32, f32)>;

    /// [`ray_interval`](Self::ray_interval) with the ray's part computed
    /// once per ray.
    fn interval(&self, r: &SlabRay) -> Option<(f32, f32)>;
}

impl SlabVolume for SlabBounds {
    fn from_points(points: &[[f32; 3]]) -> SlabBounds {
        let mut s = SlabBounds::EMPTY;
        include_f64(&mut s, points.iter().map(|p| dvec(*p)), 0.0);
        s
    }

    fn from_points_f64(points: &[[f64; 3]], pad: f64) -> SlabBounds {
        let mut s = SlabBounds::EMPTY;
        include_f64(&mut s, points.iter().copied(), pad);
        s
    }

    fn around_sphere(sp: &BoundSphere) -> SlabBounds {
        if sp.is_empty() {
            return SlabBounds::EMPTY;
        }
        let c = d3(sp.center);
        let r = sp.radius as f64;
        let mut s = SlabBounds::EMPTY;
        for k in 0..SLAB_COUNT {
            let n = dvec(SLAB_NORMALS[k]);
            let (nc, len) = (dot(n, c), dot(n, n).sqrt());
            let e = r * len * (1.0 + 4.0 * f64::EPSILON) + nc.abs() * 4.0 * f64::EPSILON;
            s.lo[k] = f32_down(nc - e);
            s.hi[k] = f32_up(nc + e);
        }
        s
    }

    fn intersect(&self, o: &SlabBounds) -> SlabBounds {
        let mut s = *self;
        for k in 0..SLAB_COUNT {
            s.lo[k] = s.lo[k].max(o.lo[k]);
            s.hi[k] = s.hi[k].min(o.hi[k]);
        }
        s
    }

    fn from_box(b: &Bounds3) -> SlabBounds {
        Self::from_points(&box_corners(b))
    }

    fn union(&self, o: &SlabBounds) -> SlabBounds {
        let mut s = *self;
        for k in 0..SLAB_COUNT {
            if o.lo[k] < s.lo[k] {
                s.lo[k] = o.lo[k];
            }
            if o.hi[k] > s.hi[k] {
                s.hi[k] = o.hi[k];
            }
        }
        s
    }

    fn aabb(&self) -> Bounds3 {
        Bounds3 {
            min: Float3::new(self.lo[0], self.lo[1], self.lo[2]),
            max: Float3::new(self.hi[0], self.hi[1], self.hi[2]),
        }
    }

    fn contains(&self, p: [f32; 3]) -> bool {
        let d = dvec(p);
        (0..SLAB_COUNT).all(|k| {
            let v = dot(dvec(SLAB_NORMALS[k]), d);
            self.lo[k] as f64 - REL * v.abs() <= v && v <= self.hi[k] as f64 + REL * v.abs()
        })
    }

    fn ray_interval(&self, ray: &Ray) -> Option<(f32, f32)> {
        self.interval(&SlabRay::new(ray))
    }

    fn interval(&self, r: &SlabRay) -> Option<(f32, f32)> {
        if self.is_empty() {
            return None;
        }
        let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
        for k in 0..SLAB_COUNT {
            let (lo, hi, no) = (self.lo[k] as f64, self.hi[k] as f64, r.no[k]);
            let scale = lo.abs().max(hi.abs()) + no.abs();
            if r.parallel[k] {
                // Parallel: inside the slab or never.
                if no < lo - REL * scale || no > hi + REL * scale {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - no) * r.inv[k], (hi - no) * r.inv[k]);
            let (near, far) = if a <= b { (a, b) } else { (b, a) };
            let pad = REL * (scale * r.inv[k].abs() + far.abs().max(near.abs()));
            enter = enter.max(near - pad);
            exit = exit.min(far + pad);
            if enter > exit {
                return None;
            }
        }
        Some((f32_down(enter), f32_up(exit)))
    }
}

fn include_f64(s: &mut SlabBounds, points: impl Iterator<Item = [f64; 3]>, pad: f64) {
    let mut lo = [f64::INFINITY; SLAB_COUNT];
    let mut hi = [f64::NEG_INFINITY; SLAB_COUNT];
    for d in points {
        for k in 0..SLAB_COUNT {
            let v = dot(dvec(SLAB_NORMALS[k]), d);
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    for k in 0..SLAB_COUNT {
        if lo[k] <= hi[k] {
            // |n|₁ is 1 on the axes, 3 on the diagonals: how far a point
            // `pad` off along every axis moves along n.
            let l1: f64 = SLAB_NORMALS[k].iter().map(|c| c.abs() as f64).sum();
            let (a, b) = (f32_down(lo[k] - pad * l1), f32_up(hi[k] + pad * l1));
            // The axes are exact; a diagonal's f64 sum may carry one
            // rounding, which a further f32 step outward covers.
            let (a, b) = if k < 3 && pad == 0.0 {
                (a, b)
            } else {
                (a.next_down(), b.next_up())
            };
            s.lo[k] = s.lo[k].min(a);
            s.hi[k] = s.hi[k].max(b);
        }
    }
}

/// Whether the interval `(enter, exit)` meets a ray's `(t_min, t_max)`; the
/// entry distance to order visits by when it does.
#[inline]
pub fn overlaps(interval: Option<(f32, f32)>, t_min: f32, t_max: f32) -> Option<f32> {
    let (enter, exit) = interval?;
    (exit >= t_min && enter <= t_max).then_some(enter.max(t_min))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_abi::RngState;

    fn rand_points(rng: &mut RngState, n: usize, scale: f32) -> Vec<[f32; 3]> {
        (0..n)
            .map(|_| {
                [
                    (rng.next_f32() - 0.5) * scale,
                    (rng.next_f32() - 0.5) * scale + 3.0,
                    (rng.next_f32() - 0.5) * scale,
                ]
            })
            .collect()
    }

    #[test]
    fn volumes_contain_their_points() {
        let mut rng = RngState::seeded(7);
        for scale in [1e-3, 1.0, 1e4] {
            let pts = rand_points(&mut rng, 200, scale);
            let s = BoundSphere::around_points(&pts);
            let sl = SlabBounds::from_points(&pts);
            for p in &pts {
                assert!(s.contains(*p));
                assert!(sl.contains(*p));
            }
            let half = BoundSphere::around_points(&pts[..100])
                .union(&BoundSphere::around_points(&pts[100..]));
            assert!(pts.iter().all(|p| half.contains(*p)));
        }
    }

    /// A ray starting exactly at one of the points (so it is in the volume
    /// at t = 0, with no rounding in the set-up) always meets it there, in
    /// any direction, axis-parallel ones included; a ray from far away aimed
    /// at a point just inside meets it too.
    #[test]
    fn ray_tests_never_miss_a_contained_point() {
        let mut rng = RngState::seeded(11);
        for scale in [1e-2, 1.0, 1e5] {
            let pts = rand_points(&mut rng, 64, scale);
            let s = BoundSphere::around_points(&pts);
            let sl = SlabBounds::from_points(&pts);
            let mid = [0.0, 3.0, 0.0];
            for p in &pts {
                for _ in 0..50 {
                    let mut d = [
                        rng.next_f32() - 0.5,
                        rng.next_f32() - 0.5,
                        rng.next_f32() - 0.5,
                    ];
                    if rng.next_f32() < 0.3 {
                        d[(rng.next_f32() * 3.0) as usize % 3] = 0.0;
                    }
                    let ray = Ray::new((*p).into(), d.into());
                    for (name, iv) in [
                        ("sphere", s.ray_interval(&ray)),
                        ("slabs", sl.ray_interval(&ray)),
                    ] {
                        let (a, b) = iv.unwrap_or_else(|| panic!("{name} missed {p:?}"));
                        assert!(a <= 0.0 && b >= 0.0, "{name}: {a}..{b}");
                    }
                    // From far away at a point 5 % inside.
                    let q: [f32; 3] = std::array::from_fn(|i| p[i] + 0.05 * (mid[i] - p[i]));
                    let t = 10.0 * scale;
                    let o: [f32; 3] = std::array::from_fn(|i| q[i] - d[i] * t);
                    let far = Ray::new(o.into(), d.into());
                    assert!(overlaps(s.ray_interval(&far), 0.0, f32::INFINITY).is_some());
                    assert!(overlaps(sl.ray_interval(&far), 0.0, f32::INFINITY).is_some());
                }
            }
        }
    }

    #[test]
    fn empty_volumes_are_never_hit() {
        let ray = Ray::new([0.0, 0.0, -5.0].into(), [0.0, 0.0, 1.0].into());
        assert!(BoundSphere::EMPTY.ray_interval(&ray).is_none());
        assert!(SlabBounds::EMPTY.ray_interval(&ray).is_none());
        assert!(BoundSphere::around_points(&[]).is_empty());
    }

    #[test]
    fn slabs_cut_a_box_corner_off() {
        // A single triangle near one corner of its box: the diagonal slab
        // (1,1,1) rejects a ray through the opposite corner that the box
        // accepts.
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let sl = SlabBounds::from_points(&tri);
        let b = sl.aabb();
        assert_eq!((b.max.x, b.max.y, b.max.z), (1.0, 1.0, 0.0));
        let ray = Ray::new([0.95, 0.95, -1.0].into(), [0.0, 0.0, 1.0].into());
        assert!(sl.ray_interval(&ray).is_none());
        let s = BoundSphere::around_box(&b);
        assert!((s.radius - 0.5f32.sqrt()).abs() < 1e-6);
    }
}
