//! The kd-tree and its SAH build (pbrt-v3/v4, `KdTreeAggregate`).
//!
//! Split candidates are the primitive boxes' faces inside the cell; each is
//! priced with the surface-area heuristic and the cheapest wins if it beats
//! making a leaf. A primitive straddling the plane goes to both children, so
//! one primitive may sit in several leaves (the queries use a mailbox).
//!
//! Depth is bounded by construction (`8 + 1.3 log2 n`, at most
//! [`MAX_DEPTH`]): a node that deep becomes a leaf however many primitives it
//! holds, so the traversal stack, sized from that bound, never overflows and
//! never drops a node.

use rtk_kernel::Bounds3;

/// Deepest tree ever built: the traversal stack holds one entry per level.
pub const MAX_DEPTH: usize = 64;

/// Cost of visiting an inner node, in the SAH (the unit of the other costs).
const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one primitive test relative to a node visit: pbrt-v4's default
/// (`intersectcost`). A node visit is one plane distance and a branch, far
/// cheaper than a triangle test, so splits pay off readily.
const PRIM_COST: f32 = 5.0;

/// Build settings.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// A node of this many primitives or fewer becomes a leaf without trying
    /// a split.
    pub max_leaf: usize,
    /// Discount (0 to 1) of a split that cuts off empty space: empty leaves
    /// let rays skip space without any primitive test.
    pub empty_bonus: f32,
}

/// A node of the flat tree. The `below` child of an inner node is the next
/// node in the array (depth-first order), so only `above` is stored.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Node {
    /// A split plane `axis = split`.
    Inner { axis: u8, split: f32, above: u32 },
    /// A range `first..first + count` of [`KdTree::ids`].
    Leaf { first: u32, count: u32 },
}

/// A kd-tree over primitive boxes; leaves list primitive ids (indices into
/// the box slice it was built from).
pub struct KdTree {
    /// Depth-first; the root is node 0 (no nodes when there is nothing).
    pub nodes: Vec<Node>,
    /// The leaves' primitive ids, one range per leaf.
    pub ids: Vec<u32>,
    /// Box of every primitive that can be hit; the root cell.
    pub bounds: Bounds3,
    /// Depth limit of this build (root at depth 0).
    pub max_depth: usize,
    /// Deepest leaf built.
    pub depth: usize,
}

/// A primitive box's face along the axis being swept, in sweep order: by
/// position, then [`Kind`] (ends of boxes before starts at one position, so
/// the plane there puts a box touching it from one side on that side only;
/// a flat box's end after its start, so every box starts before it ends).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
struct Edge {
    t: f32,
    kind: Kind,
    prim: u32,
}

/// What an [`Edge`] is; the declaration order is the sweep order at one
/// position.
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
enum Kind {
    /// The upper face of a box with extent on this axis.
    End,
    /// A lower face.
    Start,
    /// The upper face of a box flat on this axis (both faces at one position).
    FlatEnd,
}

impl Edge {
    fn is_end(&self) -> bool {
        self.kind != Kind::Start
    }
}

/// The chosen split: the edge index in the sorted sweep and its cost.
struct Split {
    axis: usize,
    offset: usize,
    cost: f32,
}

impl KdTree {
    /// Build over `boxes`. A box containing no point (`Bounds3::is_empty`:
    /// an empty child, and a NaN coordinate too) is left out, as the
    /// kernel's BVH never enters empty boxes; the sweep's order then has no
    /// NaN to meet.
    pub fn build(boxes: &[Bounds3], s: Settings) -> KdTree {
        let prims: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| !boxes[i as usize].is_empty())
            .collect();
        let bounds = prims
            .iter()
            .fold(Bounds3::EMPTY, |b, &i| b.union(boxes[i as usize]));
        let max_depth = depth_limit(prims.len());
        let mut b = Builder {
            boxes,
            s,
            nodes: Vec::new(),
            ids: Vec::new(),
            edges: Vec::with_capacity(2 * prims.len()),
            depth: 0,
        };
        if !prims.is_empty() {
            b.node(prims, bounds, 0, max_depth, 0);
        }
        KdTree {
            nodes: b.nodes,
            ids: b.ids,
            bounds,
            max_depth,
            depth: b.depth,
        }
    }
}

