//! The film file: a checkpoint (`--checkpoint`, `--resume`) and a crop for
//! `rtk merge` (`-o PART.rtkfilm`) are the same format, an [`Accum`] with a
//! header naming the scene and the settings it was rendered with.
//!
//! Layout, little-endian:
//!
//! | bytes | what |
//! |---|---|
//! | 8 | magic `RTKFILM2` (version 2: version 1 had no squares, and is refused) |
//! | 8 | FNV-1a 64 hash of the scene text and its `--set` overrides (those of the settings below excepted) |
//! | 4 × 3 | full width, full height, spp |
//! | 8 | seed |
//! | 4 | pixel filter: 0 none, 1 box, 2 tent, 3 gaussian, 4 mitsuba_gaussian |
//! | 4 | sampler: 0 independent, 1 stratified |
//! | 4 × 4 | the rectangle held: x0, y0, x1, y1 |
//! | 52 per pixel | row-major over the rectangle: the f64 sums of R, G, B, the f64 sums of their squares, then the u32 sample count |

use crate::render::render_loop::{Accum, Rect};
use anyhow::{bail, Context, Result};
use rtk_shell::desc::render::Filter;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

const MAGIC: &[u8; 8] = b"RTKFILM2";
/// The magic of the first version, which held no sums of squares: such a
/// file cannot give a variance, so it is refused by name rather than read
/// as something else.
const MAGIC_V1: &[u8; 8] = b"RTKFILM1";
const HEADER_BYTES: u64 = 8 + 8 + 12 + 8 + 4 + 4 + 16;
const PIXEL_BYTES: u64 = 52;

/// The file name extension of film files written as the render's output.
pub const EXTENSION: &str = "rtkfilm";

/// What a film was rendered from: refusing to mix films of different
/// scenes or settings is what keeps resume and merge exact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Hash of the scene text and the `--set` overrides.
    pub scene_hash: u64,
    /// Full image width.
    pub width: u32,
    /// Full image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed.
    pub seed: u64,
    /// Pixel filter code.
    pub filter: u32,
    /// Sampler code: 0 independent, 1 stratified.
    pub sampler: u32,
}

/// `--set` keys covered by the header's own fields (so `--spp 64` and
/// `--set render.spp=64` make the same scene hash).
const SETTINGS: [&str; 6] = [
    "render.width",
    "render.height",
    "render.spp",
    "render.seed",
    "render.filter",
    "render.sampler",
];

/// FNV-1a, 64 bits: stable across builds and platforms.
fn fnv1a(h: &mut u64, bytes: &[u8]) {
    for b in bytes {
        *h ^= *b as u64;
        *h = h.wrapping_mul(0x100_0000_01b3);
    }
}

impl Header {
    /// The header of a render of `scene_text` with overrides `sets` and
    /// settings `r`.
    pub fn new(scene_text: &str, sets: &[String], r: &rtk_shell::desc::render::Render) -> Header {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        fnv1a(&mut h, scene_text.as_bytes());
        for s in sets {
            let key = s.split('=').next().unwrap_or("").trim();
            if !SETTINGS.contains(&key) {
                fnv1a(&mut h, &[0]);
                fnv1a(&mut h, s.as_bytes());
            }
        }
        Header {
            scene_hash: h,
            width: r.width,
            height: r.height,
            spp: r.spp,
            seed: r.seed,
            filter: match r.filter {
                None => 0,
                Some(Filter::Box) => 1,
                Some(Filter::Tent) => 2,
                Some(Filter::Gaussian) => 3,
                Some(Filter::MitsubaGaussian) => 4,
            },
            sampler: r.stratified as u32,
        }
    }

    /// Why a film with header `self` (from `file`) cannot continue or join
    /// a render with header `want`, if it cannot.
    pub fn check_matches(&self, want: &Header, file: &Path, scene: &Path) -> Result<()> {
        let filter_name = |f: u32| {
            ["none", "box", "tent", "gaussian", "mitsuba_gaussian"]
                .get(f as usize)
                .copied()
                .unwrap_or("?")
        };
        let mut diffs = Vec::new();
        if (self.width, self.height) != (want.width, want.height) {
            diffs.push(format!(
                "image size {}x{} (this render: {}x{})",
                self.width, self.height, want.width, want.height
            ));
        }
        if self.spp != want.spp {
            diffs.push(format!("spp {} (this render: {})", self.spp, want.spp));
        }
        if self.seed != want.seed {
            diffs.push(format!("seed {} (this render: {})", self.seed, want.seed));
        }
        if self.filter != want.filter {
            diffs.push(format!(
                "filter {} (this render: {})",
                filter_name(self.filter),
                filter_name(want.filter)
            ));
        }
        if self.sampler != want.sampler {
            let name = |s: u32| if s == 1 { "stratified" } else { "independent" };
            diffs.push(format!(
                "sampler {} (this render: {})",
                name(self.sampler),
                name(want.sampler)
            ));
        }
        if !diffs.is_empty() {
            bail!(
                "{} was rendered with other settings: {}; it cannot be continued or merged with a render of {} with these settings",
                file.display(),
                diffs.join(", "),
                scene.display()
            );
        }
        if self.scene_hash != want.scene_hash {
            bail!(
                "{} was rendered from another scene than {} (the scene text or its --set overrides differ); refusing to mix them",
                file.display(),
                scene.display()
            );
        }
        Ok(())
    }
}

