#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::accel::{CellAggregate, CellsAlongRay, Primitives};
use rtk_kernel::geom::RayBoxPrecomp;
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "eight")]
    max_leaf: u32,
    #[serde(default = "sixteen")]
    max_depth: u32,
}

fn eight() -> u32 {
    8
}
fn sixteen() -> u32 {
    16
}

/// Deepest octree ever built: the traversal stack is sized from it.
const DEPTH_LIMIT: usize = 24;
/// At most seven siblings wait on the stack per level.
const STACK: usize = 7 * DEPTH_LIMIT + 1;

/// A cell: inner (its eight children are `first..first + 8`) or a leaf
/// (`ids[first..first + count]`).
struct Cell {
    bounds: Bounds3,
    first: u32,
    count: u32,
    leaf: bool,
}

struct Tree {
    cells: Vec<Cell>,
    ids: Vec<u32>,
}

struct Octree {
    children: Vec<Child>,
    max_leaf: usize,
    max_depth: usize,
    built: Option<CellAggregate<Tree>>,
}

impl Plugin for Octree {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(1..=1024).contains(&p.max_leaf) {
            return Err(PluginError::key("max_leaf", "must be between 1 and 1024"));
        }
        if !(1..=DEPTH_LIMIT as u32).contains(&p.max_depth) {
            return Err(PluginError::key("max_depth", "must be between 1 and 24"));
        }
        Ok(Octree {
            children: Vec::new(),
            max_leaf: p.max_leaf as usize,
            max_depth: p.max_depth as usize,
            built: None,
        })
    }
}

/// The octant `k` (bit 0: upper x half, bit 1: y, bit 2: z) of a box.
fn octant(b: &Bounds3, k: usize) -> Bounds3 {
    let (lo, hi) = (b.min.v(), b.max.v());
    let mid = (lo + hi) * 0.5;
    let pick = |bit: usize, a: usize| -> (f32, f32) {
        if k & bit != 0 {
            (mid[a], hi[a])
        } else {
            (lo[a], mid[a])
        }
    };
    let (x, y, z) = (pick(1, 0), pick(2, 1), pick(4, 2));
    Bounds3::new(Vec3::new(x.0, y.0, z.0), Vec3::new(x.1, y.1, z.1))
}

/// Do the boxes overlap, `b` grown by a thousandth of `cell`'s size?
fn overlaps(cell: &Bounds3, b: &Bounds3) -> bool {
    let m = (cell.max.v() - cell.min.v()) * 1e-3;
    let (lo, hi) = (b.min.v() - m, b.max.v() + m);
    !b.is_empty() && lo.cmple(cell.max.v()).all() && hi.cmpge(cell.min.v()).all()
}

struct Builder<'a> {
    boxes: &'a [Bounds3],
    max_leaf: usize,
    max_depth: usize,
    tree: Tree,
}

impl Builder<'_> {
    /// Fill cell `at` (its box set) with `ids` at `depth`.
    fn cell(&mut self, at: usize, ids: Vec<u32>, depth: usize) {
        let bounds = self.tree.cells[at].bounds;
        if ids.len() > self.max_leaf && depth < self.max_depth {
            let parts: Vec<Vec<u32>> = (0..8)
                .map(|k| {
                    let ob = octant(&bounds, k);
                    ids.iter()
                        .copied()
                        .filter(|&i| overlaps(&ob, &self.boxes[i as usize]))
                        .collect()
                })
                .collect();
            // Split only if it separates the primitives: every octant holds
            // fewer than the cell, and the references grow at most twofold
            // (a crowd of primitives around one point, as at a mesh's pole,
            // would otherwise be copied into eight cells at every level).
            let total: usize = parts.iter().map(Vec::len).sum();
            if parts.iter().all(|p| p.len() < ids.len()) && total <= 2 * ids.len() {
                let first = self.tree.cells.len();
                for k in 0..8 {
                    self.tree.cells.push(Cell {
                        bounds: octant(&bounds, k),
                        first: 0,
                        count: 0,
                        leaf: true,
                    });
                }
                self.tree.cells[at] = Cell {
                    bounds,
                    first: first as u32,
                    count: 8,
                    leaf: false,
                };
                for (k, p) in parts.into_iter().enumerate() {
                    self.cell(first + k, p, depth + 1);
                }
                return;
            }
        }
        let c = &mut self.tree.cells[at];
        c.first = self.tree.ids.len() as u32;
        c.count = ids.len() as u32;
        self.tree.ids.extend(ids);
    }
}

impl CellsAlongRay for Tree {
    fn bounds(&self) -> Bounds3 {
        self.cells[0].bounds
    }

    /// Descend from the root, nearest octant first (a stack of the octants
    /// entered, farthest pushed first); an octant entered beyond the best
    /// hit is skipped.
    #[inline]
    fn walk(&self, ray: &Ray, node_tests: &mut u64, mut leaf: impl FnMut(&[u32]) -> Option<f32>) {
        let pre = RayBoxPrecomp::new(ray);
        let Some(root) = pre.intersect(&self.cells[0].bounds, ray.t_min, ray.t_max) else {
            return;
        };
        let mut best = ray.t_max;
        let mut stack = [(0u32, 0f32); STACK];
        stack[0] = (0, root.t0);
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let (n, t_entry) = stack[sp];
            if t_entry > best {
                continue;
            }
            *node_tests += 1;
            let c = &self.cells[n as usize];
            if c.leaf {
                let ids = &self.ids[c.first as usize..(c.first + c.count) as usize];
                if !ids.is_empty() {
                    match leaf(ids) {
                        Some(t) => best = t,
                        None => return,
                    }
                }
                continue;
            }
            let mut kids = [(0u32, 0f32); 8];
            let mut k = 0;
            for i in 0..8 {
                let child = c.first + i;
                if let Some(h) = pre.intersect(&self.cells[child as usize].bounds, ray.t_min, best)
                {
                    kids[k] = (child, h.t0);
                    k += 1;
                }
            }
            // Farthest first on the stack, so the nearest is popped next.
            let kids = &mut kids[..k];
            kids.sort_unstable_by(|a, b| b.1.total_cmp(&a.1));
            for &e in kids.iter() {
                stack[sp] = e;
                sp += 1;
            }
        }
    }
}

impl Object for Octree {
    /// Inside any child: the union of their interiors.
    fn in_interior(&self, ctx: &mut TraceCtx, p: rtk_kernel::glam::Vec3, time: f32) -> Interior {
        union_interior(&self.children, ctx, p, time)
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        let g = Primitives::gather(&self.children)?;
        let bounds = g.boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(*b));
        let mut b = Builder {
            boxes: &g.boxes,
            max_leaf: self.max_leaf,
            max_depth: self.max_depth,
            tree: Tree {
                cells: vec![Cell {
                    bounds,
                    first: 0,
                    count: 0,
                    leaf: true,
                }],
                ids: Vec::new(),
            },
        };
        b.cell(0, (0..g.boxes.len() as u32).collect(), 0);
        self.built = Some(CellAggregate::new(g.prims, b.tree, env.max_threads()));
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.built
            .as_ref()
            .map_or(Bounds3::EMPTY, CellAggregate::bounds)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        self.built
            .as_ref()
            .is_some_and(|b| b.intersect(ctx, ray, hit, level))
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        self.built
            .as_ref()
            .is_some_and(|b| b.occluded(ctx, ray, level))
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
        if let Some(b) = &self.built {
            b.local_geom(ctx, ray, hit, level, mask, out);
        }
    }
}

impl FlattensPrimitives for Octree {}

rtk_kernel::export_object!(
    Octree,
    class = "octree",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
