//! The mesh's own BVH over its triangles: binary, median split on the
//! longest centroid axis, up to 4 triangles a leaf. Simple and fast to build;
//! the acceleration-structure plugins (bvh, grid, kd-tree) are where the
//! tuned structures live.

use rtk_kernel::geom::RayBoxPrecomp;
use rtk_kernel::glam::Vec3;
use rtk_kernel::Bounds3;

pub struct Node {
    pub bounds: Bounds3,
    /// Leaf: first index into `order`; inner: index of the second child (the first follows).
    pub offset: u32,
    /// Leaf: triangle count; inner: 0.
    pub count: u32,
}

pub struct Bvh {
    pub nodes: Vec<Node>,
    /// Triangle ids in leaf order.
    pub order: Vec<u32>,
    /// Levels of the deepest leaf (the root is level 1).
    pub depth: usize,
}

const LEAF: usize = 4;

/// Deepest tree the traversal stack holds. Median splits halve the count at
/// every level, so a `u32` count of triangles never needs more than 33
/// levels; the builder turns a node at this depth into a leaf regardless, so
/// the bound holds by construction and traversal never drops a node.
pub const MAX_DEPTH: usize = 64;

impl Bvh {
    pub fn build(boxes: &[Bounds3]) -> Bvh {
        Self::build_with_limit(boxes, MAX_DEPTH)
    }

    /// Build with leaves forced at `max_depth` levels (at most [`MAX_DEPTH`]).
    pub fn build_with_limit(boxes: &[Bounds3], max_depth: usize) -> Bvh {
        let centroids: Vec<Vec3> = boxes
            .iter()
            .map(|b| (b.min.v() + b.max.v()) * 0.5)
            .collect();
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut b = Builder {
            boxes,
            c: &centroids,
            nodes: Vec::with_capacity(2 * boxes.len() / LEAF + 1),
            max_depth: max_depth.clamp(1, MAX_DEPTH),
            depth: 0,
        };
        b.node(&mut order, 0, 1);
        Bvh {
            nodes: b.nodes,
            order,
            depth: b.depth,
        }
    }

    /// Visit the leaves the ray may hit, nearest-first; `leaf(ids, t_max)`
    /// returns the narrowed `t_max` (or `None` to stop: any-hit queries).
    #[inline]
    pub fn traverse(
        &self,
        pre: &RayBoxPrecomp,
        t_min: f32,
        mut t_max: f32,
        node_tests: &mut u64,
        mut leaf: impl FnMut(&[u32], f32) -> Option<f32>,
    ) {
        // Each level pushes at most one node: the tree's depth bounds the
        // stack, and the builder bounds the depth by MAX_DEPTH.
        debug_assert!(self.depth <= MAX_DEPTH);
        let mut stack = [0u32; MAX_DEPTH];
        let mut sp = 0usize;
        let mut cur = 0u32;
        loop {
            let n = &self.nodes[cur as usize];
            *node_tests += 1;
            if pre.intersect(&n.bounds, t_min, t_max).is_some() {
                if n.count > 0 {
                    let ids = &self.order[n.offset as usize..(n.offset + n.count) as usize];
                    match leaf(ids, t_max) {
                        Some(t) => t_max = t,
                        None => return,
                    }
                } else {
                    // Visit the nearer child first.
                    let (a, b) = (cur + 1, n.offset);
                    let ta = pre
                        .intersect(&self.nodes[a as usize].bounds, t_min, t_max)
                        .map(|h| h.t0);
                    let tb = pre
                        .intersect(&self.nodes[b as usize].bounds, t_min, t_max)
                        .map(|h| h.t0);
                    *node_tests += 2;
                    let (first, second) = match (ta, tb) {
                        (Some(x), Some(y)) if y < x => (Some(b), Some(a)),
                        (Some(_), Some(_)) => (Some(a), Some(b)),
                        (Some(_), None) => (Some(a), None),
                        (None, Some(_)) => (Some(b), None),
                        (None, None) => (None, None),
                    };
                    if let Some(s) = second {
                        stack[sp] = s;
                        sp += 1;
                    }
                    if let Some(f) = first {
                        cur = f;
                        continue;
                    }
                }
            }
            if sp == 0 {
                return;
            }
            sp -= 1;
            cur = stack[sp];
        }
    }
}

