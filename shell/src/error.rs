//! The shell's error: what went wrong, and where — file, line and column,
//! the object path and the key.

use crate::tree::{line_col, Origin};
use std::fmt;
use std::path::PathBuf;

/// What kind of failure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The scene file could not be read.
    Io,
    /// TOML syntax.
    Syntax,
    /// A value is missing, of the wrong type, or out of range.
    Invalid,
    /// A name refers to no definition.
    UnknownReference,
    /// Instancing cycle or a DAG deeper than the hit stack.
    Cycle,
    /// A plugin library could not be found or was refused.
    Plugin,
    /// A plugin reported an error (or panicked) creating or building an object.
    PluginCall,
}

/// Where in the input an error is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// A position in the scene file.
    File {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        col: usize,
    },
    /// A `--set` on the command line.
    CommandLine(String),
    /// Nowhere more precise than the file.
    Unknown,
}

/// A scene error. Its `Display` reads
/// `FILE:LINE:COL: OBJECT: key `KEY`: MESSAGE` followed by any notes.
#[derive(Debug, Clone)]
pub struct SceneError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// The scene file.
    pub file: PathBuf,
    /// Where in it.
    pub place: Place,
    /// Object path such as `objects.ball` (empty for the document).
    pub object: String,
    /// Key path within the object (empty when the object as a whole is at fault).
    pub key: String,
    /// The message.
    pub message: String,
    /// Further lines (folders searched, classes found...).
    pub notes: Vec<String>,
}

impl SceneError {
    /// Build an error at an origin of the file `src`.
    pub fn at(
        kind: ErrorKind,
        file: &std::path::Path,
        src: &str,
        origin: &Origin,
        object: impl Into<String>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        let place = match origin {
            Origin::File(r) => {
                let (line, col) = line_col(src, r.start);
                Place::File { line, col }
            }
            Origin::CommandLine(s) => Place::CommandLine(s.clone()),
        };
        SceneError {
            kind,
            file: file.to_path_buf(),
            place,
            object: object.into(),
            key: key.into(),
            message: message.into(),
            notes: Vec::new(),
        }
    }

    /// Add a note line.
    pub fn note(mut self, n: impl Into<String>) -> Self {
        self.notes.push(n.into());
        self
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        match &self.place {
            Place::File { line, col } => write!(f, ":{line}:{col}")?,
            Place::CommandLine(s) => write!(f, " (from --set {s})")?,
            Place::Unknown => {}
        }
        f.write_str(": ")?;
        if !self.object.is_empty() {
            write!(f, "{}: ", self.object)?;
        }
        if !self.key.is_empty() {
            write!(f, "key `{}`: ", self.key)?;
        }
        f.write_str(&self.message)?;
        for n in &self.notes {
            write!(f, "\n  {n}")?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}
