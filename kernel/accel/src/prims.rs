//! The primitives an aggregate builds over, gathered from its children, and
//! the leaf queries that return exactly the `list`'s answer.
//!
//! Each child contributes, in order of preference:
//! - its **triangles as data** (capability `Triangles`): copied into this
//!   table and intersected inline with the kernel's watertight routine — no
//!   call into the child per leaf;
//! - its **primitive set** (`PrimitiveSet`): one batched `intersect_prims`
//!   call per run of its primitives in a leaf;
//! - **itself**, whole: an opaque object (a transform, another aggregate).
//!
//! The tie rule: at equal `t` the lowest (child, primitive) wins, whatever
//! order a structure visits them in. The query keeps the best key and lets an
//! equal `t` through (one ulp more) only to a lower key.

use rtk_abi::*;
use rtk_geom::{intersect_triangle_sheared, is_degenerate, RayShear, SlabVolume, SphereVolume};
use rtk_sdk::{Child, PluginError, PrimSet};

use super::Line;

/// The `prim` of an entry that stands for a whole child.
pub const WHOLE: u32 = u32::MAX;

/// One primitive of the table: which child, which of its primitives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimRef {
    /// The child's slot (the order of `add_child`).
    pub child: u32,
    /// The primitive within the child, or [`WHOLE`].
    pub prim: u32,
}

impl PrimRef {
    /// The tie-rule key: lower wins at equal `t`.
    #[inline]
    fn key(self) -> u64 {
        ((self.child as u64) << 32) | self.prim as u64
    }
}

/// How a child is queried.
#[derive(Clone)]
enum Source {
    Triangles,
    Set(PrimSet),
    Whole,
}

/// A nearest-hit query in progress: the ray (its `t_max` narrowed to the best
/// hit so far) and the best hit's tie-rule key.
pub struct Nearest {
    /// The ray; `t_max` is the best hit's `t` once one is found.
    pub ray: Ray,
    best: u64,
    /// The ray's shear for the triangle test, computed once.
    shear: RayShear<f32>,
    /// The same, in the form the 4-wide leaf screen reads.
    screen: ScreenRay,
}

impl Nearest {
    /// A query over `(ray.t_min, ray.t_max)` with nothing found yet.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let shear = RayShear::new(ray.origin.to_array(), ray.dir.to_array());
        Nearest {
            ray: *ray,
            best: u64::MAX,
            screen: ScreenRay::new(&shear),
            shear,
        }
    }

    /// A hit was accepted.
    #[inline]
    pub fn found(&self) -> bool {
        self.best != u64::MAX
    }

    /// The exclusive upper end to test a primitive of key `key` against: one
    /// ulp above the best `t` for a lower key (a tie goes to it), the best `t`
    /// otherwise.
    #[inline]
    fn limit(&self, key: u64) -> f32 {
        if self.found() && key < self.best {
            self.ray.t_max.next_up()
        } else {
            self.ray.t_max
        }
    }
}

/// The primitives of an aggregate's children.
pub struct Primitives {
    children: Vec<Child>,
    sources: Vec<Source>,
    refs: Vec<PrimRef>,
    /// The three vertices of each triangle entry, parallel to `refs`
    /// (zeros for other entries): the leaf's own layout, no index lookup.
    tris: Vec<[[f32; 3]; 3]>,
    /// The entries four to a block ([`Primitives::pack`]).
    blocks: Vec<Tri4>,
}

/// Four entries of the table, a leaf's unit: their triangles in
/// structure-of-arrays order (`v[vertex][axis][lane]`) and their
/// [`PrimRef`]s, in three whole cache lines, so a leaf visit reads one
/// contiguous block and nothing else.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
struct Tri4 {
    v: [[[f32; 4]; 3]; 3],
    refs: [PrimRef; 4],
    /// The lanes holding triangles when every entry of the block is a
    /// triangle or a gap (screened 4-wide); 0 when it holds another kind
    /// (queried entry by entry).
    lanes: u32,
    /// Entries that are not gaps (they come first).
    entries: u32,
    /// 1: a leaf ends with this block ([`Primitives::mark_leaves`]).
    last: u32,
    /// No implicit padding: every byte is initialised, so a block can be
    /// copied as cache lines ([`Primitives::leaf_lines`]).
    _pad: [u32; 1],
}

/// Three lines, no padding: the layout [`Primitives::leaf_lines`] relies on.
const _: () = assert!(std::mem::size_of::<Tri4>() == 192 && std::mem::align_of::<Tri4>() == 64);

/// What the 4-wide screen needs of a ray, computed once per query: the
/// sheared space's axes as row offsets, and the origin and shear in that
/// order.
#[derive(Clone, Copy)]
pub struct ScreenRay {
    k: [usize; 3],
    o: [f32; 3],
    s: [f32; 3],
}

impl ScreenRay {
    #[inline(always)]
    fn new(r: &RayShear<f32>) -> Self {
        let (o, k, s) = r.parts();
        ScreenRay {
            k,
            o: k.map(|a| o[a]),
            s,
        }
    }
}

impl Tri4 {
    fn new(entries: &[([[f32; 3]; 3], PrimRef, bool)]) -> Self {
        let mut v = [[[0.0f32; 4]; 3]; 3];
        let mut refs = [GAP; 4];
        let mut lanes = 0;
        let mut packed = true;
        for (lane, &(t, r, is_tri)) in entries.iter().enumerate() {
            for (k, p) in t.iter().enumerate() {
                for a in 0..3 {
                    v[k][a][lane] = p[a];
                }
            }
            refs[lane] = r;
            if is_tri {
                lanes |= 1 << lane;
            } else if r != GAP {
                packed = false;
            }
        }
        Tri4 {
            v,
            refs,
            lanes: if packed { lanes } else { 0 },
            entries: refs.iter().filter(|&&r| r != GAP).count() as u32,
            last: 0,
            _pad: [0],
        }
    }

    /// The triangle in `lane`.
    #[inline(always)]
    fn tri(&self, lane: usize) -> [[f32; 3]; 3] {
        let v = &self.v;
        [0, 1, 2].map(|k| [v[k][0][lane], v[k][1][lane], v[k][2][lane]])
    }