/// pbrt's depth limit, `8 + 1.3 log2 n` rounded, capped at [`MAX_DEPTH`]:
/// deep enough for the SAH's useful splits, shallow enough that pathological
/// inputs (every split straddled) cannot blow up the duplication.
pub fn depth_limit(n: usize) -> usize {
    let d = (8.0 + 1.3 * (n.max(1) as f64).log2()).round() as usize;
    d.min(MAX_DEPTH)
}

struct Builder<'a> {
    boxes: &'a [Bounds3],
    s: Settings,
    nodes: Vec<Node>,
    ids: Vec<u32>,
    /// The sweep's edges, reused from node to node.
    edges: Vec<Edge>,
    depth: usize,
}

impl Builder<'_> {
    /// Build the subtree of `prims` in `cell` at `depth`; `bad` counts the
    /// splits on the path that did not pay off (pbrt's `badRefines`: a few
    /// are allowed, since a later split may recover, but not many).
    fn node(&mut self, prims: Vec<u32>, cell: Bounds3, depth: usize, max_depth: usize, bad: u32) {
        let n = prims.len();
        if n <= self.s.max_leaf || depth >= max_depth {
            return self.leaf(&prims, depth);
        }
        let leaf_cost = PRIM_COST * n as f32;
        let Some(split) = self.best_split(&prims, &cell) else {
            return self.leaf(&prims, depth);
        };
        let bad = bad + u32::from(split.cost > leaf_cost);
        if (split.cost > 4.0 * leaf_cost && n < 16) || bad == 3 {
            return self.leaf(&prims, depth);
        }
        // `self.edges` holds the sweep of the chosen axis (the last one tried).
        let (below, above) = classify(&self.edges, split.offset);
        let at = self.edges[split.offset].t;
        drop(prims);
        let (mut cell_below, mut cell_above) = (cell, cell);
        set_axis(&mut cell_below.max, split.axis, at);
        set_axis(&mut cell_above.min, split.axis, at);
        let me = self.nodes.len();
        self.nodes.push(Node::Leaf { first: 0, count: 0 });
        self.node(below, cell_below, depth + 1, max_depth, bad);
        let above_at = self.nodes.len() as u32;
        self.node(above, cell_above, depth + 1, max_depth, bad);
        self.nodes[me] = Node::Inner {
            axis: split.axis as u8,
            split: at,
            above: above_at,
        };
    }

    fn leaf(&mut self, prims: &[u32], depth: usize) {
        self.depth = self.depth.max(depth);
        self.nodes.push(Node::Leaf {
            first: self.ids.len() as u32,
            count: prims.len() as u32,
        });
        self.ids.extend_from_slice(prims);
    }

    /// The cheapest split on the cell's longest axis, or on the next axes if
    /// that one offers no plane inside the cell (pbrt's retries). Leaves the
    /// chosen axis's sorted edges in `self.edges`.
    fn best_split(&mut self, prims: &[u32], cell: &Bounds3) -> Option<Split> {
        let (lo, hi) = (cell.min.to_array(), cell.max.to_array());
        let ext: [f32; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        let first = if ext[0] >= ext[1] && ext[0] >= ext[2] {
            0
        } else if ext[1] >= ext[2] {
            1
        } else {
            2
        };
        (0..3).map(|k| (first + k) % 3).find_map(|axis| {
            self.sweep_edges(prims, axis);
            sweep(&self.edges, cell, axis, prims.len(), self.s.empty_bonus)
        })
    }

    /// Fill `self.edges` with the boxes' faces along `axis`, in sweep order.
    fn sweep_edges(&mut self, prims: &[u32], axis: usize) {
        self.edges.clear();
        for &p in prims {
            let b = &self.boxes[p as usize];
            let (lo, hi) = (b.min.to_array()[axis], b.max.to_array()[axis]);
            let end = if hi > lo { Kind::End } else { Kind::FlatEnd };
            self.edges.push(Edge {
                t: lo,
                kind: Kind::Start,
                prim: p,
            });
            self.edges.push(Edge {
                t: hi,
                kind: end,
                prim: p,
            });
        }
        // Boxes that contain a point have no NaN coordinate: a total order
        // (the `Equal` fallback is never taken).
        self.edges
            .sort_unstable_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    }
}

