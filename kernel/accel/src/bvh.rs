//! The codebase's one BVH: a binned-SAH binary build collapsed into a
//! W-wide tree (W = 4 or 8) whose nodes are tested W boxes at a time (SSE
//! at 4; AVX2 or AVX-512 at 8, chosen at run time by CPU feature detection,
//! [`Simd`]; a portable test the unit tests check against each), near
//! children first.
//!
//! What it takes from the public leaders:
//! - **Embree's BVH4/BVH8**: four or eight children per node in
//!   structure-of-arrays layout, one SIMD slab test for all of them; its
//!   binned SAH builder (Wald 2007, 16–32 bins on centroids), with a leaf's
//!   cost counted in whole blocks of four ([`BuildParams::block`]), so
//!   leaves fill the 4-wide triangle blocks they are tested in.
//! - **tinybvh's BVH8_CPU** (after Fuetterling et al. 2017): the 8-wide test
//!   compiled into a whole AVX2 traversal, so the dispatch is one branch per
//!   ray; children ordered by a per-node permutation for the ray's octant
//!   (`Node::perm`) and pushed with one compressed 8-wide store, instead of
//!   sorted by distance; leaves of four triangles in one block.
//! - **obvhs and tinybvh**: the collapse of a binary SAH tree into the wide
//!   one (open the child with the largest surface area until W). As
//!   Embree's builders fill a wide node, a child the SAH would make a leaf
//!   of more than one block is opened too while the node has free slots;
//!   only the children left when it is full become leaves. On the dragon
//!   this gives a tree of Embree's shape: node count and SAH cost
//!   ([`Bvh::sah`]) close to its own (BENCHMARKS.md, issue 7, "Fourth
//!   session: Embree's own tree").
//!
//! What is rtk's own: the robustness (`docs/numerics.md` rule 10: the far
//! distance widened by `1 + 2γ₄` — Ize 2013's `1 + 2γ₃`, plus the
//! widening's own rounding, [`slab`](rtk_geom::slab) — and a NaN from
//! `0 · ∞`, an origin on a slab plane, leaving the previous bound in place,
//! so a box is never culled by rounding); leaves named by their first entry,
//! so a leaf visit reads the leaf's own block and nothing else; the
//! deferred children prefetched while the nearest is walked ([`Visit`]).
//!
//! Depth is bounded by construction ([`MAX_DEPTH`]): a node that deep becomes
//! a leaf however many primitives it holds, so the traversal stack, sized
//! from that bound, never overflows and never drops a node.

use glam::Vec3;
use rtk_abi::{Bounds3, Ray};
use std::ops::Range;

/// What a child slot of a 4-wide node holds ([`Bvh4::slots`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Slot {
    /// Nothing (a node with fewer than four children).
    Empty,
    /// An inner node: its index (its slots are `4 × index ..`).
    Node(usize),
    /// A leaf: a range of [`Bvh4::order`].
    Leaf(Range<usize>),
}

/// Which walk an 8-wide tree's traversals run ([`Bvh::set_simd`]). A
/// build picks the best the CPU has ([`Bvh::best_simd`]); the others stay
/// selectable, to compare them or to test the fallback. Every walk visits
/// the same nodes in the same order and gives the same hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// One box at a time, any CPU. (A 4-wide tree ignores the choice: it
    /// runs its SSE test on every x86_64 CPU, the portable one elsewhere.)
    Portable,
    /// The 8-wide test and ordering in AVX2 registers.
    Avx2,
    /// The AVX2 walk with AVX-512's mask registers and register
    /// compresses in place of its lookup table, and the leaf test compiled
    /// for AVX-512 VL.
    Avx512,
}

impl Simd {
    /// The name a scene gives this walk (the `bvh`'s `simd` key) and
    /// reports print.
    pub fn name(self) -> &'static str {
        match self {
            Simd::Portable => "portable",
            Simd::Avx2 => "avx2",
            Simd::Avx512 => "avx512",
        }
    }
}

/// A gap in a padded leaf order ([`Bvh4::pad_leaves`]).
pub const PAD: u32 = u32::MAX;

/// Deepest binary tree built; the 4-wide tree is no deeper.
pub const MAX_DEPTH: usize = 64;
/// Entries of the traversal stack: at most seven siblings (8-wide) pushed
/// per level. It is never initialised, so its size costs nothing per ray.
const STACK: usize = 7 * MAX_DEPTH + 1;
/// Bins of the SAH sweep per axis.
const BINS: usize = 16;

/// Build settings, each a trade-off of build time against trace time.
#[derive(Debug, Clone, Copy)]
pub struct BuildParams {
    /// Largest leaf the SAH may choose (larger leaves: fewer nodes, more
    /// primitive tests).
    pub max_leaf: usize,
    /// Cost of testing one block of primitives relative to a node visit,
    /// in the SAH.
    pub prim_cost: f32,
    /// Primitives tested together (the leaf's SIMD width): the SAH counts
    /// a leaf's cost in whole blocks, as Embree's builders do, since a
    /// block of one costs what a block of four does. Leaves then fill
    /// their blocks: fewer leaves, fewer nodes, no padding to read.
    pub block: usize,
}

impl Default for BuildParams {
    /// Leaves of up to 4 primitives tested one at a time, a test costing
    /// about one box test.
    fn default() -> Self {
        BuildParams {
            max_leaf: 4,
            prim_cost: 1.0,
            block: 1,
        }
    }
}

/// A node of `W` children, boxes in structure-of-arrays order (128 bytes
/// at W = 4, 256 at W = 8: two and four cache lines, aligned to them).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
struct Node<const W: usize> {
    /// Lower corners: `lo[axis][child]`.
    lo: [[f32; W]; 3],
    /// Upper corners.
    hi: [[f32; W]; 3],
    /// What each slot holds, in the form the traversal stack keeps: an
    /// inner node's index, [`LEAF`] | the leaf's first entry in
    /// [`Bvh::order`], or [`EMPTY`] (whose box is empty: never entered).
    child: [u32; W],
    /// The slots in front-to-back order for each of the eight octants of
    /// ray directions (Fuetterling et al. 2017, as tinybvh's BVH8_CPU):
    /// bits `3q..3q + 3` of `perm[i]` name the slot `i`-th nearest for
    /// octant `q` (bit `a` of `q` set: the direction is negative on axis
    /// `a`), ranked by the child box's nearest corner along that octant's
    /// diagonal. The 8-wide walk orders the children it enters by one
    /// permutation instead of sorting their distances.
    perm: [u32; W],
}

impl<const W: usize> Node<W> {
    const EMPTY: Self = Node {
        lo: [[f32::INFINITY; W]; 3],
        hi: [[f32::NEG_INFINITY; W]; 3],
        child: [EMPTY; W],
        perm: [0; W],
    };
}

/// The 4-wide tree: SSE, every x86_64 CPU (and the portable test elsewhere).
pub type Bvh4 = Bvh<4>;
/// The 8-wide tree: AVX-512 or AVX2 where the CPU has it (detected at run
/// time, [`Simd`]), the portable test otherwise. Half the depth of
/// [`Bvh4`]: fewer dependent node fetches per ray, which is what incoherent
/// rays wait on.
pub type Bvh8 = Bvh<8>;

/// A `W`-wide BVH over primitive boxes (W = 4 or 8). Leaves are ranges of
/// [`Bvh::order`].
pub struct Bvh<const W: usize> {
    nodes: Vec<Node<W>>,
    /// Every leaf: its range of [`Bvh::order`] and the slot naming it.
    leaves: Vec<LeafInfo>,
    /// The 8-wide walk's layout, when [`Bvh::interleave`] made one.
    lines: HugeLines,
    /// The walk traversals run (chosen at run time: [`Bvh::set_simd`]).
    simd: Simd,
    /// Leaf order: `order[k]` is the primitive stored `k`-th.
    pub order: Vec<u32>,
    /// The root is itself a leaf (fewer primitives than a node splits).
    root_leaf: Option<Range<u32>>,
    /// Levels of the binary tree built (the 4-wide one is shallower).
    pub depth: usize,
    bounds: Bounds3,
}

/// A binary node during the build.
struct Node2 {
    bounds: Bounds3,
    /// Leaf: range of `order`; inner: the two children.
    kind: Kind2,
    /// An inner node the SAH would rather make a leaf: it is split only so
    /// that a parent with free slots can open it (Embree's builders fill a
    /// wide node so); a node it is not opened into becomes one leaf.
    leaf_ok: Option<(u32, u32)>,
}

impl Node2 {
    /// The range this node is a leaf of, if it ends up one (unopened).
    fn as_leaf(&self) -> Option<(u32, u32)> {
        match self.kind {
            Kind2::Leaf(first, count) => Some((first, count)),
            Kind2::Inner(..) => self.leaf_ok,
        }
    }
}

#[derive(Clone, Copy)]
enum Kind2 {
    Leaf(u32, u32),
    Inner(u32, u32),
}

impl<const W: usize> Bvh<W> {
    /// Children per node.
    pub const WIDTH: usize = W;

    /// Whether this CPU runs the `W`-wide test in SIMD (always for W = 4 on
    /// x86_64; for W = 8, when it has AVX2).
    pub fn simd_available() -> bool {
        (cfg!(target_arch = "x86_64") && W == 4) || Self::supports(Simd::Avx2)
    }

    /// Whether this CPU can run the `simd` walk of a `W`-wide tree.
    /// [`Simd::Portable`] runs anywhere; the AVX walks are 8-wide only.
    pub fn supports(simd: Simd) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            // Every CPU with AVX2 has FMA, BMI1/2, POPCNT and LZCNT too
            // (Haswell, Zen); the walk is compiled for all of them. The
            // AVX-512 walk uses 256-bit vectors with mask registers and
            // compresses (F, VL), compiled with BW and DQ as well, which
            // every AVX-512 CPU since Skylake-X has.
            let avx2 = || {
                has!("avx2")
                    && has!("fma")
                    && has!("bmi1")
                    && has!("bmi2")
                    && has!("popcnt")
                    && has!("lzcnt")
            };
            match simd {
                Simd::Portable => true,
                Simd::Avx2 => W == 8 && avx2(),
                Simd::Avx512 => {
                    W == 8
                        && avx2()
                        && has!("avx512f")
                        && has!("avx512vl")
                        && has!("avx512bw")
                        && has!("avx512dq")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            simd == Simd::Portable
        }
    }

    /// The fastest walk this CPU runs: AVX-512, else AVX2, else portable
    /// (what a build chooses).
    pub fn best_simd() -> Simd {
        [Simd::Avx512, Simd::Avx2]
            .into_iter()
            .find(|&s| Self::supports(s))
            .unwrap_or(Simd::Portable)
    }

    /// Run the `simd` walk from now on, if this CPU can
    /// ([`Bvh::supports`]); returns whether it was set (else the walk is
    /// unchanged). The tests run every walk the CPU has, so CI checks the
    /// portable fallback on any machine.
    pub fn set_simd(&mut self, simd: Simd) -> bool {
        let ok = Self::supports(simd);
        if ok {
            self.simd = simd;
        }
        ok
    }

    /// The walk traversals run.
    pub fn simd(&self) -> Simd {
        self.simd
    }

    /// Build over `boxes` (one per primitive; empty boxes are never hit),
    /// on this thread.
    pub fn build(boxes: &[Bounds3], params: BuildParams) -> Self {
        Self::build_on(boxes, params, &|n, f| (0..n).for_each(f))
    }