    /// Whether triangle `lane` lies in an axis-aligned plane (its three
    /// vertices share one coordinate exactly) that `o` lies in too. A ray
    /// from such an origin meets that plane only at t = 0 (or, lying in it,
    /// never: its determinant is 0), so the triangle is a miss for any ray
    /// whose `t_min` is not negative — exactly what the scalar test's f64
    /// recheck concludes, found without it. Why it matters: a hit on a wall
    /// of a box has an exact coordinate across the wall (its error bound is
    /// 0 there), so every ray spawned from a box's wall starts in the wall's
    /// plane, and its two triangles would each take the scalar test.
    #[inline(always)]
    fn origin_in_axis_plane(&self, lane: usize, o: [f32; 3]) -> bool {
        let v = &self.v;
        (0..3).any(|k| {
            let a = v[0][k][lane];
            a == o[k] && v[1][k][lane] == a && v[2][k][lane] == a
        })
    }

    /// The 4-wide watertight test over `(t_min, t_max)`: per lane, the
    /// scalar test's operations in the same order ([`intersect_triangle_sheared`]),
    /// so a lane it decides gets the scalar test's `t` and barycentrics bit
    /// for bit. Lanes it cannot decide in f32 — an exactly zero edge
    /// function (decided in f64), a `t` within its error bound of 0 — are
    /// left to the scalar test (`slow`). One case differs, as documented
    /// for the scalar test's callers: a `t` beyond `t_max` yet within its
    /// error bound of 0, which the scalar test resolves in f64, is rejected
    /// here; it needs a `t_max` within the rounding of the ray's origin,
    /// which rtk's spawned rays never have (their offset keeps `t_min` past
    /// it).
    #[inline(always)]
    fn test(&self, r: &ScreenRay, t_min: f32, t_max: f32) -> Lanes4 {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: SSE/SSE2 only, part of every x86_64 CPU.
            unsafe { self.test_sse(r, t_min, t_max) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (r, t_min, t_max);
            Lanes4 {
                hit: 0,
                slow: 0b1111,
                t: [0.0; 4],
                b1: [0.0; 4],
                b2: [0.0; 4],
            }
        }
    }

    /// # Safety
    /// The CPU must have SSE2 (every x86_64 CPU does).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn test_sse(&self, r: &ScreenRay, t_min: f32, t_max: f32) -> Lanes4 {
        use std::arch::x86_64::*;
        debug_assert!(r.k.iter().all(|&a| a < 3));
        // SAFETY: SSE2 is part of every x86_64 CPU (the contract), which is
        // all the steps need: `shear4` reads the block's own rows, the rest
        // is register arithmetic.
        unsafe {
            let p = shear4(&self.v, r);
            let e = edges4(&p);
            let within = within_limit4(&e, t_max);
            let zeros = _mm_movemask_ps(e.has_zero) as u32;
            if _mm_movemask_ps(within.lanes) as u32 & !zeros == 0 {
                // Nothing to finish here: every lane missed, or is the
                // scalar test's (an exactly zero edge function).
                return Lanes4 {
                    hit: 0,
                    slow: zeros,
                    t: [0.0; 4],
                    b1: [0.0; 4],
                    b2: [0.0; 4],
                };
            }
            decide4(&e, ts_error4(&p, &e), &within, t_min, t_max)
        }
    }
}

/// Four triangles' vertices in the ray's sheared space (pbrt-v4's
/// watertight test: translated to the ray's origin, axes permuted so the
/// ray runs along z, sheared so it is the z axis): `x[vertex]` holds the
/// four lanes' x of that vertex, and so for `y` and `z`.
#[cfg(target_arch = "x86_64")]
struct Sheared4 {
    x: [std::arch::x86_64::__m128; 3],
    y: [std::arch::x86_64::__m128; 3],
    z: [std::arch::x86_64::__m128; 3],
}

/// The three edge functions of four triangles and what they decide: lanes
/// with an edge function exactly 0 (`has_zero`: the scalar test's, in
/// f64), lanes whose edge functions differ in sign (`mixed`: a miss), the
/// determinant (their sum) and the scaled distance `ts`.
#[cfg(target_arch = "x86_64")]
struct Edges4 {
    e: [std::arch::x86_64::__m128; 3],
    has_zero: std::arch::x86_64::__m128,
    mixed: std::arch::x86_64::__m128,
    det: std::arch::x86_64::__m128,
    ts: std::arch::x86_64::__m128,
}

/// The lanes [`within_limit4`] keeps, with the determinant's sign (which
/// way `ts` must lie).
#[cfg(target_arch = "x86_64")]
struct Within4 {
    neg: std::arch::x86_64::__m128,
    pos: std::arch::x86_64::__m128,
    lanes: std::arch::x86_64::__m128,
}

/// The block's vertices `v` in the sheared space of `r`, the scalar test's
/// operations in its order.
///
/// # Safety
/// SSE2 (every x86_64 CPU); `r.k` holds axes (0..3).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn shear4(v: &[[[f32; 4]; 3]; 3], r: &ScreenRay) -> Sheared4 {
    use std::arch::x86_64::*;
    let (o, k, s) = (r.o, r.k, r.s);
    // SAFETY: `k` holds axes (0..3), so each row read is one of the
    // block's (four floats, 16-byte aligned); the rest is register
    // arithmetic.
    unsafe {
        let load = |vert: &[[f32; 4]; 3], a: usize| _mm_load_ps(vert.as_ptr().add(a).cast());
        let (sx, sy, sz) = (_mm_set1_ps(s[0]), _mm_set1_ps(s[1]), _mm_set1_ps(s[2]));
        let (ox, oy, oz) = (_mm_set1_ps(o[0]), _mm_set1_ps(o[1]), _mm_set1_ps(o[2]));
        let mut p = Sheared4 {
            x: [_mm_setzero_ps(); 3],
            y: [_mm_setzero_ps(); 3],
            z: [_mm_setzero_ps(); 3],
        };
        for (vi, vert) in v.iter().enumerate() {
            let tx = _mm_sub_ps(load(vert, k[0]), ox);
            let ty = _mm_sub_ps(load(vert, k[1]), oy);
            let tz = _mm_sub_ps(load(vert, k[2]), oz);
            p.x[vi] = _mm_add_ps(tx, _mm_mul_ps(sx, tz));
            p.y[vi] = _mm_add_ps(ty, _mm_mul_ps(sy, tz));
            p.z[vi] = _mm_mul_ps(tz, sz);
        }
        p
    }
}