/// Price every edge strictly inside the cell as a split plane along `axis`
/// (one sweep: counts below and above update edge by edge); the cheapest, or
/// `None` when no edge lies inside. A NaN cost (a cell of zero area) never
/// wins: `<` is false for it.
fn sweep(edges: &[Edge], cell: &Bounds3, axis: usize, n: usize, empty_bonus: f32) -> Option<Split> {
    let (lo, hi) = (cell.min.to_array(), cell.max.to_array());
    let d: [f32; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
    let (o0, o1) = ((axis + 1) % 3, (axis + 2) % 3);
    let inv_area = 1.0 / (2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0]));
    let (cap, rim) = (d[o0] * d[o1], d[o0] + d[o1]);
    let (mut below, mut above) = (0usize, n);
    let mut best: Option<Split> = None;
    let mut best_cost = f32::INFINITY;
    for (i, e) in edges.iter().enumerate() {
        above -= usize::from(e.is_end());
        if e.t > lo[axis] && e.t < hi[axis] {
            let p_below = 2.0 * (cap + (e.t - lo[axis]) * rim) * inv_area;
            let p_above = 2.0 * (cap + (hi[axis] - e.t) * rim) * inv_area;
            let bonus = if below == 0 || above == 0 {
                empty_bonus
            } else {
                0.0
            };
            let cost = TRAVERSAL_COST
                + PRIM_COST * (1.0 - bonus) * (p_below * below as f32 + p_above * above as f32);
            if cost < best_cost {
                best_cost = cost;
                best = Some(Split {
                    axis,
                    offset: i,
                    cost,
                });
            }
        }
        below += usize::from(!e.is_end());
    }
    best
}

/// Split the primitives at sweep index `offset`: below are those starting
/// before it, above those ending after it. Every box starts before it ends in
/// the sweep, so it lands in at least one child; a box straddling the plane
/// lands in both. A box in one child only lies on that side of the plane or
/// touches it, and the traversal overlaps the children's intervals at the
/// plane, so a ray meeting it there finds it from its side.
fn classify(edges: &[Edge], offset: usize) -> (Vec<u32>, Vec<u32>) {
    let below = edges[..offset]
        .iter()
        .filter(|e| !e.is_end())
        .map(|e| e.prim)
        .collect();
    let above = edges[offset + 1..]
        .iter()
        .filter(|e| e.is_end())
        .map(|e| e.prim)
        .collect();
    (below, above)
}

