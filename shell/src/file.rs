//! A scene file: its text, its spanned tree, and `--set` overrides.

use crate::error::{ErrorKind, FileText, SceneError};
use crate::tree::{self, Node, Origin, Val};
use std::path::{Path, PathBuf};

/// Largest scene file read: 64 MiB. A scene is text that names its bulk
/// data (meshes) by file; a larger one is a mistake or an attack, and
/// reading it whole (`/dev/zero`, a huge file) would exhaust memory.
pub const MAX_SCENE_BYTES: u64 = 64 << 20;

/// The sections of a scene file, in the order they are documented.
pub const SECTIONS: [&str; 5] = ["render", "cameras", "lights", "shaders", "objects"];

/// Most nested `include`s: deeper is a mistake (or a loop the path check
/// could not see), not a scene.
pub const MAX_INCLUDE_DEPTH: usize = 16;

/// A scene file: its text and its spanned tree.
#[derive(Debug, Clone)]
pub struct SceneFile {
    /// Path and text (errors are located in it).
    pub text: FileText,
    /// Parsed tree, with every included file's tables merged in.
    pub root: Node,
    /// The files `include` named, as resolved, with where each is named
    /// (`--safe` checks them).
    pub includes: Vec<(PathBuf, Origin)>,
    /// Arrays a host attached to definitions (the Python module's meshes
    /// from NumPy), by definition path (`objects.bunny`): handed to that
    /// definition's `create` by pointer ([`rtk_handles::Bulk`]), never as
    /// text. Empty for a scene read from files.
    pub arrays: std::collections::BTreeMap<String, Vec<AttachedArray>>,
}

/// An array a host attached to a definition: a C-order `rows × cols` block
/// of `rtk_abi::bulk_dtype` elements in native byte order.
#[derive(Debug, Clone)]
pub struct AttachedArray {
    /// The parameter it stands for (`vertices`, `indices`).
    pub name: String,
    /// An `rtk_abi::bulk_dtype` code.
    pub dtype: u32,
    /// Number of rows.
    pub rows: u64,
    /// Number of columns.
    pub cols: u64,
    /// The elements' bytes.
    pub data: Vec<u8>,
}

