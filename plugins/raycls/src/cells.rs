//! The five-dimensional cells of ray classification, their beams, and their
//! lazy, lock-free subdivision under a memory budget.
//!
//! A ray is the point (origin x, y, z; u, v) of one of six spaces, one per
//! *dominant face* (each with an inner and an outer root, see [`Tree`]): the axis `a0` of the direction's largest component and
//! its sign, with `u = d[a1] / |d[a0]|`, `v = d[a2] / |d[a0]|` (`a1`, `a2`
//! the next axes in cyclic order), both in [−1, 1]. A cell is a box of that
//! space; its *beam* is every ray with origin in the cell's origin box and
//! (u, v) in its direction square, and its candidates are the primitives
//! whose boxes the beam may meet.

use rtk_kernel::Bounds3;
use std::sync::atomic::{AtomicU32, AtomicU64, AtomicU8, Ordering};
use std::sync::{Arc, OnceLock};

/// The allowance on a cell's direction square, in u and v: a ray's computed
/// u is within 2⁻²⁴ of its exact value (one correctly rounded division of
/// a smaller by a larger magnitude), so 2⁻²⁰ covers it sixteen times over.
pub const EPS_DIR: f64 = 1.0 / 1_048_576.0;

/// What the allocator keeps besides a block, counted per allocation.
const ALLOC_OVERHEAD: usize = 16;

/// Levels without a shorter candidate list after which a path of short
/// lists stops splitting: one level per dimension and one more. A short
/// list that five splits in a row left whole is a cluster of boxes the beam
/// crosses whole (triangles around a vertex); more splits would only cost
/// memory.
const STALL: u32 = 6;

/// Lists longer than this many times `max_candidates` never stall: a long
/// list that does not shrink is a beam still spanning the scene (the first
/// splits of an outer root's origin box gain nothing), and the splits to
/// come pay.
const STALL_LIST: usize = 4;

/// One candidate: a primitive and the near side of its box along the
/// face's axis (`min` for a positive face, `max` for a negative one), so
/// that a ray's distance to it along that axis is one subtraction and one
/// product.
#[derive(Clone, Copy, Debug)]
pub struct Cand {
    /// Near side of the box along the face's axis.
    pub near: f32,
    /// Index into the primitive table.
    pub id: u32,
}

/// A cell: its candidates, sorted by their near side along the face's
/// axis, nearest first, and its two halves, each built on first use.
pub struct Cell {
    /// The candidates, nearest first; shared with the parent when the
    /// split left them all (the first splits of an outer root's origin box
    /// keep every primitive: a copy per level would cost the table's size
    /// each time).
    pub cands: Arc<[Cand]>,
    kids: [OnceLock<Box<Cell>>; 2],
    /// Rays that reached this cell and found the half they wanted missing,
    /// counted up to the splitting threshold (`min_visits`).
    visits: AtomicU32,
    /// The axis the cell is halved along, chosen when it first splits
    /// ([`UNDECIDED`] before).
    axis: AtomicU8,
}

/// A cell's axis before its first split.
const UNDECIDED: u8 = u8::MAX;

/// Candidates sampled, at most, to choose a cell's axis.
const SAMPLE: usize = 256;

impl Cell {
    fn new(cands: Arc<[Cand]>) -> Cell {
        Cell {
            cands,
            kids: [OnceLock::new(), OnceLock::new()],
            visits: AtomicU32::new(0),
            axis: AtomicU8::new(UNDECIDED),
        }
    }

    /// Bytes a cell holds, counted against the budget, without its list:
    /// the cell and the allocator's keep of its block.
    pub const COST: u64 = (std::mem::size_of::<Cell>() + ALLOC_OVERHEAD) as u64;

    /// Bytes a list of `n` candidates holds: the shared block (its two
    /// counts), the entries and the allocator's keep.
    pub fn list_cost(n: usize) -> u64 {
        (2 * std::mem::size_of::<usize>() + n * std::mem::size_of::<Cand>() + ALLOC_OVERHEAD) as u64
    }

    /// Bytes a scratch vector of room for `n` candidates holds.
    fn scratch_cost(n: usize) -> u64 {
        (n * std::mem::size_of::<Cand>() + ALLOC_OVERHEAD) as u64
    }
}

/// A box of the five-dimensional space: origin x, y, z (world axes), u, v.
#[derive(Clone, Copy, Debug)]
pub struct Box5 {
    pub lo: [f64; 5],
    pub hi: [f64; 5],
}

/// The dominant face of a direction: axis `a0` and its sign; u runs along
/// `a1`, v along `a2`.
#[derive(Clone, Copy, Debug)]
pub struct Face {
    pub a0: usize,
    pub a1: usize,
    pub a2: usize,
    pub neg: bool,
}

