//! The plugin path: the folders searched, in order.

use super::{is_identifier, library_file_name};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The folders searched for plugins, in order.
#[derive(Debug, Clone, Default)]
pub struct PluginPath {
    /// The folders.
    pub dirs: Vec<PathBuf>,
}

impl PluginPath {
    /// `extra` (from `--plugin-path`), then `RTK_PLUGIN_PATH`, then `plugins/`
    /// beside the executable, then the executable's folder.
    pub fn standard(extra: &[PathBuf]) -> Self {
        let mut dirs: Vec<PathBuf> = extra.to_vec();
        if let Some(v) = std::env::var_os("RTK_PLUGIN_PATH") {
            dirs.extend(std::env::split_paths(&v).filter(|p| !p.as_os_str().is_empty()));
        }
        if let Some(exe_dir) = std::env::current_exe()
            .ok()
            .and_then(|p| p.parent().map(Path::to_path_buf))
        {
            dirs.push(exe_dir.join("plugins"));
            dirs.push(exe_dir);
        }
        PluginPath { dirs }
    }

    /// The first library for `class` along the path.
    pub fn find(&self, class: &str) -> Option<PathBuf> {
        let name = library_file_name(class);
        self.dirs
            .iter()
            .map(|d| d.join(&name))
            .find(|p| p.is_file())
    }

    /// Every class available along the path (the first folder holding a
    /// class wins), by name.
    pub fn available(&self) -> BTreeMap<String, PathBuf> {
        let (pre, suf) = (
            format!("{}rtk_", std::env::consts::DLL_PREFIX),
            std::env::consts::DLL_SUFFIX,
        );
        let mut out = BTreeMap::new();
        for d in &self.dirs {
            let Ok(rd) = std::fs::read_dir(d) else {
                continue;
            };
            let mut names: Vec<_> = rd
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            for n in names {
                if let Some(class) = n.strip_prefix(&pre).and_then(|r| r.strip_suffix(suf)) {
                    // Only files (through symlinks) are libraries: a FIFO or
                    // a folder of that name is no class.
                    let file = d.join(&n);
                    if is_identifier(class) && std::fs::metadata(&file).is_ok_and(|m| m.is_file()) {
                        out.entry(class.to_string()).or_insert(file);
                    }
                }
            }
        }
        out
    }

    /// Every plugin library along the path, folder by folder in path
    /// order and by file name within a folder, shadowed ones included:
    /// each file named `<prefix>rtk_<name><suffix>` with the class its name
    /// promises (`None` when that is not an identifier, which
    /// [`available`](Self::available) skips).
    pub fn libraries(&self) -> Vec<(PathBuf, Option<String>)> {
        let (pre, suf) = (
            format!("{}rtk_", std::env::consts::DLL_PREFIX),
            std::env::consts::DLL_SUFFIX,
        );
        let mut out = Vec::new();
        for d in &self.dirs {
            let Ok(rd) = std::fs::read_dir(d) else {
                continue;
            };
            let mut names: Vec<_> = rd
                .flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            names.sort();
            for n in names {
                if let Some(class) = n.strip_prefix(&pre).and_then(|r| r.strip_suffix(suf)) {
                    let class = is_identifier(class).then(|| class.to_string());
                    out.push((d.join(&n), class));
                }
            }
        }
        out
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    /// A FIFO or a folder named like a plugin is no class: listing it
    /// would send `rtk plugins` to load it (a FIFO would hang `dlopen`).
    #[test]
    fn only_files_are_classes() {
        let dir = std::env::temp_dir().join(format!("rtk-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let name = |c: &str| {
            format!(
                "{}rtk_{c}{}",
                std::env::consts::DLL_PREFIX,
                std::env::consts::DLL_SUFFIX
            )
        };
        std::fs::write(dir.join(name("real")), b"not really a library").unwrap();
        std::fs::create_dir_all(dir.join(name("folder"))).unwrap();
        let fifo = dir.join(name("pipe"));
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        let path = PluginPath {
            dirs: vec![dir.clone()],
        };
        let classes: Vec<String> = path.available().into_keys().collect();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(classes, ["real"]);
        assert!(made, "mkfifo is needed for this test");
    }
}
