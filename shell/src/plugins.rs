//! Finding and loading plugin libraries.
//!
//! A class name (a plain identifier, never a path) maps to the file
//! `librtk_<class>.so` (platform prefix and suffix), searched along the plugin
//! path: `--plugin-path` folders, then `RTK_PLUGIN_PATH`, then `plugins/`
//! beside the executable, then the executable's own folder.
//!
//! Loading checks, before any of the plugin's code runs: the plain
//! [`PluginHeader`] (magic, ABI version, kernel version, panic strategy, class
//! name), then abi_stable's deep layout check of the root module. Libraries
//! are never unloaded (abi_stable does not support it, and objects point into
//! them until the process ends).

use abi_stable::library::{lib_header_from_path, LibraryError, RootModule};
use rtk_kernel::abi::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a library was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The OS could not load it.
    #[error("cannot load {path}: {msg}")]
    Open {
        /// The file.
        path: PathBuf,
        /// The loader's message.
        msg: String,
    },
    /// No rtk header symbol.
    #[error("{path} is not an rtk plugin (it exports no RTK_PLUGIN_HEADER)")]
    NotAPlugin {
        /// The file.
        path: PathBuf,
    },
    /// Built against another kernel ABI or version.
    #[error(
        "plugin '{class}' ({path}) was built against rtk-kernel {plugin_kernel} (ABI {plugin_abi}); \
         this rtk uses rtk-kernel {host_kernel} (ABI {host_abi}). Rebuild the plugin against rtk-kernel {host_kernel}."
    )]
    Version {
        /// The class.
        class: String,
        /// The file.
        path: PathBuf,
        /// Kernel version the plugin saw.
        plugin_kernel: String,
        /// ABI version the plugin saw.
        plugin_abi: u32,
        /// This host's kernel version.
        host_kernel: String,
        /// This host's ABI version.
        host_abi: u32,
    },
    /// Built with panic = "abort".
    #[error(
        "plugin '{class}' ({path}) was built with panic = \"abort\": a panic in it would abort rtk. \
         Rebuild it with panic = \"unwind\" (the default)."
    )]
    PanicAbort {
        /// The class.
        class: String,
        /// The file.
        path: PathBuf,
    },
    /// The header says another class than the file name.
    #[error("{path} declares class '{declared}', but its file name says '{expected}'")]
    ClassMismatch {
        /// The file.
        path: PathBuf,
        /// From the file name.
        expected: String,
        /// From the header.
        declared: String,
    },
    /// abi_stable's layout check failed.
    #[error(
        "plugin '{class}' ({path}) does not match this rtk's kernel records: {summary}\n  \
         Rebuild the plugin against rtk-kernel {host_kernel}."
    )]
    Layout {
        /// The class.
        class: String,
        /// The file.
        path: PathBuf,
        /// The first lines of abi_stable's report.
        summary: String,
        /// This host's kernel version.
        host_kernel: String,
    },
    /// The header is malformed.
    #[error("{path}: {msg}")]
    BadHeader {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
}

/// The root module of a loaded plugin, by kind.
#[derive(Clone, Copy)]
pub enum Module {
    /// An object class, with its hot table copied out of the prefix record.
    Object(ObjectModuleRef, &'static ObjectFns),
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
    /// Class name.
    pub class: String,
    /// Library file.
    pub path: PathBuf,
    /// Kind.
    pub kind: PluginKind,
    /// Plugin crate version.
    pub version: String,
    /// Documentation.
    pub doc: String,
    /// Root module.
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
                    if is_identifier(class) {
                        out.entry(class.to_string()).or_insert_with(|| d.join(&n));
                    }
                }
            }
        }
        out
    }
}