impl Face {
    /// Face `index` in 0..6: `2·a0 + (negative as usize)`.
    pub fn of(index: usize) -> Face {
        let a0 = index / 2;
        Face {
            a0,
            a1: (a0 + 1) % 3,
            a2: (a0 + 2) % 3,
            neg: index % 2 == 1,
        }
    }
}

/// `x` rounded up by more than f64 arithmetic's error on it (relative
/// 2⁻⁴⁰, plus the smallest normal for a zero).
#[inline]
fn up(x: f64) -> f64 {
    x + x.abs() * (1.0 / 1_099_511_627_776.0) + f64::MIN_POSITIVE
}

/// `x` rounded down likewise.
#[inline]
fn down(x: f64) -> f64 {
    x - x.abs() * (1.0 / 1_099_511_627_776.0) - f64::MIN_POSITIVE
}

/// May a ray of the beam of `cell` (face `f`, origin box padded by `eps`,
/// direction square by [`EPS_DIR`]) meet the box `b`? Conservative: false
/// only when no such ray meets it.
///
/// The beam's rays are `p + s·(±1 along a0, u along a1, v along a2)` with
/// `s ≥ 0` the distance travelled along `a0`. Some such ray is in `b` at
/// `s` when some origin puts its `a0` coordinate in `b` (`s` in an interval
/// set by the origin box and `b` along `a0`) and, independently per other
/// axis — the origin's coordinate and u (v) are free of each other and of
/// the rest — the beam's reach there, `[lo + u_lo·s, hi + u_hi·s]`, meets
/// `b`: two linear inequalities in `s` per axis. So the test is exact (for the padded cell): the beam meets
/// the box if and only if the five intervals of `s` share a point. In f64
/// from f32 boxes, each bound rounded outward by far more than its error.
pub fn beam_meets(b: &Bounds3, f: &Face, cell: &Box5, eps: f64) -> bool {
    let (bl, bh) = (b.min.to_array(), b.max.to_array());
    let lo = |k: usize| cell.lo[k] - eps;
    let hi = |k: usize| cell.hi[k] + eps;
    let (a0, bl0, bh0) = (f.a0, bl[f.a0] as f64, bh[f.a0] as f64);
    let (mut s0, mut s1) = if f.neg {
        (down(lo(a0) - bh0), up(hi(a0) - bl0))
    } else {
        (down(bl0 - hi(a0)), up(bh0 - lo(a0)))
    };
    if s0 < 0.0 {
        s0 = 0.0;
    }
    for (a, k) in [(f.a1, 3), (f.a2, 4)] {
        let (bla, bha) = (bl[a] as f64, bh[a] as f64);
        let (ulo, uhi) = (cell.lo[k] - EPS_DIR, cell.hi[k] + EPS_DIR);
        // Lowest reach at s is lo + ulo·s: it must not pass b's top.
        let r = bha - lo(a);
        if ulo > 0.0 {
            s1 = s1.min(up(r / ulo));
        } else if ulo < 0.0 {
            s0 = s0.max(down(r / ulo));
        } else if r < 0.0 {
            return false;
        }
        // Highest reach at s is hi + uhi·s: it must reach b's bottom.
        let r = bla - hi(a);
        if uhi > 0.0 {
            s0 = s0.max(down(r / uhi));
        } else if uhi < 0.0 {
            s1 = s1.min(up(r / uhi));
        } else if r > 0.0 {
            return false;
        }
    }
    s0 <= s1
}

/// The memory budget: bytes counted, reserved before any allocation with a
/// compare-and-swap that never lets the count pass the limit.
pub struct Budget {
    /// The limit, in bytes.
    pub limit: u64,
    used: AtomicU64,
    peak: AtomicU64,
    /// Cells built (and kept).
    pub cells: AtomicU64,
    /// Roots and halves not built because the budget could not hold them.
    pub refused: AtomicU64,
    /// Cells built twice by threads racing to the same half (the loser's
    /// copy freed).
    pub raced: AtomicU64,
}

impl Budget {
    /// A budget of `limit` bytes of which `fixed` are spent already (the
    /// structure built by `prepare`; it may exceed the limit, and then no
    /// cell is ever built).
    pub fn new(limit: u64, fixed: u64) -> Budget {
        Budget {
            limit,
            used: AtomicU64::new(fixed),
            peak: AtomicU64::new(fixed),
            cells: AtomicU64::new(0),
            refused: AtomicU64::new(0),
            raced: AtomicU64::new(0),
        }
    }