fn set_axis(p: &mut rtk_kernel::Float3, axis: usize, v: f32) {
    match axis {
        0 => p.x = v,
        1 => p.y = v,
        _ => p.z = v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::glam::Vec3;

    const SETTINGS: Settings = Settings {
        max_leaf: 1,
        empty_bonus: 0.5,
    };

    /// Walk the tree: the depth of every leaf, each inner node's `below`
    /// child right after it, and how often each primitive is referenced.
    fn check(t: &KdTree, n: usize) -> Vec<u32> {
        let mut refs = vec![0u32; n];
        let mut todo = vec![(0usize, 0usize)];
        while let Some((i, depth)) = todo.pop() {
            match t.nodes[i] {
                Node::Inner { above, .. } => {
                    assert!(above as usize > i + 1, "above child after below subtree");
                    todo.push((i + 1, depth + 1));
                    todo.push((above as usize, depth + 1));
                }
                Node::Leaf { first, count } => {
                    assert!(
                        depth <= t.max_depth,
                        "leaf at depth {depth} > {}",
                        t.max_depth
                    );
                    for &p in &t.ids[first as usize..(first + count) as usize] {
                        refs[p as usize] += 1;
                    }
                }
            }
        }
        assert!(t.depth <= t.max_depth && t.max_depth <= MAX_DEPTH);
        refs
    }

    fn cube(c: Vec3, h: f32) -> Bounds3 {
        Bounds3::new(c - Vec3::splat(h), c + Vec3::splat(h))
    }

    /// Pathological inputs: the depth bound holds and every primitive stays
    /// in at least one leaf, with the duplication kept finite.
    #[test]
    fn pathological_inputs_keep_every_primitive() {
        let n = 5000;
        let cases: Vec<(&str, Vec<Bounds3>)> = vec![
            ("identical", vec![cube(Vec3::ONE, 0.5); n]),
            // Nested boxes, radii in geometric progression: every plane
            // straddles all the larger boxes.
            (
                "nested",
                (0..n)
                    .map(|i| cube(Vec3::ZERO, 1.002f32.powi(i as i32)))
                    .collect(),
            ),
            // Positions in geometric progression along x.
            (
                "geometric",
                (0..n)
                    .map(|i| cube(Vec3::new(1.01f32.powi(i as i32), 0.0, 0.0), 0.5))
                    .collect(),
            ),
            // All flat, in one plane, sharing edges on integers.
            (
                "coplanar",
                (0..n)
                    .map(|i| {
                        let c = Vec3::new((i % 70) as f32, 0.0, (i / 70) as f32);
                        Bounds3::new(c, c + Vec3::new(1.0, 0.0, 1.0))
                    })
                    .collect(),
            ),
        ];
        for (name, boxes) in &cases {
            let t = KdTree::build(boxes, SETTINGS);
            assert_eq!(t.max_depth, depth_limit(n));
            let refs = check(&t, n);
            let lost = refs.iter().filter(|&&r| r == 0).count();
            assert_eq!(lost, 0, "{name}: {lost} primitives in no leaf");
            assert!(t.ids.len() < 64 * n, "{name}: {} references", t.ids.len());
            if *name == "coplanar" {
                // Boxes sharing faces on the planes go to their own side only.
                assert_eq!(t.ids.len(), n, "{name}: touching boxes duplicated");
            }
        }
    }

    /// The depth limit grows with `log2 n` and never passes [`MAX_DEPTH`].
    #[test]
    fn depth_limit_is_bounded() {
        assert_eq!(depth_limit(0), 8);
        assert_eq!(depth_limit(1), 8);
        assert_eq!(depth_limit(1024), 21);
        assert_eq!(depth_limit(usize::MAX), MAX_DEPTH);
    }

    /// Empty boxes are left out; nothing at all builds no node.
    #[test]
    fn empty_boxes_are_left_out() {
        let t = KdTree::build(&[Bounds3::EMPTY; 3], SETTINGS);
        assert!(t.nodes.is_empty() && t.bounds.is_empty());
        let boxes = [Bounds3::EMPTY, cube(Vec3::ZERO, 1.0), Bounds3::EMPTY];
        let t = KdTree::build(&boxes, SETTINGS);
        assert_eq!(t.ids, vec![1]);
        assert_eq!(t.bounds, boxes[1]);
    }

    /// Scattered boxes are split: a real tree, not one big leaf.
    #[test]
    fn scattered_boxes_split() {
        let boxes: Vec<Bounds3> = (0..1000)
            .map(|i| {
                cube(
                    Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32) * 3.0,
                    0.4,
                )
            })
            .collect();
        let t = KdTree::build(&boxes, SETTINGS);
        let refs = check(&t, boxes.len());
        assert!(
            refs.iter().all(|&r| r == 1),
            "disjoint boxes are never duplicated"
        );
        assert!(t.nodes.len() > 1000, "{} nodes", t.nodes.len());
    }
}