/// Write `accum` with `header` to `path` atomically (temporary file, then rename).
pub fn write(path: &Path, header: &Header, accum: &Accum) -> Result<()> {
    crate::shared::output::write_atomically(path, |tmp| {
        let f = std::fs::File::create(tmp)?;
        let mut w = BufWriter::new(f);
        w.write_all(MAGIC)?;
        w.write_all(&header.scene_hash.to_le_bytes())?;
        for v in [header.width, header.height, header.spp] {
            w.write_all(&v.to_le_bytes())?;
        }
        w.write_all(&header.seed.to_le_bytes())?;
        w.write_all(&header.filter.to_le_bytes())?;
        w.write_all(&header.sampler.to_le_bytes())?;
        let r = accum.rect;
        for v in [r.x0, r.y0, r.x1, r.y1] {
            w.write_all(&v.to_le_bytes())?;
        }
        for ((s, q), c) in accum.sums.iter().zip(&accum.squares).zip(&accum.counts) {
            for v in s.iter().chain(q) {
                w.write_all(&v.to_le_bytes())?;
            }
            w.write_all(&c.to_le_bytes())?;
        }
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        Ok(())
    })
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// Read a film file: its header and its film (allocated fallibly, after
/// checking that the file's size is what its header says).
pub fn read(path: &Path) -> Result<(Header, Accum)> {
    let what = || format!("reading the film file {}", path.display());
    let f = std::fs::File::open(path).with_context(what)?;
    let meta = f.metadata().with_context(what)?;
    if !meta.is_file() {
        bail!("{}: not a regular file", path.display());
    }
    parse(path, &mut BufReader::new(f), meta.len())
}

/// A film file of `len` bytes read from `r` (`path` names it in messages):
/// what [`read`] does once the file is open, and what the fuzz targets call
/// on bytes ([`crate::fuzzing`]).
pub(crate) fn parse(path: &Path, r: &mut impl Read, len: u64) -> Result<(Header, Accum)> {
    let (header, rect) = read_header(path, r, len)?;
    let want = HEADER_BYTES + rect.len() as u64 * PIXEL_BYTES;
    if len != want {
        bail!(
            "{}: the film file is {} bytes, its header says {want}: truncated or damaged",
            path.display(),
            len
        );
    }
    let mut accum = Accum::new(header.width, header.height, rect)
        .map_err(|m| anyhow::anyhow!("{}: {m}", path.display()))?;
    read_pixels(path, r, &header, &mut accum)?;
    Ok((header, accum))
}

/// The header of a film file of `len` bytes and the rectangle of the image
/// it holds, refused unless it is a film file and its values make sense.
fn read_header(path: &Path, r: &mut impl Read, len: u64) -> Result<(Header, Rect)> {
    let mut head = [0u8; HEADER_BYTES as usize];
    let read = len >= HEADER_BYTES && r.read_exact(&mut head).is_ok();
    if read && &head[..8] == MAGIC_V1 {
        bail!(
            "{} is a film file of version 1 (an rtk before the sums of squares): this rtk reads version 2 only; render it again",
            path.display()
        );
    }
    if !read || &head[..8] != MAGIC {
        bail!(
            "{} is not an rtk film file (checkpoint or crop): it does not start with {}",
            path.display(),
            String::from_utf8_lossy(MAGIC)
        );
    }
    let header = Header {
        scene_hash: u64_at(&head, 8),
        width: u32_at(&head, 16),
        height: u32_at(&head, 20),
        spp: u32_at(&head, 24),
        seed: u64_at(&head, 28),
        filter: u32_at(&head, 36),
        sampler: u32_at(&head, 40),
    };
    let rect = Rect {
        x0: u32_at(&head, 44),
        y0: u32_at(&head, 48),
        x1: u32_at(&head, 52),
        y1: u32_at(&head, 56),
    };
    if header.filter > 4
        || header.sampler > 1
        || !(1..=65536).contains(&header.width)
        || !(1..=65536).contains(&header.height)
        || header.width as u64 * header.height as u64 > rtk_shell::desc::MAX_PIXELS
        || !(1..=1 << 24).contains(&header.spp)
        || rect.x0 >= rect.x1
        || rect.y0 >= rect.y1
        || rect.x1 > header.width
        || rect.y1 > header.height
    {
        bail!(
            "{}: a damaged film header (image {}x{}, {} spp, rectangle {rect})",
            path.display(),
            header.width,
            header.height,
            header.spp
        );
    }
    Ok((header, rect))
}

/// Fill `accum` with the pixels that follow the header, refusing sums that
/// are not finite and counts above the film's spp (a damaged file).
fn read_pixels(path: &Path, r: &mut impl Read, header: &Header, accum: &mut Accum) -> Result<()> {
    let mut px = [0u8; PIXEL_BYTES as usize];
    let pixels = (accum.sums.iter_mut())
        .zip(accum.squares.iter_mut())
        .zip(accum.counts.iter_mut());
    for ((s, q), c) in pixels {
        r.read_exact(&mut px)
            .with_context(|| format!("reading the film file {}", path.display()))?;
        *s = std::array::from_fn(|k| f64::from_bits(u64_at(&px, 8 * k)));
        *q = std::array::from_fn(|k| f64::from_bits(u64_at(&px, 24 + 8 * k)));
        *c = u32_at(&px, 48);
        if !s.iter().all(|x| x.is_finite()) {
            bail!(
                "{}: a pixel's sum is not a finite number: damaged",
                path.display()
            );
        }
        if !q.iter().all(|x| x.is_finite() && *x >= 0.0) {
            bail!(
                "{}: a pixel's sum of squares is not a finite non-negative number: damaged",
                path.display()
            );
        }
        if *c > header.spp {
            bail!(
                "{}: a pixel has {} samples, more than the film's {} spp: damaged",
                path.display(),
                *c,
                header.spp
            );
        }
    }
    Ok(())
}

/// Parse `--crop x0,y0,x1,y1` against the image size.
pub fn parse_crop(s: &str, width: u32, height: u32) -> Result<Rect> {
    let v: Vec<u32> = s
        .split(',')
        .map(|p| p.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            anyhow::anyhow!("--crop {s}: expected x0,y0,x1,y1 (four non-negative integers)")
        })?;
    let [x0, y0, x1, y1] = v[..] else {
        bail!("--crop {s}: expected x0,y0,x1,y1 (four non-negative integers)");
    };
    if x0 >= x1 || y0 >= y1 || x1 > width || y1 > height {
        bail!(
            "--crop {s}: the rectangle [x0, x1) x [y0, y1) must be non-empty and inside the {width}x{height} image"
        );
    }
    Ok(Rect { x0, y0, x1, y1 })
}