    /// [`Bvh::build`] with the subtrees below the top few levels built in
    /// parallel: `par(n, f)` runs `f(i)` for every `i < n`, on any threads
    /// (a plugin passes the host's pool, `Prepare::parallel_for`). The
    /// tree is the same whatever runs the tasks: each subtree is built
    /// alone, and they are joined in a fixed order.
    ///
    /// The top levels have few nodes, each over many primitives: their
    /// passes over the primitives (boxes, bins) are split into pieces
    /// across `par`, their partitions stay serial. Below them, whole
    /// subtrees are independent tasks. Why both: the top levels hold every
    /// primitive but few nodes, so as tasks they would keep one thread busy
    /// while the others wait for their subtrees (build times on one and two
    /// threads: BENCHMARKS.md, issue 7, "The build runs on the host's pool").
    pub fn build_on(boxes: &[Bounds3], params: BuildParams, par: &Parallel<'_>) -> Self {
        assert!(W == 4 || W == 8, "a BVH is 4 or 8 wide");
        let centroids: Vec<Vec3> = boxes
            .iter()
            .map(|b| (b.min.v() + b.max.v()) * 0.5)
            .collect();
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut b = Builder {
            boxes,
            centroids: &centroids,
            params,
            nodes: Vec::with_capacity(2 * boxes.len() / params.max_leaf.max(1) + 1),
            depth: 0,
            // Subtrees of at most 1/32 of the primitives (and at least
            // `MIN_TASK`) are left as tasks: enough of them to balance two
            // threads or a few more. A small build runs on its own.
            task_size: if boxes.len() >= 2 * MIN_TASK {
                (boxes.len() / 32).max(MIN_TASK)
            } else {
                0
            },
            tasks: Vec::new(),
            par: Some(par),
        };
        let root = b.node(&mut order, 0, 1);
        b.run_tasks(&mut order, par);
        let bounds = b.nodes[root as usize].bounds;
        let depth = b.depth;
        let nodes2 = b.nodes;
        let mut out = Bvh {
            nodes: Vec::with_capacity(nodes2.len() / 2 + 1),
            leaves: Vec::with_capacity(nodes2.len() / 2 + 1),
            lines: HugeLines::empty(),
            simd: Simd::Portable,
            order,
            root_leaf: None,
            depth,
            bounds,
        };
        match nodes2[root as usize].as_leaf() {
            Some((first, n)) => out.root_leaf = Some(first..first + n),
            None => {
                out.nodes.push(Node::EMPTY);
                out.collapse(&nodes2, root, 0);
            }
        }
        out.name_leaves();
        out.nodes.shrink_to_fit();
        out.leaves.shrink_to_fit();
        out.set_simd(Self::best_simd());
        out
    }

    /// Give every leaf a range starting at a multiple of `to` in a longer
    /// order, the gaps holding [`PAD`]: a leaf's first entry then names its
    /// `to`-wide block by itself (`first / to`), with no lookup per leaf.
    pub fn pad_leaves(&mut self, to: usize) {
        let mut out: Vec<u32> = Vec::with_capacity(self.order.len() * 2);
        let place = |first: u32, count: u32, out: &mut Vec<u32>| -> u32 {
            let at = out.len() as u32;
            out.extend_from_slice(&self.order[first as usize..(first + count) as usize]);
            while !out.len().is_multiple_of(to) {
                out.push(PAD);
            }
            at
        };
        if let Some(r) = &self.root_leaf {
            let at = place(r.start, r.end - r.start, &mut out);
            self.root_leaf = Some(at..at + (r.end - r.start));
        }
        for leaf in &mut self.leaves {
            leaf.first = place(leaf.first, leaf.count, &mut out);
        }
        self.order = out;
        self.name_leaves();
    }

    /// The leaves: ranges of [`Bvh4::order`].
    pub fn leaves(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        let root = self
            .root_leaf
            .iter()
            .map(|r| r.start as usize..r.end as usize);
        let inner = self
            .leaves
            .iter()
            .map(|l| l.first as usize..(l.first + l.count) as usize);
        root.chain(inner)
    }

