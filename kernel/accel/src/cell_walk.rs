//! The queries of a structure that lists primitives in cells (grid, octree,
//! kd-tree): walk the cells along the ray, test each cell's primitives not
//! tested yet in this query, keep the best hit. What differs between such
//! structures is only how they find the cells along a ray
//! ([`CellsAlongRay`]); [`CellAggregate`] is the rest.
//!
//! Why the walk is shaped as it is:
//! - **The visitor returns the best `t`, the walker decides when to stop.**
//!   A primitive spans cells, so a hit found in a cell may lie beyond it: the
//!   walk cannot stop at the first cell with a hit, only once the next cell
//!   starts beyond the best hit. A cell entered exactly at the best `t` is
//!   still visited: at equal `t` a later cell may hold a lower (child,
//!   primitive), which wins the tie (rule 11). How conservatively a walker
//!   rounds a cell's entry is its own (the kd-tree widens it by
//!   [`cull_bound`](crate::cull_bound)).
//! - **Mailboxes** ([`Mailbox`]): a primitive listed in several cells is
//!   tested once per query. That is exact because a primitive's test covers
//!   the ray's whole interval, not the cell's: its first answer is its
//!   answer in every cell that lists it.
//! - **The answer is the `list`'s**, whatever order the cells come in: the
//!   leaf queries of [`Primitives`] keep the list's tie rule, so the order
//!   only changes how soon the best `t` narrows.
//! - **The node tests are counted in a local** and added to the context's
//!   statistics afterwards: the visitor borrows the context.
//! - **An any-hit query stops at its first occluder**: the visitor returns
//!   `None` and the walk ends there.

use crate::{Mailbox, Nearest, Primitives};
use rtk_abi::{Bounds3, Hit, LocalGeom, Ray, TraceCtx};

/// How a structure finds the cells along a ray: the part of a grid, an
/// octree or a kd-tree that [`CellAggregate`] does not share.
pub trait CellsAlongRay {
    /// The box around every cell: the structure's bounds.
    fn bounds(&self) -> Bounds3;

    /// Visit the non-empty cells the ray crosses within
    /// `(ray.t_min, ray.t_max)`, nearest first, adding each cell or node
    /// visited to `node_tests`. `cell(ids)` tests the primitives listed in
    /// a cell and returns the best `t` so far, or `None` to stop; a cell
    /// that starts beyond the best `t` is not visited (one that starts
    /// exactly at it is: a tie may be won there).
    fn walk(&self, ray: &Ray, node_tests: &mut u64, cell: impl FnMut(&[u32]) -> Option<f32>);
}

/// An aggregate's primitives listed in cells, and the marks that keep a
/// primitive listed in several cells from being tested twice in one query:
/// what a cell structure's `Object` answers queries with.
pub struct CellAggregate<C> {
    prims: Primitives,
    cells: C,
    mailbox: Mailbox,
}

impl<C: CellsAlongRay> CellAggregate<C> {
    /// `cells` built over `prims` (their ids index `prims`), queried by at
    /// most `threads` threads at once (`Prepare::max_threads`).
    pub fn new(prims: Primitives, cells: C, threads: u32) -> Self {
        let mailbox = Mailbox::new(prims.len(), threads);
        CellAggregate {
            prims,
            cells,
            mailbox,
        }
    }

    /// The cell structure.
    pub fn cells(&self) -> &C {
        &self.cells
    }

    /// The structure's bounds.
    pub fn bounds(&self) -> Bounds3 {
        self.cells.bounds()
    }

    /// The nearest hit along `ray` (`Object::intersect`; `level`: this
    /// aggregate's level in `hit`).
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let mut q = Nearest::new(ray);
        let query = Mailbox::query(ctx);
        let mut nodes = 0;
        self.cells.walk(ray, &mut nodes, |ids| {
            self.mailbox.fresh(ctx, query, ids, |ctx, fresh| {
                let fresh = fresh.iter().map(|&i| i as usize);
                self.prims.intersect_ids(ctx, &mut q, fresh, hit, level);
                true
            });
            Some(q.ray.t_max)
        });
        ctx.stats.node_tests += nodes;
        q.found()
    }

    /// Whether anything blocks `ray` (`Object::occluded`).
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let query = Mailbox::query(ctx);
        let mut found = false;
        let mut nodes = 0;
        self.cells.walk(ray, &mut nodes, |ids| {
            self.mailbox.fresh(ctx, query, ids, |ctx, fresh| {
                let fresh = fresh.iter().map(|&i| i as usize);
                found = self.prims.occluded_ids(ctx, ray, fresh, level);
                !found
            });
            (!found).then_some(ray.t_max)
        });
        ctx.stats.node_tests += nodes;
        found
    }

    /// The surface at `hit` (`Object::local_geom`): the child hit answers.
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
        self.prims.local_geom(ctx, ray, hit, level, mask, out);
    }
}
