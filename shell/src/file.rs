//! A scene file: its text, its spanned tree, and `--set` overrides.

use crate::error::{ErrorKind, FileText, SceneError};
use crate::tree::{self, Node, Origin};
use std::path::{Path, PathBuf};

/// The sections of a scene file, in the order they are documented.
pub const SECTIONS: [&str; 5] = ["render", "cameras", "lights", "shaders", "objects"];

/// A scene file: its text and its spanned tree.
#[derive(Debug, Clone)]
pub struct SceneFile {
    /// Path and text (errors are located in it).
    pub text: FileText,
    /// Parsed tree.
    pub root: Node,
}

impl SceneFile {
    /// Read and parse a scene file.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let src = std::fs::read_to_string(path).map_err(|e| {
            SceneError::new(
                ErrorKind::Io,
                &Origin::Whole,
                "",
                "",
                format!("cannot read the scene file: {e}"),
            )
            .in_file(&FileText {
                path: path.to_path_buf(),
                src: "".into(),
            })
        })?;
        Self::parse(path, src)
    }

    /// Parse scene text (the path is for messages and relative files).
    pub fn parse(path: &Path, src: String) -> Result<Self, SceneError> {
        let text = FileText {
            path: path.to_path_buf(),
            src: src.into(),
        };
        match tree::parse(&text.src) {
            Ok(root) => Ok(SceneFile { text, root }),
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
        if keys.iter().any(|k| k.is_empty()) || !SECTIONS.contains(&keys[0]) {
            return Err(SceneError::invalid(
                &origin,
                "",
                key,
                format!(
                    "the key path must start with one of {}",
                    SECTIONS.join(", ")
                ),
            ));
        }
        let node = tree::parse_override_value(s, value.trim());
        self.root
            .set_path(&keys, node)
            .map_err(|m| SceneError::invalid(&origin, "", key, m))
    }

    /// The folder relative file parameters resolve against.
    pub fn dir(&self) -> PathBuf {
        match self.path().parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }
}