    /// The box of everything.
    pub fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// Bytes held by the tree (nodes and leaf order).
    pub fn bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<Node<W>>()
            + self.lines.bytes()
            + self.leaves.capacity() * std::mem::size_of::<LeafInfo>()
            + self.order.capacity() * 4
    }

    /// The tree's SAH cost as Embree's statistics report it (`verbose=2`),
    /// so the two trees compare: over the nodes, each node's box area; over
    /// the leaves, each leaf's box area times its blocks of `block`
    /// primitives; both relative to the root box. For rays that are random
    /// lines through the root box, the node term is the expected number of
    /// node visits (Cauchy–Crofton).
    pub fn sah(&self, block: usize) -> (f64, f64) {
        let half = |lo: [f32; 3], hi: [f32; 3]| -> f64 {
            let e = [0, 1, 2].map(|a| (hi[a] as f64 - lo[a] as f64).max(0.0));
            e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
        };
        let b = self.bounds;
        let root = half(b.min.v().to_array(), b.max.v().to_array()).max(f64::MIN_POSITIVE);
        let slot = |n: &Node<W>, s: usize| {
            half(
                [n.lo[0][s], n.lo[1][s], n.lo[2][s]],
                [n.hi[0][s], n.hi[1][s], n.hi[2][s]],
            )
        };
        let mut nodes = if self.nodes.is_empty() { 0.0 } else { root };
        for n in &self.nodes {
            for s in 0..W {
                if n.child[s] != EMPTY && n.child[s] & LEAF == 0 {
                    nodes += slot(n, s);
                }
            }
        }
        let blocks = |count: u32| count.div_ceil(block.max(1) as u32) as f64;
        let mut leaves = match &self.root_leaf {
            Some(r) => root * blocks(r.end - r.start),
            None => 0.0,
        };
        for l in &self.leaves {
            leaves += slot(&self.nodes[l.node as usize], l.slot as usize) * blocks(l.count);
        }
        (nodes / root, leaves / root)
    }

    /// Fill `W`-wide node `at` from binary node `n`: open the child with the
    /// largest area until `W` children (or only leaves) remain.
    fn collapse(&mut self, n2: &[Node2], n: u32, at: usize) {
        let Kind2::Inner(a, b) = n2[n as usize].kind else {
            unreachable!("collapse starts at an inner node")
        };
        let mut kids = vec![a, b];
        while kids.len() < W {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| matches!(n2[k as usize].kind, Kind2::Inner(..)))
                .max_by(|x, y| {
                    area(&n2[*x.1 as usize].bounds).total_cmp(&area(&n2[*y.1 as usize].bounds))
                })
                .map(|(i, _)| i);
            let Some(i) = open else { break };
            let Kind2::Inner(l, r) = n2[kids[i] as usize].kind else {
                unreachable!("only inner nodes are opened")
            };
            kids.splice(i..=i, [l, r]);
        }
        let mut node = Node::EMPTY;
        for (slot, &k) in kids.iter().enumerate() {
            let bb = n2[k as usize].bounds;
            for axis in 0..3 {
                node.lo[axis][slot] = bb.min.v()[axis];
                node.hi[axis][slot] = bb.max.v()[axis];
            }
            node.child[slot] = match n2[k as usize].as_leaf() {
                Some((first, count)) => {
                    self.leaves.push(LeafInfo {
                        first,
                        count,
                        node: at as u32,
                        slot: slot as u32,
                    });
                    // Named once the order is final (`name_leaves`).
                    EMPTY
                }
                None => {
                    let child = self.nodes.len();
                    assert!(child < LEAF as usize, "more than 2^31 nodes");
                    self.nodes.push(Node::EMPTY);
                    self.collapse(n2, k, child);
                    child as u32
                }
            };
        }
        node.perm = octant_order(&node);
        self.nodes[at] = node;
    }

    /// Lay the tree out for the 8-wide walk with each node followed by its
    /// leaves' data, as tinybvh's BVH8_CPU does: `data(first)` gives the
    /// lines of the leaf starting at `first` (in a final order: call after
    /// [`Bvh::pad_leaves`]). A node and the leaves it names then share a
    /// stretch of memory, and the hardware prefetcher that fetches one
    /// fetches the other: on incoherent rays a leaf was a cache miss of its
    /// own. The walk then hands leaves to [`Visit::leaf_lines`]. Only the
    /// 8-wide AVX walks ([`Simd::Avx2`], [`Simd::Avx512`]) read this layout;
    /// the portable walk keeps reading the nodes and [`Visit::leaf`].
    /// Returns whether it made one: a tree that is a single leaf has no
    /// nodes to lay out, and its leaf is still handed to [`Visit::leaf`].
    pub fn interleave<'a>(&mut self, data: impl Fn(usize) -> &'a [Line]) -> bool {
        let node_lines = std::mem::size_of::<Node<W>>() / 64;
        if self.nodes.is_empty() {
            self.lines = HugeLines::empty();
            return false;
        }
        // Counted first, so the layout is written once, in place, on its
        // own pages (a growing `Vec` copied it twice more and faulted in
        // pages the mapping then faulted in again).
        let total = self.nodes.len() * node_lines
            + self
                .leaves
                .iter()
                .map(|l| data(l.first as usize).len())
                .sum::<usize>();
        assert!(
            total < LEAF as usize,
            "an interleaved BVH holds under 2^31 lines"
        );
        let mut out = HugeLines::zeroed(total);
        let lines = out.as_mut_slice();
        let mut len = 0;
        // (node, where its line offset goes: the parent's line and slot).
        let mut todo: Vec<(u32, Option<(usize, usize)>)> = vec![(0, None)];
        while let Some((n, parent)) = todo.pop() {
            let at = len;
            if let Some((p, slot)) = parent {
                set_child::<W>(lines, p, slot, at as u32);
            }
            let mut node = self.nodes[n as usize];
            len += node_lines;
            for slot in 0..W {
                let c = node.child[slot];
                if c == EMPTY {
                    continue;
                }
                if c & LEAF != 0 {
                    node.child[slot] = LEAF | len as u32;
                    let d = data((c & !LEAF) as usize);
                    lines[len..len + d.len()].copy_from_slice(d);
                    len += d.len();
                } else {
                    todo.push((c, Some((at, slot))));
                }
            }
            write_node(&mut lines[at..at + node_lines], &node);
        }
        assert_eq!(len, total, "every node and leaf is laid out once");
        self.lines = out;
        true
    }

    /// Visit the leaves `ray` may hit over `(t_min, t_max)`, near children
    /// first. `leaf(first)` tests a leaf's primitives and returns the
    /// narrowed `t_max`, or `None` to stop. A leaf is named by its first
    /// entry in [`Bvh::order`] (of a table reordered by it); where it ends
    /// is the table's to know ([`Bvh::leaves`] lists the ranges), so that a
    /// leaf visit reads the leaf's own data and nothing else — a table of
    /// ranges was one more cache miss per leaf on incoherent rays. Boxes whose entry lies beyond
    /// the current `t_max` are skipped; an entry equal to it is still
    /// visited (a tie may be won there).
    ///
    /// The order only changes how soon `t_max` narrows, never which
    /// primitives can win: the 4-wide and portable walks sort the entered
    /// children by entry distance; the 8-wide AVX walks rank them by the
    /// node's precomputed order for the ray's octant (`Node::perm`), which
    /// costs one permutation instead of a sort.
    #[inline]
    pub fn traverse(&self, ray: &Ray, t_max: f32, node_tests: &mut u64, leaf: impl Visit) {
        #[cfg(target_arch = "x86_64")]
        if self.simd != Simd::Portable {
            // SAFETY: `simd` names a walk only when the CPU has its
            // features (`set_simd`), and W = 8.
            return unsafe { self.walk8_on::<true>(ray, t_max, node_tests, leaf) };
        }
        let screen = |_, t, _| Some(t);
        self.walk::<false, false>(ray, t_max, node_tests, screen, leaf)
    }

    /// [`traverse`](Self::traverse) for any-hit queries, which stop at the
    /// first hit and never narrow `t_max`: the 8-wide walk skips the
    /// ranking, which costs more than it saves there (an occlusion ray ends
    /// at any hit, so the order spares few node visits; BENCHMARKS.md,
    /// issue 7, "Tried and reverted"); the other walks rank as for
    /// `traverse`.
    #[inline]
    pub fn traverse_any(&self, ray: &Ray, t_max: f32, node_tests: &mut u64, leaf: impl Visit) {
        #[cfg(target_arch = "x86_64")]
        if self.simd != Simd::Portable {
            // SAFETY: `simd` names a walk only when the CPU has its
            // features (`set_simd`), and W = 8.
            return unsafe { self.walk8_on::<false>(ray, t_max, node_tests, leaf) };
        }
        let screen = |_, t, _| Some(t);
        self.walk::<false, false>(ray, t_max, node_tests, screen, leaf)
    }

    /// [`traverse`](Self::traverse) with a second test per child: of the
    /// children whose box the ray enters, `screen(slot, t_entry, t_max)` is
    /// asked for each (`slot` = node × W + position, as [`Bvh::slots`]
    /// names them) and may reject it (`None`) or return a later entry
    /// distance. An aggregate bounding its children with tighter volumes
    /// than boxes (spheres, slabs) tests them here, on the box test's
    /// survivors only.
    #[inline]
    pub fn traverse_screened(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        screen: impl FnMut(usize, f32, f32) -> Option<f32>,
        leaf: impl Visit,
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.simd != Simd::Portable {
            // SAFETY: `simd` is set only when the CPU has its features, and
            // every walk but the portable one needs AVX2.
            return unsafe { self.walk_avx2_screened(ray, t_max, node_tests, screen, leaf) };
        }
        self.walk::<true, false>(ray, t_max, node_tests, screen, leaf)
    }

    /// The sorted walk compiled with AVX2 enabled, so the 8-wide test's
    /// intrinsics inline into it: the dispatch is one branch per ray.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,popcnt,lzcnt")]
    unsafe fn walk_avx2_screened(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        screen: impl FnMut(usize, f32, f32) -> Option<f32>,
        leaf: impl Visit,
    ) {
        self.walk::<true, true>(ray, t_max, node_tests, screen, leaf)
    }

    /// The 8-wide walk for `ORDERED` (nearest-hit) or any-hit queries,
    /// in the layout the tree has and with the SIMD it was set to.
    ///
    /// # Safety
    /// `self.simd` is AVX2 or AVX-512 (set only when the CPU has it); `W`
    /// must be 8.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn walk8_on<const ORDERED: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        leaf: impl Visit,
    ) {
        let lines = !self.lines.is_empty();
        // SAFETY: per the contract, the CPU has what each walk is compiled for.
        unsafe {
            match (self.simd, lines) {
                (Simd::Avx512, false) => {
                    self.walk8_avx512::<ORDERED, false>(ray, t_max, node_tests, leaf)
                }
                (Simd::Avx512, true) => {
                    self.walk8_avx512::<ORDERED, true>(ray, t_max, node_tests, leaf)
                }
                (Simd::Avx2, false) => {
                    self.walk8_avx2::<ORDERED, false>(ray, t_max, node_tests, leaf)
                }
                (Simd::Avx2, true) => {
                    self.walk8_avx2::<ORDERED, true>(ray, t_max, node_tests, leaf)
                }
                (Simd::Portable, _) => unreachable!("the portable walk is not 8-wide SIMD"),
            }
        }
    }

    /// [`Bvh::walk8`] compiled with AVX2 enabled, so the 8-wide test's
    /// intrinsics and the leaf test inline into it: the dispatch is one
    /// branch per ray.
    ///
    /// # Safety
    /// The CPU must have AVX2 (and what [`Bvh::supports`] checks with it);
    /// `W` must be 8.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,popcnt,lzcnt")]
    unsafe fn walk8_avx2<const ORDERED: bool, const LINES: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        leaf: impl Visit,
    ) {
        // SAFETY: the CPU has AVX2, per the contract.
        unsafe { self.walk8::<ORDERED, LINES, false>(ray, t_max, node_tests, leaf) }
    }

    /// [`Bvh::walk8`] with its AVX-512 steps, compiled with AVX-512 (F, VL,
    /// BW, DQ) enabled: the leaf test inlined into it is compiled so too
    /// (mask registers for its lane logic).
    ///
    /// # Safety
    /// The CPU must have what [`Bvh::supports`] checks for
    /// [`Simd::Avx512`]; `W` must be 8.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,popcnt,lzcnt,avx512f,avx512vl,avx512bw,avx512dq")]
    unsafe fn walk8_avx512<const ORDERED: bool, const LINES: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        leaf: impl Visit,
    ) {
        // SAFETY: the CPU has AVX-512 F, VL, BW and DQ (and AVX2), per the
        // contract: `supports` checks each.
        unsafe { self.walk8::<ORDERED, LINES, true>(ray, t_max, node_tests, leaf) }
    }

    /// The 8-wide walk, all in vector registers: each node is six aligned
    /// row loads (the near and far rows chosen once per ray), a subtract
    /// and a multiply per row, a compare and a mask ([`Ray8::test`]). The
    /// children entered are put in the octant's front-to-back order
    /// (`Node::perm`) and pushed in one pair of 8-wide stores, so no branch
    /// depends on their distances; the nearest comes straight back off the
    /// stack (any-hit queries, `!ORDERED`, skip the ranking). How the
    /// entered children are packed together differs by `X512`:
    /// - AVX2: the ranked children and distances are each permuted by an
    ///   entry of a lookup table (`COMPRESS`, 8 KiB) indexed by the mask
    ///   ([`push_by_table`]);
    /// - AVX-512: the rank itself is compressed (`VPCOMPRESSD` into a
    ///   register; never into memory, microcoded on Zen 4) and children and
    ///   distances are permuted by it: no table, and on nearest-hit queries
    ///   one permutation fewer (any-hit queries permute the mask instead of
    ///   loading a table entry: as many operations; [`push_by_compress`]).
    ///
    /// `LINES`: the tree is interleaved ([`Bvh::interleave`]); nodes and
    /// leaves are line offsets into it.
    ///
    /// Every step is an `#[inline(always)]` function without features of
    /// its own, so it is compiled into `walk8_avx2` or `walk8_avx512` with
    /// theirs: the loop makes no call but the leaf's.
    ///
    /// # Safety
    /// The CPU must have AVX2, and AVX-512 F, VL and DQ if `X512`; the
    /// caller is compiled with them (`walk8_avx2`, `walk8_avx512`), so the
    /// intrinsics inline. `W` must be 8.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn walk8<const ORDERED: bool, const LINES: bool, const X512: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        mut leaf: impl Visit,
    ) {
        debug_assert!(W == 8);
        if self.no_nodes(&mut leaf) {
            return;
        }
        let mut ids = std::mem::MaybeUninit::<[u32; STACK8]>::uninit();
        let mut dists = std::mem::MaybeUninit::<[f32; STACK8]>::uninit();
        let (ids, dists) = (ids.as_mut_ptr() as *mut u32, dists.as_mut_ptr() as *mut f32);
        let mut sp = 0usize;
        let mut t_max = t_max;
        // SAFETY: the CPU has AVX2 (and AVX-512 F, VL, DQ if `X512`), per
        // the contract, which is all `Ray8` and the push functions need
        // besides their pointers: a node's rows are read from a node the
        // tree holds (`node`, `node_at`); the stack is written at
        // `sp..sp + 8` only after `sp + 8 <= STACK8` is asserted, and read
        // below `sp`, where entries were written; a leaf's lines start at an
        // offset `interleave` wrote into its slot.
        unsafe {
            let r = Ray8::new::<W>(&Precomp::new(ray), ray.t_min);
            let mut cur = 0u32;
            loop {
                if cur & LEAF == 0 {
                    let node = if LINES {
                        self.node_at(cur)
                    } else {
                        self.node(cur)
                    };
                    *node_tests += 1;
                    let (hit, t0) = r.test(node, t_max);
                    let mask = lane_mask::<X512>(hit);
                    if mask != 0 {
                        if mask & (mask - 1) == 0 {
                            cur = node.child[mask.trailing_zeros() as usize];
                            continue;
                        }
                        assert!(sp + 8 <= STACK8, "BVH traversal stack overflow");
                        let top = (ids.add(sp), dists.add(sp));
                        if X512 {
                            push_by_compress::<ORDERED, W>(node, hit, t0, r.shift, top);
                        } else {
                            push_by_table::<ORDERED, W>(node, hit, t0, mask, r.shift, top);
                        }
                        // Farthest first: the nearest is on top, taken now.
                        let deferred = mask.count_ones() as usize - 1;
                        self.prefetch_deferred::<LINES>(ids, sp..sp + deferred, &leaf);
                        sp += deferred;
                        cur = *ids.add(sp);
                        continue;
                    }
                } else {
                    let at = (cur & !LEAF) as usize;
                    let r = if LINES {
                        leaf.leaf_lines(self.lines.as_slice().get_unchecked(at..))
                    } else {
                        leaf.leaf(at)
                    };
                    match r {
                        Some(t) => t_max = t,
                        None => return,
                    }
                }
                match pop_within::<ORDERED>(ids, dists, &mut sp, t_max) {
                    Some(next) => cur = next,
                    None => return,
                }
            }
        }
    }

    /// Start fetching the children deferred at `ids[deferred]` (an
    /// incoherent ray spends most of its time waiting on memory, and they
    /// wait until the nearest child's subtree is done).
    ///
    /// # Safety
    /// `ids[deferred]` are children of this tree's nodes (written by a push).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn prefetch_deferred<const LINES: bool>(
        &self,
        ids: *const u32,
        deferred: Range<usize>,
        leaf: &impl Visit,
    ) {
        use std::arch::x86_64::*;
        // SAFETY: per the contract, each entry read was written and is a
        // child slot of this tree, so the addresses computed are within its
        // nodes or its layout (a prefetch of any address is harmless besides).
        unsafe {
            for i in deferred {
                let c = *ids.add(i);
                if LINES {
                    // A node's first four lines, or a leaf's
                    // first block (three) and what follows.
                    let p = self.lines.ptr.as_ptr().add((c & !LEAF) as usize) as *const i8;
                    for line in 0..4 {
                        _mm_prefetch::<_MM_HINT_T0>(p.add(64 * line));
                    }
                } else if c & LEAF != 0 {
                    leaf.prefetch((c & !LEAF) as usize);
                } else {
                    let p = self.node(c) as *const Node<W> as *const i8;
                    for line in 0..std::mem::size_of::<Node<W>>() / 64 {
                        _mm_prefetch::<_MM_HINT_T0>(p.add(64 * line));
                    }
                }
            }
        }
    }

    /// Every child slot of the tree, children before their parents
    /// (reverse node order: a node's children are stored after it): its id
    /// (node × W + position) and what it holds. The root is not a slot;
    /// when the whole tree is one leaf there are none.
    pub fn slots(&self) -> impl Iterator<Item = (usize, Slot)> + '_ {
        let mut slots = vec![Slot::Empty; self.nodes.len() * W];
        for (n, node) in self.nodes.iter().enumerate() {
            for (k, &c) in node.child.iter().enumerate() {
                if c != EMPTY && c & LEAF == 0 {
                    slots[n * W + k] = Slot::Node(c as usize);
                }
            }
        }
        for l in &self.leaves {
            slots[l.node as usize * W + l.slot as usize] =
                Slot::Leaf(l.first as usize..(l.first + l.count) as usize);
        }
        slots.into_iter().enumerate().rev()
    }

    /// Number of slot ids ([`Bvh::slots`]): `W` per node.
    pub fn slot_count(&self) -> usize {
        self.nodes.len() * W
    }

    /// The walk of the 4-wide tree, of the portable test, and of screened
    /// queries: children entered are ranked by entry distance.
    #[inline(always)]
    fn walk<const SCREEN: bool, const AVX: bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        node_tests: &mut u64,
        mut screen: impl FnMut(usize, f32, f32) -> Option<f32>,
        mut leaf: impl Visit,
    ) {
        if self.no_nodes(&mut leaf) {
            return;
        }
        let pre = Precomp::new(ray);
        let mut t_max = t_max;
        let mut buf = std::mem::MaybeUninit::uninit();
        let mut stack = Stack::on(&mut buf);
        // The node or leaf being visited, as its slot names it.
        let mut cur = 0u32;
        loop {
            if cur & LEAF != 0 {
                match leaf.leaf((cur & !LEAF) as usize) {
                    Some(t) => t_max = t,
                    None => return,
                }
            } else {
                let node = self.node(cur);
                *node_tests += 1;
                let (mut mask, mut t_near) = pre.test::<W, AVX>(node, ray.t_min, t_max);
                if SCREEN {
                    let mut m = mask;
                    while m != 0 {
                        let k = m.trailing_zeros() as usize;
                        m &= m - 1;
                        match screen(cur as usize * W + k, t_near[k], t_max) {
                            Some(t) => t_near[k] = t,
                            None => mask &= !(1 << k),
                        }
                    }
                }
                if mask != 0 {
                    cur = descend(node, mask, &t_near, &mut stack);
                    continue;
                }
            }
            // Next: the nearest deferred child not beyond the best hit.
            loop {
                let Some((r, t_entry)) = stack.pop() else {
                    return;
                };
                if t_entry <= t_max {
                    cur = r;
                    break;
                }
            }
        }
    }

    /// A tree without nodes, walked: its one leaf (if it holds anything)
    /// is visited. Returns whether the tree has no nodes, so the walk is done.
    #[inline(always)]
    fn no_nodes(&self, leaf: &mut impl Visit) -> bool {
        if let Some(r) = &self.root_leaf {
            if !r.is_empty() {
                leaf.leaf(r.start as usize);
            }
            return true;
        }
        self.nodes.is_empty()
    }

    /// Write each leaf's name (`LEAF | first`) into its slot, once the
    /// order is final.
    fn name_leaves(&mut self) {
        for l in &self.leaves {
            assert!(l.first < LEAF, "a BVH holds fewer than 2^31 entries");
            self.nodes[l.node as usize].child[l.slot as usize] = LEAF | l.first;
        }
    }

    /// The node at line `i` of the interleaved layout, without a bounds
    /// check: every line offset the walk follows was written by
    /// [`Bvh::interleave`] (a node's own, in its parent's slot).
    #[inline(always)]
    fn node_at(&self, i: u32) -> &Node<W> {
        let node_lines = std::mem::size_of::<Node<W>>() / 64;
        debug_assert!(i as usize + node_lines <= self.lines.len);
        // SAFETY: `i` is a node's line offset (the walk follows only those
        // `interleave` wrote), so lines `i..i + node_lines` hold a node written by
        // `write_node` (every field a plain number, so any bytes are valid),
        // 64-byte aligned as `Node` is; the layout is immutable once made.
        unsafe { &*(self.lines.ptr.as_ptr().add(i as usize) as *const Node<W>) }
    }

    /// Node `i` of the traversal, without a bounds check: every index the
    /// walk follows was written by `collapse` (an inner slot's `child`),
    /// all below `nodes.len()`.
    #[inline(always)]
    fn node(&self, i: u32) -> &Node<W> {
        debug_assert!((i as usize) < self.nodes.len());
        // SAFETY: `i` is below `nodes.len()`: the walk follows only the
        // indices `collapse` wrote, and the tree is immutable after the build.
        unsafe { self.nodes.get_unchecked(i as usize) }
    }
}

