//! Loading one library: the plain header first (magic, ABI version, kernel
//! version, panic strategy, class name), then abi_stable's deep layout check
//! of the root module — all before any of the plugin's code runs. Libraries
//! are never unloaded (abi_stable does not support it, and objects point into
//! them until the process ends).

use super::{Module, Plugin};
use abi_stable::library::{lib_header_from_path, LibraryError, RootModule};
use rtk_kernel::abi::*;
use std::path::{Path, PathBuf};

/// Why a library was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The OS could not load it.
    #[error("cannot load {path}: {msg}")]
    Open {
        /// The library file.
        path: PathBuf,
        /// The OS loader's reason (missing file, wrong architecture, undefined symbol...).
        msg: String,
    },
    /// No rtk header symbol.
    #[error("{path} is not an rtk plugin (it exports no RTK_PLUGIN_HEADER)")]
    NotAPlugin {
        /// The library file.
        path: PathBuf,
    },
    /// Built against another ABI (another major version of `rtk-abi`).
    #[error(
        "plugin '{class}' ({path}) was built against ABI {plugin_abi} (rtk-abi {plugin_kernel}); \
         this rtk uses ABI {host_abi} (rtk-abi {host_kernel}). Rebuild the plugin against rtk-kernel {kernel} (its `rtk-kernel` dependency), \
         or use an rtk of ABI {plugin_abi}."
    )]
    Version {
        /// The class it declares.
        class: String,
        /// The library file.
        path: PathBuf,
        /// `rtk-abi` version the plugin was built against.
        plugin_kernel: String,
        /// ABI version the plugin saw.
        plugin_abi: u32,
        /// This host's `rtk-abi` version.
        host_kernel: String,
        /// This host's `rtk-kernel` version: what to rebuild against.
        kernel: &'static str,
        /// This host's ABI version.
        host_abi: u32,
    },
    /// Built with panic = "abort".
    #[error(
        "plugin '{class}' ({path}) was built with panic = \"abort\": a panic in it would abort rtk. \
         Rebuild it with panic = \"unwind\" (the default)."
    )]
    PanicAbort {
        /// The class it declares.
        class: String,
        /// The library file.
        path: PathBuf,
    },
    /// The header says another class than the file name.
    #[error("{path} declares class '{declared}', but its file name says '{expected}'")]
    ClassMismatch {
        /// The library file.
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
        /// The class it declares.
        class: String,
        /// The library file.
        path: PathBuf,
        /// The first lines of abi_stable's report.
        summary: String,
        /// This host's kernel version.
        host_kernel: String,
    },
    /// The header is malformed.
    #[error("{path}: {msg}")]
    BadHeader {
        /// The library file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
}

/// Load and check one plugin library. `expected_class` is the class the file
/// name promises, if any.
pub fn load(path: &Path, expected_class: Option<&str>) -> Result<Plugin, LoadError> {
    let open_error = |msg: String| LoadError::Open {
        path: path.to_path_buf(),
        msg,
    };
    // Only a regular file: dlopen of a FIFO blocks until a writer comes.
    match std::fs::metadata(path) {
        Err(e) => return Err(open_error(e.to_string())),
        Ok(m) if !m.is_file() => return Err(open_error("not a regular file".to_string())),
        Ok(_) => {}
    }
    // SAFETY: loading a library runs its initialisers; rtk plugins are Rust
    // cdylibs whose initialisers do nothing observable. Nothing else of the
    // plugin runs until its header has been checked.
    let lib = unsafe { libloading::Library::new(path) }.map_err(|e| {
        // libloading's own message is "dlopen failed"; the reason is its source.
        open_error(match std::error::Error::source(&e) {
            Some(s) => s.to_string(),
            None => e.to_string(),
        })
    })?;
    let header = read_header(&lib, path)?;
    let kind = check_header(&header, path, expected_class)?;
    // Keep the library mapped for the life of the process.
    std::mem::forget(lib);
    init_module(path, header.class_name(), kind)
}