/// The edge functions of the sheared triangles `p`, with the determinant
/// and `ts` (plain products, as the scalar test: see
/// [`intersect_triangle_sheared`]).
///
/// # Safety
/// SSE2 (every x86_64 CPU).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn edges4(p: &Sheared4) -> Edges4 {
    use std::arch::x86_64::*;
    // SAFETY: register arithmetic on SSE2, part of every x86_64 CPU.
    unsafe {
        let (px, py, pz) = (&p.x, &p.y, &p.z);
        let cross =
            |a: usize, b: usize| _mm_sub_ps(_mm_mul_ps(px[a], py[b]), _mm_mul_ps(py[a], px[b]));
        let (e0, e1, e2) = (cross(1, 2), cross(2, 0), cross(0, 1));
        let zero = _mm_setzero_ps();
        let any = |f: unsafe fn(__m128, __m128) -> __m128| {
            _mm_or_ps(_mm_or_ps(f(e0, zero), f(e1, zero)), f(e2, zero))
        };
        let has_zero = any(_mm_cmpeq_ps);
        let mixed = _mm_and_ps(any(_mm_cmplt_ps), any(_mm_cmpgt_ps));
        let det = _mm_add_ps(_mm_add_ps(e0, e1), e2);
        let ts = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(e0, pz[0]), _mm_mul_ps(e1, pz[1])),
            _mm_mul_ps(e2, pz[2]),
        );
        Edges4 {
            e: [e0, e1, e2],
            has_zero,
            mixed,
            det,
            ts,
        }
    }
}

/// The lanes whose edge functions agree in sign and whose `ts` is within
/// the scalar test's widened limit `t_max·det·(1 + γ₄)`: the same
/// operations in the same order, so a lane is rejected only where the
/// scalar test rejects it too.
///
/// # Safety
/// SSE2 (every x86_64 CPU).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn within_limit4(e: &Edges4, t_max: f32) -> Within4 {
    use rtk_geom::gamma;
    use std::arch::x86_64::*;
    // SAFETY: register arithmetic on SSE2, part of every x86_64 CPU.
    unsafe {
        let lim = _mm_mul_ps(
            _mm_mul_ps(_mm_set1_ps(t_max), e.det),
            _mm_set1_ps(1.0 + gamma::<f32>(4)),
        );
        let zero = _mm_setzero_ps();
        let neg = _mm_cmplt_ps(e.det, zero);
        let pos = _mm_cmpgt_ps(e.det, zero);
        let lanes = _mm_andnot_ps(
            e.mixed,
            _mm_or_ps(
                _mm_and_ps(neg, _mm_cmpge_ps(e.ts, lim)),
                _mm_and_ps(pos, _mm_cmple_ps(e.ts, lim)),
            ),
        );
        Within4 { neg, pos, lanes }
    }
}

/// pbrt-v4's error bound of `ts`, as the scalar test computes it.
///
/// # Safety
/// SSE2 (every x86_64 CPU).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn ts_error4(p: &Sheared4, e: &Edges4) -> std::arch::x86_64::__m128 {
    use rtk_geom::gamma;
    use std::arch::x86_64::*;
    // SAFETY: register arithmetic on SSE2, part of every x86_64 CPU.
    unsafe {
        let max3 = |v: [__m128; 3]| _mm_max_ps(_mm_max_ps(abs4(v[0]), abs4(v[1])), abs4(v[2]));
        let (max_zt, max_xt, max_yt) = (max3(p.z), max3(p.x), max3(p.y));
        let g = |n: u32| _mm_set1_ps(gamma::<f32>(n));
        let dz = _mm_mul_ps(g(3), max_zt);
        let dx = _mm_mul_ps(g(5), _mm_add_ps(max_xt, max_zt));
        let dy = _mm_mul_ps(g(5), _mm_add_ps(max_yt, max_zt));
        let de = _mm_mul_ps(
            _mm_set1_ps(2.0),
            _mm_add_ps(
                _mm_add_ps(
                    _mm_mul_ps(_mm_mul_ps(g(2), max_xt), max_yt),
                    _mm_mul_ps(dy, max_xt),
                ),
                _mm_mul_ps(dx, max_yt),
            ),
        );
        let max_e = max3(e.e);
        _mm_mul_ps(
            _mm_set1_ps(3.0),
            _mm_add_ps(
                _mm_add_ps(
                    _mm_mul_ps(_mm_mul_ps(g(3), max_e), max_zt),
                    _mm_mul_ps(de, max_zt),
                ),
                _mm_mul_ps(dz, max_e),
            ),
        )
    }
}

/// |x| per lane.
///
/// # Safety
/// SSE2 (every x86_64 CPU).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn abs4(x: std::arch::x86_64::__m128) -> std::arch::x86_64::__m128 {
    use std::arch::x86_64::*;
    // SAFETY: register arithmetic on SSE2, part of every x86_64 CPU.
    unsafe { _mm_andnot_ps(_mm_set1_ps(-0.0), x) }
}

