//! # rtk-shell
//!
//! Reads a TOML scene and builds the object DAG through the paper's open,
//! create, instance and close steps, loading only the plugin libraries the
//! objects reachable from the root need.
//!
//! - [`file`](mod@file): the scene file read and overridden (`--set`);
//! - [`desc`]: the description checked, with errors that name the origin,
//!   object and key;
//! - [`plugins`]: the plugin path and the loader, which refuses a library
//!   built against another kernel, built with `panic = "abort"`, or that is no
//!   rtk plugin at all, before any of its code runs;
//! - [`build`](mod@build): creation of the DAG and the [`World`] the renderer
//!   uses;
//! - [`safe`]: the `--safe` check that a scene names files only inside its
//!   folder or the working directory.
//!
//! The shell never links a plugin and holds no raw pointer: it knows object
//! classes only through the kernel's host-side handles
//! ([`rtk_handles`]).
#![deny(missing_docs)]
// A scene error carries its origin and notes (~200 bytes); it is built once,
// on the way out, never on a hot path, so it is not boxed.
#![allow(clippy::result_large_err)]

pub mod build;
pub mod desc;
pub mod error;
pub mod file;
pub(crate) mod plain;
pub mod plugins;
pub mod safe;
pub mod tree;

pub use build::{build, Parallel, Sequential, Timings, World};
pub use desc::Desc;
pub use error::{ErrorKind, SceneError};
pub use file::SceneFile;
pub use plugins::{PluginPath, Registry};

/// Read a scene file, apply `--set` overrides, check it, and build it.
pub fn load(
    path: &std::path::Path,
    sets: &[String],
    registry: &mut Registry,
    parallel: &dyn Parallel,
) -> Result<World, SceneError> {
    let mut file = SceneFile::read(path)?;
    file.apply_overrides(sets)?;
    let desc = Desc::from_file(&file)?;
    build(&file, desc, registry, parallel)
}
