//! Mailboxes: a structure that references one primitive from several cells
//! (grid, octree, kd-tree) tests it once per query.
//!
//! The mark is the query id ([`TraceCtx::next_query_id`]), not the ray: a
//! grid reached twice in one trace through two instances of one DAG node
//! must test its primitives again the second time. Each thread has its own
//! row, so no two threads touch the same mark; the marks are relaxed atomics
//! (plain loads and stores on x86) because the structure is shared,
//! immutable, between threads.

use rtk_abi::TraceCtx;
use std::sync::atomic::{AtomicU64, Ordering};

/// Per-thread marks of the last query that tested each primitive.
pub struct Mailbox {
    marks: Vec<AtomicU64>,
    prims: usize,
}

impl Mailbox {
    /// Marks for `prims` primitives and `threads` threads (`Prepare::max_threads`).
    pub fn new(prims: usize, threads: u32) -> Self {
        let n = prims * threads.max(1) as usize;
        Mailbox {
            marks: (0..n).map(|_| AtomicU64::new(0)).collect(),
            prims,
        }
    }

    /// A new query: its id, to pass to [`Mailbox::first_visit`].
    #[inline]
    pub fn query(ctx: &mut TraceCtx) -> u64 {
        // +1: the marks start at 0, which no query has.
        ctx.next_query_id() + 1
    }

    /// Is this the first time query `q` on the calling thread meets `prim`?
    #[inline]
    pub fn first_visit(&self, ctx: &TraceCtx, q: u64, prim: usize) -> bool {
        let m = &self.marks[ctx.thread_index() as usize * self.prims + prim];
        if m.load(Ordering::Relaxed) == q {
            return false;
        }
        m.store(q, Ordering::Relaxed);
        true
    }

    /// Call `f` with the primitives of `ids` that query `q` has not met yet
    /// on this thread (marking them), in batches on the stack: no
    /// allocation. Stops early, returning false, when `f` does.
    #[inline]
    pub fn fresh(
        &self,
        ctx: &mut TraceCtx,
        q: u64,
        ids: &[u32],
        mut f: impl FnMut(&mut TraceCtx, &[u32]) -> bool,
    ) -> bool {
        let mut batch = [0u32; 64];
        for chunk in ids.chunks(batch.len()) {
            let mut n = 0;
            for &i in chunk {
                if self.first_visit(ctx, q, i as usize) {
                    batch[n] = i;
                    n += 1;
                }
            }
            if n > 0 && !f(ctx, &batch[..n]) {
                return false;
            }
        }
        true
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.marks.capacity() * 8
    }
}