/// Of the lanes `within` the limit, which hit in `(t_min, t_max)` (with
/// their `t` and barycentrics) and which are left to the scalar test: a
/// zero edge function, a `t` within its error bound `ts_err` of 0.
///
/// # Safety
/// SSE2 (every x86_64 CPU).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn decide4(
    e: &Edges4,
    ts_err: std::arch::x86_64::__m128,
    within: &Within4,
    t_min: f32,
    t_max: f32,
) -> Lanes4 {
    use std::arch::x86_64::*;
    let mut out = Lanes4 {
        hit: 0,
        slow: 0,
        t: [0.0; 4],
        b1: [0.0; 4],
        b2: [0.0; 4],
    };
    // SAFETY: register arithmetic on SSE2, part of every x86_64 CPU, and
    // stores of four floats into `out`'s arrays of four.
    unsafe {
        let (neg, pos, ts, zero) = (within.neg, within.pos, e.ts, _mm_setzero_ps());
        let within = within.lanes;
        let inv = _mm_div_ps(_mm_set1_ps(1.0), e.det);
        let t = _mm_mul_ps(ts, inv);
        let dt = _mm_mul_ps(ts_err, abs4(inv));
        let ahead = _mm_or_ps(
            _mm_and_ps(neg, _mm_cmplt_ps(ts, zero)),
            _mm_and_ps(pos, _mm_cmpgt_ps(ts, zero)),
        );
        // Behind the origin: a miss, unless within the error of 0.
        let near0 = _mm_cmple_ps(abs4(ts), ts_err);
        let behind = _mm_and_ps(_mm_andnot_ps(ahead, within), near0);
        let ahead = _mm_and_ps(ahead, within);
        let clear = _mm_cmpgt_ps(t, dt);
        let slow = _mm_or_ps(_mm_or_ps(e.has_zero, behind), _mm_andnot_ps(clear, ahead));
        let hit = _mm_and_ps(
            _mm_and_ps(ahead, clear),
            _mm_and_ps(
                _mm_cmpgt_ps(t, _mm_set1_ps(t_min)),
                _mm_cmplt_ps(t, _mm_set1_ps(t_max)),
            ),
        );
        out.slow = _mm_movemask_ps(slow) as u32;
        out.hit = _mm_movemask_ps(_mm_andnot_ps(slow, hit)) as u32;
        _mm_storeu_ps(out.t.as_mut_ptr(), t);
        _mm_storeu_ps(out.b1.as_mut_ptr(), _mm_mul_ps(e.e[1], inv));
        _mm_storeu_ps(out.b2.as_mut_ptr(), _mm_mul_ps(e.e[2], inv));
        out
    }
}

/// What the 4-wide test decided: lanes hit (with their `t` and
/// barycentrics), and lanes left to the scalar test.
struct Lanes4 {
    hit: u32,
    slow: u32,
    t: [f32; 4],
    b1: [f32; 4],
    b2: [f32; 4],
}

/// What [`Primitives::gather`] returns besides the table: each primitive's box,
/// in table order, for the structure to be built over.
pub struct Gathered {
    /// The table.
    pub prims: Primitives,
    /// Box of each primitive.
    pub boxes: Vec<Bounds3>,
}

impl Primitives {
    /// Gather the primitives of `children` (all prepared: their data is final).
    pub fn gather(children: &[Child]) -> Result<Gathered, PluginError> {
        let mut p = Primitives {
            children: children.to_vec(),
            sources: Vec::with_capacity(children.len()),
            refs: Vec::new(),
            tris: Vec::new(),
            blocks: Vec::new(),
        };
        let mut boxes = Vec::new();
        for (c, child) in children.iter().enumerate() {
            let c = c as u32;
            let source = match child.prim_set() {
                Some(set) => match set.triangles()? {
                    Some(t) => {
                        // Room for all at once: growing by doubling copied
                        // the dragon's tables about twice over.
                        boxes.reserve(t.indices.len());
                        p.refs.reserve(t.indices.len());
                        p.tris.reserve(t.indices.len());
                        for (i, ix) in t.indices.iter().enumerate() {
                            let v = ix.map(|k| t.positions[k as usize]);
                            // Never hit (T3): left out of the structure.
                            if is_degenerate(&v) {
                                continue;
                            }
                            boxes.push(tri_bounds(&v));
                            p.refs.push(PrimRef {
                                child: c,
                                prim: i as u32,
                            });
                            p.tris.push(v);
                        }
                        Source::Triangles
                    }
                    None => {
                        let n = set.count()?;
                        let first = boxes.len();
                        boxes.resize(first + n as usize, Bounds3::EMPTY);
                        set.bounds(0, &mut boxes[first..])?;
                        p.refs.extend((0..n).map(|i| PrimRef { child: c, prim: i }));
                        p.tris.resize(boxes.len(), [[0.0; 3]; 3]);
                        Source::Set(set)
                    }
                },
                None => {
                    boxes.push(child.bounds(0.0, 1.0)?);
                    p.refs.push(PrimRef {
                        child: c,
                        prim: WHOLE,
                    });
                    p.tris.push([[0.0; 3]; 3]);
                    Source::Whole
                }
            };
            p.sources.push(source);
        }
        Ok(Gathered { prims: p, boxes })
    }

    /// Every entry is a triangle (the children all lend theirs): a leaf
    /// then costs its 4-wide blocks, whatever its size, and a structure may
    /// choose larger leaves than over entries queried one call each.
    pub fn all_triangles(&self) -> bool {
        self.sources.iter().all(|s| matches!(s, Source::Triangles))
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.refs.len()
    }

    /// No primitives at all.
    pub fn is_empty(&self) -> bool {
        self.refs.is_empty()
    }

    /// The entry at `i`.
    pub fn get(&self, i: usize) -> PrimRef {
        self.refs[i]
    }

    /// Put the primitives in `order` (`order[k]` is the old index of the new
    /// `k`-th): a structure whose leaves are ranges stores them contiguously.
    /// [`PAD`](super::PAD) entries of `order` become gaps that no query
    /// visits.
    pub fn reorder(&mut self, order: &[u32]) {
        self.refs = order
            .iter()
            .map(|&i| self.refs.get(i as usize).copied().unwrap_or(GAP))
            .collect();
        self.tris = order
            .iter()
            .map(|&i| self.tris.get(i as usize).copied().unwrap_or_default())
            .collect();
    }

    /// Points whose hull contains entry `i` (before [`Primitives::pack`]):
    /// a triangle's vertices, a set primitive's box corners, a whole
    /// child's own hull points (`inq_bounds`); none for a gap.
    pub fn hull_points(&self, i: usize) -> Result<Vec<[f32; 3]>, PluginError> {
        let r = self.refs[i];
        if r.child == u32::MAX {
            return Ok(Vec::new());
        }
        match &self.sources[r.child as usize] {
            Source::Triangles => Ok(self.tris[i].to_vec()),
            Source::Set(set) => {
                let mut b = [Bounds3::EMPTY];
                set.bounds(r.prim, &mut b)?;
                Ok(rtk_geom::box_corners(&b[0]))
            }
            Source::Whole => self.children[r.child as usize].hull_points(0.0, 1.0),
        }
    }

