//! Front-to-back traversal (pbrt's `KdTreeAggregate::Intersect`), made
//! conservative so that it returns exactly the `list`'s answer.
//!
//! - The ray is clipped to the root box with the kernel's conservative slab
//!   test (docs/numerics.md rule 10).
//! - A plane's crossing distance is rounded (up to γ₃ relative), so each
//!   child's interval is widened past it by twice that: the two intervals
//!   overlap at the plane and a cell the ray only grazes is still entered.
//! - A direction component that is ±0 never divides: the ray stays on its
//!   origin's side, and an origin exactly on the plane visits both children.
//! - A hit found in a leaf may lie beyond that leaf's cell (primitives span
//!   cells), so a pending cell is skipped only when its entry lies beyond
//!   the best hit by more than the kernel's tie margin (`cull_bound`): at
//!   equal `t` a later cell may still hold a lower (child, primitive) key,
//!   which wins the tie.

use crate::tree::{KdTree, Node, MAX_DEPTH};
use rtk_kernel::accel::cull_bound;
use rtk_kernel::geom::{gamma, RayBoxPrecomp};
use rtk_kernel::Ray;

/// A node to visit and the ray's interval inside its cell.
#[derive(Clone, Copy, Default)]
struct Entry {
    node: u32,
    t0: f32,
    t1: f32,
}

/// Per-ray data for the plane tests.
struct Planes {
    origin: [f32; 3],
    dir: [f32; 3],
    inv_dir: [f32; 3],
    /// Relative widening of a plane distance: 2γ₄, as the slab test's.
    slack: f32,
}

impl Planes {
    fn new(ray: &Ray) -> Self {
        let dir = ray.dir.to_array();
        Planes {
            origin: ray.origin.to_array(),
            dir,
            inv_dir: dir.map(|d| 1.0 / d),
            slack: 2.0 * gamma::<f32>(4),
        }
    }

    /// The children of an inner node to visit, nearest first, with their
    /// intervals; either may be `None`.
    #[inline]
    fn children(&self, e: Entry, axis: u8, split: f32, above: u32) -> [Option<Entry>; 2] {
        let a = axis as usize;
        let below = e.node + 1;
        let with = |node, t0, t1| Some(Entry { node, t0, t1 });
        let (o, d) = (self.origin[a], self.dir[a]);
        let tp = (split - o) * self.inv_dir[a];
        // Parallel to the plane (d = ±0), or a direction so small that 1/d
        // overflowed and the origin is on the plane (0·∞): the side of the
        // origin decides, both sides when it is on the plane.
        if d == 0.0 || tp.is_nan() {
            return if o < split {
                [with(below, e.t0, e.t1), None]
            } else if o > split {
                [with(above, e.t0, e.t1), None]
            } else {
                [with(below, e.t0, e.t1), with(above, e.t0, e.t1)]
            };
        }
        let widen = tp.abs() * self.slack;
        let (lo, hi) = if widen.is_finite() {
            (tp - widen, tp + widen)
        } else {
            (tp, tp)
        };
        // The ray is on the `first` side before the plane, `second` after.
        let (first, second) = if d > 0.0 {
            (below, above)
        } else {
            (above, below)
        };
        let near = (e.t0 <= hi).then_some(Entry {
            node: first,
            t0: e.t0,
            t1: if hi < e.t1 { hi } else { e.t1 },
        });
        let far = (lo <= e.t1).then_some(Entry {
            node: second,
            t0: if lo > e.t0 { lo } else { e.t0 },
            t1: e.t1,
        });
        [near, far]
    }
}

/// Pending far children: one per level of the current path at most, so the
/// depth bound sizes it and a push never drops a node (indexing checks it).
struct Stack {
    items: [Entry; MAX_DEPTH + 1],
    len: usize,
}

impl Stack {
    fn push(&mut self, e: Entry) {
        self.items[self.len] = e;
        self.len += 1;
    }

    fn pop(&mut self) -> Option<Entry> {
        self.len = self.len.checked_sub(1)?;
        Some(self.items[self.len])
    }
}