/// Of the children of `node` in `mask`, return the nearest and defer the
/// others (farthest pushed first, so they come back nearest first).
#[inline(always)]
fn descend<const W: usize>(node: &Node<W>, mask: u32, t_near: &[f32; W], stack: &mut Stack) -> u32 {
    let first = mask.trailing_zeros() as usize;
    let rest = mask & (mask - 1);
    if rest == 0 {
        return node.child[first];
    }
    if rest & (rest - 1) == 0 {
        // Two: the commonest case after one, without a sort.
        let second = rest.trailing_zeros() as usize;
        let (near, far) = if t_near[second] < t_near[first] {
            (second, first)
        } else {
            (first, second)
        };
        stack.push((node.child[far], t_near[far]));
        return node.child[near];
    }
    // More: push them all, order that run of the stack farthest first
    // (insertion sort of at most W), and take the nearest off the top.
    let base = stack.len;
    let mut m = mask;
    while m != 0 {
        let slot = m.trailing_zeros() as usize;
        m &= m - 1;
        stack.push((node.child[slot], t_near[slot]));
    }
    let run = stack.top_run(base);
    for i in 1..run.len() {
        let mut j = i;
        while j > 0 && run[j - 1].1 < run[j].1 {
            run.swap(j - 1, j);
            j -= 1;
        }
    }
    match stack.pop() {
        Some((c, _)) => c,
        None => unreachable!("three or more children were pushed"),
    }
}

/// What the 8-wide walk's node test needs of a ray, in vector registers,
/// made once per ray.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Ray8 {
    /// Float offset of each axis's near row within a node: the lower
    /// corners where the direction is positive, the upper ones where not.
    near: [usize; 3],
    /// Float offset of each axis's far row.
    far: [usize; 3],
    /// Three times the ray's octant, as a shift count: it brings the
    /// octant's rank of each slot (`Node::perm`) to the low bits.
    shift: std::arch::x86_64::__m128i,
    /// The origin, per axis.
    o: [std::arch::x86_64::__m256; 3],
    /// −1/d per axis: (o − b)·(−1/d) is (b − o)·(1/d) bit for bit
    /// (negation is exact), and lets each row load fold into the
    /// subtraction.
    inv: [std::arch::x86_64::__m256; 3],
    /// −(1/d)·`FAR_SCALE`: the conservative far side.
    inv_far: [std::arch::x86_64::__m256; 3],
    /// The ray's `t_min`, the entry distances' floor.
    t_lo: std::arch::x86_64::__m256,
}

#[cfg(target_arch = "x86_64")]
impl Ray8 {
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    unsafe fn new<const W: usize>(pre: &Precomp, t_min: f32) -> Self {
        use std::arch::x86_64::*;
        let row = |upper: bool, a: usize| (if upper { 3 + a } else { a }) * W;
        let octant = pre.neg[0] as u32 | (pre.neg[1] as u32) << 1 | (pre.neg[2] as u32) << 2;
        // SAFETY: register arithmetic, on a CPU with AVX2 (the contract).
        unsafe {
            Ray8 {
                near: [0, 1, 2].map(|a| row(pre.neg[a], a)),
                far: [0, 1, 2].map(|a| row(!pre.neg[a], a)),
                shift: _mm_cvtsi32_si128(3 * octant as i32),
                o: pre.o.map(|x| _mm256_set1_ps(x)),
                inv: pre.inv.map(|x| _mm256_set1_ps(-x)),
                inv_far: pre.inv.map(|x| _mm256_set1_ps(-(x * FAR_SCALE))),
                t_lo: _mm256_set1_ps(t_min),
            }
        }
    }

    /// The slab test of a node's eight boxes over `[t_min, t_max]`: which
    /// the ray enters (all-ones lanes) and the entry distances.
    ///
    /// # Safety
    /// The CPU must have AVX2; `node` is an 8-wide node (64-byte aligned).
    #[inline(always)]
    unsafe fn test<const W: usize>(
        &self,
        node: &Node<W>,
        t_max: f32,
    ) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
        use std::arch::x86_64::*;
        let base = node as *const Node<W> as *const f32;
        // SAFETY: each load is a whole row of the node (eight floats at a
        // 32-byte offset of a 64-byte aligned node, `near` and `far` being
        // row offsets); the rest is register arithmetic on a CPU with AVX2.
        unsafe {
            let mut t0 = self.t_lo;
            let mut t1 = _mm256_set1_ps(t_max);
            for a in 0..3 {
                let n = _mm256_load_ps(base.add(self.near[a]));
                let f = _mm256_load_ps(base.add(self.far[a]));
                // MAXPS/MINPS return the second operand when either is
                // NaN (0·∞): the running bound stays in place.
                t0 = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(self.o[a], n), self.inv[a]), t0);
                t1 = _mm256_min_ps(
                    _mm256_mul_ps(_mm256_sub_ps(self.o[a], f), self.inv_far[a]),
                    t1,
                );
            }
            (_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1), t0)
        }
    }
}

/// The lanes of `hit` set, as a bit mask (`X512`: through a mask register).
///
/// # Safety
/// The CPU must have AVX2, and AVX-512 VL and DQ if `X512`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn lane_mask<const X512: bool>(hit: std::arch::x86_64::__m256) -> u32 {
    use std::arch::x86_64::*;
    // SAFETY: register arithmetic on a CPU with the features (the contract).
    unsafe {
        if X512 {
            _mm256_movepi32_mask(_mm256_castps_si256(hit)) as u32
        } else {
            _mm256_movemask_ps(hit) as u32
        }
    }
}

/// Store the children of `node` the ray enters (`hit`) at `ids`, and
/// their entry distances (`t0`) at `dists` if `ORDERED`: farthest first
/// (by the octant's rank when `ORDERED`, by slot otherwise), so the
/// nearest ends on top. AVX-512: the rank is compressed in a register and
/// permutes children and distances; eight lanes are written.
///
/// # Safety
/// The CPU must have AVX2 and AVX-512 F, VL and DQ; `ids` and `dists`
/// have room for eight.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn push_by_compress<const ORDERED: bool, const W: usize>(
    node: &Node<W>,
    hit: std::arch::x86_64::__m256,
    t0: std::arch::x86_64::__m256,
    shift: std::arch::x86_64::__m128i,
    (ids, dists): (*mut u32, *mut f32),
) {
    use std::arch::x86_64::*;
    // SAFETY: the loads are a node's aligned `child` and `perm` rows
    // (eight u32s, 32-byte aligned in a 64-byte aligned node); the stores
    // are eight lanes at `ids` and `dists`, which have room (the contract).
    unsafe {
        let child = _mm256_load_si256(node.child.as_ptr() as *const __m256i);
        // The slots to push, farthest first (the stack's order, as
        // `COMPRESS` makes it).
        let backwards = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
        let rank = if ORDERED {
            let perm = _mm256_load_si256(node.perm.as_ptr() as *const __m256i);
            // VPERMD reads the low three bits of each index: the
            // octant's, after the shift.
            _mm256_permutevar8x32_epi32(_mm256_srl_epi32(perm, shift), backwards)
        } else {
            backwards
        };
        let ranked = _mm256_permutevar8x32_epi32(_mm256_castps_si256(hit), rank);
        let pick = _mm256_maskz_compress_epi32(_mm256_movepi32_mask(ranked), rank);
        _mm256_storeu_si256(
            ids as *mut __m256i,
            _mm256_permutevar8x32_epi32(child, pick),
        );
        if ORDERED {
            _mm256_storeu_ps(dists, _mm256_permutevar8x32_ps(t0, pick));
        }
    }
}

/// [`push_by_compress`] with AVX2 only: the ranked children and distances
/// are each permuted by the `COMPRESS` entry of the ranked mask (`mask`:
/// the lanes of `hit`).
///
/// # Safety
/// The CPU must have AVX2; `ids` and `dists` have room for eight.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn push_by_table<const ORDERED: bool, const W: usize>(
    node: &Node<W>,
    hit: std::arch::x86_64::__m256,
    t0: std::arch::x86_64::__m256,
    mask: u32,
    shift: std::arch::x86_64::__m128i,
    (ids, dists): (*mut u32, *mut f32),
) {
    use std::arch::x86_64::*;
    // SAFETY: the loads are a node's aligned `child` and `perm` rows and a
    // `COMPRESS` entry (eight u32s, 32-byte aligned; the mask is below
    // 256); the stores are eight lanes at `ids` and `dists`, which have
    // room (the contract).
    unsafe {
        let child = _mm256_load_si256(node.child.as_ptr() as *const __m256i);
        let (mut m, mut t, mut c) = (mask, t0, child);
        if ORDERED {
            let perm = _mm256_load_si256(node.perm.as_ptr() as *const __m256i);
            // VPERMPS reads the low three bits of each index.
            let rank = _mm256_srl_epi32(perm, shift);
            m = _mm256_movemask_ps(_mm256_permutevar8x32_ps(hit, rank)) as u32;
            t = _mm256_permutevar8x32_ps(t0, rank);
            c = _mm256_permutevar8x32_epi32(child, rank);
        }
        let pick = _mm256_load_si256(COMPRESS[m as usize].as_ptr() as *const __m256i);
        _mm256_storeu_si256(ids as *mut __m256i, _mm256_permutevar8x32_epi32(c, pick));
        if ORDERED {
            // An any-hit query's t_max never narrows: every deferred child
            // stays in range, no distance kept.
            _mm256_storeu_ps(dists, _mm256_permutevar8x32_ps(t, pick));
        }
    }
}