    /// A sphere containing entry `i` (before [`Primitives::pack`]); a whole
    /// child answers with its own.
    pub fn bound_sphere(&self, i: usize) -> Result<BoundSphere, PluginError> {
        let r = self.refs[i];
        match self.sources.get(r.child as usize) {
            Some(Source::Whole) => self.children[r.child as usize].bound_sphere(0.0, 1.0),
            _ => Ok(BoundSphere::around_points(&self.hull_points(i)?)),
        }
    }

    /// Kay–Kajiya slabs containing entry `i` (before [`Primitives::pack`]);
    /// a whole child answers with its own.
    pub fn slabs(&self, i: usize) -> Result<SlabBounds, PluginError> {
        let r = self.refs[i];
        match self.sources.get(r.child as usize) {
            Some(Source::Whole) => self.children[r.child as usize].slabs(0.0, 1.0),
            _ => Ok(SlabBounds::from_points(&self.hull_points(i)?)),
        }
    }

    /// Bytes held, for the benchmarks' memory figures.
    pub fn bytes(&self) -> usize {
        self.refs.capacity() * std::mem::size_of::<PrimRef>()
            + self.tris.capacity() * std::mem::size_of::<[[f32; 3]; 3]>()
            + self.blocks.capacity() * std::mem::size_of::<Tri4>()
            + self.children.capacity() * std::mem::size_of::<Child>()
    }

    /// Nearest hit among the primitives `ids` (indices into the table),
    /// recorded from `level` on when it beats `q`'s best. Primitives of a
    /// primitive set that follow each other in `ids` go to the child in one
    /// batched call.
    #[inline]
    pub fn intersect_ids(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        ids: impl Iterator<Item = usize>,
        hit: &mut Hit,
        level: u32,
    ) {
        let entries = ids.map(|i| (self.refs[i], i));
        let entries = entries.map(|(r, i)| match &self.sources[r.child as usize] {
            Source::Triangles => (r, self.vertices(i)),
            _ => (r, [[0.0; 3]; 3]),
        });
        self.intersect_entries(ctx, q, entries, hit, level)
    }

    /// [`Primitives::intersect_ids`] over entries given as their reference
    /// and, for a triangle, its vertices.
    #[inline]
    fn intersect_entries(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        entries: impl Iterator<Item = (PrimRef, [[f32; 3]; 3])>,
        hit: &mut Hit,
        level: u32,
    ) {
        let d = q.ray.dir.to_array();
        let mut tests = 0u64;
        let mut run = Run::default();
        for (r, v) in entries {
            tests += 1;
            match &self.sources[r.child as usize] {
                Source::Triangles => self.triangle(q, d, r, v, hit, level),
                Source::Set(_) => {
                    if !run.push(r) {
                        self.flush(ctx, q, &mut run, hit, level);
                        run.push(r);
                    }
                }
                Source::Whole => {
                    self.flush(ctx, q, &mut run, hit, level);
                    self.whole(ctx, q, r, hit, level);
                }
            }
        }
        self.flush(ctx, q, &mut run, hit, level);
        ctx.stats.prim_tests += tests;
    }

    /// The vertices of triangle entry `i`: from the unpacked copy, or from
    /// its block once [`Primitives::pack`] dropped that copy.
    #[inline(always)]
    fn vertices(&self, i: usize) -> [[f32; 3]; 3] {
        match self.tris.get(i) {
            Some(v) => *v,
            None => self.blocks[i / 4].tri(i % 4),
        }
    }

    /// The exact test of triangle entry `i` (vertices `v`) under the tie rule.
    #[inline(always)]
    fn triangle(
        &self,
        q: &mut Nearest,
        d: [f32; 3],
        r: PrimRef,
        v: [[f32; 3]; 3],
        hit: &mut Hit,
        level: u32,
    ) {
        let limit = q.limit(r.key());
        if let Some(h) = intersect_triangle_sheared(&q.shear, d, v, q.ray.t_min, limit) {
            q.ray.t_max = h.t;
            q.best = r.key();
            hit.record_child(level, r.child);
            hit.record_leaf(level + 1, h.t, r.prim, [h.b[1], h.b[2]]);
        }
    }

    /// Pack the entries four to a block, for [`Primitives::intersect_range`]'s
    /// 4-wide test. The table must be in a padded leaf order
    /// ([`Bvh4::pad_leaves`](super::Bvh4::pad_leaves) with 4): every leaf
    /// starts a block, so a leaf's first entry names its block. A block is
    /// screened 4-wide if it holds triangles only; other blocks are queried
    /// entry by entry. The unpacked copy of the vertices is then dropped:
    /// the blocks hold them.
    pub fn pack(&mut self) {
        let entry = |i: usize| {
            let r = self.refs[i];
            let is_tri = r != GAP && matches!(self.sources[r.child as usize], Source::Triangles);
            (self.tris[i], r, is_tri)
        };
        // Block by block, each from its four entries on the stack (no
        // table of all entries first: it was as large as the blocks).
        let n = self.refs.len();
        self.blocks = (0..n.div_ceil(4))
            .map(|b| {
                let mut four = [([[0.0; 3]; 3], GAP, false); 4];
                let k = (n - 4 * b).min(4);
                for (lane, e) in four[..k].iter_mut().enumerate() {
                    *e = entry(4 * b + lane);
                }
                Tri4::new(&four[..k])
            })
            .collect();
        self.tris = Vec::new();
    }

    /// Mark where each leaf ends (after [`Primitives::pack`]), for
    /// [`Primitives::intersect_leaf`], which is given only a leaf's first
    /// entry.
    pub fn mark_leaves(&mut self, leaves: impl Iterator<Item = std::ops::Range<usize>>) {
        for r in leaves.filter(|r| !r.is_empty()) {
            debug_assert!(r.start.is_multiple_of(4), "leaves start blocks");
            self.blocks[(r.end - 1) / 4].last = 1;
        }
    }

