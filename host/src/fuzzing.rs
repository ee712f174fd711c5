//! The readers of outside data, each from bytes: the entry points of the
//! fuzz targets (`tests/tests/fuzz.rs`, issue 25 item 2).
//!
//! Why here and not in the tests: the readers are private to the commands
//! that use them (the ray file to `rtk trace`, the film file to `rtk render
//! --resume` and `rtk merge`), and a fuzz target must call the very code a
//! user's file reaches, minus the file system. Each target returns whether
//! the input was accepted; a refusal is an answer, a panic or a hang is
//! the defect the fuzzer looks for.

use std::path::Path;

/// A fuzz target: a name, the reader, and what makes good seeds for it.
pub struct Target {
    /// The reader's name in the fuzz figures.
    pub name: &'static str,
    /// Read the bytes; `Ok` if accepted, the message if refused.
    pub read: fn(&[u8]) -> Result<(), String>,
}

fn scene_text(bytes: &[u8]) -> Result<(), String> {
    let text = String::from_utf8_lossy(bytes).into_owned();
    let file =
        rtk_shell::SceneFile::parse(Path::new("fuzz.toml"), text).map_err(|e| e.to_string())?;
    rtk_shell::Desc::from_file(&file)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// The seed scene the `--set` target overrides.
pub const SET_BASE: &str = "[render]\nwidth = 8\nheight = 8\nroot = \"world\"\n\
[cameras.main]\nclass = \"pinhole\"\neye = [0.0, 0.0, 5.0]\n\
[objects.ball]\nclass = \"sphere\"\nradius = 1.0\n\
[objects.world]\nclass = \"list\"\nchildren = [\"ball\"]\n";

fn scene_sets(bytes: &[u8]) -> Result<(), String> {
    let sets: Vec<String> = String::from_utf8_lossy(bytes)
        .lines()
        .map(str::to_string)
        .collect();
    let mut file = rtk_shell::SceneFile::parse(Path::new("fuzz.toml"), SET_BASE.to_string())
        .map_err(|e| e.to_string())?;
    file.apply_overrides(&sets).map_err(|e| e.to_string())?;
    rtk_shell::Desc::from_file(&file)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

fn ray_file(bytes: &[u8]) -> Result<(), String> {
    crate::trace::rays::parse_rays(Path::new("fuzz.rays"), bytes)
        .map(|_| ())
        .map_err(|e| format!("{e:#}"))
}

fn film_file(bytes: &[u8]) -> Result<(), String> {
    crate::render::film_file::parse(
        Path::new("fuzz.rtkfilm"),
        &mut &bytes[..],
        bytes.len() as u64,
    )
    .map(|_| ())
    .map_err(|e| format!("{e:#}"))
}

fn pfm_image(bytes: &[u8]) -> Result<(), String> {
    crate::shared::images::parse_pfm(bytes)
        .map(|_| ())
        .map_err(|e| format!("{e:#}"))
}

fn npy_image(bytes: &[u8]) -> Result<(), String> {
    crate::shared::images::parse_npy(bytes)
        .map(|_| ())
        .map_err(|e| format!("{e:#}"))
}

/// A Mitsuba scene (`rtk import`): the bytes as a file of its own
/// folder, imported as `rtk import` does (its includes and meshes, named
/// relative to it, are mostly absent: a refusal like any other).
fn mitsuba_xml(bytes: &[u8]) -> Result<(), String> {
    let dir = tempfile::tempdir().map_err(|e| format!("a temporary folder: {e}"))?;
    let path = dir.path().join("fuzz.xml");
    std::fs::write(&path, bytes).map_err(|e| format!("writing {}: {e}", path.display()))?;
    let opts = rtk_import::Options {
        out_dir: dir.path().to_path_buf(),
        ..Default::default()
    };
    rtk_import::import(&path, &opts)
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// Every target.
pub const TARGETS: &[Target] = &[
    Target {
        name: "scene-toml",
        read: scene_text,
    },
    Target {
        name: "set-overrides",
        read: scene_sets,
    },
    Target {
        name: "ray-file",
        read: ray_file,
    },
    Target {
        name: "film-file",
        read: film_file,
    },
    Target {
        name: "pfm-image",
        read: pfm_image,
    },
    Target {
        name: "npy-image",
        read: npy_image,
    },
    Target {
        name: "mitsuba-xml",
        read: mitsuba_xml,
    },
];

/// A valid film file of a `width` x `height` image (seed for `film-file`).
pub fn film_seed(width: u32, height: u32) -> Vec<u8> {
    use crate::render::render_loop::{Accum, Rect};
    let accum = Accum::new(width, height, Rect::full(width, height)).expect("a small film");
    let r = rtk_shell::Desc::from_file(
        &rtk_shell::SceneFile::parse(Path::new("seed.toml"), SET_BASE.to_string())
            .expect("the seed scene"),
    )
    .expect("the seed scene checks")
    .render;
    let header = crate::render::film_file::Header::new(SET_BASE, &[], &r);
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = dir.path().join("seed.rtkfilm");
    crate::render::film_file::write(&path, &header, &accum).expect("writing the seed film");
    std::fs::read(&path).expect("reading the seed film")
}

/// A valid PFM and NPY image of 2x2 pixels (seeds for the image targets).
pub fn image_seeds() -> (Vec<u8>, Vec<u8>) {
    let img = crate::shared::images::Image::uniform(2, 2, [0.25, 0.5, 1.0]);
    (
        crate::shared::images::pfm_bytes(&img),
        crate::shared::images::npy_bytes(&img),
    )
}
