//! `--safe`: rendering a scene from someone else. A scene names files — the
//! image it writes (`[render] output`) and the files its plugins read — and
//! a hostile scene could name any path (`output = "/home/me/.bashrc.png"`,
//! `file = "/etc/shadow.ply"`). Under `--safe` every such path must lie
//! inside the scene's folder or the working directory, symbolic links
//! resolved, and the output may not be absolute at all.
//!
//! The shell knows which plugin parameters are files by convention: a key
//! named `file` or ending in `_file`, at any depth of a definition's table
//! or of an instance's attribute block. Values given on the command line
//! (`--set`, `-o`) are the user's own and are not checked.

use crate::desc::Desc;
use crate::error::SceneError;
use crate::file::SceneFile;
use crate::tree::{Node, Origin, Val};
use std::path::{Component, Path, PathBuf};

/// Where a scene may name files: its folder and the working directory,
/// both with symbolic links resolved.
struct Roots {
    scene_dir: PathBuf,
    cwd: PathBuf,
}

/// Check every path the scene names, as `--safe` requires.
pub fn check(file: &SceneFile, desc: &Desc) -> Result<(), SceneError> {
    check_desc(file, desc).map_err(|e| e.in_file(&file.text))
}

fn check_desc(file: &SceneFile, desc: &Desc) -> Result<(), SceneError> {
    let cwd = std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
    let base = cwd.join(file.dir());
    let roots = Roots {
        scene_dir: resolved(&base),
        cwd: resolved(&cwd),
    };
    for (path, origin) in &file.includes {
        if !roots.inside(&cwd.join(path)) {
            return Err(SceneError::invalid(
                origin,
                "include",
                "",
                format!("--safe: {}", roots.outside(&path.display().to_string())),
            ));
        }
    }
    if let (Some(out), Some(n)) = (&desc.render.output, output_node(file)) {
        roots.check_output(out, n)?;
    }
    let defs = desc
        .cameras
        .values()
        .chain(desc.lights.values())
        .chain(desc.shaders.values())
        .chain(desc.objects.values().map(|o| &o.def))
        .chain(std::iter::once(&desc.render.integrator));
    for def in defs {
        roots.check_files(&def.node, &def.path(), "", &base)?;
    }
    let instances = desc.objects.values().flat_map(|o| o.children.iter());
    for inst in std::iter::once(&desc.render.root).chain(instances) {
        if let Some(a) = &inst.attributes {
            roots.check_files(a, &inst.path, "attributes", &base)?;
        }
    }
    Ok(())
}

/// The `[render] output` node, for its origin.
fn output_node(file: &SceneFile) -> Option<&Node> {
    file.root.get("render")?.get("output")
}

impl Roots {
    /// The output: relative (it resolves against the working directory) and
    /// inside the roots.
    fn check_output(&self, out: &str, n: &Node) -> Result<(), SceneError> {
        if matches!(n.origin, Origin::CommandLine(_)) {
            return Ok(());
        }
        let refuse = |why: String| {
            SceneError::invalid(&n.origin, "render", "output", format!("--safe: {why}"))
        };
        let p = Path::new(out);
        if p.is_absolute() {
            return Err(refuse(format!(
                "the scene names an absolute output path `{out}`: under --safe it may only name a file in the working directory or the scene's folder"
            )));
        }
        if !self.inside(&self.cwd.join(p)) {
            return Err(refuse(self.outside(out)));
        }
        Ok(())
    }

    /// Every `file` / `*_file` string under `n` (a definition's table or
    /// an attribute block), resolved as plugins resolve it: against the
    /// scene's folder.
    fn check_files(
        &self,
        n: &Node,
        object: &str,
        key: &str,
        base: &Path,
    ) -> Result<(), SceneError> {
        match &n.value {
            Val::Table(t) => {
                for (k, _, v) in t {
                    let path = if key.is_empty() {
                        k.clone()
                    } else {
                        format!("{key}.{k}")
                    };
                    let is_file = k == "file" || k.ends_with("_file");
                    match &v.value {
                        Val::Str(s) if is_file => self.check_file(s, v, object, &path, base)?,
                        _ => self.check_files(v, object, &path, base)?,
                    }
                }
            }
            Val::Arr(a) => {
                for (i, v) in a.iter().enumerate() {
                    self.check_files(v, object, &format!("{key}[{i}]"), base)?;
                }
            }
            _ => {}
        }
        Ok(())
    }

    fn check_file(
        &self,
        s: &str,
        n: &Node,
        object: &str,
        key: &str,
        base: &Path,
    ) -> Result<(), SceneError> {
        if matches!(n.origin, Origin::CommandLine(_)) || self.inside(&base.join(s)) {
            return Ok(());
        }
        Err(SceneError::invalid(
            &n.origin,
            object,
            key,
            format!("--safe: {}", self.outside(s)),
        ))
    }

    fn outside(&self, value: &str) -> String {
        format!(
            "`{value}` is outside the scene's folder ({}) and the working directory ({})",
            self.scene_dir.display(),
            self.cwd.display()
        )
    }

    /// Whether `p` (absolute), links resolved, lies inside a root.
    fn inside(&self, p: &Path) -> bool {
        let r = resolved(p);
        r.starts_with(&self.scene_dir) || r.starts_with(&self.cwd)
    }
}

/// `p` (absolute) with its longest existing prefix resolved by the file
/// system (symbolic links, `..`) and the names after it appended; a path
/// whose missing part holds `..` is normalised lexically instead.
fn resolved(p: &Path) -> PathBuf {
    let mut existing = p.to_path_buf();
    let mut rest = Vec::new();
    loop {
        if let Ok(c) = existing.canonicalize() {
            let mut out = c;
            for part in rest.iter().rev() {
                out.push(part);
            }
            return out;
        }
        match (
            existing.file_name().map(|n| n.to_os_string()),
            existing.parent(),
        ) {
            (Some(name), Some(parent)) => {
                rest.push(name);
                existing = parent.to_path_buf();
            }
            _ => return lexical(p),
        }
    }
}

/// `p` with `.` removed and `..` applied lexically.
fn lexical(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}
