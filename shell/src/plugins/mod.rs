//! Finding and loading plugin libraries.
//!
//! A class name (a plain identifier, never a path) maps to the file
//! `librtk_<class>.so` (platform prefix and suffix), searched along the
//! [`PluginPath`]. [`load()`] checks a library before any of its code runs;
//! the [`Registry`] loads each class at most once.

mod load;
mod path;

pub use load::{load, LoadError};
pub use path::PluginPath;

use rtk_kernel::abi::*;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// The root module of a loaded plugin, by kind.
#[derive(Clone, Copy)]
pub enum Module {
    /// An object class.
    Object(ObjectModuleRef),
    /// A shader.
    Shader(ShaderModuleRef),
    /// An integrator.
    Integrator(IntegratorModuleRef),
    /// A camera.
    Camera(CameraModuleRef),
    /// A light.
    Light(LightModuleRef),
}

/// A loaded plugin.
pub struct Plugin {
    /// Class name (as its header declares and its file name promises).
    pub class: String,
    /// The library it was loaded from (the first match on the plugin path).
    pub path: PathBuf,
    /// What kind of plugin: it must match the scene's use of the class.
    pub kind: PluginKind,
    /// The plugin crate's own version (not the kernel's).
    pub version: String,
    /// Its README: parameter table and a TOML example (`rtk plugins` prints it).
    pub doc: String,
    /// The checked root module, by kind.
    pub module: Module,
}

impl std::fmt::Debug for Plugin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Plugin")
            .field("class", &self.class)
            .field("path", &self.path)
            .field("kind", &self.kind)
            .finish()
    }
}

/// Is `s` a plain identifier (what class names must be).
pub fn is_identifier(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(ch) if ch.is_ascii_alphabetic() || ch == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

/// The library file name of a class.
pub fn library_file_name(class: &str) -> String {
    format!(
        "{}rtk_{}{}",
        std::env::consts::DLL_PREFIX,
        class,
        std::env::consts::DLL_SUFFIX
    )
}

/// Plugins loaded so far, by class: each library is loaded at most once.
#[derive(Debug, Default)]
pub struct Registry {
    /// Where to look.
    pub path: PluginPath,
    loaded: BTreeMap<String, Arc<Plugin>>,
}

/// Why a class could not be provided.
#[derive(Debug)]
pub enum ClassError {
    /// Not a plain identifier.
    BadName,
    /// No library on the path; the folders searched and the classes found.
    NotFound {
        /// Folders searched.
        searched: Vec<PathBuf>,
        /// Classes available there.
        available: Vec<String>,
    },
    /// Found but refused.
    Refused(LoadError),
}

impl Registry {
    /// A registry over a plugin path.
    pub fn new(path: PluginPath) -> Self {
        Registry {
            path,
            loaded: BTreeMap::new(),
        }
    }

    /// The plugin for `class`, loading it on first use.
    pub fn get(&mut self, class: &str) -> Result<Arc<Plugin>, ClassError> {
        if let Some(p) = self.loaded.get(class) {
            return Ok(p.clone());
        }
        if !is_identifier(class) {
            return Err(ClassError::BadName);
        }
        let Some(file) = self.path.find(class) else {
            return Err(ClassError::NotFound {
                searched: self.path.dirs.clone(),
                available: self.path.available().into_keys().collect(),
            });
        };
        let p = Arc::new(load(&file, Some(class)).map_err(ClassError::Refused)?);
        self.loaded.insert(class.to_string(), p.clone());
        Ok(p)
    }

    /// The plugin for `class` if it is loaded already.
    pub fn loaded_class(&self, class: &str) -> Option<&Arc<Plugin>> {
        self.loaded.get(class)
    }

    /// The plugins loaded so far.
    pub fn loaded(&self) -> impl Iterator<Item = &Arc<Plugin>> {
        self.loaded.values()
    }
}