/// Pop the nearest deferred child not beyond the best hit (`t_max`; an
/// any-hit query's, `!ORDERED`, never narrows: it takes the top), or
/// `None` when the stack runs out.
///
/// # Safety
/// `ids` (and `dists` if `ORDERED`) hold `*sp` written entries.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn pop_within<const ORDERED: bool>(
    ids: *const u32,
    dists: *const f32,
    sp: &mut usize,
    t_max: f32,
) -> Option<u32> {
    // SAFETY: every read is below `*sp`, written (the contract).
    unsafe {
        while *sp > 0 {
            *sp -= 1;
            if !ORDERED || *dists.add(*sp) <= t_max {
                return Some(*ids.add(*sp));
            }
        }
        None
    }
}

/// What a traversal does at a leaf: test the primitives of the leaf
/// starting at entry `first` and return the narrowed `t_max`, or `None` to
/// stop. Any `FnMut(usize) -> Option<f32>` will do; a hot path implements
/// it on a struct with `#[inline(always)]`, so the leaf test is compiled
/// into the walk (with its SIMD features, and without spilling the ray's
/// registers around a call), which a closure cannot ask for.
pub trait Visit {
    /// Test the leaf starting at `first`.
    fn leaf(&mut self, first: usize) -> Option<f32>;

    /// The leaf starting at `first` will likely be tested soon (it was
    /// deferred on the stack): start fetching its data. Nothing by default.
    #[inline(always)]
    fn prefetch(&self, _first: usize) {}

    /// Test the leaf whose data ([`Bvh::interleave`]'s `data`) starts
    /// `lines` (which run on past it). Called instead of
    /// [`Visit::leaf`] on an interleaved tree, whose caller provides it.
    #[inline(always)]
    fn leaf_lines(&mut self, _lines: &[Line]) -> Option<f32> {
        unreachable!("an interleaved BVH is walked by a visitor of its lines")
    }
}

/// The interleaved layout's lines, in memory the OS is asked to back with
/// 2 MiB pages (Linux's transparent huge pages, `madvise` mode). Why: an
/// incoherent ray touches a few lines of each of a dozen 4 KiB pages of a
/// layout of tens of MiB, and a TLB miss under a hypervisor's nested paging
/// costs a walk of up to 24 memory references: the rays that jump across
/// the layout, incoherent and occlusion rays, gain most (BENCHMARKS.md,
/// issue 7).
///
/// A layout of 2 MiB or more gets pages of its own (`mmap`), starting on a
/// 2 MiB boundary, so every page of it can be a huge one. A heap copy
/// could not: its first and last partial 2 MiB keep 4 KiB pages, and so
/// does any part of it the heap reuses from the build's freed (already
/// touched) memory — on the dragon, a quarter of the layout. A smaller
/// layout, or one on another OS, is a plain heap copy.
struct HugeLines {
    ptr: std::ptr::NonNull<Line>,
    len: usize,
    /// Where the lines live: the heap (`Vec` storage) or a mapping of
    /// `(base, bytes)` to unmap.
    owner: LinesOwner,
}

enum LinesOwner {
    Heap(#[allow(dead_code)] Vec<Line>),
    #[cfg(target_os = "linux")]
    Mapped(usize, usize),
}

// SAFETY: `HugeLines` owns its storage (as a `Vec` does); it hands out
// shared slices of plain bytes, and a mutable one only through `&mut self`
// (`as_mut_slice`, while `interleave` fills it).
unsafe impl Send for HugeLines {}
// SAFETY: `&HugeLines` only reads (`as_slice`, the raw pointer the walks
// load through); writing needs `&mut self`.
unsafe impl Sync for HugeLines {}

impl HugeLines {
    const HUGE: usize = 2 << 20;

    fn empty() -> Self {
        HugeLines {
            ptr: std::ptr::NonNull::dangling(),
            len: 0,
            owner: LinesOwner::Heap(Vec::new()),
        }
    }

    /// `n` zeroed lines, to be written through [`HugeLines::as_mut_slice`]
    /// before the walk reads them: on a mapping of their own if they fill
    /// a huge page (Linux), else on the heap.
    fn zeroed(n: usize) -> Self {
        #[cfg(target_os = "linux")]
        if let Some(mapped) = Self::mapped(n) {
            return mapped;
        }
        let mut v = vec![Line([0; 64]); n];
        HugeLines {
            ptr: std::ptr::NonNull::new(v.as_mut_ptr()).expect("a Vec's pointer"),
            len: n,
            owner: LinesOwner::Heap(v),
        }
    }

    /// A copy of `src` (as [`HugeLines::zeroed`] places it).
    #[cfg(test)]
    fn new(src: &[Line]) -> Self {
        let mut out = Self::zeroed(src.len());
        out.as_mut_slice().copy_from_slice(src);
        out
    }

    /// `n` zeroed lines on fresh pages advised huge, or `None` (too few to
    /// fill a huge page, or the mapping failed).
    #[cfg(target_os = "linux")]
    fn mapped(n: usize) -> Option<Self> {
        let bytes = n * std::mem::size_of::<Line>();
        if bytes < Self::HUGE {
            return None;
        }
        // Room to start on a 2 MiB boundary and end on one; the slack on
        // either side is never touched, so it takes no memory.
        let size = bytes.next_multiple_of(Self::HUGE) + Self::HUGE;
        // SAFETY: a new private anonymous mapping: it aliases nothing.
        let base = unsafe {
            libc::mmap(
                std::ptr::null_mut(),
                size,
                libc::PROT_READ | libc::PROT_WRITE,
                libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
                -1,
                0,
            )
        };
        if base == libc::MAP_FAILED {
            return None;
        }
        let at = (base as usize).next_multiple_of(Self::HUGE);
        // SAFETY: `at .. at + bytes` rounded up to 2 MiB lies inside the
        // mapping (`size` leaves a whole 2 MiB for the alignment) and is
        // untouched yet; madvise only advises the kernel, reads and writes
        // no memory, and its failure (a kernel without THP) leaves ordinary
        // pages.
        unsafe {
            let advised = bytes.next_multiple_of(Self::HUGE);
            libc::madvise(at as *mut libc::c_void, advised, libc::MADV_HUGEPAGE);
        }
        Some(HugeLines {
            // An anonymous mapping reads as zeros: `n` zeroed lines, page
            // aligned (so aligned for `Line`).
            ptr: std::ptr::NonNull::new(at as *mut Line).expect("a mapping is never at address 0"),
            len: n,
            owner: LinesOwner::Mapped(base as usize, size),
        })
    }

    /// The lines, to fill (only while the layout is being made: `&mut
    /// self` excludes any reader).
    fn as_mut_slice(&mut self) -> &mut [Line] {
        // SAFETY: `ptr` holds `len` initialised lines (zeros at least) or
        // is dangling with `len` 0, owned by `self` and borrowed mutably
        // through it alone.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.as_ptr(), self.len) }
    }

    fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn as_slice(&self) -> &[Line] {
        // SAFETY: `ptr` holds `len` initialised lines (or is dangling with
        // `len` 0, which a slice allows), alive as long as `self`.
        unsafe { std::slice::from_raw_parts(self.ptr.as_ptr(), self.len) }
    }

    /// Bytes held.
    fn bytes(&self) -> usize {
        match &self.owner {
            LinesOwner::Heap(v) => v.capacity() * 64,
            #[cfg(target_os = "linux")]
            LinesOwner::Mapped(_, _) => (self.len * 64).next_multiple_of(Self::HUGE),
        }
    }
}

impl Drop for HugeLines {
    fn drop(&mut self) {
        #[cfg(target_os = "linux")]
        if let LinesOwner::Mapped(base, size) = self.owner {
            // SAFETY: the mapping made in `mapped`, unmapped once; no slice
            // of it outlives `self`.
            unsafe { libc::munmap(base as *mut libc::c_void, size) };
        }
    }
}

/// A cache line of [`Bvh::interleave`]'s layout.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub struct Line(pub [u8; 64]);

/// Node `node` as the bytes of its lines (`repr(C)`, no padding: its fields
/// are arrays of 4-byte numbers, 32 · W bytes in all).
fn write_node<const W: usize>(lines: &mut [Line], node: &Node<W>) {
    let words = node
        .lo
        .iter()
        .chain(&node.hi)
        .flatten()
        .map(|x| x.to_bits())
        .chain(node.child)
        .chain(node.perm);
    for (k, w) in words.enumerate() {
        lines[k / 16].0[4 * (k % 16)..4 * (k % 16) + 4].copy_from_slice(&w.to_ne_bytes());
    }
}

/// Set slot `slot`'s child of the node at line `at` in a layout.
fn set_child<const W: usize>(lines: &mut [Line], at: usize, slot: usize, child: u32) {
    let k = std::mem::offset_of!(Node<W>, child) / 4 + slot;
    let line = &mut lines[at + k / 16];
    line.0[4 * (k % 16)..4 * (k % 16) + 4].copy_from_slice(&child.to_ne_bytes());
}

impl<F: FnMut(usize) -> Option<f32>> Visit for F {
    #[inline(always)]
    fn leaf(&mut self, first: usize) -> Option<f32> {
        self(first)
    }
}

/// A leaf: its range of the order and the slot that names it.
#[derive(Clone, Copy, Debug)]
struct LeafInfo {
    first: u32,
    count: u32,
    node: u32,
    slot: u32,
}

/// Marks a leaf slot (`LEAF | first entry`); a node index has this bit
/// clear.
const LEAF: u32 = 1 << 31;
/// An unused slot (its box is empty, so it is never entered).
const EMPTY: u32 = u32::MAX;

/// Entries of the 8-wide walk's stack: at most seven deferred per level,
/// and room for the last 8-wide store.
const STACK8: usize = 7 * MAX_DEPTH + 8;

/// For each mask of entered children (in rank order), the lanes to gather
/// so that they come first, highest rank first: stored at the stack's top,
/// the nearest (lowest rank) ends up on top.
#[cfg(target_arch = "x86_64")]
#[repr(C, align(32))]
struct CompressTable([[u32; 8]; 256]);

#[cfg(target_arch = "x86_64")]
impl std::ops::Index<usize> for CompressTable {
    type Output = [u32; 8];
    fn index(&self, m: usize) -> &[u32; 8] {
        &self.0[m]
    }
}

#[cfg(target_arch = "x86_64")]
static COMPRESS: CompressTable = CompressTable({
    let mut t = [[0u32; 8]; 256];
    let mut m = 0;
    while m < 256 {
        let (mut k, mut lane) = (0, 8);
        while lane > 0 {
            lane -= 1;
            if m >> lane & 1 == 1 {
                t[m][k] = lane as u32;
                k += 1;
            }
        }
        m += 1;
    }
    t
});

/// The slots of `node` in front-to-back order for each octant of
/// directions ([`Node::perm`]): ranked by the nearest corner of each child
/// box along the octant's diagonal, empty slots last, ties by slot.
fn octant_order<const W: usize>(node: &Node<W>) -> [u32; W] {
    let mut perm = [0u32; W];
    for q in 0..8 {
        let key = |s: usize| -> f32 {
            if node.child[s] == EMPTY {
                return f32::INFINITY;
            }
            (0..3)
                .map(|a| {
                    if q >> a & 1 == 1 {
                        // Negative along `a`: the upper face is met first.
                        -node.hi[a][s]
                    } else {
                        node.lo[a][s]
                    }
                })
                .sum()
        };
        let mut slots: [usize; W] = std::array::from_fn(|s| s);
        slots.sort_by(|&x, &y| key(x).total_cmp(&key(y)).then(x.cmp(&y)));
        for (i, &s) in slots.iter().enumerate() {
            perm[i] |= (s as u32) << (3 * q);
        }
    }
    perm
}

/// The traversal stack over a buffer of [`STACK`] entries the caller keeps
/// uninitialised (created once per ray; zeroing 1.5 KB would cost more than a
/// node test — and rustc zero-fills a `MaybeUninit` held in a struct, so the
/// buffer is a local of the traversal and this borrows it).
struct Stack<'a> {
    items: *mut (u32, f32),
    len: usize,
    _buf: std::marker::PhantomData<&'a mut [(u32, f32); STACK]>,
}

