//! `rtk render --profile`: where a render's time goes — traversal,
//! surface records, light sampling, the integrator and shaders, the render
//! loop — and an estimate of what the plugin boundary costs.
//!
//! How it is measured: the host's scene services ([`Tracer`](super::Tracer))
//! read a cycle counter (x86-64 `rdtsc`; elsewhere the monotonic clock)
//! before and after each call of the kind timed, and add the difference to
//! the calling thread's slot: traversal is `intersect` and `occluded` (the
//! root aggregate's walk and every primitive test under it, single rays and
//! batches), surface is `local_geom`, lights is `sample_light`, and
//! integrator is each camera sample's `li` (or a batch's `li_batch`) as a
//! whole. What `li` spends outside the three services is the integrator's
//! and the shaders' own work (the shaders are called by the integrator
//! plugin directly, not through the host, so they cannot be timed apart);
//! what the threads spend outside `li` is the render loop's (camera rays,
//! sample streams, the film). No service nests inside another of these
//! three, so their times add up; a shader that traces recursively
//! (`whitted`'s mirrors) is counted through the services it calls.
//!
//! The boundary cannot be timed per crossing (a crossing is a few
//! nanoseconds, the counter read costs as much), so it is estimated: the
//! crossings the host sees (each service call is two: integrator to host,
//! host to root aggregate; each camera sample one; each shader call one)
//! times the cost of one empty crossing, measured before the render by
//! calling a service through the scene record a million times. That is a
//! lower bound: it omits the inlining a crossing prevents.
//!
//! What the measuring costs: two counter reads and a relaxed add per timed
//! call, on a cache line no other thread writes (BENCHMARKS.md has the
//! figure). Without `--profile` the services pay one predictable branch.

use rtk_handles::SceneRecord;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::time::Instant;

/// What is timed.
#[derive(Clone, Copy)]
pub(crate) enum Part {
    /// `intersect` and `occluded`, single and batched.
    Traversal = 0,
    /// `local_geom`, single and batched.
    Surface = 1,
    /// `sample_light`.
    Lights = 2,
    /// A camera sample's `li` (or a batch's), everything in it included.
    Integrator = 3,
}

/// Parts timed.
const PARTS: usize = 4;

/// One thread's ticks and service calls, alone on its cache line.
#[repr(align(64))]
#[derive(Default)]
struct Slot {
    ticks: [AtomicU64; PARTS],
    calls: [AtomicU64; PARTS],
}

/// Per-thread accumulators of the timed parts.
pub(crate) struct Profile {
    slots: Vec<Slot>,
    /// Ticks and seconds at the start, to convert ticks to seconds.
    start: (u64, Instant),
    /// Seconds of one empty crossing through the scene record.
    crossing_s: f64,
}

/// The cycle counter, or nanoseconds of the monotonic clock.
#[inline(always)]
pub(crate) fn ticks() -> u64 {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: `rdtsc` exists on every x86-64 CPU and only reads the time
    // stamp counter: no memory is touched.
    unsafe {
        std::arch::x86_64::_rdtsc()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        use std::sync::OnceLock;
        static EPOCH: OnceLock<Instant> = OnceLock::new();
        EPOCH.get_or_init(Instant::now).elapsed().as_nanos() as u64
    }
}

/// Empty crossings timed to estimate one.
const CROSSINGS: u32 = 1 << 20;

impl Profile {
    /// Accumulators for `threads` threads; times one empty crossing of
    /// `scene` (a service the plugins call, through its record).
    pub(crate) fn new(threads: usize, scene: &SceneRecord) -> Profile {
        let s = scene.scene();
        let t = Instant::now();
        let mut n = 0u32;
        for _ in 0..CROSSINGS {
            n = n.wrapping_add(std::hint::black_box(s).light_count());
        }
        std::hint::black_box(n);
        let crossing_s = t.elapsed().as_secs_f64() / CROSSINGS as f64;
        Profile {
            slots: (0..threads.max(1)).map(|_| Slot::default()).collect(),
            start: (ticks(), Instant::now()),
            crossing_s,
        }
    }

    /// Add `since`'s ticks to now to `part` on `thread`.
    #[inline(always)]
    pub(crate) fn add(&self, thread: u32, part: Part, since: u64) {
        let dt = ticks().wrapping_sub(since);
        if let Some(s) = self.slots.get(thread as usize) {
            s.ticks[part as usize].fetch_add(dt, Relaxed);
            s.calls[part as usize].fetch_add(1, Relaxed);
        }
    }

    fn sum(&self, part: Part) -> (u64, u64) {
        self.slots.iter().fold((0, 0), |(t, c), s| {
            (
                t + s.ticks[part as usize].load(Relaxed),
                c + s.calls[part as usize].load(Relaxed),
            )
        })
    }

    /// The `--profile` record: each part's seconds (summed over threads)
    /// and share of the threads' rendering time, `render_s` wall-clock
    /// seconds on `threads` threads with `shader_calls` shader calls.
    pub(crate) fn json(
        &self,
        render_s: f64,
        threads: usize,
        shader_calls: u64,
    ) -> serde_json::Value {
        let secs_per_tick = {
            let dt = ticks().wrapping_sub(self.start.0).max(1);
            self.start.1.elapsed().as_secs_f64() / dt as f64
        };
        let secs = |p| self.sum(p).0 as f64 * secs_per_tick;
        let (trav, surf, lights, li) = (
            secs(Part::Traversal),
            secs(Part::Surface),
            secs(Part::Lights),
            secs(Part::Integrator),
        );
        let all = (render_s * threads as f64).max(1e-12);
        let services: u64 = [Part::Traversal, Part::Surface, Part::Lights]
            .iter()
            .map(|&p| self.sum(p).1)
            .sum();
        let crossings = 2 * services + self.sum(Part::Integrator).1 + shader_calls;
        let boundary = crossings as f64 * self.crossing_s;
        let own = (li - trav - surf - lights).max(0.0);
        let share = |s: f64| s / all;
        serde_json::json!({
            "thread_seconds": all,
            "seconds": {
                "traversal": trav, "surface": surf, "lights": lights,
                "integrator_and_shaders": own, "render_loop": (all - li).max(0.0),
            },
            "shares": {
                "traversal": share(trav), "surface": share(surf), "lights": share(lights),
                "integrator_and_shaders": share(own), "render_loop": share((all - li).max(0.0)),
            },
            "boundary": {
                "crossings": crossings,
                "seconds_per_crossing": self.crossing_s,
                "share_estimate": share(boundary),
            },
        })
    }
}