impl SceneFile {
    /// Read and parse a scene file (a regular file of at most
    /// [`MAX_SCENE_BYTES`], in UTF-8) and the files it includes: a
    /// top-level `include = "file.toml"` or `include = ["a.toml", ...]`
    /// merges their sections into this one (a definition given twice is an
    /// error; paths relative to the including file; loops refused). Errors
    /// inside an included file name that file and its line.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let mut f = Self::read_one(path)?;
        let mut stack = vec![canonical(path)];
        f.resolve_includes(&mut stack)?;
        Ok(f)
    }

    /// Merge the files this one's `include` names, recursively.
    fn resolve_includes(&mut self, stack: &mut Vec<PathBuf>) -> Result<(), SceneError> {
        let here = self.text.clone();
        let Some((origin, node)) = take_key(&mut self.root, "include") else {
            return Ok(());
        };
        let bad = |o: &Origin, m: String| SceneError::invalid(o, "include", "", m).in_file(&here);
        let names: Vec<(String, Origin)> = match node.value {
            Val::Str(s) => vec![(s, node.origin)],
            Val::Arr(items) => items
                .into_iter()
                .map(|n| match n.value {
                    Val::Str(s) => Ok((s, n.origin)),
                    v => Err(bad(
                        &n.origin,
                        format!("expected a path, found {}", v.type_name()),
                    )),
                })
                .collect::<Result<_, _>>()?,
            v => {
                return Err(bad(
                    &origin,
                    format!(
                        "expected a path or an array of paths, found {}",
                        v.type_name()
                    ),
                ))
            }
        };
        for (name, at) in names {
            let path = self.dir().join(&name);
            let key = canonical(&path);
            if let Some(i) = stack.iter().position(|p| *p == key) {
                let cycle: Vec<String> = stack[i..]
                    .iter()
                    .chain(std::iter::once(&key))
                    .map(|p| p.display().to_string())
                    .collect();
                return Err(bad(&at, format!("include loop: {}", cycle.join(" -> "))));
            }
            if stack.len() >= MAX_INCLUDE_DEPTH {
                return Err(bad(
                    &at,
                    format!("includes nested more than {MAX_INCLUDE_DEPTH} deep"),
                ));
            }
            let mut inner = Self::read_one(&path)?;
            stack.push(key);
            inner.resolve_includes(stack)?;
            stack.pop();
            self.includes.push((path, at.clone()));
            self.includes.append(&mut inner.includes);
            let file = std::sync::Arc::new(inner.text.clone());
            let root = std::mem::replace(&mut inner.root, Node::empty_table()).into_included(&file);
            merge(&mut self.root, root).map_err(|e| e.in_file(&here))?;
        }
        Ok(())
    }

    /// Read and parse one file.
    fn read_one(path: &Path) -> Result<Self, SceneError> {
        let io_error = |msg: String| {
            SceneError::new(ErrorKind::Io, &Origin::Whole, "", "", msg).in_file(&FileText {
                path: path.to_path_buf(),
                src: "".into(),
            })
        };
        let bytes = read_regular_file(path, MAX_SCENE_BYTES, "scene file")
            .map_err(|e| io_error(e.to_string()))?;
        match String::from_utf8(bytes) {
            Ok(src) => Self::parse(path, src),
            Err(e) => {
                let at = e.utf8_error().valid_up_to();
                let byte = e.as_bytes()[at];
                let text = FileText {
                    path: path.to_path_buf(),
                    src: String::from_utf8_lossy(e.as_bytes()).into(),
                };
                Err(SceneError::new(
                    ErrorKind::Syntax,
                    &Origin::File(at..at + 1),
                    "",
                    "",
                    format!("the scene file is not UTF-8 text (byte 0x{byte:02X})"),
                )
                .in_file(&text))
            }
        }
    }

    /// Parse scene text (the path is for messages and relative files).
    pub fn parse(path: &Path, src: String) -> Result<Self, SceneError> {
        let text = FileText {
            path: path.to_path_buf(),
            src: src.into(),
        };
        match tree::parse(&text.src) {
            Ok(root) => Ok(SceneFile {
                text,
                root,
                includes: Vec::new(),
                arrays: Default::default(),
            }),
            Err((msg, span)) => Err(SceneError::new(
                ErrorKind::Syntax,
                &Origin::File(span.unwrap_or(0..0)),
                "",
                "",
                msg.trim_end(),
            )
            .in_file(&text)),
        }
    }

    /// The path as given.
    pub fn path(&self) -> &Path {
        &self.text.path
    }

    /// Apply `--set key.path=value` overrides.
    pub fn apply_overrides(&mut self, sets: &[String]) -> Result<(), SceneError> {
        for s in sets {
            self.apply_override(s).map_err(|e| e.in_file(&self.text))?;
        }
        Ok(())
    }

    fn apply_override(&mut self, s: &str) -> Result<(), SceneError> {
        let origin = Origin::CommandLine(s.to_string());
        let Some((key, value)) = s.split_once('=') else {
            return Err(SceneError::invalid(
                &origin,
                "",
                "",
                "expected --set key.path=value",
            ));
        };
        let keys: Vec<&str> = key.trim().split('.').collect();
        let params = crate::desc::params::SECTION;
        if keys.iter().any(|k| k.is_empty()) || !(SECTIONS.contains(&keys[0]) || keys[0] == params)
        {
            return Err(SceneError::invalid(
                &origin,
                "",
                key,
                format!(
                    "the key path must start with one of {}, {params}",
                    SECTIONS.join(", ")
                ),
            ));
        }
        self.check_defined(&keys, &origin)?;
        let node = tree::parse_override_value(s, value.trim())
            .map_err(|m| SceneError::invalid(&origin, "", key, m))?;
        self.root
            .set_path(&keys, node)
            .map_err(|m| SceneError::invalid(&origin, "", key, m))
    }

    /// A `--set` inside a definition (`objects.ball.radius`) needs the
    /// definition: otherwise a typo in its name would create a definition
    /// without a class, reported as a missing `class`. A new definition is
    /// made by setting its `class` first (`--set objects.x.class=sphere`),
    /// or whole, as a table (`--set 'objects.x={ class = "sphere" }'`).
    fn check_defined(&self, keys: &[&str], origin: &Origin) -> Result<(), SceneError> {
        if let [crate::desc::params::SECTION, name, ..] = keys {
            return self.check_param_defined(name, origin);
        }
        let [section, name, key, ..] = keys else {
            return Ok(());
        };
        let defined = self.root.get(section).and_then(|s| s.get(name)).is_some();
        if *section == "render" || defined || (keys.len() == 3 && *key == "class") {
            return Ok(());
        }
        let defined: Vec<&str> = match self.root.get(section).map(|s| &s.value) {
            Some(tree::Val::Table(t)) => t.iter().map(|(k, _, _)| k.as_str()).collect(),
            _ => Vec::new(),
        };
        Err(SceneError::new(
            ErrorKind::UnknownReference,
            origin,
            format!("{section}.{name}"),
            "",
            format!(
                "the scene defines no `{name}` in [{section}]: --set can change a definition's keys; a new definition needs its `class` set first"
            ),
        )
        .note(format!(
            "{section} defined: {}",
            if defined.is_empty() { "none".to_string() } else { defined.join(", ") }
        )))
    }

    /// `--set params.name=...` sets a parameter the scene declares: a
    /// misspelt name would otherwise set nothing the scene uses.
    fn check_param_defined(&self, name: &str, origin: &Origin) -> Result<(), SceneError> {
        let section = crate::desc::params::SECTION;
        let declared: Vec<&str> = match self.root.get(section).map(|s| &s.value) {
            Some(tree::Val::Table(t)) => t.iter().map(|(k, _, _)| k.as_str()).collect(),
            _ => Vec::new(),
        };
        if declared.contains(&name) {
            return Ok(());
        }
        Err(SceneError::new(
            ErrorKind::UnknownReference,
            origin,
            section,
            name,
            format!("the scene declares no parameter `{name}` in [params]"),
        )
        .note(format!(
            "parameters declared: {}",
            if declared.is_empty() {
                "none".to_string()
            } else {
                declared.join(", ")
            }
        )))
    }

    /// The folder relative file parameters resolve against.
    pub fn dir(&self) -> PathBuf {
        match self.path().parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }
}

