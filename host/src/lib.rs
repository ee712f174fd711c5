//! rtk as a library: the `rtk` binary's commands ([`cli`]) and, for other
//! hosts of the kernel and shell (the Python module), [`embed`]: load a
//! scene from a file, text or arrays, render it into memory, cast rays.
//!
//! Each command lives in its own module (`render/`, `trace/`, `stress/`,
//! `converge/`, `conform/`, `diff/`, `plugins.rs`, `merge.rs`, `new.rs`,
//! `bench_aggregate.rs`); what several commands use lives in `shared/`.
//! The binary (`src/main.rs`) only calls [`cli::main`], so the Python module
//! and `rtk` share every code path [`embed`] reaches.

mod bench_aggregate;
pub mod cli;
mod conform;
mod converge;
mod diff;
pub mod embed;
pub mod fuzzing;
mod import;
mod merge;
mod new;
mod plugins;
mod render;
mod shared;
mod stress;
mod trace;