/// Does `path` name a film file (`.rtkfilm`)?
pub fn is_film_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(EXTENSION))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Header {
        Header {
            scene_hash: 0x1234_5678_9abc_def0,
            width: 5,
            height: 4,
            spp: 9,
            seed: 7,
            filter: 2,
            sampler: 1,
        }
    }

    #[test]
    fn a_film_file_round_trips_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f.rtkfilm");
        let rect = Rect {
            x0: 1,
            y0: 2,
            x1: 4,
            y1: 4,
        };
        let mut a = Accum::new(5, 4, rect).unwrap();
        for (i, (s, c)) in a.sums.iter_mut().zip(a.counts.iter_mut()).enumerate() {
            *s = [0.1 * i as f64, -0.0, f64::MIN_POSITIVE / 3.0];
            *c = i as u32 % 10;
        }
        for (i, q) in a.squares.iter_mut().enumerate() {
            *q = [0.01 * i as f64, 0.0, 1e300];
        }
        write(&p, &header(), &a).unwrap();
        let (h, b) = read(&p).unwrap();
        assert_eq!(h, header());
        assert_eq!(b.rect, rect);
        assert_eq!((b.full_width, b.full_height), (5, 4));
        assert_eq!(b.counts, a.counts);
        let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&b.sums), bits(&a.sums));
        assert_eq!(bits(&b.squares), bits(&a.squares));
        // Truncated: refused with the sizes.
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() - 1]).unwrap();
        let e = read(&p).err().unwrap().to_string();
        assert!(e.contains("truncated or damaged"), "{e}");
        // A version 1 file (no squares): refused by its version.
        let mut v1 = bytes.clone();
        v1[..8].copy_from_slice(MAGIC_V1);
        std::fs::write(&p, &v1).unwrap();
        let e = read(&p).err().unwrap().to_string();
        assert!(e.contains("version 1") && e.contains("version 2"), "{e}");
    }

    #[test]
    fn headers_name_what_differs() {
        let (a, mut b) = (header(), header());
        assert!(a.check_matches(&b, Path::new("c"), Path::new("s")).is_ok());
        b.seed = 8;
        let e = a
            .check_matches(&b, Path::new("c"), Path::new("s"))
            .unwrap_err();
        assert!(e.to_string().contains("seed 7 (this render: 8)"), "{e}");
        let mut b = header();
        b.scene_hash ^= 1;
        let e = a
            .check_matches(&b, Path::new("c"), Path::new("s"))
            .unwrap_err();
        assert!(e.to_string().contains("from another scene"), "{e}");
    }

    #[test]
    fn crops_must_lie_inside_the_image() {
        assert_eq!(
            parse_crop("1, 2,3,4", 10, 10).unwrap(),
            Rect {
                x0: 1,
                y0: 2,
                x1: 3,
                y1: 4
            }
        );
        for bad in ["1,2,3", "3,0,3,4", "0,0,11,4", "a,b,c,d", "-1,0,2,2"] {
            assert!(parse_crop(bad, 10, 10).is_err(), "{bad}");
        }
    }
}
