//! Small images on every thread: a render with fewer tiles than threads
//! splits each pixel's samples into chunks that the threads take in
//! parallel. The chunks' sample values are buffered and added to the
//! pixels' running sums afterwards, in sample order, so the sums — and the
//! image — are the very f64s the tile-per-thread loop computes: for any
//! thread count, chunk size, crop and resume. (Summing each chunk apart
//! and adding the partial sums would round differently, and make the
//! image depend on where the chunks fall.)

use super::{add_sample, Accum, Job, Rect, Sink};
use rtk_kernel::abi::{Color, Stats, TraceCtx};
use std::sync::atomic::Ordering;
use std::sync::Mutex;

/// Samples a tile takes in one round at most (its pixels together): their
/// buffered values, 16 bytes each, stay within 4 MiB, and an interrupt
/// loses at most one round.
const ROUND: usize = 1 << 18;

/// Samples a pass holds at least when there are no more tiles than
/// threads (the pass size grows to it): a pass of 16 samples of a 1x1
/// image costs more to start than to sample, and leaves threads idle.
pub(super) const MIN_PASS: usize = 1 << 16;

/// Samples a thread takes at once: many batches of camera rays, so the
/// task costs nothing beside them, and few enough that the threads share a
/// round evenly.
const CHUNK: usize = 4096;

/// A sample's tile pixel and value, as [`Sink::sample`] got them.
type Value = (u32, Option<Color>);

impl Job<'_, '_> {
    /// Bring tile `t`'s pixels up to `target` samples, the samples taken by
    /// every thread of the pool, round after round; returns the samples
    /// taken. A round cut short (an interrupt, a failure) is dropped whole,
    /// so every pixel's samples stay the first ones of its sequence.
    pub(super) fn tile_chunked(
        &self,
        pool: &rayon::ThreadPool,
        film: &Mutex<&mut Accum>,
        t: u32,
        target: u32,
    ) -> u64 {
        let tr = self.tile_rect(t);
        let mut px = self.read_tile(film, &tr);
        let mut stats = Stats::default();
        let per_pixel = (ROUND / tr.len().max(1)).max(1) as u32;
        let mut taken = 0;
        loop {
            let work: Vec<(usize, u32, u32)> = (px.iter().enumerate())
                .filter(|(_, p)| p.count < target)
                .map(|(i, p)| (i, p.count, target.min(p.count.saturating_add(per_pixel))))
                .collect();
            if work.is_empty() {
                break;
            }
            let Some(values) = self.round(pool, &tr, &work, &mut stats) else {
                break;
            };
            taken += values.len() as u64;
            for (i, l) in values {
                add_sample(&mut px[i as usize], l, &mut stats);
            }
            if self.stopped() {
                break;
            }
        }
        self.write_tile(film, &tr, px, &stats);
        taken
    }

    /// The samples `work` asks for, in chunks on the pool's threads: their
    /// values in sample order per pixel, or `None` when a chunk was cut
    /// short.
    fn round(
        &self,
        pool: &rayon::ThreadPool,
        tr: &Rect,
        work: &[(usize, u32, u32)],
        stats: &mut Stats,
    ) -> Option<Vec<Value>> {
        use rayon::prelude::*;
        let chunks = split(work, CHUNK);
        let done: Vec<Option<(Vec<Value>, Stats)>> =
            pool.install(|| chunks.par_iter().map(|c| self.chunk(tr, c)).collect());
        let mut values = Vec::with_capacity(done.iter().flatten().map(|d| d.0.len()).sum());
        for d in done {
            let (v, s) = d?;
            stats.merge(&s);
            values.extend(v);
        }
        Some(values)
    }

    /// One chunk's samples on the calling pool thread, buffered; `None`
    /// when it stopped early.
    fn chunk(&self, tr: &Rect, work: &[(usize, u32, u32)]) -> Option<(Vec<Value>, Stats)> {
        let ti = rayon::current_thread_index().unwrap_or(0);
        let counter = &self.next_query[ti];
        let mut ctx = TraceCtx::new(ti as u32, self.threads, counter.load(Ordering::Relaxed));
        let n: u64 = work.iter().map(|w| (w.2 - w.1) as u64).sum();
        let mut buf = Buffered(Vec::with_capacity(n as usize));
        let taken = self.sample_tile(&mut ctx, tr, work, &mut buf);
        counter.store(ctx.query_counter(), Ordering::Relaxed);
        (taken == n && buf.0.len() as u64 == n).then_some((buf.0, ctx.stats))
    }
}

/// `work` (per pixel, a range of samples) cut into pieces of `size`
/// samples, in order.
fn split(work: &[(usize, u32, u32)], size: usize) -> Vec<Vec<(usize, u32, u32)>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    let mut room = size as u32;
    for &(i, mut start, end) in work {
        while start < end {
            let take = (end - start).min(room);
            cur.push((i, start, start + take));
            start += take;
            room -= take;
            if room == 0 {
                out.push(std::mem::take(&mut cur));
                room = size as u32;
            }
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// A sink that keeps each sample's value for the round to add in order.
struct Buffered(Vec<Value>);

impl Sink for Buffered {
    #[inline]
    fn sample(&mut self, i: usize, l: Option<Color>, _: &mut Stats) {
        self.0.push((i as u32, l));
    }
}

#[cfg(test)]
mod tests {
    use super::split;

    #[test]
    fn split_cuts_the_ranges_in_order_into_pieces_of_the_size() {
        let work = [(0, 3, 10), (1, 0, 2), (2, 5, 6)];
        let pieces = split(&work, 4);
        assert_eq!(
            pieces,
            vec![
                vec![(0, 3, 7)],
                vec![(0, 7, 10), (1, 0, 1)],
                vec![(1, 1, 2), (2, 5, 6)],
            ]
        );
        assert!(split(&[], 4).is_empty());
    }
}