impl<'a> Stack<'a> {
    #[inline(always)]
    fn on(buf: &'a mut std::mem::MaybeUninit<[(u32, f32); STACK]>) -> Self {
        Stack {
            items: buf.as_mut_ptr() as *mut (u32, f32),
            len: 0,
            _buf: std::marker::PhantomData,
        }
    }

    /// Push; the depth bound (`MAX_DEPTH`, at most W − 1 siblings a level)
    /// makes overflow impossible, and the assertion checks it regardless.
    #[inline(always)]
    fn push(&mut self, v: (u32, f32)) {
        assert!(self.len < STACK, "BVH traversal stack overflow");
        // SAFETY: `len < STACK`: the slot is inside the borrowed buffer.
        unsafe { self.items.add(self.len).write(v) };
        self.len += 1;
    }

    /// The entries pushed since the stack held `base`.
    #[inline(always)]
    fn top_run(&mut self, base: usize) -> &mut [(u32, f32)] {
        debug_assert!(base <= self.len);
        // SAFETY: the slots `base..len` were written by `push` and lie in
        // the borrowed buffer, which this `&mut self` borrows exclusively.
        unsafe { std::slice::from_raw_parts_mut(self.items.add(base), self.len - base) }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below `len` was written by `push`.
        Some(unsafe { self.items.add(self.len).read() })
    }
}

/// Surface area (half of it: only ratios matter).
fn area(b: &Bounds3) -> f32 {
    if b.is_empty() {
        return 0.0;
    }
    let e = b.max.v() - b.min.v();
    e.x * e.y + e.y * e.z + e.z * e.x
}

struct Builder<'a> {
    boxes: &'a [Bounds3],
    centroids: &'a [Vec3],
    params: BuildParams,
    nodes: Vec<Node2>,
    depth: usize,
    /// A node of at most this many primitives (and not the root) is left
    /// to be built as a task of its own ([`Builder::run_tasks`]); 0: none.
    task_size: usize,
    /// The nodes left so: (node, first, count, level).
    tasks: Vec<(u32, usize, usize, usize)>,
    /// The pool the top levels' passes over their primitives are split
    /// across (their nodes are few and large; below them, whole subtrees
    /// are tasks); `None` in a task.
    par: Option<&'a Parallel<'a>>,
}

/// Primitives per piece of a top-level node's pass ([`Builder::split_fold`]).
const PAR_PIECE: usize = 16 * 1024;

/// Runs `f(i)` for every `i < n`, on any threads ([`Bvh::build_on`]).
pub type Parallel<'a> = dyn Fn(u64, &(dyn Fn(u64) + Sync)) + 'a;

/// A subtree built by a task: its nodes (its root first) and depth.
type Subtree = (Vec<Node2>, usize);

/// The smallest subtree worth a task of its own.
const MIN_TASK: usize = 4096;

/// The best split of a node found by the SAH sweep.
struct Split {
    axis: usize,
    /// Primitives in bins below this one go left.
    bin: usize,
    cost: f32,
}

impl Builder<'_> {
    /// Build the subtrees left as tasks, in parallel on `par`, each by a
    /// builder of its own over its own part of `order`, and join them in
    /// task order: the tree is the one a serial build makes.
    fn run_tasks(&mut self, order: &mut [u32], par: &Parallel<'_>) {
        use std::sync::Mutex;
        let tasks = std::mem::take(&mut self.tasks);
        if tasks.is_empty() {
            return;
        }
        // Each task's part of the order (they are disjoint, in order).
        let mut parts = Vec::with_capacity(tasks.len());
        let (mut rest, mut at) = (order, 0);
        for &(_, first, count, _) in &tasks {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut(first - at);
            let (part, tail) = tail.split_at_mut(count);
            parts.push(Mutex::new(part));
            (rest, at) = (tail, first + count);
        }
        let built: Vec<Mutex<Option<Subtree>>> = tasks.iter().map(|_| Mutex::new(None)).collect();
        let (boxes, centroids, params) = (self.boxes, self.centroids, self.params);
        par(tasks.len() as u64, &|i| {
            let i = i as usize;
            let (_, first, _, level) = tasks[i];
            let mut part = parts[i].lock().unwrap_or_else(|e| e.into_inner());
            let mut b = Builder {
                boxes,
                centroids,
                params,
                nodes: Vec::new(),
                depth: 0,
                // A task builds its whole subtree itself.
                task_size: 0,
                tasks: Vec::new(),
                par: None,
            };
            b.node(&mut part, first, level);
            *built[i].lock().unwrap_or_else(|e| e.into_inner()) = Some((b.nodes, b.depth));
        });
        for (&(at, ..), out) in tasks.iter().zip(built) {
            let (nodes, depth) = out
                .into_inner()
                .unwrap_or_else(|e| e.into_inner())
                .expect("every task ran");
            self.depth = self.depth.max(depth);
            // The task's root takes the placeholder's place; the rest follow
            // the nodes so far, their links moved by the same offset.
            let shift = |k: u32| {
                if k == 0 {
                    at
                } else {
                    k + self.nodes.len() as u32 - 1
                }
            };
            let moved = |n: &Node2| Node2 {
                bounds: n.bounds,
                kind: match n.kind {
                    Kind2::Inner(a, b) => Kind2::Inner(shift(a), shift(b)),
                    leaf @ Kind2::Leaf(..) => leaf,
                },
                leaf_ok: n.leaf_ok,
            };
            let root = moved(&nodes[0]);
            let rest: Vec<Node2> = nodes[1..].iter().map(moved).collect();
            self.nodes[at as usize] = root;
            self.nodes.extend(rest);
        }
    }

    /// Build the node over `ids` (at `first` in the order) at `level`.
    fn node(&mut self, ids: &mut [u32], first: usize, level: usize) -> u32 {
        if ids.len() <= self.task_size && level > 1 && !ids.is_empty() {
            // Built later, as a task ([`Builder::run_tasks`]).
            let me = self.nodes.len() as u32;
            self.nodes.push(Node2 {
                bounds: Bounds3::EMPTY,
                kind: Kind2::Leaf(first as u32, ids.len() as u32),
                leaf_ok: None,
            });
            self.tasks.push((me, first, ids.len(), level));
            return me;
        }
        self.depth = self.depth.max(level);
        let (bounds, cb) = self.extents(ids);
        let me = self.nodes.len() as u32;
        self.nodes.push(Node2 {
            bounds,
            kind: Kind2::Leaf(first as u32, ids.len() as u32),
            leaf_ok: None,
        });
        if ids.len() <= 1 || level >= MAX_DEPTH {
            return me;
        }
        let mid = match self.sah(ids, &cb, area(&bounds)) {
            Some(s) if s.cost < self.leaf_cost(ids.len()) || ids.len() > self.params.max_leaf => {
                self.partition(ids, &cb, &s)
            }
            // A leaf of one block is never opened.
            Some(_) if ids.len() <= self.params.block => return me,
            Some(s) => {
                self.nodes[me as usize].leaf_ok = Some((first as u32, ids.len() as u32));
                self.partition(ids, &cb, &s)
            }
            // All centroids in one bin (coincident): split the list in half
            // if it is too big for a leaf, else keep it.
            None if ids.len() > self.params.max_leaf => ids.len() / 2,
            None => return me,
        };
        let (l, r) = ids.split_at_mut(mid);
        let a = self.node(l, first, level + 1);
        let b = self.node(r, first + mid, level + 1);
        self.nodes[me as usize].kind = Kind2::Inner(a, b);
        me
    }

    /// SAH cost of making `n` primitives a leaf, relative to traversing a node.
    fn leaf_cost(&self, n: usize) -> f32 {
        self.blocks(n) * self.params.prim_cost
    }

    /// Blocks `n` primitives take.
    #[inline]
    fn blocks(&self, n: usize) -> f32 {
        n.div_ceil(self.params.block.max(1)) as f32
    }

    /// The box of `ids` and the box of their centroids: one pass, split
    /// across the pool for a node of the top levels ([`Builder::par`]).
    fn extents(&self, ids: &[u32]) -> (Bounds3, Bounds3) {
        let (boxes, centroids) = (self.boxes, self.centroids);
        let fold = move |ids: &[u32]| {
            ids.iter()
                .fold((Bounds3::EMPTY, Bounds3::EMPTY), |(b, c), &i| {
                    (b.union(boxes[i as usize]), c.include(centroids[i as usize]))
                })
        };
        let merge =
            |(a, b): (Bounds3, Bounds3), (c, d): (Bounds3, Bounds3)| (a.union(c), b.union(d));
        self.split_fold(ids, fold, merge)
    }

    /// Every axis's bins over `ids` (each bin's box and count), in one
    /// pass, split across the pool for a node of the top levels. A bin's
    /// box is a union, exact in any order: the bins, and so the tree, do
    /// not depend on the split.
    fn bins(&self, ids: &[u32], cb: &Bounds3) -> [[(Bounds3, u32); BINS]; 3] {
        use glam::Vec3A;
        let (boxes, centroids) = (self.boxes, self.centroids);
        let binning = Binning::new(cb);
        // Bins as SIMD corners (`Vec3A`: one MINPS and one MAXPS per union,
        // against six scalar comparisons). `b.min(acc)` is `acc.union(b)`
        // lane for lane: MINPS(b, acc) keeps `acc` unless `b < acc`, as
        // `min_of` does, NaN and signed zeros included.
        type Bins = [[(Vec3A, Vec3A, u32); BINS]; 3];
        const EMPTY_BIN: (Vec3A, Vec3A, u32) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0);
        let fold = move |ids: &[u32]| {
            let mut bins: Bins = [[EMPTY_BIN; BINS]; 3];
            for &i in ids {
                let (b, c) = (&boxes[i as usize], centroids[i as usize]);
                let (lo, hi) = (Vec3A::from(b.min.v()), Vec3A::from(b.max.v()));
                for (axis, bins) in bins.iter_mut().enumerate() {
                    let bin = &mut bins[binning.bin(c[axis], axis)];
                    bin.0 = lo.min(bin.0);
                    bin.1 = hi.max(bin.1);
                    bin.2 += 1;
                }
            }
            bins
        };
        let merge = |mut a: Bins, b: Bins| {
            for (a, b) in a.iter_mut().flatten().zip(b.iter().flatten()) {
                *a = (b.0.min(a.0), b.1.max(a.1), a.2 + b.2);
            }
            a
        };
        let bins = self.split_fold(ids, fold, merge);
        bins.map(|axis| axis.map(|(lo, hi, n)| (Bounds3::new(Vec3::from(lo), Vec3::from(hi)), n)))
    }

    /// `fold` over `ids`, in pieces across the pool when there are many
    /// (`PAR_PIECE` or more per piece, at least two), merged in order.
    fn split_fold<T: Send>(
        &self,
        ids: &[u32],
        fold: impl Fn(&[u32]) -> T + Sync,
        merge: impl Fn(T, T) -> T,
    ) -> T {
        let Some(par) = self.par.filter(|_| ids.len() >= 2 * PAR_PIECE) else {
            return fold(ids);
        };
        use std::sync::Mutex;
        let pieces: Vec<&[u32]> = ids.chunks(PAR_PIECE).collect();
        let out: Vec<Mutex<Option<T>>> = pieces.iter().map(|_| Mutex::new(None)).collect();
        par(pieces.len() as u64, &|i| {
            let r = fold(pieces[i as usize]);
            *out[i as usize].lock().unwrap_or_else(|e| e.into_inner()) = Some(r);
        });
        out.into_iter()
            .map(|m| {
                m.into_inner()
                    .unwrap_or_else(|e| e.into_inner())
                    .expect("every piece ran")
            })
            .reduce(merge)
            .expect("at least two pieces")
    }

    /// The cheapest binned split, if the centroids spread over more than one bin.
    fn sah(&self, ids: &[u32], cb: &Bounds3, parent: f32) -> Option<Split> {
        let ext = cb.max.v() - cb.min.v();
        let mut best: Option<Split> = None;
        let all = self.bins(ids, cb);
        for (axis, bins) in all.iter().enumerate() {
            if !(ext[axis] > 0.0) {
                continue;
            }
            // Sweep: areas and counts of everything right of each boundary.
            let mut right = [(0f32, 0u32); BINS];
            let (mut rb, mut rn) = (Bounds3::EMPTY, 0);
            for k in (1..BINS).rev() {
                rb = rb.union(bins[k].0);
                rn += bins[k].1;
                right[k] = (area(&rb), rn);
            }
            let (mut lb, mut ln) = (Bounds3::EMPTY, 0);
            for k in 1..BINS {
                lb = lb.union(bins[k - 1].0);
                ln += bins[k - 1].1;
                let (ra, rn) = right[k];
                if ln == 0 || rn == 0 {
                    continue;
                }
                let cost = 1.0
                    + self.params.prim_cost
                        * (area(&lb) * self.blocks(ln as usize) + ra * self.blocks(rn as usize))
                        / parent.max(f32::MIN_POSITIVE);
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Split { axis, bin: k, cost });
                }
            }
        }
        best
    }

    /// Put the primitives of bins below `s.bin` first; returns how many.
    fn partition(&self, ids: &mut [u32], cb: &Bounds3, s: &Split) -> usize {
        let binning = Binning::new(cb);
        let c = self.centroids;
        let mut i = 0;
        for j in 0..ids.len() {
            if binning.bin(c[ids[j] as usize][s.axis], s.axis) < s.bin {
                ids.swap(i, j);
                i += 1;
            }
        }
        i
    }
}

