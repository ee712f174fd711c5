//! # rtk-import
//!
//! Scenes written for other renderers, translated to rtk's TOML scene
//! format (docs/import.md): `rtk import FILE.xml -o scene.toml` writes the
//! translation for a person to read and edit, and `rtk render FILE.xml`
//! renders it directly through the same code.
//!
//! The rule every translator here follows: what rtk cannot express exactly
//! is never silently dropped. An unsupported plugin, parameter or value is
//! an [`ImportError::Unsupported`] naming the file, line and column of its
//! element, the plugin and the parameter; with [`Options::lenient`] it is
//! dropped and reported as one warning line instead. A parameter whose
//! default rtk matches is accepted silently; a semantic difference (a
//! filter's footprint, a one-sided BSDF, a depth convention) is either
//! translated exactly or refused.
//!
//! - [`mitsuba`]: Mitsuba XML, versions 0.5, 2.x and 3.x;
//! - [`pbrt`]: pbrt-v4's scene format (a first subset);
//! - [`rtk_scene`]: the scene the translators build and its TOML text.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod error;
pub mod mitsuba;
pub mod pbrt;
pub mod rtk_scene;

pub use error::{ImportError, Loc};
use std::path::{Path, PathBuf};

/// How to import.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Drop what cannot be translated, with a warning each, instead of
    /// failing on the first.
    pub lenient: bool,
    /// Scene parameters given on the command line (Mitsuba's `-D
    /// name=value`), overriding the scene's `<default>`s.
    pub params: Vec<(String, String)>,
    /// The folder the TOML will be read from: file names in it are written
    /// relative to this folder.
    pub out_dir: PathBuf,
}

/// A translated scene.
#[derive(Debug)]
pub struct Imported {
    /// The rtk scene, as TOML text.
    pub toml: String,
    /// One line per thing dropped (lenient) or translated with a note.
    pub warnings: Vec<String>,
}

fn extension(path: &Path) -> String {
    (path.extension().and_then(|e| e.to_str()))
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// The formats an importer exists for, by file extension.
pub fn is_importable(path: &Path) -> bool {
    matches!(extension(path).as_str(), "xml" | "pbrt")
}

/// Import `path` by its extension.
pub fn import(path: &Path, opts: &Options) -> Result<Imported, ImportError> {
    match extension(path).as_str() {
        "xml" => mitsuba::import(path, opts),
        "pbrt" => pbrt::import(path, opts),
        _ => Err(ImportError::Read {
            path: path.to_path_buf(),
            message:
                "not a scene rtk can import: Mitsuba scenes end in .xml, pbrt-v4 scenes in .pbrt"
                    .into(),
        }),
    }
}
