//! The rendering threads: one rayon pool per run, sized by `--threads`,
//! and the same pool handed to the shell as its [`Parallel`], so that
//! building the scene and rendering it share the threads asked for.

use anyhow::{bail, Context, Result};
use rtk_shell::Parallel;

/// The host's rayon pool as the shell's [`Parallel`].
pub(crate) struct Pool<'a>(pub(crate) &'a rayon::ThreadPool);

impl Parallel for Pool<'_> {
    fn max_threads(&self) -> u32 {
        self.0.current_num_threads() as u32
    }
    fn run(&self, n: u64, f: &(dyn Fn(u64) + Sync)) {
        use rayon::prelude::*;
        self.0.install(|| (0..n).into_par_iter().for_each(f));
    }
}

/// Most rendering threads: starting the pool and the plugins' per-thread
/// state grow faster than linearly with the count (4096 threads take seconds
/// to start, 100000 practically never finish).
const MAX_THREADS: usize = 1024;

/// The rendering pool: `threads` threads (default: all cores, at most
/// [`MAX_THREADS`]).
pub(crate) fn pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, |n| n.get().min(MAX_THREADS))
    });
    if threads == 0 {
        bail!("--threads must be at least 1");
    }
    if threads > MAX_THREADS {
        bail!("--threads must be at most {MAX_THREADS}, got {threads}");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("rtk-render-{i}"))
        // Whitted recursion goes through plugin frames at every bounce
        // (max_depth up to 1024): a roomy stack, committed only as used.
        .stack_size(64 << 20)
        .build()
        .context("starting the thread pool")?;
    Ok((pool, threads))
}