    /// Start fetching the first block of the leaf starting at `first` (see
    /// [`Visit::prefetch`](super::Visit::prefetch)).
    #[inline(always)]
    pub fn prefetch_leaf(&self, first: usize) {
        #[cfg(target_arch = "x86_64")]
        if let Some(b) = self.blocks.get(first / 4) {
            use std::arch::x86_64::*;
            let p = b as *const Tri4 as *const i8;
            for line in 0..std::mem::size_of::<Tri4>() / 64 {
                // SAFETY: a prefetch never faults; the address is within
                // the block anyway.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(p.add(64 * line)) };
            }
        }
    }

    /// Nearest hit among the entries of the leaf starting at `first` (a
    /// table packed and marked: [`Primitives::mark_leaves`]): its blocks
    /// are read up to the one marked last, and nothing else.
    #[inline(always)]
    pub fn intersect_leaf(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        first: usize,
        hit: &mut Hit,
        level: u32,
    ) {
        self.intersect_blocks(ctx, q, &self.blocks[first / 4..], hit, level);
    }

    /// Nearest hit among the entries of the leaf whose blocks start
    /// `blocks` (up to the one marked last).
    #[inline(always)]
    fn intersect_blocks(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        blocks: &[Tri4],
        hit: &mut Hit,
        level: u32,
    ) {
        for block in blocks {
            self.intersect_block(ctx, q, block, block.entries as usize, hit, level);
            if block.last != 0 {
                return;
            }
        }
    }

    /// The lines of the leaf starting at `first`, its blocks up to the one
    /// marked last ([`Primitives::mark_leaves`]): to be copied next to the
    /// node that names the leaf ([`Bvh::interleave`](super::Bvh::interleave)),
    /// and read back by [`Primitives::intersect_lines`].
    pub fn leaf_lines(&self, first: usize) -> &[Line] {
        let b = first / 4;
        let n = self.blocks[b..]
            .iter()
            .position(|k| k.last != 0)
            .map_or(self.blocks.len() - b, |i| i + 1);
        let blocks = &self.blocks[b..b + n];
        // SAFETY: `Tri4` is `repr(C)`, 64-byte aligned, three lines long
        // and has no padding (checked at compile time above): its bytes are
        // all initialised, and a `Line` is any 64 bytes at 64-byte alignment.
        unsafe { std::slice::from_raw_parts(blocks.as_ptr() as *const Line, 3 * n) }
    }

    /// Free the blocks once a structure holds its own copy of every leaf's
    /// lines ([`Bvh::interleave`](super::Bvh::interleave)): the leaf data
    /// is not kept twice. Only [`Primitives::intersect_lines`] and
    /// [`Primitives::occluded_lines`] answer afterwards; the queries by
    /// entry index panic.
    pub fn drop_blocks(&mut self) {
        self.blocks = Vec::new();
    }

    /// [`Primitives::intersect_leaf`] over a leaf's lines as
    /// [`Primitives::leaf_lines`] gave them (copied next to its node).
    #[inline(always)]
    pub fn intersect_lines(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        lines: &[Line],
        hit: &mut Hit,
        level: u32,
    ) {
        self.intersect_blocks(ctx, q, blocks_of(lines), hit, level);
    }

    /// [`Primitives::occluded_leaf`] over a leaf's lines (see
    /// [`Primitives::intersect_lines`]).
    #[inline(always)]
    pub fn occluded_lines(
        &self,
        ctx: &mut TraceCtx,
        q: &AnyHit,
        lines: &[Line],
        level: u32,
    ) -> bool {
        self.occluded_blocks(ctx, q, blocks_of(lines), level)
    }

    /// Nearest hit among the entries of `range` (a leaf of a structure that
    /// called [`Primitives::pack`], starting a block).
    #[inline(always)]
    pub fn intersect_range(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        range: std::ops::Range<usize>,
        hit: &mut Hit,
        level: u32,
    ) {
        for b in range.start / 4..range.end.div_ceil(4) {
            let n = (range.end - 4 * b).min(4);
            self.intersect_block(ctx, q, &self.blocks[b], n, hit, level);
        }
    }

