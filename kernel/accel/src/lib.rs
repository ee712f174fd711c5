//! # rtk-accel
//!
//! Building blocks for acceleration structures: what every aggregate plugin
//! shares, in the kernel so that aggregates, the tests and the benchmarks use
//! one implementation.
//!
//! - [`Primitives`]: an aggregate's children flattened into primitives
//!   (triangles as data, primitive sets, whole children), with leaf queries
//!   that keep the `list`'s exact answer and tie rule;
//! - [`Bvh`]: the one BVH of the codebase (binned SAH; 8-wide AVX-512 or AVX2 nodes
//!   chosen at run time, 4-wide SSE nodes, a portable test for both);
//! - [`Mailbox`]: per-thread "tested already in this query" marks for
//!   structures that reference a primitive from several cells;
//! - [`CellAggregate`]: the queries such a structure (grid, octree,
//!   kd-tree) answers by walking its cells along the ray, given how it finds
//!   them ([`CellsAlongRay`]);
//! - [`TriangleSolid`]: the interior of a closed triangle mesh (the paper's
//!   "in interior" for objects made of triangles).

#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![deny(clippy::missing_safety_doc)]

mod bvh;
mod cell_walk;
mod mailbox;
mod prims;
mod solid;

pub use bvh::{BuildParams, Bvh, Bvh4, Bvh8, Line, Parallel, Simd, Slot, Visit, MAX_DEPTH, PAD};
pub use cell_walk::{CellAggregate, CellsAlongRay};
pub use mailbox::Mailbox;
pub use prims::{tri_bounds, AnyHit, Gathered, Nearest, PrimRef, Primitives, WHOLE};
pub use solid::TriangleSolid;

/// The distance beyond which a front-to-back traversal may skip a box or
/// cell, given the best hit's `t`: `t` widened by 2⁻¹⁴ relative.
///
/// Why: rule 11 gives a tie at equal `t` to the lowest (child, primitive),
/// so a box holding a coincident copy of the best hit must still be entered.
/// Its computed entry can exceed the copy's computed `t`: the box's entry is
/// rounded, and a triangle's `t` is a weighted sum that cancels when the
/// hit is close to the origin next to the triangle's size, or grazing
/// (`rtk stress` A3 measured up to 3.6e-6 relative, about 30 ulps). The
/// margin is 17 times that; primitive tests still use the exact `t`, so it
/// only makes a few more boxes near the hit be entered.
#[inline]
pub fn cull_bound(t: f32) -> f32 {
    t + t.abs() * (1.0 / 16384.0)
}