/// Which bin a centroid falls in, per axis, over a node's centroid box:
/// one subtraction and one multiplication by a factor made once per node
/// (a division per centroid and axis was a third of the binning's time).
/// The bins and the partition use this one mapping, so they agree.
#[derive(Clone, Copy)]
struct Binning {
    lo: [f32; 3],
    scale: [f32; 3],
}

impl Binning {
    fn new(cb: &Bounds3) -> Self {
        let (lo, hi) = (cb.min.v(), cb.max.v());
        Binning {
            lo: lo.to_array(),
            // A flat axis (0 extent) gives ∞: every centroid there is 0·∞
            // (NaN), which the conversion takes to bin 0; the SAH skips it.
            scale: (hi - lo).to_array().map(|e| BINS as f32 / e),
        }
    }

    #[inline(always)]
    fn bin(&self, x: f32, axis: usize) -> usize {
        let k = ((x - self.lo[axis]) * self.scale[axis]) as isize;
        k.clamp(0, BINS as isize - 1) as usize
    }
}

/// What a ray's box tests share: origin, reciprocal direction, and which
/// corner is near on each axis.
struct Precomp {
    o: [f32; 3],
    inv: [f32; 3],
    /// Per axis: the near plane is the upper corner (direction negative).
    neg: [bool; 3],
}

/// Widening of the far distance that makes the slab test conservative:
/// `1 + 2γ₄` (γ as in [`gamma`](rtk_geom::gamma), computed at compile
/// time; why γ₄: [`slab`](rtk_geom::slab)). The 8-wide walk folds it
/// into the reciprocal (`(1/d)·s` once per ray): the same four roundings
/// on the far side, in another order.
const FAR_SCALE: f32 = {
    let ne = 4.0 * (f32::EPSILON * 0.5);
    1.0 + 2.0 * (ne / (1.0 - ne))
};