    /// The first `n` entries of `block`: a packed block's triangles are
    /// tested four at a time and only the lanes that test cannot decide take
    /// the scalar test; another block is queried entry by entry.
    #[inline(always)]
    fn intersect_block(
        &self,
        ctx: &mut TraceCtx,
        q: &mut Nearest,
        block: &Tri4,
        n: usize,
        hit: &mut Hit,
        level: u32,
    ) {
        if block.lanes == 0 {
            let entries = (0..n).map(|lane| (block.refs[lane], block.tri(lane)));
            return self.intersect_entries(ctx, q, entries, hit, level);
        }
        ctx.stats.prim_tests += n as u64;
        // Test with the loosest limit a tie could need; each hit is then
        // held to its own (`Nearest::limit`), in lane order.
        let limit = if q.found() {
            q.ray.t_max.next_up()
        } else {
            q.ray.t_max
        };
        let valid = block.lanes & ((1 << n) - 1);
        let l = block.test(&q.screen, q.ray.t_min, limit);
        let mut mask = (l.hit | l.slow) & valid;
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let r = block.refs[lane];
            if l.slow >> lane & 1 == 1 {
                if q.ray.t_min >= 0.0 && block.origin_in_axis_plane(lane, q.ray.origin.to_array()) {
                    debug_assert!(rtk_geom::intersect_triangle(
                        q.ray.origin.to_array(),
                        q.ray.dir.to_array(),
                        block.tri(lane),
                        q.ray.t_min,
                        q.ray.t_max
                    )
                    .is_none());
                    continue;
                }
                let d = q.ray.dir.to_array();
                self.triangle(q, d, r, block.tri(lane), hit, level);
            } else if l.t[lane] < q.limit(r.key()) {
                q.ray.t_max = l.t[lane];
                q.best = r.key();
                hit.record_child(level, r.child);
                hit.record_leaf(level + 1, l.t[lane], r.prim, [l.b1[lane], l.b2[lane]]);
            }
        }
    }

    /// Any hit among the entries of the leaf starting at `first` (see
    /// [`Primitives::intersect_leaf`]), for the query `q` (made once per ray).
    #[inline(always)]
    pub fn occluded_leaf(&self, ctx: &mut TraceCtx, q: &AnyHit, first: usize, level: u32) -> bool {
        self.occluded_blocks(ctx, q, &self.blocks[first / 4..], level)
    }

    /// Any hit among the entries of the leaf whose blocks start `blocks`.
    #[inline(always)]
    fn occluded_blocks(&self, ctx: &mut TraceCtx, q: &AnyHit, blocks: &[Tri4], level: u32) -> bool {
        for block in blocks {
            if self.occluded_block(ctx, q, block, block.entries as usize, level) {
                return true;
            }
            if block.last != 0 {
                return false;
            }
        }
        false
    }

    /// Any hit among the entries of `range` (see [`Primitives::intersect_range`]).
    #[inline(always)]
    pub fn occluded_range(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        range: std::ops::Range<usize>,
        level: u32,
    ) -> bool {
        let pre = AnyHit::new(ray);
        (range.start / 4..range.end.div_ceil(4)).any(|b| {
            self.occluded_block(
                ctx,
                &pre,
                &self.blocks[b],
                (range.end - 4 * b).min(4),
                level,
            )
        })
    }

    /// Any hit among the first `n` entries of `block`.
    #[inline(always)]
    fn occluded_block(
        &self,
        ctx: &mut TraceCtx,
        pre: &AnyHit,
        block: &Tri4,
        n: usize,
        level: u32,
    ) -> bool {
        let ray = &pre.ray;
        if block.lanes == 0 {
            let entries = (0..n).map(|lane| (block.refs[lane], block.tri(lane)));
            return self.occluded_entries(ctx, ray, entries, level);
        }
        ctx.stats.prim_tests += n as u64;
        let valid = block.lanes & ((1 << n) - 1);
        let l = block.test(&pre.screen, ray.t_min, ray.t_max);
        if l.hit & valid != 0 {
            return true;
        }
        let d = ray.dir.to_array();
        let o = ray.origin.to_array();
        let mut mask = l.slow & valid;
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if ray.t_min >= 0.0 && block.origin_in_axis_plane(lane, o) {
                debug_assert!(rtk_geom::intersect_triangle(
                    o,
                    d,
                    block.tri(lane),
                    ray.t_min,
                    ray.t_max
                )
                .is_none());
                continue;
            }
            let t = block.tri(lane);
            if intersect_triangle_sheared(&pre.shear, d, t, ray.t_min, ray.t_max).is_some() {
                return true;
            }
        }
        false
    }

    /// Query a run of one primitive set's primitives: those that win a tie
    /// against the best so far first (with one ulp more), then the others.
    fn flush(&self, ctx: &mut TraceCtx, q: &mut Nearest, run: &mut Run, hit: &mut Hit, level: u32) {
        if run.len == 0 {
            return;
        }
        let c = run.child;
        let Source::Set(set) = &self.sources[c as usize] else {
            unreachable!("runs hold primitive-set entries only")
        };
        let key = |p: u32| PrimRef { child: c, prim: p }.key();
        let ids = &run.prims[..run.len];
        let (mut low, mut high) = ([0u32; RUN], [0u32; RUN]);
        let (mut nl, mut nh) = (0, 0);
        for &p in ids {
            if q.found() && key(p) < q.best {
                (low[nl], nl) = (p, nl + 1);
            } else {
                (high[nh], nh) = (p, nh + 1);
            }
        }
        for (batch, equal_wins) in [(&low[..nl], true), (&high[..nh], false)] {
            if batch.is_empty() {
                continue;
            }
            let mut ray = q.ray;
            if equal_wins {
                ray.t_max = ray.t_max.next_up();
            }
            if set.intersect(ctx, &ray, batch, hit, level + 1) {
                q.ray.t_max = hit.t;
                q.best = key(hit.at(level + 1));
                hit.record_child(level, c);
            }
        }
        run.len = 0;
    }

    /// A whole child: its own answer, under the same tie rule by slot.
    fn whole(&self, ctx: &mut TraceCtx, q: &mut Nearest, r: PrimRef, hit: &mut Hit, level: u32) {
        let mut ray = q.ray;
        ray.t_max = q.limit(r.key());
        if self.children[r.child as usize].intersect(ctx, &ray, hit, level + 1) {
            q.ray.t_max = hit.t;
            q.best = r.key();
            hit.record_child(level, r.child);
        }
    }

    /// Any hit among the primitives `ids`.
    #[inline]
    pub fn occluded_ids(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        ids: impl Iterator<Item = usize>,
        level: u32,
    ) -> bool {
        let entries = ids.map(|i| (self.refs[i], i));
        let entries = entries.map(|(r, i)| match &self.sources[r.child as usize] {
            Source::Triangles => (r, self.vertices(i)),
            _ => (r, [[0.0; 3]; 3]),
        });
        self.occluded_entries(ctx, ray, entries, level)
    }

    /// [`Primitives::occluded_ids`] over entries given as their reference
    /// and, for a triangle, its vertices.
    #[inline]
    fn occluded_entries(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        entries: impl Iterator<Item = (PrimRef, [[f32; 3]; 3])>,
        level: u32,
    ) -> bool {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let shear = RayShear::new(o, d);
        let mut tests = 0u64;
        let mut found = false;
        for (r, v) in entries {
            tests += 1;
            found = match &self.sources[r.child as usize] {
                Source::Triangles => {
                    intersect_triangle_sheared(&shear, d, v, ray.t_min, ray.t_max).is_some()
                }
                Source::Set(set) => set.occluded(ctx, ray, &[r.prim], level + 1),
                Source::Whole => self.children[r.child as usize].occluded(ctx, ray, level + 1),
            };
            if found {
                break;
            }
        }
        ctx.stats.prim_tests += tests;
        found
    }

    /// Local geometry of a hit this table recorded at `level`.
    #[inline]
    pub fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let c = hit.at(level) as usize;
        self.children[c].local_geom(ctx, ray, hit, level + 1, mask, out);
    }
}

