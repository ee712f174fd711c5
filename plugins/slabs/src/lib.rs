#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::accel::{cull_bound, Nearest, Primitives, PAD};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::ops::Range;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "four")]
    max_leaf: u32,
}

fn four() -> u32 {
    4
}

/// Number of plane-set normals: Kay and Kajiya's seven (the kernel's).
const K: usize = SLAB_COUNT;

/// The four diagonal normals (unnormalised: components ±1, so a point's
/// distance along one is a signed sum of its coordinates). The first three
/// normals are the axes (the kernel's SLAB_NORMALS).
const DIAG: [[f32; 3]; 4] = [
    SLAB_NORMALS[3],
    SLAB_NORMALS[4],
    SLAB_NORMALS[5],
    SLAB_NORMALS[6],
];

/// Deepest tree built: a node this deep becomes a leaf, which bounds the
/// fallback depth-first stack.
const MAX_DEPTH: usize = 64;
/// Capacity of the per-ray priority queue (on the stack).
const HEAP: usize = 64;
/// Bins of the SAH sweep per axis.
const BINS: usize = 16;

/// Far distance widening of the kernel's slab test: `1 + 2γ₃` (rule 10).
const FAR_SCALE: f32 = {
    let ne = 3.0 * (f32::EPSILON * 0.5);
    1.0 + 2.0 * (ne / (1.0 - ne))
};

/// A plane-set bounding volume: `[lo[k], hi[k]]` along each normal.
#[derive(Clone, Copy, Debug)]
struct Slabs {
    lo: [f32; K],
    hi: [f32; K],
}

impl Slabs {
    const EMPTY: Slabs = Slabs {
        lo: [f32::INFINITY; K],
        hi: [f32::NEG_INFINITY; K],
    };

    /// Union; written with comparisons so a NaN never enters.
    fn union(mut self, o: &Slabs) -> Slabs {
        for k in 0..K {
            if o.lo[k] < self.lo[k] {
                self.lo[k] = o.lo[k];
            }
            if o.hi[k] > self.hi[k] {
                self.hi[k] = o.hi[k];
            }
        }
        self
    }
}

/// A node of the binary hierarchy.
#[derive(Clone, Copy, Debug)]
struct Node {
    s: Slabs,
    /// Inner: the left child (the right one is `b`); leaf: first entry of
    /// the (padded) leaf order.
    a: u32,
    b: u32,
    /// 0 for an inner node, else the leaf's primitive count.
    count: u32,
}

/// Per-ray data for the slab tests, computed once per ray.
struct Pre {
    o: [f32; 3],
    inv: [f32; 3],
    /// Axis slabs: the near plane is `hi` (direction negative).
    neg: [bool; 3],
    /// Diagonal slabs: `t = (plane + c) · inv`, with `c` already holding
    /// `-(n·o)` and the error allowance (so the near and far constants
    /// differ), for the near and far planes as ordered by `dneg`.
    dinv: [f32; 4],
    dnear: [f32; 4],
    dfar: [f32; 4],
    dneg: [bool; 4],
}

