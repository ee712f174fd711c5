//! What `prepare` calls on the host: its thread pool and the file log.

use rtk_handles::PrepareServices;
use std::sync::Mutex;

/// The host's thread pool, as the shell's caller provides it.
pub trait Parallel: Sync {
    /// Number of threads queries may come from.
    fn max_threads(&self) -> u32;
    /// Run `f(i)` for every `i < n`, returning when all are done.
    fn run(&self, n: u64, f: &(dyn Fn(u64) + Sync));
}

/// Runs everything on the calling thread (tools and tests).
pub struct Sequential;

impl Parallel for Sequential {
    fn max_threads(&self) -> u32 {
        1
    }
    fn run(&self, n: u64, f: &(dyn Fn(u64) + Sync)) {
        (0..n).for_each(f)
    }
}

/// The pool plus the files plugins said they read.
pub(crate) struct PrepareHost<'a> {
    pub par: &'a dyn Parallel,
    pub files: Mutex<Vec<String>>,
}

impl PrepareServices for PrepareHost<'_> {
    fn max_threads(&self) -> u32 {
        self.par.max_threads()
    }
    fn parallel_for(&self, n: u64, f: &(dyn Fn(u64) + Sync)) {
        self.par.run(n, f)
    }
    fn note_file(&self, path: &str) {
        if let Ok(mut f) = self.files.lock() {
            f.push(path.to_string());
        }
    }
}
