//! Image output: PNG (8-bit sRGB) and OpenEXR (linear f32), written to a
//! temporary file beside the target and renamed into place, so that a failed
//! or interrupted run never leaves a half-written image.

use crate::render::render_loop::Film;
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// Output formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// 8-bit sRGB PNG.
    Png,
    /// Linear 32-bit float OpenEXR.
    Exr,
    /// rtk's film file (f64 sums and sample counts: checkpoints and crops,
    /// `crate::render::film_file`), written by the caller, not by [`write()`].
    Film,
}

/// The format an output path asks for (checked before rendering).
pub fn format_of(path: &Path) -> Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") => Ok(Format::Png),
        Some("exr") => Ok(Format::Exr),
        Some(crate::render::film_file::EXTENSION) => Ok(Format::Film),
        _ => bail!(
            "output {}: the file name must end in .png or .exr (or .rtkfilm, a film file: docs/farm.md)",
            path.display()
        ),
    }
}

/// Check, before spending time rendering, that the output can be written:
/// its name says a format, it is not a folder, and its folder exists and
/// takes a new file (tried by creating and removing an empty one: only the
/// file system knows about read-only mounts, ACLs and quotas).
pub fn check_writable(path: &Path) -> Result<()> {
    format_of(path)?;
    check_can_create(path, "output")
}

/// Check that the file `path` (`what`: output, checkpoint) can be created:
/// its folder exists and takes a new file, and it is not a folder.
pub fn check_can_create(path: &Path, what: &str) -> Result<()> {
    let dir = parent(path);
    if !dir.is_dir() {
        bail!(
            "{what} {}: the folder {} does not exist",
            path.display(),
            dir.display()
        );
    }
    if path.is_dir() {
        bail!("{what} {}: is a folder", path.display());
    }
    let probe = temp_path(path, "probe");
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => bail!(
            "{what} {}: cannot write in the folder {}: {e}",
            path.display(),
            dir.display()
        ),
    }
}

/// Remove the temporaries `.NAME.PID.tmp` beside `path` whose process is
/// gone (a run killed while writing): best effort, where `/proc` tells
/// which processes live; a live process's temporary is never touched.
fn remove_stale_temporaries(path: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let prefix = format!(".{name}.");
    let Ok(entries) = std::fs::read_dir(parent(path)) else {
        return;
    };
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let pid = file
            .strip_prefix(&prefix)
            .and_then(|r| r.strip_suffix(".tmp"))
            .and_then(|p| p.parse::<u32>().ok());
        if let Some(pid) = pid {
            let gone = pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists();
            if gone && e.file_type().is_ok_and(|t| t.is_file()) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// A hidden file beside `path` for this process: `.NAME.PID.KIND`.
fn temp_path(path: &Path, kind: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    parent(path).join(format!(".{name}.{}.{kind}", std::process::id()))
}

/// `film`'s pixels converted by `f`, in a buffer allocated fallibly: the
/// 8-bit or f32 copy of a large image must fail with a message, not abort.
fn converted<T>(film: &Film, f: impl Fn(f64) -> T) -> Result<Vec<T>> {
    let mut data = Vec::new();
    data.try_reserve_exact(film.pixels.len() * 3).map_err(|_| {
        anyhow::anyhow!(
            "cannot allocate the {}x{} image to write",
            film.width,
            film.height
        )
    })?;
    data.extend(film.pixels.iter().flat_map(|p| p.map(&f)));
    Ok(data)
}

fn parent(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Linear to sRGB-encoded 8-bit.
pub fn srgb8(v: f64) -> u8 {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let e = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// Write the film atomically.
pub fn write(film: &Film, path: &Path) -> Result<()> {
    let fmt = format_of(path)?;
    write_atomically(path, |tmp| {
        match fmt {
            Format::Png => {
                let data = converted(film, srgb8)?;
                let img = image::RgbImage::from_raw(film.width, film.height, data)
                    .context("image size")?;
                img.save_with_format(tmp, image::ImageFormat::Png)?;
            }
            Format::Exr => {
                let data = converted(film, |v| v as f32)?;
                let img = image::Rgb32FImage::from_raw(film.width, film.height, data)
                    .context("image size")?;
                img.save_with_format(tmp, image::ImageFormat::OpenExr)?;
            }
            Format::Film => bail!("a film file is written from the render's sums, not an image"),
        }
        Ok(())
    })
}

/// Write `path` atomically: `fill` writes a temporary file beside it, which
/// is renamed into place only if `fill` succeeds (and removed otherwise).
/// The temporary is flushed to the disk before the rename, so that after a
/// crash the target holds the old file or the whole new one. Temporaries of
/// `path` that a killed run left behind are removed first.
pub fn write_atomically(path: &Path, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    remove_stale_temporaries(path);
    let tmp = temp_path(path, "tmp");
    let res = fill(&tmp).and_then(|()| {
        std::fs::File::open(&tmp)?.sync_all()?;
        Ok(std::fs::rename(&tmp, path)?)
    });
    if res.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    res.with_context(|| format!("writing {}", path.display()))
}