impl Pre {
    /// `scale[j]`: the largest |plane| of diagonal normal `j` in the tree.
    fn new(ray: &Ray, scale: &[f32; 4]) -> Pre {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let inv = d.map(|x| 1.0 / x);
        let mut p = Pre {
            o,
            inv,
            neg: inv.map(|x| x.is_sign_negative()),
            dinv: [1.0; 4],
            dnear: [f32::NEG_INFINITY; 4],
            dfar: [f32::INFINITY; 4],
            dneg: [false; 4],
        };
        let so = o[0].abs() + o[1].abs() + o[2].abs();
        let sd = d[0].abs() + d[1].abs() + d[2].abs();
        for (j, n) in DIAG.iter().enumerate() {
            let a = n[0] * o[0] + n[1] * o[1] + n[2] * o[2];
            let den = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            // Relative error of the computed `den` (three terms) with a wide
            // margin; a ray too close to parallel to these planes, or any
            // non-finite value, leaves the normal out (always conservative:
            // the axis slabs still bound the node).
            let rho = sd * (1.0 / 1_048_576.0) / den.abs();
            let s = scale[j];
            if !(rho < 1.0 / 16.0) || !s.is_finite() || !so.is_finite() || !a.is_finite() {
                continue;
            }
            // Absolute allowance on the numerator `plane - n·o`: its rounding
            // (a few ulps of |plane| + Σ|o|), and the relative error of `den`,
            // of the reciprocal and of the two operations per node, all moved
            // onto the numerator (|numerator| ≤ s + so). 2⁻¹⁹ is over 30
            // times the rounding alone.
            let delta = (so + s) * (1.0 / 524_288.0 + 4.0 * rho) * 2.0;
            let dinv = 1.0 / den;
            p.dinv[j] = dinv;
            if dinv < 0.0 {
                // t decreases along the normal: the far plane enters.
                p.dneg[j] = true;
                p.dnear[j] = -(a - delta);
                p.dfar[j] = -(a + delta);
            } else {
                p.dnear[j] = -(a + delta);
                p.dfar[j] = -(a - delta);
            }
        }
        p
    }

    /// The overlap of `[t_min, t_max]` with the volume: its entry distance,
    /// or `None`. A NaN distance (`0·∞`) keeps the previous bound.
    #[inline(always)]
    fn enter(&self, s: &Slabs, t_min: f32, t_max: f32) -> Option<f32> {
        let (mut t0, mut t1) = (t_min, t_max);
        for a in 0..3 {
            let (near, far) = if self.neg[a] {
                (s.hi[a], s.lo[a])
            } else {
                (s.lo[a], s.hi[a])
            };
            let tn = (near - self.o[a]) * self.inv[a];
            let tf = (far - self.o[a]) * self.inv[a] * FAR_SCALE;
            if tn > t0 {
                t0 = tn;
            }
            if tf < t1 {
                t1 = tf;
            }
        }
        for j in 0..4 {
            let (near, far) = if self.dneg[j] {
                (s.hi[3 + j], s.lo[3 + j])
            } else {
                (s.lo[3 + j], s.hi[3 + j])
            };
            let tn = (near + self.dnear[j]) * self.dinv[j];
            let tf = (far + self.dfar[j]) * self.dinv[j];
            if tn > t0 {
                t0 = tn;
            }
            if tf < t1 {
                t1 = tf;
            }
        }
        (t0 <= t1).then_some(t0)
    }
}

/// Kay and Kajiya's priority queue: a binary min-heap on entry distance,
/// fixed capacity, on the stack.
struct Heap {
    items: [(f32, u32); HEAP],
    len: usize,
}

impl Heap {
    #[inline(always)]
    fn new() -> Heap {
        Heap {
            items: [(0.0, 0); HEAP],
            len: 0,
        }
    }

    /// Push; false when full.
    #[inline(always)]
    fn push(&mut self, t: f32, n: u32) -> bool {
        if self.len == HEAP {
            return false;
        }
        let mut i = self.len;
        self.len += 1;
        while i > 0 {
            let p = (i - 1) / 2;
            if self.items[p].0 <= t {
                break;
            }
            self.items[i] = self.items[p];
            i = p;
        }
        self.items[i] = (t, n);
        true
    }

    /// The entry nearest first.
    #[inline(always)]
    fn pop(&mut self) -> Option<(f32, u32)> {
        if self.len == 0 {
            return None;
        }
        let top = self.items[0];
        self.len -= 1;
        let last = self.items[self.len];
        let mut i = 0;
        loop {
            let l = 2 * i + 1;
            if l >= self.len {
                break;
            }
            let r = l + 1;
            let c = if r < self.len && self.items[r].0 < self.items[l].0 {
                r
            } else {
                l
            };
            if self.items[c].0 >= last.0 {
                break;
            }
            self.items[i] = self.items[c];
            i = c;
        }
        self.items[i] = last;
        Some(top)
    }
}