/// The library's [`PluginHeader`], read as plain data (no plugin code runs).
fn read_header(lib: &libloading::Library, path: &Path) -> Result<PluginHeader, LoadError> {
    // SAFETY: the symbol, if present, is a `PluginHeader` static: plain data
    // with no pointers, valid for as long as the library stays loaded.
    let sym = unsafe { lib.get::<*const PluginHeader>(PLUGIN_HEADER_SYMBOL) };
    let Ok(sym) = sym else {
        return Err(LoadError::NotAPlugin {
            path: path.to_path_buf(),
        });
    };
    let p: *const PluginHeader = *sym;
    // Read the fixed leading fields first: another ABI's header may be smaller.
    // SAFETY: every header starts with the magic and its own size (both ABIs).
    let (magic, size, abi) = unsafe {
        (
            std::ptr::read_unaligned(p as *const [u8; 8]),
            std::ptr::read_unaligned((p as *const u8).add(8) as *const u32),
            std::ptr::read_unaligned((p as *const u8).add(12) as *const u32),
        )
    };
    if magic != PLUGIN_MAGIC {
        return Err(LoadError::BadHeader {
            path: path.to_path_buf(),
            msg: "RTK_PLUGIN_HEADER has the wrong magic bytes".into(),
        });
    }
    if size as usize != std::mem::size_of::<PluginHeader>() {
        return Err(LoadError::Version {
            class: "?".into(),
            path: path.to_path_buf(),
            plugin_kernel: "unknown".into(),
            plugin_abi: abi,
            host_kernel: ABI_CRATE_VERSION.into(),
            host_abi: ABI_VERSION,
            kernel: rtk_kernel::KERNEL_VERSION,
        });
    }
    // SAFETY: the header has this kernel's size and layout (unchanged since ABI 1).
    Ok(unsafe { std::ptr::read_unaligned(p) })
}

/// Refuse another ABI or kernel version, `panic = "abort"`, a class other
/// than the file name says, an unknown kind.
fn check_header(
    h: &PluginHeader,
    path: &Path,
    expected_class: Option<&str>,
) -> Result<PluginKind, LoadError> {
    let class = h.class_name();
    let plugin_kernel = h.abi_crate_version();
    if h.abi_version != ABI_VERSION || !same_major(&plugin_kernel, ABI_CRATE_VERSION) {
        return Err(LoadError::Version {
            class,
            path: path.to_path_buf(),
            plugin_kernel,
            plugin_abi: h.abi_version,
            host_kernel: ABI_CRATE_VERSION.into(),
            host_abi: ABI_VERSION,
            kernel: rtk_kernel::KERNEL_VERSION,
        });
    }
    if h.panic_unwind != 1 {
        return Err(LoadError::PanicAbort {
            class,
            path: path.to_path_buf(),
        });
    }
    if let Some(exp) = expected_class.filter(|e| *e != class) {
        return Err(LoadError::ClassMismatch {
            path: path.to_path_buf(),
            expected: exp.to_string(),
            declared: class,
        });
    }
    PluginKind::from_u32(h.kind).ok_or_else(|| LoadError::BadHeader {
        path: path.to_path_buf(),
        msg: format!("unknown plugin kind {}", h.kind),
    })
}

/// abi_stable's deep layout check of the root module of `kind`.
fn init_module(path: &Path, class: String, kind: PluginKind) -> Result<Plugin, LoadError> {
    let layout_err = |e: LibraryError| LoadError::Layout {
        class: class.clone(),
        path: path.to_path_buf(),
        summary: summarize_abi_error(&e.to_string()),
        host_kernel: rtk_kernel::KERNEL_VERSION.into(),
    };
    let h = lib_header_from_path(path).map_err(layout_err)?;
    fn init<M: RootModule>(
        h: &'static abi_stable::library::LibHeader,
        e: impl Fn(LibraryError) -> LoadError,
    ) -> Result<M, LoadError> {
        h.init_root_module::<M>().map_err(e)
    }
    let (module, meta) = match kind {
        PluginKind::Object => {
            init(h, layout_err).map(|m: ObjectModuleRef| (Module::Object(m), m.meta()))
        }
        PluginKind::Shader => {
            init(h, layout_err).map(|m: ShaderModuleRef| (Module::Shader(m), m.meta()))
        }
        PluginKind::Integrator => {
            init(h, layout_err).map(|m: IntegratorModuleRef| (Module::Integrator(m), m.meta()))
        }
        PluginKind::Camera => {
            init(h, layout_err).map(|m: CameraModuleRef| (Module::Camera(m), m.meta()))
        }
        PluginKind::Light => {
            init(h, layout_err).map(|m: LightModuleRef| (Module::Light(m), m.meta()))
        }
    }?;
    Ok(Plugin {
        class,
        path: path.to_path_buf(),
        kind,
        version: meta.plugin_version.as_str().to_string(),
        doc: meta.doc.as_str().to_string(),
        module,
    })
}

/// Plugins of one ABI load into any host of that ABI: entries appended in a
/// later minor version are read as absent (prefix records), so only the
/// major version of `rtk-abi` must agree.
fn same_major(a: &str, b: &str) -> bool {
    let major = |s: &str| s.split('.').next().unwrap_or("").to_string();
    major(a) == major(b)
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