/// Load and check one plugin library. `expected_class` is the class the file
/// name promises, if any.
pub fn load(path: &Path, expected_class: Option<&str>) -> Result<Plugin, LoadError> {
    // SAFETY: loading a library runs its initialisers; rtk plugins are Rust
    // cdylibs whose initialisers do nothing observable. Nothing else of the
    // plugin runs until its header has been checked.
    let lib = unsafe { libloading::Library::new(path) }.map_err(|e| LoadError::Open {
        path: path.to_path_buf(),
        msg: e.to_string(),
    })?;
    // SAFETY: the symbol, if present, is a `PluginHeader` static: plain data
    // with no pointers, valid for as long as the library stays loaded (forever).
    let header: PluginHeader = unsafe {
        match lib.get::<*const PluginHeader>(PLUGIN_HEADER_SYMBOL) {
            Ok(sym) => {
                let p: *const PluginHeader = *sym;
                // Read the fixed leading fields first: an older header may be smaller.
                let magic = std::ptr::read_unaligned(p as *const [u8; 8]);
                if magic != PLUGIN_MAGIC {
                    return Err(LoadError::BadHeader {
                        path: path.to_path_buf(),
                        msg: "RTK_PLUGIN_HEADER has the wrong magic bytes".into(),
                    });
                }
                let size = std::ptr::read_unaligned((p as *const u8).add(8) as *const u32);
                let abi = std::ptr::read_unaligned((p as *const u8).add(12) as *const u32);
                if abi != ABI_VERSION || size as usize != std::mem::size_of::<PluginHeader>() {
                    return Err(LoadError::Version {
                        class: expected_class.unwrap_or("?").to_string(),
                        path: path.to_path_buf(),
                        plugin_kernel: "unknown".into(),
                        plugin_abi: abi,
                        host_kernel: rtk_kernel::KERNEL_VERSION.into(),
                        host_abi: ABI_VERSION,
                    });
                }
                std::ptr::read(p)
            }
            Err(_) => {
                return Err(LoadError::NotAPlugin {
                    path: path.to_path_buf(),
                })
            }
        }
    };
    let class = header.class_name();
    let plugin_kernel = header.kernel_version();
    if !same_minor(&plugin_kernel, rtk_kernel::KERNEL_VERSION) {
        return Err(LoadError::Version {
            class,
            path: path.to_path_buf(),
            plugin_kernel,
            plugin_abi: header.abi_version,
            host_kernel: rtk_kernel::KERNEL_VERSION.into(),
            host_abi: ABI_VERSION,
        });
    }
    if header.panic_unwind != 1 {
        return Err(LoadError::PanicAbort {
            class,
            path: path.to_path_buf(),
        });
    }
    if let Some(exp) = expected_class {
        if exp != class {
            return Err(LoadError::ClassMismatch {
                path: path.to_path_buf(),
                expected: exp.to_string(),
                declared: class,
            });
        }
    }
    let kind = PluginKind::from_u32(header.kind).ok_or_else(|| LoadError::BadHeader {
        path: path.to_path_buf(),
        msg: format!("unknown plugin kind {}", header.kind),
    })?;
    // Keep the library mapped for the life of the process.
    std::mem::forget(lib);

    let layout_err = |e: LibraryError| LoadError::Layout {
        class: class.clone(),
        path: path.to_path_buf(),
        summary: summarize_abi_error(&e.to_string()),
        host_kernel: rtk_kernel::KERNEL_VERSION.into(),
    };
    let lib_header = lib_header_from_path(path).map_err(layout_err)?;
    fn init<M: RootModule>(
        h: &'static abi_stable::library::LibHeader,
        e: impl Fn(LibraryError) -> LoadError,
    ) -> Result<M, LoadError> {
        h.init_root_module::<M>().map_err(e)
    }
    let (module, meta) = match kind {
        PluginKind::Object => {
            let m: ObjectModuleRef = init(lib_header, layout_err)?;
            let fns: &'static ObjectFns = Box::leak(Box::new(m.fns()));
            (Module::Object(m, fns), m.meta())
        }
        PluginKind::Shader => {
            let m: ShaderModuleRef = init(lib_header, layout_err)?;
            (Module::Shader(m), m.meta())
        }
        PluginKind::Integrator => {
            let m: IntegratorModuleRef = init(lib_header, layout_err)?;
            (Module::Integrator(m), m.meta())
        }
        PluginKind::Camera => {
            let m: CameraModuleRef = init(lib_header, layout_err)?;
            (Module::Camera(m), m.meta())
        }
        PluginKind::Light => {
            let m: LightModuleRef = init(lib_header, layout_err)?;
            (Module::Light(m), m.meta())
        }
    };
    Ok(Plugin {
        class,
        path: path.to_path_buf(),
        kind,
        version: meta.plugin_version.as_str().to_string(),
        doc: meta.doc.as_str().to_string(),
        module,
    })
}

fn same_minor(a: &str, b: &str) -> bool {
    let mm = |s: &str| s.split('.').take(2).collect::<Vec<_>>().join(".");
    mm(a) == mm(b)
}

/// abi_stable's report runs to hundreds of lines; keep what says where the
/// layouts differ: the last error with its expected and found values, and the
/// chain of fields leading to it (e.g. `... -> param_2: *const Ray -> generation: u64`).
fn summarize_abi_error(full: &str) -> String {
    if std::env::var_os("RTK_DEBUG_ABI").is_some() {
        eprintln!("{full}");
    }
    let lines: Vec<&str> = full.lines().map(str::trim).collect();
    let next_value = |from: usize| {
        lines[from + 1..]
            .iter()
            .find(|l| !l.is_empty())
            .copied()
            .unwrap_or("")
    };
    let mut errors = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if let Some(msg) = l.strip_prefix("Error:") {
            let mut e = msg.trim().to_string();
            if let Some(j) = lines[i..].iter().position(|x| *x == "Expected:") {
                e.push_str(&format!(" (expected {}", next_value(i + j)));
                if let Some(k) = lines[i + j..].iter().position(|x| *x == "Found:") {
                    e.push_str(&format!(", found {}", next_value(i + j + k)));
                }
                e.push(')');
            }
            errors.push((i, e));
        }
    }
    let Some((last, msg)) = errors.last() else {
        return lines
            .iter()
            .filter(|l| !l.is_empty())
            .take(4)
            .copied()
            .collect::<Vec<_>>()
            .join("; ");
    };
    // The field chain: `field_name:` / `type:` pairs of the last "inside:" block.
    let inside = lines[..*last]
        .iter()
        .rposition(|l| l.ends_with("inside:"))
        .unwrap_or(0);
    let mut chain = Vec::new();
    let mut i = inside;
    while i < *last && !lines[i].starts_with("Layout of") {
        if let Some(f) = lines[i].strip_prefix("field_name:") {
            let ty = lines
                .get(i + 1)
                .and_then(|t| t.strip_prefix("type:"))
                .unwrap_or("?");
            chain.push(format!("{f}: {}", ty.trim()));
        }
        i += 1;
    }
    format!("{msg} at {}", chain.join(" -> "))
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

    /// The plugins loaded so far.
    pub fn loaded(&self) -> impl Iterator<Item = &Arc<Plugin>> {
        self.loaded.values()
    }
}