    /// Take `n` bytes if the count stays within the limit.
    fn reserve(&self, n: u64) -> bool {
        let mut cur = self.used.load(Ordering::Relaxed);
        loop {
            let Some(next) = cur.checked_add(n).filter(|&x| x <= self.limit) else {
                return false;
            };
            match self
                .used
                .compare_exchange_weak(cur, next, Ordering::Relaxed, Ordering::Relaxed)
            {
                Ok(_) => {
                    self.peak.fetch_max(next, Ordering::Relaxed);
                    return true;
                }
                Err(c) => cur = c,
            }
        }
    }

    /// Give `n` bytes back.
    fn release(&self, n: u64) {
        self.used.fetch_sub(n, Ordering::Relaxed);
    }

    /// Bytes counted now.
    pub fn used(&self) -> u64 {
        self.used.load(Ordering::Relaxed)
    }

    /// Most bytes ever counted.
    pub fn peak(&self) -> u64 {
        self.peak.load(Ordering::Relaxed)
    }
}

/// How far beyond the scene's box, in its largest extent, the outer roots'
/// origin box reaches on every side.
const OUTER: f64 = 2.0;

/// Deepest cell.
pub const MAX_DEPTH: u32 = 64;

/// When cells split (the parameters of the same names, README.md).
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// A cell with more candidates may split.
    pub max_cands: usize,
    /// Deepest cell.
    pub max_depth: u32,
    /// Rays that must reach a cell before it splits.
    pub min_visits: u32,
    /// The memory budget, in bytes.
    pub budget_bytes: u64,
}

/// The twelve roots and everything their subdivision needs.
///
/// Faces 0–5 are the *inner* roots: origins in the scene's box (padded by
/// `eps`). Faces 6–11 are the *outer* roots: origins in a box [`OUTER`]
/// times the scene's largest extent larger on every side, for rays from
/// outside the scene — a camera's rays share one origin there, so their
/// cells split down to it and then only in direction, as Arvo and Kirk
/// intended, instead of spreading over the points where they enter the
/// scene. Rays from farther out are classified by where they enter the
/// outer box.
pub struct Tree {
    /// Each primitive's box (over the whole shutter), by table index.
    boxes: Vec<Bounds3>,
    /// The primitives classified: finite, non-empty boxes.
    live: Vec<u32>,
    /// The origin boxes of the inner and outer roots (direction [−1, 1]²).
    inner: Box5,
    outer: Box5,
    /// Padding of every cell's origin box in the beam test, and the most a
    /// ray's classification point may be off its exact value.
    eps: f64,
    /// Per dominant axis, the length a direction extent is weighted by to
    /// compare it with the origin's (the scene's extent along that axis: a
    /// beam widens by Δu per unit travelled, over about that length).
    dir_weight: [f64; 3],
    /// Built on first use, through the budget like any cell.
    roots: [OnceLock<Cell>; 12],
    limits: Limits,
    /// The memory budget and the counters.
    pub budget: Budget,
}

/// `x` rounded to an f32 away from the box's inside (`s` the side: −1 or 1).
fn outward(x: f64, s: f64) -> f64 {
    if s < 0.0 {
        rtk_kernel::geom::f32_down(x) as f64
    } else {
        rtk_kernel::geom::f32_up(x) as f64
    }
}

impl Tree {
    /// The structure over `boxes` (`live`: the primitives to classify, with
    /// finite, non-empty boxes), inside `bounds` (their union). `fixed`:
    /// the bytes the caller holds already, counted against the budget.
    pub fn new(
        boxes: Vec<Bounds3>,
        live: Vec<u32>,
        bounds: Bounds3,
        limits: Limits,
        fixed_bytes: u64,
    ) -> Tree {
        let (lo, hi) = if bounds.is_empty() {
            ([0.0; 3], [0.0; 3])
        } else {
            (
                bounds.min.to_array().map(f64::from),
                bounds.max.to_array().map(f64::from),
            )
        };
        let ext: [f64; 3] = std::array::from_fn(|k| hi[k] - lo[k]);
        let ext_max = ext[0].max(ext[1]).max(ext[2]);
        let mag = (0..3).fold(0.0f64, |m, k| m.max(lo[k].abs()).max(hi[k].abs()));
        // Far above the rounding of a classification point (2⁻²⁴ of the
        // outer box's coordinates, see `Tree::point`), and negligible next
        // to the scene.
        let eps = ext_max / 65_536.0 + mag / 1_048_576.0 + 1e-30;
        let grown = |g: f64| Box5 {
            lo: [
                outward(lo[0] - g, -1.0),
                outward(lo[1] - g, -1.0),
                outward(lo[2] - g, -1.0),
                -1.0,
                -1.0,
            ],
            hi: [
                outward(hi[0] + g, 1.0),
                outward(hi[1] + g, 1.0),
                outward(hi[2] + g, 1.0),
                1.0,
                1.0,
            ],
        };
        let fallback = if ext_max > 0.0 { ext_max } else { 1.0 };
        let dir_weight = ext.map(|e| if e > 0.0 { e } else { fallback });
        let (inner, outer) = (grown(eps), grown(OUTER * ext_max + eps));
        let fixed = fixed_bytes
            + (boxes.capacity() * std::mem::size_of::<Bounds3>()
                + live.capacity() * std::mem::size_of::<u32>()) as u64;
        Tree {
            boxes,
            live,
            inner,
            outer,
            eps,
            dir_weight,
            roots: std::array::from_fn(|_| OnceLock::new()),
            budget: Budget::new(limits.budget_bytes, fixed),
            limits,
        }
    }

