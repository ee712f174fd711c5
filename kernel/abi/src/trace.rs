//! The per-thread trace context passed to every hot-path call.
//!
//! It is plain data: counters, the random stream, the query counter and a
//! failure record. A plugin that fails on the hot path panics with a message;
//! the SDK catches the panic and writes the failure *into the context*, with
//! the plugin's class name; the host reads it after every camera sample,
//! stops the render and exits with that name. (The success path costs
//! nothing: no flag is checked on the way out of an entry.) Holding no
//! pointer, the context cannot be turned against the plugins that read it.

use abi_stable::StableAbi;

/// Per-thread counters. Plain `u64`s in the per-thread context: no atomics on
/// the hot path; the host sums them after the render for `--stats`.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Rays traced, by [`ray_kind`](super::ray_kind).
    pub rays: [u64; 8],
    /// Calls of `local_geom` at the root.
    pub local_geom_calls: u64,
    /// Per [`geom_mask`](super::geom_mask) bit, how many `local_geom` requests asked for it.
    pub local_geom_fields: [u64; 8],
    /// Bounding-volume (node, voxel, box) tests made by aggregates.
    pub node_tests: u64,
    /// Primitive intersection tests.
    pub prim_tests: u64,
    /// Material queries and shading calls.
    pub shader_calls: u64,
    /// Light samples taken.
    pub light_samples: u64,
    /// Non-finite radiance samples replaced by black.
    pub nonfinite_samples: u64,
}

/// A PCG32 stream, seeded per (seed, pixel, sample) by the host so that images
/// do not depend on the thread count. Also the one deterministic generator the
/// tests use ([`RngState::seeded`]).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct RngState {
    /// Generator state.
    pub state: u64,
    /// Stream increment (odd).
    pub inc: u64,
}

/// Longest plugin class name kept in a failure record, in bytes.
pub const FAILURE_CLASS_BYTES: usize = 64;
/// Longest failure message kept, in bytes (longer ones are cut at a character
/// boundary).
pub const FAILURE_MESSAGE_BYTES: usize = 384;

/// The first failure on this thread: which plugin, and what it said.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct FailureRecord {
    /// Non-zero once a failure was recorded.
    failed: u32,
    /// Bytes used in `class`.
    class_len: u32,
    /// Bytes used in `message`.
    message_len: u32,
    /// Plugin class name, UTF-8.
    class: [u8; FAILURE_CLASS_BYTES],
    /// What went wrong, UTF-8 (e.g. "panicked in intersect: index out of bounds").
    message: [u8; FAILURE_MESSAGE_BYTES],
}

/// Per-thread trace context, passed to every hot-path call.
#[repr(C)]
#[derive(StableAbi, Clone, Debug)]
pub struct TraceCtx {
    /// Index of the calling thread, below `max_threads`.
    thread_index: u32,
    /// The `max_threads` given to `prepare`: per-thread state (mailboxes) is
    /// sized with it and indexed by `thread_index`.
    max_threads: u32,
    /// Next query id on this thread ([`TraceCtx::next_query_id`]).
    next_query: u64,
    /// Random stream for this camera sample.
    pub rng: RngState,
    /// The wavelengths (nm) whose values a [`Color`](crate::Color)'s four
    /// lanes carry in spectral rendering; zero in RGB rendering, where the
    /// lanes are red, green, blue and 0. Laid out now so that spectral
    /// rendering (ROADMAP) needs no new ABI.
    pub wavelengths: [f32; 4],
    /// Counters.
    pub stats: Stats,
    /// The first failure recorded on this context.
    failure: FailureRecord,
}

impl TraceCtx {
    /// A context for thread `thread_index` of `max_threads`, with no failure,
    /// zero counters and query ids starting at `first_query`.
    pub fn new(thread_index: u32, max_threads: u32, first_query: u64) -> Self {
        TraceCtx {
            thread_index,
            max_threads: max_threads.max(thread_index + 1),
            next_query: first_query,
            rng: RngState::default(),
            wavelengths: [0.0; 4],
            stats: Stats::default(),
            failure: FailureRecord {
                failed: 0,
                class_len: 0,
                message_len: 0,
                class: [0; FAILURE_CLASS_BYTES],
                message: [0; FAILURE_MESSAGE_BYTES],
            },
        }
    }

    /// Index of the calling thread, below [`max_threads`](Self::max_threads).
    #[inline]
    pub fn thread_index(&self) -> u32 {
        self.thread_index
    }

    /// Upper bound of [`thread_index`](Self::thread_index).
    #[inline]
    pub fn max_threads(&self) -> u32 {
        self.max_threads
    }

    /// A fresh id for a query (mailboxes are keyed by it, not by the ray: a
    /// grid reached twice through two instances must not skip children the
    /// second time). Unique per thread for the whole render.
    #[inline]
    pub fn next_query_id(&mut self) -> u64 {
        let id = self.next_query;
        self.next_query += 1;
        id
    }

