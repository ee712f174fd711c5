//! The shell's error: what went wrong and where — the origin (a span of the
//! scene file, or a `--set` on the command line), the object path and the key.
//!
//! Errors are made where the problem is found, with its [`Origin`] only; the
//! file is attached once, on the way out ([`SceneError::in_file`]), and the
//! span becomes `line:column` only when the error is shown.

use crate::tree::{line_col, Origin};
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

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

/// The scene file an error is located in: its path and text.
#[derive(Debug, Clone)]
pub struct FileText {
    /// Path as given on the command line (messages show it unchanged).
    pub path: PathBuf,
    /// The text the spans index.
    pub src: Arc<str>,
}

/// A scene error. Its `Display` reads
/// `FILE:LINE:COL: OBJECT: key `KEY`: MESSAGE` followed by any notes.
#[derive(Debug, Clone)]
pub struct SceneError {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// Where in the input.
    pub origin: Origin,
    /// Object path such as `objects.ball` (empty for the document).
    pub object: String,
    /// Key path within the object (empty when the object as a whole is at fault).
    pub key: String,
    /// The message.
    pub message: String,
    /// Further lines (folders searched, classes found...).
    pub notes: Vec<String>,
    /// The file, once attached.
    pub file: Option<FileText>,
}

impl SceneError {
    /// An error at `origin`, about `key` of `object`.
    pub fn new(
        kind: ErrorKind,
        origin: &Origin,
        object: impl Into<String>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError {
            kind,
            origin: origin.clone(),
            object: object.into(),
            key: key.into(),
            message: message.into(),
            notes: Vec::new(),
            file: None,
        }
    }

    /// An [`ErrorKind::Invalid`] error: the common case.
    pub fn invalid(
        origin: &Origin,
        object: impl Into<String>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::new(ErrorKind::Invalid, origin, object, key, message)
    }

    /// Add a note line.
    pub fn note(mut self, n: impl Into<String>) -> Self {
        self.notes.push(n.into());
        self
    }

    /// Attach the file the origin refers to (kept if one is already attached).
    pub fn in_file(mut self, file: &FileText) -> Self {
        self.file.get_or_insert_with(|| file.clone());
        self
    }

    /// 1-based line and column of the origin, when it is in the file.
    pub fn line_col(&self) -> Option<(usize, usize)> {
        match (&self.origin, &self.file) {
            (Origin::File(r), Some(f)) => Some(line_col(&f.src, r.start)),
            _ => None,
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}", file.path.display())?;
        }
        match (&self.origin, self.line_col()) {
            (_, Some((line, col))) => write!(f, ":{line}:{col}: ")?,
            (Origin::CommandLine(s), _) => write!(f, " (from --set {s}): ")?,
            _ if self.file.is_some() => f.write_str(": ")?,
            _ => {}
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_with_line_and_column_once_the_file_is_attached() {
        let file = FileText {
            path: "s.toml".into(),
            src: "a = 1\nb = 2\n".into(),
        };
        let e = SceneError::invalid(&Origin::File(10..11), "render", "b", "too big");
        assert_eq!(e.to_string(), "render: key `b`: too big");
        let e = e.in_file(&file).note("see above");
        assert_eq!(
            e.to_string(),
            "s.toml:2:5: render: key `b`: too big\n  see above"
        );
        let c =
            SceneError::invalid(&Origin::CommandLine("x=1".into()), "", "x", "bad").in_file(&file);
        assert_eq!(c.to_string(), "s.toml (from --set x=1): key `x`: bad");
    }
}