/// The blocks a leaf's lines hold ([`Primitives::leaf_lines`]): `lines`
/// starts at the leaf and may run past it.
#[inline(always)]
fn blocks_of(lines: &[Line]) -> &[Tri4] {
    // SAFETY: a `Line` is 64-byte aligned as `Tri4` is, and every field of
    // `Tri4` is a plain number (f32, u32), so any bytes are a valid block.
    // A leaf's lines start with its blocks (copied by
    // `Primitives::leaf_lines`); readers stop at the one marked last, before
    // whatever follows in the slice.
    unsafe { std::slice::from_raw_parts(lines.as_ptr() as *const Tri4, lines.len() / 3) }
}

/// An any-hit query: the ray and what the triangle tests need of it,
/// computed once per ray.
pub struct AnyHit {
    ray: Ray,
    shear: RayShear<f32>,
    screen: ScreenRay,
}

impl AnyHit {
    /// The end of the interval searched.
    #[inline(always)]
    pub fn t_max(&self) -> f32 {
        self.ray.t_max
    }

    /// The query of `ray` over `(ray.t_min, ray.t_max)`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let shear = RayShear::new(ray.origin.to_array(), ray.dir.to_array());
        AnyHit {
            ray: *ray,
            screen: ScreenRay::new(&shear),
            shear,
        }
    }
}

/// The entry of a gap in a padded order.
const GAP: PrimRef = PrimRef {
    child: u32::MAX,
    prim: u32::MAX,
};

/// Longest run of one primitive set's primitives sent in one call.
const RUN: usize = 32;

/// A run of one primitive set's primitives collected from a leaf.
struct Run {
    child: u32,
    prims: [u32; RUN],
    len: usize,
}

impl Default for Run {
    fn default() -> Self {
        Run {
            child: 0,
            prims: [0; RUN],
            len: 0,
        }
    }
}

impl Run {
    /// Add `r` if it continues the run (same child, room left).
    #[inline]
    fn push(&mut self, r: PrimRef) -> bool {
        if self.len == 0 {
            self.child = r.child;
        } else if self.child != r.child || self.len == RUN {
            return false;
        }
        self.prims[self.len] = r.prim;
        self.len += 1;
        true
    }
}

/// Box of a triangle.
#[inline]
pub fn tri_bounds(v: &[[f32; 3]; 3]) -> Bounds3 {
    Bounds3::EMPTY
        .include(v[0].into())
        .include(v[1].into())
        .include(v[2].into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_abi::RngState;

    /// Triangles that stress the test: random ones, pairs sharing an edge
    /// the ray crosses, axis-aligned ones (exactly zero edge functions
    /// for axis-parallel rays), and ones the ray's origin touches.
    fn tri(r: &mut RngState, o: [f32; 3], d: [f32; 3], k: usize) -> [[f32; 3]; 3] {
        let p = |r: &mut RngState| [0, 1, 2].map(|_| r.range_f32(-2.0, 2.0));
        match k % 4 {
            0 => [p(r), p(r), p(r)],
            1 => {
                // An edge through a point of the ray.
                let t = r.range_f32(-1.0, 3.0);
                let m = [0, 1, 2].map(|a| o[a] + t * d[a]);
                let a = p(r);
                let b = [0, 1, 2].map(|i| 2.0 * m[i] - a[i]);
                [a, b, p(r)]
            }
            2 => {
                let z = r.range_f32(-2.0, 2.0);
                let mut q = [p(r), p(r), p(r)];
                for v in &mut q {
                    v[2] = z;
                }
                q
            }
            _ => [o, p(r), p(r)],
        }
    }

    /// Every lane the 4-wide test decides is decided as the scalar test
    /// decides it: a hit with the same `t` and barycentrics bit for bit,
    /// a miss where it misses.
    #[test]
    fn the_4_wide_test_decides_as_the_scalar_test() {
        let mut r = RngState::seeded(21);
        let (mut hits, mut slow) = (0, 0);
        for n in 0..40_000 {
            let o = [0, 1, 2].map(|_| r.range_f32(-3.0, 3.0));
            let mut d = [0, 1, 2].map(|_| r.range_f32(-1.0, 1.0));
            if n % 3 == 0 {
                d = [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, -0.0, 0.0]][n % 9 / 3];
            }
            let tris: Vec<_> = (0..4).map(|k| tri(&mut r, o, d, n + k)).collect();
            let block = Tri4::new(
                &tris
                    .iter()
                    .enumerate()
                    .map(|(i, &t)| {
                        (
                            t,
                            PrimRef {
                                child: 0,
                                prim: i as u32,
                            },
                            true,
                        )
                    })
                    .collect::<Vec<_>>(),
            );
            let shear = RayShear::new(o, d);
            let (t_min, t_max) = [(0.0, f32::INFINITY), (0.0, 1.5), (0.25, 2.0)][n % 3];
            let l = block.test(&ScreenRay::new(&shear), t_min, t_max);
            assert_eq!(l.hit & l.slow, 0);
            for (lane, &tri) in tris.iter().enumerate() {
                if l.slow >> lane & 1 == 1 {
                    slow += 1;
                    continue;
                }
                let want = intersect_triangle_sheared(&shear, d, tri, t_min, t_max);
                if l.hit >> lane & 1 == 1 {
                    hits += 1;
                    let h = want.unwrap_or_else(|| panic!("ray {n} lane {lane}: scalar misses"));
                    assert_eq!(h.t.to_bits(), l.t[lane].to_bits(), "ray {n} lane {lane}");
                    assert_eq!(h.b[1].to_bits(), l.b1[lane].to_bits());
                    assert_eq!(h.b[2].to_bits(), l.b2[lane].to_bits());
                } else {
                    assert!(want.is_none(), "ray {n} lane {lane}: scalar hits {want:?}");
                }
            }
        }
        // Both paths are exercised.
        assert!(hits > 2_000 && slow > 1_000, "hits {hits}, slow {slow}");
    }
}