struct Builder<'a> {
    boxes: &'a [Bounds3],
    c: &'a [Vec3],
    nodes: Vec<Node>,
    max_depth: usize,
    depth: usize,
}

impl Builder<'_> {
    /// Build the node over `ids` (starting at `first` in the order) at `level`.
    fn node(&mut self, ids: &mut [u32], first: usize, level: usize) -> u32 {
        self.depth = self.depth.max(level);
        let me = self.nodes.len();
        let bounds = ids
            .iter()
            .fold(Bounds3::EMPTY, |b, &i| b.union(self.boxes[i as usize]));
        self.nodes.push(Node {
            bounds,
            offset: first as u32,
            count: ids.len() as u32,
        });
        if ids.len() <= LEAF || level >= self.max_depth {
            return me as u32;
        }
        let c = self.c;
        let cb = ids
            .iter()
            .fold(Bounds3::EMPTY, |b, &i| b.include(c[i as usize]));
        let ext = cb.max.v() - cb.min.v();
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        if !(ext[axis] > 0.0) {
            return me as u32; // all centroids coincide: one leaf
        }
        let mid = ids.len() / 2;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            c[a as usize][axis]
                .total_cmp(&c[b as usize][axis])
                .then(a.cmp(&b))
        });
        let (l, r) = ids.split_at_mut(mid);
        self.node(l, first, level + 1);
        let right = self.node(r, first + mid, level + 1);
        self.nodes[me].offset = right;
        self.nodes[me].count = 0;
        me as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::{Ray, RngState};

    /// Boxes spaced geometrically along x (each twice as far as the last):
    /// the distribution that makes cost-driven builders deep.
    fn geometric(n: usize) -> Vec<Bounds3> {
        (0..n)
            .map(|i| {
                let x = 1.5f32.powi(i as i32 % 60) * (1.0 + i as f32 * 1e-3);
                Bounds3::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.01, 1.0, 1.0))
            })
            .collect()
    }

    /// Every leaf box a ray overlaps is visited, for trees cut at any depth.
    fn visits_every_overlapped_box(bvh: &Bvh, boxes: &[Bounds3]) {
        let mut rng = RngState::seeded(5);
        for _ in 0..500 {
            let o = Vec3::new(rng.range_f32(-5.0, 5e10), rng.range_f32(-1.0, 2.0), -3.0);
            let d = Vec3::new(rng.range_f32(-1.0, 1.0), rng.range_f32(-0.2, 0.2), 1.0).normalize();
            let ray = Ray::new(o, d);
            let pre = RayBoxPrecomp::new(&ray);
            let want: Vec<u32> = (0..boxes.len() as u32)
                .filter(|&i| {
                    pre.intersect(&boxes[i as usize], 0.0, f32::INFINITY)
                        .is_some()
                })
                .collect();
            let mut got = Vec::new();
            bvh.traverse(&pre, 0.0, f32::INFINITY, &mut 0, |ids, t| {
                got.extend_from_slice(ids);
                Some(t)
            });
            got.sort_unstable();
            assert!(
                want.iter().all(|i| got.binary_search(i).is_ok()),
                "a box was skipped"
            );
        }
    }

    #[test]
    fn depth_is_bounded_and_no_node_is_dropped() {
        let boxes = geometric(20_000);
        let bvh = Bvh::build(&boxes);
        // Median splits: about log2(n / LEAF) + 1 levels, far below MAX_DEPTH.
        assert!(bvh.depth <= 15, "depth {}", bvh.depth);
        visits_every_overlapped_box(&bvh, &boxes);
    }

    #[test]
    fn a_depth_limit_makes_bigger_leaves_not_lost_ones() {
        let boxes = geometric(5_000);
        for limit in [1, 2, 3, 7] {
            let bvh = Bvh::build_with_limit(&boxes, limit);
            assert_eq!(bvh.depth, limit);
            let mut ids = bvh.order.clone();
            ids.sort_unstable();
            assert_eq!(ids, (0..5_000).collect::<Vec<u32>>());
            visits_every_overlapped_box(&bvh, &boxes);
        }
    }
}