    /// The id the next [`next_query_id`](Self::next_query_id) call returns
    /// (the host carries it from one tile to the next).
    #[inline]
    pub fn query_counter(&self) -> u64 {
        self.next_query
    }

    /// Has a plugin failed on this context.
    #[inline]
    pub fn failed(&self) -> bool {
        self.failure.failed != 0
    }

    /// The failure recorded, as (plugin class, message).
    pub fn failure(&self) -> Option<(&str, &str)> {
        if !self.failed() {
            return None;
        }
        let f = &self.failure;
        fn text(b: &[u8]) -> &str {
            std::str::from_utf8(b).unwrap_or("(not UTF-8)")
        }
        Some((
            text(&f.class[..f.class_len as usize]),
            text(&f.message[..f.message_len as usize]),
        ))
    }

    /// Record a failure of `class`. The first one wins.
    #[doc(hidden)]
    pub fn record_failure(&mut self, class: &str, message: &str) {
        let f = &mut self.failure;
        if f.failed == 0 {
            f.failed = 1;
            f.message_len = copy_cut(&mut f.message, message) as u32;
            f.class_len = copy_cut(&mut f.class, class) as u32;
        }
    }
}

/// Copy as much of `s` as fits, cut at a character boundary; returns the length.
fn copy_cut(dst: &mut [u8], s: &str) -> usize {
    let mut n = s.len().min(dst.len());
    while !s.is_char_boundary(n) {
        n -= 1;
    }
    dst[..n].copy_from_slice(&s.as_bytes()[..n]);
    n
}

impl Stats {
    /// Add another thread's counters.
    pub fn merge(&mut self, o: &Stats) {
        for (a, b) in self.rays.iter_mut().zip(o.rays) {
            *a += b;
        }
        self.local_geom_calls += o.local_geom_calls;
        for (a, b) in self.local_geom_fields.iter_mut().zip(o.local_geom_fields) {
            *a += b;
        }
        self.node_tests += o.node_tests;
        self.prim_tests += o.prim_tests;
        self.shader_calls += o.shader_calls;
        self.light_samples += o.light_samples;
        self.nonfinite_samples += o.nonfinite_samples;
    }
}

impl RngState {
    /// A stream for (seed, pixel, sample): hashed so that neighbouring pixels
    /// and samples are uncorrelated, and independent of thread scheduling.
    pub fn for_sample(seed: u64, pixel: u64, sample: u64) -> Self {
        let s = splitmix(seed ^ splitmix(pixel ^ splitmix(sample)));
        let inc = splitmix(s ^ 0x9E37_79B9_7F4A_7C15) | 1;
        let mut r = RngState { state: 0, inc };
        r.next_u32();
        r.state = r.state.wrapping_add(s);
        r.next_u32();
        r
    }

    /// A stream from one seed (tests, benchmarks, random scenes).
    pub fn seeded(seed: u64) -> Self {
        Self::for_sample(seed, 0, 0)
    }

    /// Next 32 random bits (PCG32 XSH-RR).
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [0, 1), 53 bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    #[inline]
    pub fn range_f32(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_uniform_and_deterministic() {
        let mut a = RngState::for_sample(1, 2, 3);
        let mut b = RngState::for_sample(1, 2, 3);
        let mut sum = 0.0f64;
        for _ in 0..10_000 {
            let x = a.next_f32();
            assert_eq!(x, b.next_f32());
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        assert!((sum / 10_000.0 - 0.5).abs() < 0.01);
        assert_ne!(
            RngState::for_sample(1, 2, 3).next_u32(),
            RngState::for_sample(1, 2, 4).next_u32()
        );
        let mut c = RngState::seeded(9);
        assert!((0..1000)
            .map(|_| c.next_f64())
            .all(|x| (0.0..1.0).contains(&x)));
    }

    #[test]
    fn the_first_failure_wins() {
        let mut c = TraceCtx::new(0, 1, 0);
        assert!(c.failure().is_none());
        c.record_failure("inner", "bad input");
        c.record_failure("outer", "later");
        assert_eq!(c.failure(), Some(("inner", "bad input")));
    }

    #[test]
    fn long_messages_are_cut_at_a_character_boundary() {
        let mut c = TraceCtx::new(0, 1, 0);
        let long = "é".repeat(FAILURE_MESSAGE_BYTES);
        c.record_failure("x", &long);
        let (_, m) = c.failure().unwrap();
        assert!(m.len() <= FAILURE_MESSAGE_BYTES && m.chars().all(|ch| ch == 'é'));
    }

    #[test]
    fn query_ids_never_repeat() {
        let mut c = TraceCtx::new(0, 2, 40);
        assert_eq!((c.next_query_id(), c.next_query_id()), (40, 41));
        assert_eq!(c.query_counter(), 42);
    }
}
