//! `<texture type="bitmap">` → an rtk image texture with Mitsuba's lookup
//! (`to_uv`, `wrap`, `filter`, `v_origin = "top"`: the sdk's `Lookup`).
//!
//! Mitsuba reads an OBJ's texture coordinates with v flipped
//! (`flip_tex_coords`, on by default) and looks textures up with v = 0 at
//! the image's top row; rtk keeps the file's v. The flip is folded into the
//! translated `to_uv`, so the same texel is seen.

use super::{Props, Tx};
use crate::error::ImportError;
use crate::mitsuba::xml::{Obj, Value};
use crate::rtk_scene::{inline_table, Keys};
use toml::Value as T;

/// How the shape a texture is looked up on gives its uv, against
/// Mitsuba's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UvSource {
    /// The same uv as Mitsuba's (a rectangle, a PLY mesh).
    Same,
    /// Mitsuba's v is 1 − rtk's (an OBJ mesh with `flip_tex_coords`).
    FlippedV,
}

/// A texture's TOML value, or `None` when lenient dropped it.
pub fn texture(tx: &mut Tx, o: &Obj, key: &str) -> Result<Option<T>, ImportError> {
    if o.ty != "bitmap" {
        tx.refuse_plugin(o, "rtk translates the bitmap texture so far")?;
        return Ok(None);
    }
    let Some(uv) = tx.uv_source else {
        tx.refuse(ImportError::unsupported(
            &o.loc,
            format!("{} as `{key}`", o.what()),
            "a texture on a shape whose uv rtk does not parameterise as Mitsuba does (textures translate on OBJ, PLY and rectangle shapes)",
        ))?;
        return Ok(None);
    };
    let mut p = Props::new(o);
    let Some(f) = p.get("filename") else {
        return Err(ImportError::invalid(
            &o.loc,
            "<texture type=\"bitmap\"> needs `filename`",
        ));
    };
    let Value::Str(name) = &f.value else {
        return Err(ImportError::invalid(&f.loc, "`filename` is a <string>"));
    };
    let file = tx.file(&f.loc, name)?;
    check_size(&tx.doc.resolve(&f.loc, name), &f.loc)?;
    let lower = name.to_ascii_lowercase();
    let float = lower.ends_with(".exr") || lower.ends_with(".hdr") || lower.ends_with(".pfm");
    // Float images are linear either way; 8-bit ones are sRGB unless raw.
    let raw = p.bool("raw", false)? && !float;
    let filter = p.string("filter_type", "bilinear")?;
    let wrap = p.string("wrap_mode", "repeat")?;
    for (k, v, ok) in [
        ("filter_type", &filter, &["bilinear", "nearest"][..]),
        ("wrap_mode", &wrap, &["repeat", "mirror", "clamp"][..]),
    ] {
        if !ok.contains(&v.as_str()) {
            return Err(ImportError::invalid(
                &o.loc,
                format!(
                    "{}: {k} = \"{v}\": expected one of {}",
                    o.what(),
                    ok.join(", ")
                ),
            ));
        }
    }
    let m = match p.transform("to_uv")? {
        // Mitsuba's 2D affine part: rows 0, 1 and columns 0, 1, 3.
        Some(t) => [
            t.m[0][0], t.m[0][1], t.m[0][3], t.m[1][0], t.m[1][1], t.m[1][3],
        ],
        None => [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
    };
    // Mitsuba's uv from rtk's: (u, 1 − v) for a flipped OBJ.
    let m = match uv {
        UvSource::Same => m,
        UvSource::FlippedV => [m[0], -m[1], m[1] + m[2], m[3], -m[4], m[4] + m[5]],
    };
    p.ignore(&["format", "accel"]);
    p.finish(tx)?;
    let mut k: Keys = vec![("image_file".into(), T::String(file))];
    if m != [1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        k.push((
            "to_uv".into(),
            T::Array(m.iter().map(|x| T::Float(*x)).collect()),
        ));
    }
    k.push(("wrap".into(), T::String(wrap)));
    k.push(("filter".into(), T::String(filter)));
    k.push(("v_origin".into(), T::String("top".into())));
    if raw {
        k.push(("raw".into(), T::Boolean(true)));
    }
    Ok(Some(inline_table(k)))
}

/// Refuse at the scene's own element an image the renderer would refuse
/// (its header read, nothing decoded): unreadable, or beyond the sdk's
/// limits of texels a side and in all.
fn check_size(path: &std::path::Path, loc: &crate::error::Loc) -> Result<(), ImportError> {
    use rtk_sdk::texture::{MAX_SIDE, MAX_TEXELS};
    let dims = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| e.to_string())
        .and_then(|r| r.into_dimensions().map_err(|e| e.to_string()));
    let (w, h) = dims.map_err(|e| {
        ImportError::invalid(
            loc,
            format!(
                "the texture {}: not an image rtk reads (PNG, JPEG, EXR): {e}",
                path.display()
            ),
        )
    })?;
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE || w as u64 * h as u64 > MAX_TEXELS {
        return Err(ImportError::invalid(
            loc,
            format!(
                "the texture {} declares {w} x {h} texels: rtk's textures are 1 to {MAX_SIDE} a side and at most 2^26 in all",
                path.display()
            ),
        ));
    }
    Ok(())
}
