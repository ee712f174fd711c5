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
#[derive(Debug, Clone, PartialEq, Eq)]
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
        // A value from an included file carries its file: the error is
        // located there, whatever file the caller attaches later.
        let (origin, file) = match origin {
            Origin::Included(f, r) => (Origin::File(r.clone()), Some(FileText::clone(f))),
            o => (o.clone(), None),
        };
        SceneError {
            kind,
            origin,
            object: object.into(),
            key: key.into(),
            message: message.into(),
            notes: Vec::new(),
            file,
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
            write!(
                f,
                "{}",
                shown(&file.path.display().to_string(), MAX_SHOWN_PATH)
            )?;
        }
        match (&self.origin, self.line_col()) {
            (_, Some((line, col))) => write!(f, ":{line}:{col}: ")?,
            (Origin::CommandLine(s), _) => {
                write!(f, " (from --set {}): ", shown(s, MAX_SHOWN_NAME))?
            }
            _ if self.file.is_some() => f.write_str(": ")?,
            _ => {}
        }
        if !self.object.is_empty() {
            write!(f, "{}: ", shown(&self.object, MAX_SHOWN_NAME))?;
        }
        if !self.key.is_empty() {
            write!(f, "key `{}`: ", shown(&self.key, MAX_SHOWN_NAME))?;
        }
        f.write_str(&shown_message(&self.message))?;
        for n in &self.notes {
            write!(f, "\n  {}", shown(n, MAX_SHOWN_MESSAGE))?;
        }
        Ok(())
    }
}

/// Longest object path, key or `--set` shown, in characters: a scene may
/// hold a 10 MB key, and echoing it buries the message.
pub const MAX_SHOWN_NAME: usize = 120;
/// Longest path shown.
const MAX_SHOWN_PATH: usize = 1000;
/// Longest message or note shown, in characters.
pub const MAX_SHOWN_MESSAGE: usize = 2000;

/// `s` made safe to print on a terminal: control characters (escape
/// sequences could rewrite the screen or the title) become `\u{..}` escapes,
/// and text past `max` characters becomes an ellipsis.
pub fn shown(s: &str, max: usize) -> String {
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i == max {
            out.push('…');
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// A message made safe to print: every `quoted` value (the scene's own keys
/// and values, echoed by rtk or by serde) cut to [`MAX_SHOWN_NAME`]
/// characters, control characters escaped except the line breaks between a
/// message's own lines, and the whole cut to [`MAX_SHOWN_MESSAGE`].
pub fn shown_message(msg: &str) -> String {
    let quoted_cut: Vec<String> = msg
        .split('`')
        .enumerate()
        .map(|(i, part)| match i % 2 {
            1 => shown(part, MAX_SHOWN_NAME),
            _ => part.to_string(),
        })
        .collect();
    shown_lines(&quoted_cut.join("`"), MAX_SHOWN_MESSAGE)
}

/// [`shown`] line by line (the line breaks kept), the whole cut to `max`
/// characters.
fn shown_lines(s: &str, max: usize) -> String {
    let mut out = String::new();
    let mut left = max;
    for (i, line) in s.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        let n = line.chars().count();
        if n > left {
            out.push_str(&shown(line, left));
            break;
        }
        out.push_str(&shown(line, usize::MAX));
        left -= n;
    }
    out
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

    #[test]
    fn control_characters_are_escaped_and_long_values_cut() {
        let long = "k".repeat(10_000_000);
        let e = SceneError::invalid(
            &Origin::Whole,
            "objects.\x1b[2J",
            &long,
            format!("unknown field `{long}`, \x07expected\none of `a`"),
        );
        let s = e.to_string();
        assert!(s.len() < 1000, "{} bytes shown", s.len());
        assert!(!s.chars().any(|c| c.is_control() && c != '\n'), "{s:?}");
        assert!(s.contains("objects.\\u{1b}[2J"), "{s}");
        assert!(s.contains("…`"), "{s}");
        assert!(s.contains("\\u{7}expected\none of `a`"), "{s}");
    }
}
