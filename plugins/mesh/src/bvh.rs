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
}

const LEAF: usize = 4;

impl Bvh {
    pub fn build(boxes: &[Bounds3]) -> Bvh {
        let centroids: Vec<Vec3> = boxes
            .iter()
            .map(|b| (b.min.v() + b.max.v()) * 0.5)
            .collect();
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len() / LEAF + 1);
        build_rec(boxes, &centroids, &mut order, 0, &mut nodes);
        Bvh { nodes, order }
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
        let mut stack = [0u32; 64];
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
                        if sp < stack.len() {
                            stack[sp] = s;
                            sp += 1;
                        }
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

fn build_rec(
    boxes: &[Bounds3],
    c: &[Vec3],
    ids: &mut [u32],
    first: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let me = nodes.len();
    let bounds = ids
        .iter()
        .fold(Bounds3::EMPTY, |b, &i| b.union(boxes[i as usize]));
    nodes.push(Node {
        bounds,
        offset: first as u32,
        count: ids.len() as u32,
    });
    if ids.len() <= LEAF {
        return me as u32;
    }
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
    build_rec(boxes, c, l, first, nodes);
    let right = build_rec(boxes, c, r, first + mid, nodes);
    nodes[me].offset = right;
    nodes[me].count = 0;
    me as u32
}