/// The path with links and `..` resolved where it exists (to recognise a
/// file included twice under two names), else as given.
fn canonical(p: &Path) -> PathBuf {
    p.canonicalize().unwrap_or_else(|_| p.to_path_buf())
}

/// Remove a top-level key, returning its key origin and value.
fn take_key(root: &mut Node, key: &str) -> Option<(Origin, Node)> {
    let Val::Table(t) = &mut root.value else {
        return None;
    };
    let i = t.iter().position(|(k, _, _)| k == key)?;
    let (_, o, n) = t.remove(i);
    Some((o, n))
}

/// Merge an included file's top level into the scene's: sections are
/// joined, and a definition (or `[render]` key) given in both is an error
/// located at the second.
fn merge(into: &mut Node, from: Node) -> Result<(), SceneError> {
    let (Val::Table(dst), Val::Table(src)) = (&mut into.value, from.value) else {
        return Ok(());
    };
    for (section, origin, node) in src {
        let Some(pos) = dst.iter().position(|(k, _, _)| *k == section) else {
            dst.push((section, origin, node));
            continue;
        };
        let existing = &mut dst[pos].2;
        match (&mut existing.value, node.value) {
            (Val::Table(a), Val::Table(b)) => {
                for (k, ko, v) in b {
                    if a.iter().any(|(k2, _, _)| *k2 == k) {
                        return Err(SceneError::invalid(
                            &ko,
                            format!("{section}.{k}"),
                            "",
                            format!("`{section}.{k}` is defined both here and in the including file"),
                        ));
                    }
                    a.push((k, ko, v));
                }
            }
            (_, v) => {
                return Err(SceneError::invalid(
                    &origin,
                    section.clone(),
                    "",
                    format!(
                        "`{section}` is given both here and in the including file, not both as tables ({})",
                        v.type_name()
                    ),
                ))
            }
        }
    }
    Ok(())
}

/// Why [`read_regular_file`] refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file system's error.
    #[error("cannot read the {what}: {source}")]
    Io {
        /// What the file is ("scene file").
        what: String,
        /// The error.
        source: std::io::Error,
    },
    /// A FIFO, a device, a socket or a folder.
    #[error("cannot read the {what}: it is {kind}, not a regular file")]
    NotRegular {
        /// What the file should be.
        what: String,
        /// What it is ("a FIFO").
        kind: &'static str,
    },
    /// Larger than the limit.
    #[error("the {what} is {len} bytes, more than rtk's limit of {} MiB for a {what}", .limit >> 20)]
    TooBig {
        /// What the file is.
        what: String,
        /// Its size (or as much as was read).
        len: u64,
        /// The limit, in bytes.
        limit: u64,
    },
}

/// Read a whole regular file of at most `limit` bytes; `what` names it in
/// messages. Anything but a regular file is refused before it is opened:
/// opening a FIFO blocks until a writer comes, and a device (`/dev/zero`)
/// never ends. The file is opened without blocking and checked again through
/// its handle, in case the path changed in between, and read no further
/// than the limit, in case it grows.
pub fn read_regular_file(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, ReadError> {
    use std::io::Read;
    let io = |source: std::io::Error| ReadError::Io {
        what: what.to_string(),
        source,
    };
    let too_big = |len: u64| ReadError::TooBig {
        what: what.to_string(),
        len,
        limit,
    };
    let regular = |meta: &std::fs::Metadata| -> Result<(), ReadError> {
        if !meta.is_file() {
            return Err(ReadError::NotRegular {
                what: what.to_string(),
                kind: file_kind(meta),
            });
        }
        match meta.len() > limit {
            true => Err(too_big(meta.len())),
            false => Ok(()),
        }
    };
    regular(&std::fs::metadata(path).map_err(io)?)?;
    let file = open_nonblocking(path).map_err(io)?;
    regular(&file.metadata().map_err(io)?)?;
    let mut bytes = Vec::new();
    file.take(limit + 1).read_to_end(&mut bytes).map_err(io)?;
    match bytes.len() as u64 > limit {
        true => Err(too_big(bytes.len() as u64)),
        false => Ok(bytes),
    }
}

#[cfg(unix)]
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
}

#[cfg(not(unix))]
fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::File::open(path)
}

/// What a file that is not a regular file is, for messages.
fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a folder"
    } else {
        "a special file"
    }
}