impl Precomp {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        // 1/±0 = ±inf: an axis the ray does not move along.
        let inv = d.map(|x| 1.0 / x);
        Precomp {
            o,
            inv,
            // The sign of the reciprocal orders the slab (never a comparison
            // of t values, which a NaN would spoil).
            neg: inv.map(|x| x.is_sign_negative()),
        }
    }

    /// The children of `n` the ray's interval `[t_min, t_max]` overlaps: a
    /// bit mask and each child's entry distance. `AVX`: the caller runs
    /// with AVX2 enabled (W = 8).
    #[inline(always)]
    fn test<const W: usize, const AVX: bool>(
        &self,
        n: &Node<W>,
        t_min: f32,
        t_max: f32,
    ) -> (u32, [f32; W]) {
        let mut tn = [0f32; W];
        let rows = |r: &[[f32; W]; 3]| [r[0].as_ptr(), r[1].as_ptr(), r[2].as_ptr()];
        #[cfg(target_arch = "x86_64")]
        {
            if W == 4 {
                // SAFETY: the rows are four floats, `tn` has room for four;
                // SSE2 is part of every x86_64 CPU.
                let m = unsafe {
                    self.test4_sse(rows(&n.lo), rows(&n.hi), t_min, t_max, tn.as_mut_ptr())
                };
                return (m, tn);
            }
            if W == 8 && AVX {
                // SAFETY: the rows are eight floats, `tn` has room for
                // eight; the caller runs with AVX2 (`walk_avx2_screened`).
                let m = unsafe {
                    self.test8_avx(rows(&n.lo), rows(&n.hi), t_min, t_max, tn.as_mut_ptr())
                };
                return (m, tn);
            }
        }
        (self.test_scalar(n, t_min, t_max, &mut tn), tn)
    }

    /// The portable test, one box at a time, with the same NaN rule.
    fn test_scalar<const W: usize>(
        &self,
        n: &Node<W>,
        t_min: f32,
        t_max: f32,
        tn: &mut [f32; W],
    ) -> u32 {
        let mut mask = 0;
        for (slot, tn) in tn.iter_mut().enumerate() {
            let (mut t0, mut t1) = (t_min, t_max);
            for a in 0..3 {
                let (near, far) = if self.neg[a] {
                    (n.hi[a][slot], n.lo[a][slot])
                } else {
                    (n.lo[a][slot], n.hi[a][slot])
                };
                let tna = (near - self.o[a]) * self.inv[a];
                let tfa = (far - self.o[a]) * self.inv[a] * FAR_SCALE;
                // A NaN (0·∞) compares false and leaves the bound as it was.
                if tna > t0 {
                    t0 = tna;
                }
                if tfa < t1 {
                    t1 = tfa;
                }
            }
            *tn = t0;
            if t0 <= t1 {
                mask |= 1 << slot;
            }
        }
        mask
    }

    /// The SSE test of four boxes. Not a `#[target_feature]` function
    /// (those are never inlined into callers without the feature): SSE and
    /// SSE2 are part of the x86_64 baseline.
    ///
    /// # Safety
    /// Each row pointer reads four floats; `out` has room for four.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn test4_sse(
        &self,
        lo: [*const f32; 3],
        hi: [*const f32; 3],
        t_min: f32,
        t_max: f32,
        out: *mut f32,
    ) -> u32 {
        use std::arch::x86_64::*;
        // SAFETY: per the contract; the rest is register arithmetic.
        unsafe {
            let mut t0 = _mm_set1_ps(t_min);
            let mut t1 = _mm_set1_ps(t_max);
            let scale = _mm_set1_ps(FAR_SCALE);
            for a in 0..3 {
                let (near, far) = if self.neg[a] {
                    (hi[a], lo[a])
                } else {
                    (lo[a], hi[a])
                };
                let o = _mm_set1_ps(self.o[a]);
                let inv = _mm_set1_ps(self.inv[a]);
                let tna = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(near), o), inv);
                let tfa = _mm_mul_ps(_mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(far), o), inv), scale);
                // MAXPS/MINPS return the second operand when either is NaN: a
                // NaN slab (0·∞) leaves the running bound in place.
                t0 = _mm_max_ps(tna, t0);
                t1 = _mm_min_ps(tfa, t1);
            }
            _mm_storeu_ps(out, t0);
            _mm_movemask_ps(_mm_cmple_ps(t0, t1)) as u32
        }
    }

    /// The AVX test of eight boxes: the SSE test's operations, eight lanes
    /// wide (the same NaN rule: VMAXPS/VMINPS return the second operand).
    ///
    /// # Safety
    /// The CPU must have AVX (the caller is compiled with AVX2 enabled);
    /// each row pointer reads eight floats; `out` has room for eight.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn test8_avx(
        &self,
        lo: [*const f32; 3],
        hi: [*const f32; 3],
        t_min: f32,
        t_max: f32,
        out: *mut f32,
    ) -> u32 {
        use std::arch::x86_64::*;
        // SAFETY: per the contract; the rest is register arithmetic.
        unsafe {
            let mut t0 = _mm256_set1_ps(t_min);
            let mut t1 = _mm256_set1_ps(t_max);
            let scale = _mm256_set1_ps(FAR_SCALE);
            for a in 0..3 {
                let (near, far) = if self.neg[a] {
                    (hi[a], lo[a])
                } else {
                    (lo[a], hi[a])
                };
                let o = _mm256_set1_ps(self.o[a]);
                let inv = _mm256_set1_ps(self.inv[a]);
                let tna = _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(near), o), inv);
                let tfa = _mm256_mul_ps(
                    _mm256_mul_ps(_mm256_sub_ps(_mm256_loadu_ps(far), o), inv),
                    scale,
                );
                t0 = _mm256_max_ps(tna, t0);
                t1 = _mm256_min_ps(tfa, t1);
            }
            _mm256_storeu_ps(out, t0);
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_abi::RngState;

    fn random_boxes(n: usize, seed: u64) -> Vec<Bounds3> {
        let mut r = RngState::seeded(seed);
        (0..n)
            .map(|_| {
                let c = Vec3::new(
                    r.range_f32(-10.0, 10.0),
                    r.range_f32(-10.0, 10.0),
                    r.range_f32(-10.0, 10.0),
                );
                let e = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 0.5;
                Bounds3::new(c - e, c + e)
            })
            .collect()
    }

    /// Every box a ray overlaps (by the kernel's scalar slab test) is in a
    /// leaf the traversal visits, and every primitive is in exactly one leaf.
    fn check<const W: usize>(boxes: &[Bounds3], bvh: &Bvh<W>, seed: u64) {
        let leaves: std::collections::HashMap<usize, Range<usize>> =
            bvh.leaves().map(|r| (r.start, r)).collect();
        assert_eq!(
            leaves.len(),
            bvh.leaves().count(),
            "leaves share a first entry"
        );
        let mut ids = bvh.order.clone();
        ids.sort_unstable();
        assert_eq!(ids, (0..boxes.len() as u32).collect::<Vec<_>>());
        let mut r = RngState::seeded(seed);
        for k in 0..2000 {
            let o = Vec3::new(
                r.range_f32(-15.0, 15.0),
                r.range_f32(-15.0, 15.0),
                r.range_f32(-15.0, 15.0),
            );
            let mut d = Vec3::new(
                r.range_f32(-1.0, 1.0),
                r.range_f32(-1.0, 1.0),
                r.range_f32(-1.0, 1.0),
            );
            // Axis-parallel and ±0 directions too (numerics A1).
            if k % 5 == 0 {
                d = [Vec3::X, Vec3::NEG_Y, Vec3::new(0.0, -0.0, 1.0)][k % 3];
            }
            let ray = Ray::new(o, d);
            let pre = rtk_geom::RayBoxPrecomp::new(&ray);
            let want: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| {
                    pre.intersect(&boxes[i as usize], 0.0, f32::INFINITY)
                        .is_some()
                })
                .collect();
            let mut got = Vec::new();
            if bvh.lines.is_empty() {
                bvh.traverse(&ray, f32::INFINITY, &mut 0, |first| {
                    got.extend(leaves[&first].clone().map(|k| bvh.order[k]));
                    Some(f32::INFINITY)
                });
            } else {
                // Interleaved: each leaf's data is one line holding its
                // first entry, read back from where the walk finds it.
                struct Lines<'a>(&'a mut Vec<usize>);
                impl Visit for Lines<'_> {
                    fn leaf(&mut self, _: usize) -> Option<f32> {
                        unreachable!("an interleaved tree hands over lines")
                    }
                    fn leaf_lines(&mut self, lines: &[Line]) -> Option<f32> {
                        let first = u64::from_ne_bytes(lines[0].0[..8].try_into().unwrap());
                        self.0.push(first as usize);
                        Some(f32::INFINITY)
                    }
                }
                let mut firsts = Vec::new();
                bvh.traverse(&ray, f32::INFINITY, &mut 0, Lines(&mut firsts));
                for first in firsts {
                    got.extend(leaves[&first].clone().map(|k| bvh.order[k]));
                }
            }
            got.sort_unstable();
            for w in want {
                assert!(got.binary_search(&w).is_ok(), "box {w} skipped by ray {k}");
            }
        }
    }

    #[test]
    fn visits_every_box_a_ray_overlaps() {
        for (n, seed) in [(1, 1), (3, 2), (17, 3), (1000, 4), (5000, 5)] {
            let boxes = random_boxes(n, seed);
            let bvh = Bvh4::build(&boxes, BuildParams::default());
            check(&boxes, &bvh, seed + 100);
            // 8-wide, with each walk the CPU has: the portable one (the
            // fallback a CPU without AVX2 runs), AVX2, AVX-512.
            let mut bvh = Bvh8::build(&boxes, BuildParams::default());
            for simd in ALL_SIMD {
                if bvh.set_simd(simd) {
                    check(&boxes, &bvh, seed + 100);
                }
            }
            // Interleaved with its leaves' data (the AVX walks' layout).
            if Bvh8::simd_available() && n > 1 {
                let data = first_lines(&bvh);
                assert!(bvh.interleave(|first| &data[&first]));
                for simd in [Simd::Avx2, Simd::Avx512] {
                    if bvh.set_simd(simd) {
                        check(&boxes, &bvh, seed + 100);
                    }
                }
            }
        }
    }

    const ALL_SIMD: [Simd; 3] = [Simd::Portable, Simd::Avx2, Simd::Avx512];

    /// Each leaf's data for [`Bvh::interleave`]: one line holding its
    /// first entry, read back by [`FirstLines`].
    fn first_lines(bvh: &Bvh8) -> std::collections::HashMap<usize, [Line; 1]> {
        bvh.leaves()
            .map(|r| {
                let mut line = Line([0; 64]);
                line.0[..8].copy_from_slice(&(r.start as u64).to_ne_bytes());
                (r.start, [line])
            })
            .collect()
    }

    /// Records the leaves a walk visits, in order, by first entry (from
    /// the index or from the interleaved line), and narrows `t_max` to
    /// `narrow(first)`.
    struct FirstLines<'a, F>(&'a mut Vec<usize>, F);
    impl<F: FnMut(usize) -> Option<f32>> Visit for FirstLines<'_, F> {
        fn leaf(&mut self, first: usize) -> Option<f32> {
            self.0.push(first);
            (self.1)(first)
        }
        fn leaf_lines(&mut self, lines: &[Line]) -> Option<f32> {
            let first = u64::from_ne_bytes(lines[0].0[..8].try_into().unwrap()) as usize;
            self.0.push(first);
            (self.1)(first)
        }
    }

    /// The AVX-512 walk is the AVX2 walk with other instructions: on
    /// nearest-hit queries whose leaves narrow `t_max` (so deferred
    /// children are dropped by distance) and on any-hit queries, in both
    /// layouts, it visits the same leaves in the same order.
    #[test]
    fn the_avx512_walk_visits_what_the_avx2_walk_does() {
        if !Bvh8::supports(Simd::Avx512) {
            eprintln!("skipped: this CPU has no AVX-512");
            return;
        }
        let boxes = random_boxes(3000, 21);
        let mut bvh = Bvh8::build(&boxes, BuildParams::default());
        let mut r = RngState::seeded(22);
        let rays: Vec<Ray> = (0..3000)
            .map(|k| {
                let o = Vec3::new(
                    r.range_f32(-15.0, 15.0),
                    r.range_f32(-15.0, 15.0),
                    r.range_f32(-15.0, 15.0),
                );
                let d = if k % 5 == 0 {
                    [Vec3::X, Vec3::NEG_Y, Vec3::new(-0.0, 0.0, -1.0)][k % 3]
                } else {
                    Vec3::new(
                        r.range_f32(-1.0, 1.0),
                        r.range_f32(-1.0, 1.0),
                        r.range_f32(-1.0, 1.0),
                    )
                };
                Ray::new(o, d)
            })
            .collect();
        let mut visited = 0;
        for interleaved in [false, true] {
            if interleaved {
                let data = first_lines(&bvh);
                assert!(bvh.interleave(|first| &data[&first]));
            }
            for ray in &rays {
                let runs = [Simd::Avx2, Simd::Avx512].map(|simd| {
                    assert!(bvh.set_simd(simd));
                    let (mut near, mut any) = (Vec::new(), Vec::new());
                    let (mut tests_near, mut tests_any) = (0, 0);
                    // A leaf "hits" at a distance its first entry picks,
                    // narrowing the query as a real hit would.
                    let t_of = |first: usize| Some(1.0 + (first % 7) as f32 * 3.0);
                    bvh.traverse(
                        ray,
                        f32::INFINITY,
                        &mut tests_near,
                        FirstLines(&mut near, t_of),
                    );
                    // Any-hit: keep going (a miss) until the fourth leaf.
                    let mut left = 4;
                    let stop = |_| {
                        left -= 1;
                        (left > 0).then_some(f32::INFINITY)
                    };
                    bvh.traverse_any(
                        ray,
                        f32::INFINITY,
                        &mut tests_any,
                        FirstLines(&mut any, stop),
                    );
                    (near, any, tests_near, tests_any)
                });
                visited += runs[0].0.len();
                assert_eq!(runs[0], runs[1], "the walks differ on {ray:?}");
            }
        }
        assert!(
            visited > 1000,
            "too few leaves visited to compare: {visited}"
        );
    }

    #[test]
    fn coincident_and_flat_boxes() {
        // All the same box, and boxes flat in z: no bin split exists.
        let same = vec![Bounds3::new(Vec3::ZERO, Vec3::ONE); 300];
        check(&same, &Bvh4::build(&same, BuildParams::default()), 7);
        check(&same, &Bvh8::build(&same, BuildParams::default()), 7);
        let flat: Vec<Bounds3> = (0..400)
            .map(|i| {
                let x = (i % 20) as f32;
                let y = (i / 20) as f32;
                Bounds3::new(Vec3::new(x, y, 0.0), Vec3::new(x + 1.0, y + 1.0, 0.0))
            })
            .collect();
        check(&flat, &Bvh4::build(&flat, BuildParams::default()), 8);
        check(&flat, &Bvh8::build(&flat, BuildParams::default()), 8);
    }

    #[test]
    fn depth_is_bounded_for_a_pathological_distribution() {
        // Boxes spaced geometrically (each 1.5x farther than the last): every
        // SAH split peels off one box, the deepest tree a builder can make.
        let boxes: Vec<Bounds3> = (0..3000)
            .map(|i| {
                let x = 1.5f32.powi(i % 200);
                Bounds3::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.001, 1.0, 1.0))
            })
            .collect();
        let bvh = Bvh4::build(&boxes, BuildParams::default());
        assert!(bvh.depth <= MAX_DEPTH, "{}", bvh.depth);
        check(&boxes, &bvh, 9);
        check(&boxes, &Bvh8::build(&boxes, BuildParams::default()), 9);
    }

    #[test]
    fn a_parallel_build_makes_the_serial_build_s_tree() {
        // Enough boxes for tasks; the tasks run on two threads, last first.
        let boxes = random_boxes(40_000, 11);
        let par = |n: u64, f: &(dyn Fn(u64) + Sync)| {
            std::thread::scope(|s| {
                for half in [1, 0] {
                    s.spawn(move || (0..n).rev().filter(|i| i % 2 == half).for_each(f));
                }
            })
        };
        let serial = Bvh8::build(&boxes, BuildParams::default());
        let parallel = Bvh8::build_on(&boxes, BuildParams::default(), &par);
        assert_eq!(serial.order, parallel.order);
        assert_eq!(serial.depth, parallel.depth);
        assert_eq!(serial.nodes.len(), parallel.nodes.len());
        for (a, b) in serial.nodes.iter().zip(&parallel.nodes) {
            assert_eq!(a.child, b.child);
            assert_eq!(a.perm, b.perm);
            assert_eq!(format!("{:?}", (a.lo, a.hi)), format!("{:?}", (b.lo, b.hi)));
        }
        check(&boxes, &parallel, 12);
    }

    #[test]
    fn huge_lines_hold_a_copy_of_their_lines() {
        // 3 MiB: mapped on Linux (2 MiB-aligned), a heap copy elsewhere;
        // and a small layout, always a heap copy.
        for n in [3 << 14, 100] {
            let src: Vec<Line> = (0..n).map(|i: usize| Line([(i % 251) as u8; 64])).collect();
            let h = HugeLines::new(&src);
            assert_eq!(h.as_slice().len(), n);
            assert!(h.as_slice().iter().zip(&src).all(|(a, b)| a.0 == b.0));
            assert!(h.bytes() >= n * 64);
            if cfg!(target_os = "linux") && n * 64 >= HugeLines::HUGE {
                assert_eq!(h.ptr.as_ptr() as usize % HugeLines::HUGE, 0);
            }
        }
        assert!(HugeLines::empty().as_slice().is_empty());
    }

    #[test]
    fn the_sah_of_eight_cubes_in_a_row() {
        // Unit cubes at x = 0, 2, .., 14, leaves of one: one 8-wide node
        // holds them all (SAH nodes = the root's 1), and each leaf counts
        // its half area 3 over the root's 15·1 + 1·1 + 1·15 = 31.
        let cubes: Vec<Bounds3> = (0..8)
            .map(|i| {
                let x = 2.0 * i as f32;
                Bounds3::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0))
            })
            .collect();
        let one = BuildParams {
            max_leaf: 1,
            ..BuildParams::default()
        };
        let (nodes, leaves) = Bvh8::build(&cubes, one).sah(4);
        assert_eq!(nodes, 1.0);
        assert!((leaves - 24.0 / 31.0).abs() < 1e-12, "{leaves}");
        // Four-wide: the root opens its halves into four pairs, each a node
        // of half area 3·1 + 1 + 3 = 7.
        let (nodes, leaves) = Bvh4::build(&cubes, one).sah(4);
        assert!((nodes - (1.0 + 4.0 * 7.0 / 31.0)).abs() < 1e-12, "{nodes}");
        assert!((leaves - 24.0 / 31.0).abs() < 1e-12, "{leaves}");
    }

    #[test]
    fn the_far_scale_is_one_plus_two_gamma_4() {
        assert_eq!(FAR_SCALE, 1.0 + 2.0 * rtk_geom::gamma::<f32>(4));
    }

    #[test]
    fn sse_and_scalar_tests_agree() {
        simd_and_scalar_agree::<4>();
        simd_and_scalar_agree::<8>();
    }

    /// The SIMD test (SSE at W = 4, AVX at W = 8 where the CPU has it)
    /// gives the portable test's mask and entry distances, bit for bit.
    fn simd_and_scalar_agree<const W: usize>() {
        let boxes = random_boxes(W, 11);
        let mut node = Node::<W>::EMPTY;
        for (s, b) in boxes.iter().enumerate() {
            for a in 0..3 {
                node.lo[a][s] = b.min.v()[a];
                node.hi[a][s] = b.max.v()[a];
            }
        }
        let avx = Bvh::<W>::simd_available();
        let mut r = RngState::seeded(12);
        for _ in 0..10_000 {
            let o = Vec3::new(r.range_f32(-15.0, 15.0), r.range_f32(-15.0, 15.0), 0.0);
            let d = Vec3::new(
                r.range_f32(-1.0, 1.0),
                [0.0, -0.0, 1.0][r.next_u32() as usize % 3],
                r.range_f32(-1.0, 1.0),
            );
            let pre = Precomp::new(&Ray::new(o, d));
            let mut tn = [0f32; W];
            let want = pre.test_scalar(&node, 0.0, f32::INFINITY, &mut tn);
            let got = if avx {
                pre.test::<W, true>(&node, 0.0, f32::INFINITY)
            } else {
                pre.test::<W, false>(&node, 0.0, f32::INFINITY)
            };
            assert_eq!(got.0, want);
            for (k, (g, w)) in got.1.iter().zip(&tn).enumerate() {
                if want >> k & 1 == 1 {
                    assert_eq!(g.to_bits(), w.to_bits());
                }
            }
        }
    }
}
