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

/// Each rendering thread's stack. Whitted recursion goes through plugin
/// frames at every bounce (max_depth up to 1024): a roomy stack, committed
/// only as used, but reserved in the address space whole.
const STACK_BYTES: u64 = 64 << 20;

/// Share of the address space left under a limit that the stacks may take:
/// the rest is for the scene, its aggregates and the film.
const STACK_SHARE: f64 = 0.5;

/// The rendering pool: `threads` threads (default: all cores, at most
/// [`MAX_THREADS`]), fewer when an address-space limit (`ulimit -v`) has
/// no room for their stacks, saying so on stderr.
pub(crate) fn pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let asked = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, |n| n.get().min(MAX_THREADS))
    });
    if asked == 0 {
        bail!("--threads must be at least 1");
    }
    if asked > MAX_THREADS {
        bail!("--threads must be at most {MAX_THREADS}, got {asked}");
    }
    let threads = match address_space_room() {
        Some((room, limit)) => {
            let fit = ((room as f64 * STACK_SHARE) as u64 / STACK_BYTES).max(1) as usize;
            if fit < asked {
                eprintln!(
                    "warning: {asked} threads asked for, using {fit}: the address-space limit \
                     (ulimit -v, {:.1} GiB) has room for {fit} threads' {} MiB stacks in half of \
                     what is left ({:.1} GiB), the other half kept for the scene",
                    limit as f64 / GIB,
                    STACK_BYTES >> 20,
                    room as f64 / GIB
                );
            }
            fit.min(asked)
        }
        None => asked,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("rtk-render-{i}"))
        .start_handler(|_| super::faults::register_thread())
        .stack_size(STACK_BYTES as usize)
        .build()
        .context("starting the thread pool")?;
    Ok((pool, threads))
}

const GIB: f64 = (1u64 << 30) as f64;

/// Under an address-space limit: the bytes still free below it (the limit
/// less what the process has mapped), and the limit. `None` without a
/// limit (or where it cannot be read).
fn address_space_room() -> Option<(u64, u64)> {
    #[cfg(target_os = "linux")]
    {
        let mut lim = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: `getrlimit` writes one `rlimit` through the pointer, which
        // points at a live, writable value of that type.
        if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut lim) } != 0
            || lim.rlim_cur == libc::RLIM_INFINITY
        {
            return None;
        }
        // `rlim_t` is u64 on 64-bit Linux, u32 on some 32-bit targets.
        #[allow(clippy::unnecessary_cast)]
        let limit = lim.rlim_cur as u64;
        // The first field of statm: pages mapped (the address space in use).
        let used = std::fs::read_to_string("/proc/self/statm")
            .ok()?
            .split_whitespace()
            .next()?
            .parse::<u64>()
            .ok()?
            * 4096;
        Some((limit.saturating_sub(used), limit))
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}
