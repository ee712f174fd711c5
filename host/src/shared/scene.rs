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
    read_any_scene(scene, sets, safe, &Default::default())
}

/// [`read_scene`] for a scene of any format rtk reads: TOML as it is, a
/// Mitsuba `.xml` through `rtk import`'s translation (with `import`'s
/// options), its file names resolved from the XML's folder.
pub(crate) fn read_any_scene(
    scene: &Path,
    sets: &[String],
    safe: bool,
    import: &crate::import::ImportOptions,
) -> Result<(rtk_shell::SceneFile, rtk_shell::Desc)> {
    let mut file = if rtk_import::is_importable(scene) {
        let dir = match scene.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let toml = crate::import::translate(scene, import, &dir)?;
        rtk_shell::SceneFile::parse(&imported_name(scene), toml)?
    } else {
        import.check_unused(scene)?;
        rtk_shell::SceneFile::read(scene)?
    };
    file.apply_overrides(sets)?;
    let desc = rtk_shell::Desc::from_file(&file)?;
    if safe {
        rtk_shell::safe::check(&file, &desc)?;
    }
    Ok((file, desc))
}

/// The name an imported scene's TOML goes by in messages: beside the XML
/// (so relative names resolve from its folder), saying what it is.
fn imported_name(xml: &Path) -> PathBuf {
    let mut name = xml.as_os_str().to_os_string();
    name.push(" (imported).toml");
    PathBuf::from(name)
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
