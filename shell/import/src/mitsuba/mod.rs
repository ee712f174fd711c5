//! Mitsuba XML (versions 0.5 to 3.x) to rtk: [`xml`] reads the file the
//! way Mitsuba's parser does, [`translate`] maps each plugin to rtk's, and
//! what has no exact rtk equivalent is refused (or, lenient, dropped with a
//! warning) — never approximated.

pub mod spectrum;
pub mod transform;
pub mod translate;
pub mod xml;

use crate::error::ImportError;
use crate::{Imported, Options};
use std::path::Path;

/// Import the Mitsuba scene `path`.
pub fn import(path: &Path, opts: &Options) -> Result<Imported, ImportError> {
    let doc = xml::read(path, &opts.params)?;
    translate::scene(&doc, path, opts)
}
