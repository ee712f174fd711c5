//! pbrt-v4's scene format to rtk: the directives read in order with
//! pbrt's graphics state (`AttributeBegin`/`End`, the current transform,
//! material and area light), each translated as it comes; what rtk cannot
//! express exactly is refused at its directive or parameter, as for
//! Mitsuba ([`crate::mitsuba`]).
//!
//! pbrt's conventions, kept: transforms post-multiply the current one (the
//! last written applies first to the shape), `Transform` and
//! `ConcatTransform` list their matrices column by column, the camera's
//! transform is the world-to-camera one in effect at `Camera`, `maxdepth`
//! counts bounces (rtk's `max_depth` counts segments: one more), and pbrt's
//! image x runs along the camera's +x (a left-handed view: a scene meant to
//! look as in a right-handed renderer mirrors it, usually `Scale -1 1 1`).

mod lexer;
mod params;
mod translate;

use crate::error::{ImportError, Loc};
use crate::{Imported, Options};
use lexer::{Tok, Token};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Deepest chain of `Include`/`Import`.
pub const MAX_INCLUDE_DEPTH: usize = 16;

/// Import the pbrt-v4 scene `path`.
pub fn import(path: &Path, opts: &Options) -> Result<Imported, ImportError> {
    let mut stack = Vec::new();
    let toks = read_tokens(path, None, &mut stack)?;
    translate::scene(&toks, path, opts)
}

/// The tokens of `path` with every `Include` and `Import` replaced by its
/// file's tokens (relative to the including file; cycles and more than
/// [`MAX_INCLUDE_DEPTH`] levels refused).
fn read_tokens(
    path: &Path,
    at: Option<&Loc>,
    stack: &mut Vec<PathBuf>,
) -> Result<Vec<Token>, ImportError> {
    let key = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    if let Some(at) = at {
        if let Some(i) = stack.iter().position(|p| *p == key) {
            let chain: Vec<String> = stack[i..]
                .iter()
                .chain([&key])
                .map(|p| p.display().to_string())
                .collect();
            return Err(ImportError::invalid(
                at,
                format!("include cycle: {}", chain.join(" -> ")),
            ));
        }
        if stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(ImportError::invalid(
                at,
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep"),
            ));
        }
    }
    let text = crate::mitsuba::xml::read_text(path).map_err(|e| match (e, at) {
        (ImportError::Read { path, message }, Some(at)) => ImportError::invalid(
            at,
            format!("the included file {}: {message}", path.display()),
        ),
        (e, _) => e,
    })?;
    let file = Arc::new(path.to_path_buf());
    let toks = lexer::tokens(&file, &text)?;
    stack.push(key);
    let mut out = Vec::with_capacity(toks.len());
    let mut i = 0;
    while i < toks.len() {
        let t = &toks[i];
        if let Tok::Word(w) = &t.tok {
            if w == "Include" || w == "Import" {
                let Some(Token {
                    tok: Tok::Str(name),
                    ..
                }) = toks.get(i + 1)
                else {
                    return Err(ImportError::invalid(
                        &t.loc,
                        format!("{w} needs a file name"),
                    ));
                };
                let inner = path.parent().unwrap_or(Path::new(".")).join(name);
                out.extend(read_tokens(&inner, Some(&t.loc), stack)?);
                i += 2;
                continue;
            }
        }
        out.push(t.clone());
        i += 1;
    }
    stack.pop();
    Ok(out)
}