/// The built hierarchy.
struct Tree {
    nodes: Vec<Node>,
    /// Largest |plane| per diagonal normal (the root's), for the per-ray
    /// error allowance.
    scale: [f32; 4],
    bounds: Bounds3,
}

impl Tree {
    /// Visit the leaves `ray` may hit over `(t_min, t_max)` in order of
    /// entry distance. `leaf(range)` tests a leaf and returns the new bound
    /// (`Some`) or stops the traversal (`None`). Entries beyond the bound
    /// end it: the queue holds nothing nearer.
    #[inline]
    fn traverse(
        &self,
        ray: &Ray,
        t_max: f32,
        tests: &mut u64,
        leaf: &mut impl FnMut(Range<usize>) -> Option<f32>,
    ) {
        let Some(root) = self.nodes.first() else {
            return;
        };
        let pre = Pre::new(ray, &self.scale);
        let mut bound = t_max;
        *tests += 1;
        let Some(t) = pre.enter(&root.s, ray.t_min, bound) else {
            return;
        };
        let mut heap = Heap::new();
        heap.push(t, 0);
        while let Some((t, n)) = heap.pop() {
            if t > bound {
                return;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let first = node.a as usize;
                match leaf(first..first + node.count as usize) {
                    Some(b) => bound = b,
                    None => return,
                }
                continue;
            }
            for c in [node.a, node.b] {
                *tests += 1;
                if let Some(tc) = pre.enter(&self.nodes[c as usize].s, ray.t_min, bound) {
                    if !heap.push(tc, c) {
                        // Queue full: this subtree depth first, now. The
                        // order changes only the work, not the answer.
                        match self.depth_first(c, &pre, ray.t_min, bound, tests, leaf) {
                            Some(b) => bound = b,
                            None => return,
                        }
                    }
                }
            }
        }
    }

    /// The subtree at `start` (its volume already entered), depth first,
    /// nearer child first; the stack is bounded by the depth.
    #[cold]
    fn depth_first(
        &self,
        start: u32,
        pre: &Pre,
        t_min: f32,
        mut bound: f32,
        tests: &mut u64,
        leaf: &mut impl FnMut(Range<usize>) -> Option<f32>,
    ) -> Option<f32> {
        let mut stack = [(0f32, 0u32); MAX_DEPTH + 2];
        let mut len = 1;
        stack[0] = (f32::NEG_INFINITY, start);
        while len > 0 {
            len -= 1;
            let (t, n) = stack[len];
            if t > bound {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let first = node.a as usize;
                bound = leaf(first..first + node.count as usize)?;
                continue;
            }
            let mut kids = [(f32::INFINITY, 0u32); 2];
            let mut k = 0;
            for c in [node.a, node.b] {
                *tests += 1;
                if let Some(tc) = pre.enter(&self.nodes[c as usize].s, t_min, bound) {
                    kids[k] = (tc, c);
                    k += 1;
                }
            }
            if k == 2 && kids[0].0 < kids[1].0 {
                kids.swap(0, 1);
            }
            // Farther first, so the nearer is popped next.
            for &kid in &kids[..k] {
                stack[len] = kid;
                len += 1;
            }
        }
        Some(bound)
    }
}

/// Top-down build over the primitives' boxes (for the split) and volumes.
struct Builder<'a> {
    boxes: &'a [Bounds3],
    centroids: Vec<[f32; 3]>,
    vols: &'a [Slabs],
    max_leaf: usize,
    nodes: Vec<Node>,
}