impl KdTree {
    /// Visit the leaves `ray` may hit over `(t_min, t_max)`, front to back.
    /// `leaf(ids)` tests a leaf's primitives and returns the narrowed
    /// `t_max`, or `None` to stop (any-hit queries). `node_tests` counts the
    /// nodes visited, leaves included.
    #[inline]
    pub fn traverse(
        &self,
        ray: &Ray,
        node_tests: &mut u64,
        mut leaf: impl FnMut(&[u32]) -> Option<f32>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let Some(h) = RayBoxPrecomp::new(ray).intersect(&self.bounds, ray.t_min, ray.t_max) else {
            return;
        };
        let planes = Planes::new(ray);
        let mut t_best = ray.t_max;
        let mut stack = Stack {
            items: [Entry::default(); MAX_DEPTH + 1],
            len: 0,
        };
        let mut next = Some(Entry {
            node: 0,
            t0: h.t0,
            t1: h.t1,
        });
        while let Some(e) = next.take().or_else(|| stack.pop()) {
            // Beyond the tie margin only: a tie at the best `t` may still be
            // won here (`cull_bound`).
            if e.t0 > cull_bound(t_best) {
                continue;
            }
            *node_tests += 1;
            match self.nodes[e.node as usize] {
                Node::Inner { axis, split, above } => {
                    let [near, far] = planes.children(e, axis, split, above);
                    if let Some(f) = far {
                        stack.push(f);
                    }
                    next = near;
                }
                Node::Leaf { first, count } => {
                    let ids = &self.ids[first as usize..(first + count) as usize];
                    match leaf(ids) {
                        Some(t) => t_best = t,
                        None => return,
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::tree::{KdTree, Settings};
    use rtk_kernel::geom::RayBoxPrecomp;
    use rtk_kernel::glam::Vec3;
    use rtk_kernel::{Bounds3, Ray, RngState};

    /// Every box the slab test says the ray crosses is in a visited leaf:
    /// the tree never loses a primitive a box-level test would keep, also
    /// for axis-parallel rays with ±0 components along the split planes.
    #[test]
    fn visits_every_box_the_ray_crosses() {
        let mut s = RngState::seeded(5);
        let mut u = |lo: f32, hi: f32| lo + (hi - lo) * s.next_f64() as f32;
        let boxes: Vec<Bounds3> = (0..2000)
            .map(|i| {
                // Integer-aligned boxes (planes on integers) and random ones.
                let c = Vec3::new(u(-8.0, 8.0), u(-8.0, 8.0), u(-8.0, 8.0));
                let c = if i % 2 == 0 { c.round() } else { c };
                let h = if i % 2 == 0 {
                    Vec3::splat(0.5)
                } else {
                    Vec3::splat(u(0.0, 0.6))
                };
                Bounds3::new(c - h, c + h)
            })
            .collect();
        let tree = KdTree::build(
            &boxes,
            Settings {
                max_leaf: 2,
                empty_bonus: 0.5,
            },
        );
        for k in 0..4000 {
            let mut o = Vec3::new(u(-10.0, 10.0), u(-10.0, 10.0), u(-10.0, 10.0));
            let mut d = Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            if k % 3 == 1 {
                o = (o * 2.0).round() * 0.5;
                d = [
                    Vec3::X,
                    Vec3::new(-0.0, -1.0, 0.0),
                    Vec3::new(0.0, -0.0, 1.0),
                ][k % 3];
            }
            let ray = Ray::new(o, d);
            let mut seen = vec![false; boxes.len()];
            let mut nodes = 0;
            tree.traverse(&ray, &mut nodes, |ids| {
                ids.iter().for_each(|&i| seen[i as usize] = true);
                Some(ray.t_max)
            });
            let pre = RayBoxPrecomp::new(&ray);
            for (i, b) in boxes.iter().enumerate() {
                let crosses = pre.intersect(b, ray.t_min, ray.t_max).is_some();
                assert!(!crosses || seen[i], "ray {k} ({o}, {d}) misses box {i}");
            }
        }
    }
}
