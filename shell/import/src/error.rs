//! What an import can fail on, each error located at the element that
//! caused it.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where an element is: its file, line and column (both from 1).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Loc {
    /// The file (as resolved from the including file or the command line).
    pub file: Arc<PathBuf>,
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1.
    pub col: u32,
}

impl Loc {
    /// The start of `file` (for errors about the file as a whole).
    pub fn file_start(file: &Path) -> Loc {
        Loc {
            file: Arc::new(file.to_path_buf()),
            line: 1,
            col: 1,
        }
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// Why a scene could not be imported.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// The file could not be read (missing, not a regular file, too large,
    /// not UTF-8).
    #[error("{path}: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Not well-formed XML.
    #[error("{loc}: malformed XML: {message}")]
    Syntax {
        /// Where the parser stopped.
        loc: Loc,
        /// The parser's message.
        message: String,
    },
    /// Well-formed, but not a scene this importer can read (a missing
    /// attribute, a bad number, an undefined `$parameter` or `id`, an
    /// include cycle).
    #[error("{loc}: {message}")]
    Invalid {
        /// The element.
        loc: Loc,
        /// What is wrong.
        message: String,
    },
    /// A plugin, parameter or value rtk cannot express exactly (an error
    /// unless `--lenient`, which drops it with a warning).
    #[error("{loc}: {what}: {message}")]
    Unsupported {
        /// The element.
        loc: Loc,
        /// The plugin and parameter, e.g. `<bsdf type="plastic">` or
        /// `<shape type="obj"> parameter \`flip_normals\``.
        what: String,
        /// Why, and what rtk would need.
        message: String,
    },
}

impl ImportError {
    /// An [`ImportError::Invalid`] at `loc`.
    pub fn invalid(loc: &Loc, message: impl Into<String>) -> ImportError {
        ImportError::Invalid {
            loc: loc.clone(),
            message: message.into(),
        }
    }

    /// An [`ImportError::Unsupported`] at `loc`.
    pub fn unsupported(loc: &Loc, what: impl Into<String>, message: impl Into<String>) -> Self {
        ImportError::Unsupported {
            loc: loc.clone(),
            what: what.into(),
            message: message.into(),
        }
    }
}