    /// The root of `face` (0–11), built now if it is the first use; `None`
    /// if the budget cannot hold it (the ray then tests every primitive).
    fn root(&self, face: usize) -> Option<&Cell> {
        if let Some(c) = self.roots[face].get() {
            return Some(c);
        }
        let n = self.live.len();
        // The sorted vector, then its copy into the shared block.
        let cost = Cell::COST + Cell::list_cost(n);
        let upper = cost + Cell::scratch_cost(n);
        if !self.budget.reserve(upper) {
            self.budget.refused.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        let f = Face::of(face % 6);
        let mut c: Vec<Cand> = self
            .live
            .iter()
            .map(|&id| {
                let b = &self.boxes[id as usize];
                let near = if f.neg {
                    b.max.to_array()[f.a0]
                } else {
                    b.min.to_array()[f.a0]
                };
                Cand { near, id }
            })
            .collect();
        // Unstable (no scratch allocation); ties by index, so the order is
        // one and the same in every run.
        if f.neg {
            c.sort_unstable_by(|x, y| y.near.total_cmp(&x.near).then(x.id.cmp(&y.id)));
        } else {
            c.sort_unstable_by(|x, y| x.near.total_cmp(&y.near).then(x.id.cmp(&y.id)));
        }
        let cands = Arc::from(c.as_slice());
        drop(c);
        self.budget.release(upper - cost);
        match self.roots[face].set(Cell::new(cands)) {
            Ok(()) => {
                self.budget.cells.fetch_add(1, Ordering::Relaxed);
            }
            Err(lost) => {
                drop(lost);
                self.budget.release(cost);
                self.budget.raced.fetch_add(1, Ordering::Relaxed);
            }
        }
        self.roots[face].get()
    }

    /// The root (0–11) and point (origin, u, v) a ray of finite origin
    /// `o` and direction `d` is classified by, or `None` when it cannot be
    /// (a zero or subnormal direction, an origin too far away: the ray then
    /// tests every primitive).
    pub fn classify(&self, o: [f32; 3], d: [f32; 3], t_min: f32) -> Option<(usize, [f64; 5])> {
        let ad = d.map(f32::abs);
        let a0 = if ad[0] >= ad[1] && ad[0] >= ad[2] {
            0
        } else if ad[1] >= ad[2] {
            1
        } else {
            2
        };
        // A normal dominant component keeps 1/d finite on the walk.
        if !(ad[a0] >= f32::MIN_POSITIVE) {
            return None;
        }
        let (a1, a2) = ((a0 + 1) % 3, (a0 + 2) % 3);
        // |u|, |v| ≤ 1 exactly: a division of a smaller by a larger magnitude.
        let u = d[a1] / ad[a0];
        let v = d[a2] / ad[a0];
        let face = 2 * a0 + usize::from(d[a0] < 0.0);
        let (outer, p) = self.point(o, d, t_min)?;
        let root = face + if outer { 6 } else { 0 };
        Some((root, [p[0], p[1], p[2], u as f64, v as f64]))
    }

    /// Where a ray is classified: whether in the outer roots, and the point.
    /// The origin itself when the ray starts there (`t_min ≥ 0`) and it lies
    /// in the inner or else the outer roots' origin box; otherwise the point
    /// where its line enters the outer box (or where it starts, if later),
    /// computed in f64, clamped into the box and rounded to f32. `None` when
    /// that point may be off by more than `eps / 2`: an origin some 10⁹
    /// scene sizes away (the ray then tests every primitive).
    ///
    /// Why this is enough: every hit lies in the scene's box, so at or after
    /// the line's entry `t_c` into the outer box; the ray from the exact
    /// point `o + t_c·d` covers them all, and the point found is within
    /// `eps / 2` of it (its f64 rounding, the clamp, and the entry's own
    /// relative error times |d|, each bounded below).
    fn point(&self, o: [f32; 3], d: [f32; 3], t_min: f32) -> Option<(bool, [f64; 3])> {
        let o64 = o.map(f64::from);
        let within = |b: &Box5| (0..3).all(|k| b.lo[k] <= o64[k] && o64[k] <= b.hi[k]);
        if t_min >= 0.0 {
            if within(&self.inner) {
                return Some((false, o64));
            }
            if within(&self.outer) {
                return Some((true, o64));
            }
        }
        let (lo, hi) = (&self.outer.lo, &self.outer.hi);
        let mut tc = t_min as f64;
        for k in 0..3 {
            if d[k] != 0.0 {
                let near = if d[k] > 0.0 { lo[k] } else { hi[k] };
                let t = (near - o64[k]) / d[k] as f64;
                if t > tc {
                    tc = t;
                }
            }
        }
        if !tc.is_finite() {
            return None;
        }
        let mut p = [0.0; 3];
        for k in 0..3 {
            let step = tc * d[k] as f64;
            let exact = o64[k] + step;
            // Clamped, then rounded to f32: the box's sides are f32s, so
            // the point stays inside.
            let pc = exact.clamp(lo[k], hi[k]) as f32 as f64;
            let err =
                (pc - exact).abs() + (o64[k].abs() + step.abs()) * (1.0 / 1_125_899_906_842_624.0);
            if !(err <= 0.5 * self.eps) {
                return None;
            }
            p[k] = pc;
        }
        Some((true, p))
    }

    /// The leaf cell of the point `x` (origin, u, v) of root `face` (0–11),
    /// splitting cells on the way as needed: a cell splits when it has more
    /// than `max_cands` candidates, is shallower than `max_depth`, its path
    /// has not stalled ([`STALL`]), `min_visits` rays have reached it, and
    /// the budget can hold the half. `nodes` counts the cells visited.
    /// `None` if the budget could not hold the root.
    pub fn descend(&self, face: usize, x: &[f64; 5], nodes: &mut u64) -> Option<&Cell> {
        let l = &self.limits;
        let mut cell = self.root(face)?;
        let root = if face < 6 { &self.inner } else { &self.outer };
        let (mut lo, mut hi) = (root.lo, root.hi);
        let f = Face::of(face % 6);
        let (mut depth, mut stall) = (0, 0);
        loop {
            *nodes += 1;
            if cell.cands.len() <= l.max_cands || depth >= l.max_depth || stall >= STALL {
                return Some(cell);
            }
            let mut k = cell.axis.load(Ordering::Relaxed);
            if k == UNDECIDED {
                // Not worth a split for one ray: building a half costs a
                // pass over the list, as much as testing it. Counted with a
                // load first, so a cell past the threshold is never written
                // again.
                if cell.visits.load(Ordering::Relaxed) + 1 < l.min_visits {
                    cell.visits.fetch_add(1, Ordering::Relaxed);
                    return Some(cell);
                }
                let chosen = self.choose_axis(&f, cell, &lo, &hi);
                k = match cell.axis.compare_exchange(
                    UNDECIDED,
                    chosen,
                    Ordering::Relaxed,
                    Ordering::Relaxed,
                ) {
                    Ok(_) => chosen,
                    Err(other) => other,
                };
            }
            let k = k as usize;
            let mid = 0.5 * (lo[k] + hi[k]);
            let side = usize::from(x[k] > mid);
            let child = match cell.kids[side].get() {
                Some(c) => c,
                None => {
                    let mut half = Box5 { lo, hi };
                    if side == 0 {
                        half.hi[k] = mid;
                    } else {
                        half.lo[k] = mid;
                    }
                    match self.build(&f, cell, side, &half) {
                        Some(c) => c,
                        None => return Some(cell),
                    }
                }
            };
            if side == 0 {
                hi[k] = mid;
            } else {
                lo[k] = mid;
            }
            stall = if child.cands.len() < cell.cands.len()
                || child.cands.len() > STALL_LIST * l.max_cands
            {
                0
            } else {
                stall + 1
            };
            cell = child;
            depth += 1;
        }
    }

    /// The axis to halve `cell` (box `lo`, `hi`) along: its longest extent,
    /// the direction ones (u, v) weighted by `dir_weight` (ties to the
    /// lowest of x, y, z, u, v) — unless halving that one would leave both
    /// halves every candidate while another axis would not: then the axis
    /// whose halves hold the fewest in all. Counted on up to [`SAMPLE`]
    /// candidates, evenly spaced. Any choice is correct; this one spends
    /// no level on a split that gains nothing.
    #[cold]
    fn choose_axis(&self, f: &Face, cell: &Cell, lo: &[f64; 5], hi: &[f64; 5]) -> u8 {
        let l = self.dir_weight[f.a0];
        let mut longest = 0;
        let w = |k: usize| (hi[k] - lo[k]) * if k >= 3 { l } else { 1.0 };
        for k in 1..5 {
            if w(k) > w(longest) {
                longest = k;
            }
        }
        let step = (cell.cands.len() / SAMPLE).max(1);
        let held = |k: usize| {
            let mid = 0.5 * (lo[k] + hi[k]);
            let (mut a, mut b) = (Box5 { lo: *lo, hi: *hi }, Box5 { lo: *lo, hi: *hi });
            a.hi[k] = mid;
            b.lo[k] = mid;
            let mut n = 0;
            for c in cell.cands.iter().step_by(step) {
                let bx = &self.boxes[c.id as usize];
                n += usize::from(beam_meets(bx, f, &a, self.eps))
                    + usize::from(beam_meets(bx, f, &b, self.eps));
            }
            n
        };
        let all = 2 * cell.cands.iter().step_by(step).count();
        if held(longest) < all {
            return longest as u8;
        }
        let mut best = (all, longest);
        for k in (0..5).filter(|&k| k != longest) {
            let h = held(k);
            if h < best.0 {
                best = (h, k);
            }
        }
        best.1 as u8
    }

    /// Build half `side` of `parent` (whose box is `half`), unless the
    /// budget cannot hold it (`None`); the half in place afterwards (this
    /// thread's, or a racing thread's).
    ///
    /// Lock-free: a thread that finds the half missing builds it on its own
    /// and offers it with `OnceLock::set`; if another thread's copy got
    /// there first, this one is freed (and its bytes given back) and the
    /// winner's is used. A built half is reached with one acquire load.
    #[cold]
    fn build<'a>(&self, f: &Face, parent: &'a Cell, side: usize, half: &Box5) -> Option<&'a Cell> {
        let n = parent.cands.len();
        // Reserved before allocating: the scratch list (room for all the
        // parent's candidates), the kept list (at most as long) and the cell.
        let upper = Cell::COST + Cell::scratch_cost(n) + Cell::list_cost(n);
        if !self.budget.reserve(upper) {
            self.budget.refused.fetch_add(1, Ordering::Relaxed);
            return None;
        }
        let mut scratch = Vec::with_capacity(n);
        scratch.extend(
            parent
                .cands
                .iter()
                .filter(|c| beam_meets(&self.boxes[c.id as usize], f, half, self.eps))
                .copied(),
        );
        // All kept: the parent's list is this one (a subset as long).
        let (cands, cost) = if scratch.len() == n {
            (Arc::clone(&parent.cands), Cell::COST)
        } else {
            (
                Arc::from(scratch.as_slice()),
                Cell::COST + Cell::list_cost(scratch.len()),
            )
        };
        drop(scratch);
        let cell = Box::new(Cell::new(cands));
        self.budget.release(upper - cost);
        match parent.kids[side].set(cell) {
            Ok(()) => {
                self.budget.cells.fetch_add(1, Ordering::Relaxed);
            }
            Err(lost) => {
                drop(lost);
                self.budget.release(cost);
                self.budget.raced.fetch_add(1, Ordering::Relaxed);
            }
        }
        parent.kids[side].get().map(|c| &**c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::glam::Vec3;

    fn rng(s: &mut u64) -> f64 {
        *s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A ray of the beam that meets a box always makes the test say so:
    /// random cells, random rays in them, random boxes around points on
    /// those rays.
    #[test]
    fn beam_test_never_misses_a_ray_of_the_beam() {
        let mut s = 7u64;
        for _ in 0..20_000 {
            let face = Face::of((rng(&mut s) * 6.0) as usize);
            let mut cell = Box5 {
                lo: [0.0; 5],
                hi: [0.0; 5],
            };
            for k in 0..5 {
                let (a, b) = if k < 3 {
                    (rng(&mut s) * 10.0 - 5.0, rng(&mut s) * 10.0 - 5.0)
                } else {
                    (rng(&mut s) * 2.0 - 1.0, rng(&mut s) * 2.0 - 1.0)
                };
                cell.lo[k] = a.min(b);
                cell.hi[k] = a.max(b);
            }
            // A ray of the beam, often on its edges and corners.
            let pick = |s: &mut u64, k: usize| match (rng(s) * 3.0) as u32 {
                0 => cell.lo[k],
                1 => cell.hi[k],
                _ => cell.lo[k] + rng(s) * (cell.hi[k] - cell.lo[k]),
            };
            let p = [pick(&mut s, 0), pick(&mut s, 1), pick(&mut s, 2)];
            let (u, v) = (pick(&mut s, 3), pick(&mut s, 4));
            let mut d = [0.0; 3];
            d[face.a0] = if face.neg { -1.0 } else { 1.0 };
            d[face.a1] = u;
            d[face.a2] = v;
            let t = rng(&mut s) * 20.0;
            let q: [f64; 3] = std::array::from_fn(|k| p[k] + t * d[k]);
            // A box around the point, often flat or a point.
            let w: [f64; 3] =
                std::array::from_fn(|_| if rng(&mut s) < 0.6 { 0.0 } else { rng(&mut s) });
            let b = Bounds3::new(
                Vec3::new(
                    rtk_kernel::geom::f32_down(q[0] - w[0]),
                    rtk_kernel::geom::f32_down(q[1] - w[1]),
                    rtk_kernel::geom::f32_down(q[2] - w[2]),
                ),
                Vec3::new(
                    rtk_kernel::geom::f32_up(q[0] + w[0]),
                    rtk_kernel::geom::f32_up(q[1] + w[1]),
                    rtk_kernel::geom::f32_up(q[2] + w[2]),
                ),
            );
            assert!(beam_meets(&b, &face, &cell, 0.0), "{cell:?} {b:?}");
        }
    }

    /// Does the ray `o + t·d`, `t > t_min`, meet the box (f64 slab test)?
    fn meets(o: [f32; 3], d: [f32; 3], t_min: f32, b: &Bounds3) -> bool {
        let (lo, hi) = (b.min.to_array(), b.max.to_array());
        let (mut t0, mut t1) = (t_min as f64, f64::INFINITY);
        for k in 0..3 {
            let (o, d, lo, hi) = (o[k] as f64, d[k] as f64, lo[k] as f64, hi[k] as f64);
            if d == 0.0 {
                if o < lo || o > hi {
                    return false;
                }
                continue;
            }
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        t0 <= t1
    }

    /// The heart of the method: every box an exact ray meets is a candidate
    /// of the cell the ray is classified into, and the candidates are sorted
    /// by their near side along the face's axis. Rays from inside the
    /// scene, from outside (inner and outer roots), from far away, with
    /// zero components and negative `t_min`, into cells split to depth 40.
    #[test]
    fn every_box_a_ray_meets_is_a_candidate_of_its_cell() {
        let mut s = 11u64;
        let n = 400;
        let boxes: Vec<Bounds3> = (0..n)
            .map(|_| {
                let c: [f64; 3] = std::array::from_fn(|_| rng(&mut s) * 10.0 - 5.0);
                let w: [f64; 3] = std::array::from_fn(|_| {
                    if rng(&mut s) < 0.2 {
                        0.0
                    } else {
                        rng(&mut s) * 0.8
                    }
                });
                let lo: [f32; 3] = std::array::from_fn(|k| (c[k] - w[k]) as f32);
                let hi: [f32; 3] = std::array::from_fn(|k| (c[k] + w[k]) as f32);
                Bounds3::new(Vec3::from(lo), Vec3::from(hi))
            })
            .collect();
        let bounds = boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(*b));
        let limits = Limits {
            max_cands: 2,
            max_depth: 40,
            min_visits: 1,
            budget_bytes: 1 << 32,
        };
        let tree = Tree::new(boxes.clone(), (0..n as u32).collect(), bounds, limits, 0);
        let (mut classified, mut far) = (0, 0);
        for k in 0..20_000 {
            let scale = match k % 5 {
                0 | 1 => 5.0,
                2 => 15.0,
                3 => 40.0,
                _ => 1e4,
            };
            let mut o: [f32; 3] =
                std::array::from_fn(|_| ((rng(&mut s) * 2.0 - 1.0) * scale) as f32);
            let mut d: [f32; 3] = std::array::from_fn(|_| (rng(&mut s) * 2.0 - 1.0) as f32);
            if k % 7 == 0 {
                d[k % 3] = 0.0;
            }
            if k % 11 == 0 {
                // Aimed at a box corner from afar.
                let b = &boxes[k % n];
                let t = b.max.to_array();
                o = [t[0] + 3e3, t[1] - 2e3, t[2] + 1e3];
                d = std::array::from_fn(|i| t[i] - o[i]);
            }
            if d.iter().all(|&x| x == 0.0) {
                continue;
            }
            let t_min = match k % 13 {
                0 => -3.0,
                1 => 0.5,
                _ => 0.0,
            };
            // The aggregate answers a ray that misses the scene's box
            // before classifying it.
            if !meets(o, d, t_min, &bounds) {
                continue;
            }
            let Some((root, x)) = tree.classify(o, d, t_min) else {
                far += 1;
                continue;
            };
            classified += 1;
            let mut nodes = 0;
            let cell = tree.descend(root, &x, &mut nodes).expect("root built");
            let f = Face::of(root % 6);
            for w in cell.cands.windows(2) {
                let ok = if f.neg {
                    w[0].near >= w[1].near
                } else {
                    w[0].near <= w[1].near
                };
                assert!(ok, "candidates out of order");
            }
            for (i, b) in boxes.iter().enumerate() {
                if meets(o, d, t_min, b) {
                    assert!(
                        cell.cands.iter().any(|c| c.id as usize == i),
                        "ray {o:?} {d:?} t_min {t_min} meets box {i} {b:?}, not a candidate of its cell (root {root}, {x:?}, depth {nodes})"
                    );
                }
            }
        }
        // Every ray is classified (none is far enough to need the
        // exhaustive test); the cells did split.
        assert_eq!(far, 0, "{far} rays not classified");
        assert!(classified > 8_000, "{classified}");
        assert!(tree.budget.cells.load(Ordering::Relaxed) > 1000);
    }

    /// The budget is never passed: a tiny one refuses splits, and the
    /// count stays within it.
    #[test]
    fn a_tiny_budget_is_never_passed() {
        // The fixed part (1000 bytes, 2000 boxes and ids: 57 KB) and the
        // six inner roots (16 KB each) fit, and some cells below them.
        const BUDGET: u64 = 400_000;
        let mut s = 3u64;
        let n = 2000;
        let boxes: Vec<Bounds3> = (0..n)
            .map(|_| {
                let c: [f32; 3] = std::array::from_fn(|_| (rng(&mut s) * 10.0 - 5.0) as f32);
                Bounds3::new(Vec3::from(c), Vec3::from(c) + Vec3::splat(0.1))
            })
            .collect();
        let bounds = boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(*b));
        let limits = Limits {
            max_cands: 1,
            max_depth: 64,
            min_visits: 1,
            budget_bytes: BUDGET,
        };
        let tree = Tree::new(boxes, (0..n as u32).collect(), bounds, limits, 1000);
        std::thread::scope(|sc| {
            for t in 0..4u64 {
                let tree = &tree;
                sc.spawn(move || {
                    let mut s = t + 100;
                    for _ in 0..5000 {
                        let o: [f32; 3] =
                            std::array::from_fn(|_| (rng(&mut s) * 10.0 - 5.0) as f32);
                        let d: [f32; 3] = std::array::from_fn(|_| (rng(&mut s) * 2.0 - 1.0) as f32);
                        if let Some((root, x)) = tree.classify(o, d, 0.0) {
                            let mut nodes = 0;
                            let _ = tree.descend(root, &x, &mut nodes);
                        }
                        assert!(tree.budget.used() <= BUDGET);
                    }
                });
            }
        });
        assert!(tree.budget.refused.load(Ordering::Relaxed) > 0);
        assert!(tree.budget.peak() <= BUDGET);
        assert!(tree.budget.cells.load(Ordering::Relaxed) > 10);
    }

    /// The cell's size the README states (64-bit targets).
    #[test]
    #[cfg(target_pointer_width = "64")]
    fn a_cell_is_56_bytes() {
        assert_eq!(std::mem::size_of::<Cell>(), 56);
        assert_eq!(Cell::COST, 56 + 16);
        assert_eq!(Cell::list_cost(10), 16 + 80 + 16);
    }

    /// Boxes behind the origin box, or off to the side of a narrow beam,
    /// are not candidates.
    #[test]
    fn beam_test_culls() {
        let face = Face::of(0); // +x
        let cell = Box5 {
            lo: [0.0, 0.0, 0.0, 0.0, 0.0],
            hi: [1.0, 1.0, 1.0, 0.1, 0.1],
        };
        let bx = |lo: [f32; 3], hi: [f32; 3]| Bounds3::new(Vec3::from(lo), Vec3::from(hi));
        // Behind.
        assert!(!beam_meets(
            &bx([-3.0, 0.0, 0.0], [-2.0, 1.0, 1.0]),
            &face,
            &cell,
            1e-6
        ));
        // Ahead, in the beam.
        assert!(beam_meets(
            &bx([5.0, 0.0, 0.0], [6.0, 1.0, 1.0]),
            &face,
            &cell,
            1e-6
        ));
        // Ahead, below it (the beam rises).
        assert!(!beam_meets(
            &bx([5.0, -3.0, 0.0], [6.0, -1.0, 1.0]),
            &face,
            &cell,
            1e-6
        ));
        // Ahead, above its reach at that distance (1 + 0.1 · 6).
        assert!(!beam_meets(
            &bx([5.0, 1.7, 0.0], [6.0, 2.0, 1.0]),
            &face,
            &cell,
            1e-6
        ));
        // Just within its reach.
        assert!(beam_meets(
            &bx([5.0, 1.55, 0.0], [6.0, 2.0, 1.0]),
            &face,
            &cell,
            1e-6
        ));
        // Overlapping the origin box.
        assert!(beam_meets(
            &bx([0.5, 0.5, 0.5], [0.6, 0.6, 0.6]),
            &face,
            &cell,
            1e-6
        ));
    }
}
