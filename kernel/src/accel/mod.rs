//! Building blocks for acceleration structures: what every aggregate plugin
//! shares, in the kernel so that aggregates, the tests and the benchmarks use
//! one implementation.
//!
//! - [`Primitives`]: an aggregate's children flattened into primitives
//!   (triangles as data, primitive sets, whole children), with leaf queries
//!   that keep the `list`'s exact answer and tie rule;
//! - [`Bvh4`]: the one BVH of the codebase (binned SAH, 4-wide SSE nodes);
//! - [`Mailbox`]: per-thread "tested already in this query" marks for
//!   structures that reference a primitive from several cells.

mod bvh;
mod mailbox;
mod prims;

pub use bvh::{BuildParams, Bvh4, MAX_DEPTH, PAD};
pub use mailbox::Mailbox;
pub use prims::{tri_bounds, Gathered, Nearest, PrimRef, Primitives, WHOLE};