fn area(b: &Bounds3) -> f32 {
    if b.is_empty() {
        return 0.0;
    }
    let (lo, hi) = (b.min.to_array(), b.max.to_array());
    let e = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

impl Builder<'_> {
    /// Build the node over `ids` into `nodes[at]`.
    fn node(&mut self, at: usize, ids: &mut [u32], first: usize, depth: usize) {
        let s = ids
            .iter()
            .fold(Slabs::EMPTY, |s, &i| s.union(&self.vols[i as usize]));
        self.nodes[at] = Node {
            s,
            a: first as u32,
            b: 0,
            count: ids.len() as u32,
        };
        if ids.len() <= 1 || depth >= MAX_DEPTH {
            return;
        }
        let Some(mid) = self.split(ids) else {
            return;
        };
        let l = self.nodes.len();
        let dummy = self.nodes[at];
        self.nodes.push(dummy);
        self.nodes.push(dummy);
        self.nodes[at].a = l as u32;
        self.nodes[at].b = l as u32 + 1;
        self.nodes[at].count = 0;
        let (left, right) = ids.split_at_mut(mid);
        self.node(l, left, first, depth + 1);
        self.node(l + 1, right, first + mid, depth + 1);
    }

    /// Binned SAH over the centroids; `None` makes a leaf. When no binned
    /// split exists (coincident centroids) a node above `max_leaf` is
    /// halved by position in the order.
    fn split(&self, ids: &mut [u32]) -> Option<usize> {
        let n = ids.len();
        let (mut clo, mut chi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let mut all = Bounds3::EMPTY;
        for &i in ids.iter() {
            let c = self.centroids[i as usize];
            for a in 0..3 {
                clo[a] = clo[a].min(c[a]);
                chi[a] = chi[a].max(c[a]);
            }
            all = all.union(self.boxes[i as usize]);
        }
        let leaf_cost = n as f32;
        let parent = area(&all).max(f32::MIN_POSITIVE);
        let mut best: Option<(usize, usize, f32)> = None;
        for a in 0..3 {
            let ext = chi[a] - clo[a];
            if !(ext > 0.0) || !ext.is_finite() {
                continue;
            }
            let scale = BINS as f32 / ext;
            let bin = |c: f32| (((c - clo[a]) * scale) as usize).min(BINS - 1);
            let mut cnt = [0usize; BINS];
            let mut bx = [Bounds3::EMPTY; BINS];
            for &i in ids.iter() {
                let b = bin(self.centroids[i as usize][a]);
                cnt[b] += 1;
                bx[b] = bx[b].union(self.boxes[i as usize]);
            }
            let mut right = [(0usize, 0f32); BINS];
            let (mut rc, mut rb) = (0, Bounds3::EMPTY);
            for k in (1..BINS).rev() {
                rc += cnt[k];
                rb = rb.union(bx[k]);
                right[k] = (rc, area(&rb));
            }
            let (mut lc, mut lb) = (0, Bounds3::EMPTY);
            for k in 1..BINS {
                lc += cnt[k - 1];
                lb = lb.union(bx[k - 1]);
                if lc == 0 || right[k].0 == 0 {
                    continue;
                }
                let cost = 1.0 + (lc as f32 * area(&lb) + right[k].0 as f32 * right[k].1) / parent;
                if best.is_none_or(|b| cost < b.2) {
                    best = Some((a, k, cost));
                }
            }
        }
        match best {
            Some((a, k, cost)) if n > self.max_leaf || cost < leaf_cost => {
                let ext = chi[a] - clo[a];
                let scale = BINS as f32 / ext;
                let mut mid = 0;
                for j in 0..n {
                    let c = self.centroids[ids[j] as usize][a];
                    if ((((c - clo[a]) * scale) as usize).min(BINS - 1)) < k {
                        ids.swap(j, mid);
                        mid += 1;
                    }
                }
                Some(mid)
            }
            _ if n > self.max_leaf => Some(n / 2),
            _ => None,
        }
    }
}

struct SlabTree {
    children: Vec<Child>,
    max_leaf: usize,
    built: Option<(Primitives, Tree)>,
}

impl Plugin for SlabTree {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(1..=64).contains(&p.max_leaf) {
            return Err(PluginError::key("max_leaf", "must be between 1 and 64"));
        }
        Ok(SlabTree {
            children: Vec::new(),
            max_leaf: p.max_leaf as usize,
            built: None,
        })
    }
}

