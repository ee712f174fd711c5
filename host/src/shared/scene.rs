//! A scene as `rtk render` and `rtk converge` load it: the file with its
//! `--set` overrides (checked under `--safe`), then the plugins it names and
//! the world built from it, so that both commands render the same scene.

use super::threads::Pool;
use anyhow::Result;
use rtk_shell::{PluginPath, Registry};
use std::path::{Path, PathBuf};

/// Read a scene file and apply `--set` overrides; with `safe`, check it
/// (`--safe`). Returns the file and its description.
pub(crate) fn read_scene(
    scene: &Path,
    sets: &[String],
    safe: bool,
) -> Result<(rtk_shell::SceneFile, rtk_shell::Desc)> {
    let mut file = rtk_shell::SceneFile::read(scene)?;
    file.apply_overrides(sets)?;
    let desc = rtk_shell::Desc::from_file(&file)?;
    if safe {
        rtk_shell::safe::check(&file, &desc)?;
    }
    Ok((file, desc))
}

/// Load the plugins the scene needs (searching `plugin_path` first) and
/// build its world on the pool.
pub(crate) fn build_world(
    file: &rtk_shell::SceneFile,
    desc: rtk_shell::Desc,
    plugin_path: &[PathBuf],
    pool: &rayon::ThreadPool,
) -> Result<rtk_shell::World> {
    let mut registry = Registry::new(PluginPath::standard(plugin_path));
    Ok(rtk_shell::build(file, desc, &mut registry, &Pool(pool))?)
}