/// Pad each leaf to start at a multiple of four in the order (gaps are
/// [`PAD`]), as [`Primitives::pack`] needs; returns the padded order.
fn pad_leaves(nodes: &mut [Node], order: &[u32]) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::with_capacity(order.len() * 2);
    for n in nodes.iter_mut().filter(|n| n.count > 0) {
        let (first, count) = (n.a as usize, n.count as usize);
        n.a = out.len() as u32;
        out.extend_from_slice(&order[first..first + count]);
        while !out.len().is_multiple_of(4) {
            out.push(PAD);
        }
    }
    out
}

impl Object for SlabTree {
    /// Inside any child: the union of their interiors.
    fn in_interior(&self, ctx: &mut TraceCtx, p: rtk_kernel::glam::Vec3, time: f32) -> Interior {
        union_interior(&self.children, ctx, p, time)
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        let g = Primitives::gather(&self.children)?;
        let mut prims = g.prims;
        // The volumes, from the kernel (`inq_bounds`): a triangle's from
        // its vertices exactly, a set primitive's from its box's corners, a
        // whole child's its own (a sphere's tangent planes, a transformed
        // child's placed hull points), else from its box's corners.
        let vols: Vec<Slabs> = (0..prims.len())
            .map(|i| prims.slabs(i).map(|s| Slabs { lo: s.lo, hi: s.hi }))
            .collect::<Result<_, _>>()?;
        let bounds = g.boxes.iter().fold(Bounds3::EMPTY, |b, x| b.union(*x));
        // Primitives that can never be hit (empty boxes) stay out.
        let mut order: Vec<u32> = (0..prims.len() as u32)
            .filter(|&i| !g.boxes[i as usize].is_empty())
            .collect();
        let centroids = g
            .boxes
            .iter()
            .map(|b| {
                let (lo, hi) = (b.min.to_array(), b.max.to_array());
                [0, 1, 2].map(|a| {
                    let c = 0.5 * lo[a] + 0.5 * hi[a];
                    if c.is_finite() {
                        c
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        let mut b = Builder {
            boxes: &g.boxes,
            centroids,
            vols: &vols,
            max_leaf: self.max_leaf,
            nodes: Vec::with_capacity(2 * order.len() / self.max_leaf + 1),
        };
        if !order.is_empty() {
            b.nodes.push(Node {
                s: Slabs::EMPTY,
                a: 0,
                b: 0,
                count: 0,
            });
            b.node(0, &mut order, 0, 0);
        }
        let mut nodes = b.nodes;
        let padded = pad_leaves(&mut nodes, &order);
        prims.reorder(&padded);
        prims.pack();
        let scale = match nodes.first() {
            Some(r) => [0, 1, 2, 3].map(|j| r.s.lo[3 + j].abs().max(r.s.hi[3 + j].abs())),
            None => [0.0; 4],
        };
        let tree = Tree {
            nodes,
            scale,
            bounds,
        };
        self.built = Some((prims, tree));
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.built
            .as_ref()
            .map_or(Bounds3::EMPTY, |(_, t)| t.bounds)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some((prims, tree)) = &self.built else {
            return false;
        };
        let mut q = Nearest::new(ray);
        let mut tests = 0;
        // Volumes entered within the tie margin of the best hit are still
        // visited (rule 11, `cull_bound`).
        tree.traverse(ray, cull_bound(ray.t_max), &mut tests, &mut |leaf| {
            prims.intersect_range(ctx, &mut q, leaf, hit, level);
            Some(cull_bound(q.ray.t_max))
        });
        ctx.stats.node_tests += tests;
        q.found()
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let Some((prims, tree)) = &self.built else {
            return false;
        };
        let mut found = false;
        let mut tests = 0;
        // Any hit will do: no tie to keep, no margin.
        tree.traverse(ray, ray.t_max, &mut tests, &mut |leaf| {
            found = prims.occluded_range(ctx, ray, leaf, level);
            (!found).then_some(ray.t_max)
        });
        ctx.stats.node_tests += tests;
        found
    }

    fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        if let Some((prims, _)) = &self.built {
            prims.local_geom(ctx, ray, hit, level, mask, out);
        }
    }
}

impl FlattensPrimitives for SlabTree {}

rtk_kernel::export_object!(
    SlabTree,
    class = "slabs",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
