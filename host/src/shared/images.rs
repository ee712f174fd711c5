//! Reading images to compare, and the error metrics of `rtk diff` and
//! `rtk converge`: those of the Mitsuba anchor's `compare.py`
//! (`../shared/anchors/mitsuba/`), over all pixels and the 3 channels of
//! linear radiance, accumulated in f64, nothing clamped:
//!
//! - `rmse = sqrt(mean((img - ref)^2))`
//! - `relmse = mean((img - ref)^2 / (ref^2 + 0.01))`
//!
//! Formats, by extension: OpenEXR (linear float, through `image`), PFM
//! (`PF` colour or `Pf` grey, rows bottom to top, the scale's sign giving the
//! byte order), NumPy `.npy` (float32 or float64, shape (H, W, C) with C of 1,
//! 3 or more, or (H, W); C order; row 0 at the top) and PNG (8- or 16-bit,
//! sRGB-encoded: decoded to linear; 8 bits are too coarse for small errors).

use anyhow::{bail, Context, Result};
use std::path::Path;

/// `relmse`'s regulariser (compare.py's `RELMSE_EPS`).
pub const RELMSE_EPS: f64 = 0.01;

/// Largest image read, in pixels: rtk's own limit on renders (2^28).
const MAX_PIXELS: u64 = 1 << 28;

/// A linear RGB image, row-major from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// RGB triples, `width * height * 3` values.
    pub data: Vec<f32>,
}

impl Image {
    /// An image of one colour.
    pub fn uniform(width: u32, height: u32, rgb: [f32; 3]) -> Image {
        let n = width as usize * height as usize;
        Image {
            width,
            height,
            data: rgb.iter().copied().cycle().take(n * 3).collect(),
        }
    }
}

/// The error of an image against a reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// Root mean squared error.
    pub rmse: f64,
    /// Mean of squared error over (reference² + 0.01).
    pub relmse: f64,
}

/// The metrics of `img` against `reference` (the same number of values:
/// RGB triples of images of the same size), accumulated in f64.
pub fn metrics<A: Copy + Into<f64>>(img: &[A], reference: &[f32]) -> Metrics {
    debug_assert_eq!(img.len(), reference.len());
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (&a, &b) in img.iter().zip(reference) {
        let (a, b) = (a.into(), b as f64);
        let d2 = (a - b) * (a - b);
        se += d2;
        rel += d2 / (b * b + RELMSE_EPS);
    }
    let n = img.len().max(1) as f64;
    Metrics {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
    }
}

/// Check that two images have the same size, naming both.
pub fn check_same_size(a: (u32, u32), a_name: &str, b: (u32, u32), b_name: &str) -> Result<()> {
    if a != b {
        bail!(
            "the images differ in size: {a_name} is {}x{}, {b_name} is {}x{}",
            a.0,
            a.1,
            b.0,
            b.1
        );
    }
    Ok(())
}

/// Read an image of any supported format (by its extension).
pub fn read(path: &Path) -> Result<Image> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let res = match ext.as_deref() {
        Some("pfm") => std::fs::read(path)
            .context("cannot read it")
            .and_then(|b| parse_pfm(&b)),
        Some("npy") => std::fs::read(path)
            .context("cannot read it")
            .and_then(|b| parse_npy(&b)),
        Some("exr") => read_with_image(path, false),
        Some("png") => read_with_image(path, true),
        _ => Err(anyhow::anyhow!(
            "unsupported image type: use .exr, .pfm, .npy (float32 H x W x 3) or .png"
        )),
    };
    res.with_context(|| format!("image {}", path.display()))
}

/// EXR (linear) or PNG (sRGB, decoded to linear) through the `image` crate.
fn read_with_image(path: &Path, srgb: bool) -> Result<Image> {
    let img = image::ImageReader::open(path)
        .context("cannot open it")?
        .with_guessed_format()
        .context("cannot read it")?
        .decode()?
        .into_rgb32f();
    let (width, height) = (img.width(), img.height());
    let mut data = img.into_raw();
    if srgb {
        for v in &mut data {
            *v = srgb_to_linear(*v as f64) as f32;
        }
    }
    Ok(Image {
        width,
        height,
        data,
    })
}

/// The sRGB transfer function, inverted: encoded [0, 1] to linear.
pub fn srgb_to_linear(v: f64) -> f64 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Pixels of a `w` x `h` image, refused beyond rtk's limit.
fn pixel_count(w: u64, h: u64) -> Result<usize> {
    if w == 0 || h == 0 {
        bail!("the image is empty ({w}x{h})");
    }
    if w > u32::MAX as u64 || h > u32::MAX as u64 || w * h > MAX_PIXELS {
        bail!("{w}x{h} is more than rtk's limit of {MAX_PIXELS} pixels");
    }
    Ok((w * h) as usize)
}

/// A PFM file: `PF` (RGB) or `Pf` (grey), width, height, scale (negative:
/// little-endian floats), one whitespace byte, then the rows from the bottom.
pub fn parse_pfm(bytes: &[u8]) -> Result<Image> {
    let mut pos = 0;
    let mut token = || pfm_token(bytes, &mut pos);
    let channels = match token()? {
        "PF" => 3,
        "Pf" => 1,
        _ => bail!("not a PFM file: it must start with `PF` or `Pf`"),
    };
    let dim = |s: &str, what: &str| -> Result<u64> {
        s.parse::<u64>()
            .map_err(|_| anyhow::anyhow!("PFM header: bad {what} `{s}`"))
    };
    let w = dim(token()?, "width")?;
    let h = dim(token()?, "height")?;
    let scale_s = token()?;
    let scale: f64 = scale_s
        .parse()
        .ok()
        .filter(|s: &f64| s.is_finite() && *s != 0.0)
        .with_context(|| format!("PFM header: bad scale `{scale_s}`"))?;
    let little = scale < 0.0;
    // Exactly one whitespace byte ends the header.
    if pos >= bytes.len() || !bytes[pos].is_ascii_whitespace() {
        bail!("PFM header: no data after the scale");
    }
    let body = &bytes[pos + 1..];
    let n = pixel_count(w, h)?;
    let need = n * channels * 4;
    if body.len() < need {
        bail!(
            "PFM {w}x{h}x{channels}: {need} bytes of data expected, the file holds {}",
            body.len()
        );
    }
    let (w, h) = (w as usize, h as usize);
    let mut data = Vec::with_capacity(n * 3);
    for row in (0..h).rev() {
        for x in 0..w {
            let i = (row * w + x) * channels;
            let mut px = [0.0f32; 3];
            for (c, v) in px.iter_mut().enumerate() {
                let o = (i + c.min(channels - 1)) * 4;
                let b = [body[o], body[o + 1], body[o + 2], body[o + 3]];
                *v = if little {
                    f32::from_le_bytes(b)
                } else {
                    f32::from_be_bytes(b)
                };
            }
            data.extend_from_slice(&px);
        }
    }
    Ok(Image {
        width: w as u32,
        height: h as u32,
        data,
    })
}

/// The next whitespace-separated word of a PFM header.
fn pfm_token<'a>(bytes: &'a [u8], pos: &mut usize) -> Result<&'a str> {
    while *pos < bytes.len() && bytes[*pos].is_ascii_whitespace() {
        *pos += 1;
    }
    let start = *pos;
    while *pos < bytes.len() && !bytes[*pos].is_ascii_whitespace() && *pos - start < 64 {
        *pos += 1;
    }
    std::str::from_utf8(&bytes[start..*pos]).context("not a PFM file: bad header")
}

/// Write a PFM (RGB, little-endian, rows bottom to top).
pub fn pfm_bytes(img: &Image) -> Vec<u8> {
    let mut out = format!("PF\n{} {}\n-1.0\n", img.width, img.height).into_bytes();
    let w = img.width as usize * 3;
    for row in img.data.chunks_exact(w.max(1)).rev() {
        for v in row {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// A NumPy `.npy` array of float32 or float64, C order, shape (H, W, C)
/// (C = 1: grey; C >= 3: the first three channels) or (H, W); row 0 at the top.
pub fn parse_npy(bytes: &[u8]) -> Result<Image> {
    let (header, start) = npy_header(bytes)?;
    let dtype = npy_dtype(header)?;
    if npy_value(header, "fortran_order")? != "False" {
        bail!(".npy in Fortran order is not supported: save it C-contiguous");
    }
    let shape_s = npy_value(header, "shape")?;
    let (h, w, channels) = npy_shape(shape_s)?;
    let n = pixel_count(w, h)?;
    let body = &bytes[start..];
    let need = (n as u64)
        .checked_mul(channels as u64 * dtype.size as u64)
        .context(".npy too large")?;
    if (body.len() as u64) < need {
        bail!(
            ".npy {shape_s}: {need} bytes of data expected, the file holds {}",
            body.len()
        );
    }
    let mut data = Vec::with_capacity(n * 3);
    for p in 0..n {
        for c in 0..3 {
            data.push(dtype.value(body, p * channels + c.min(channels - 1)));
        }
    }
    Ok(Image {
        width: w as u32,
        height: h as u32,
        data,
    })
}

/// The header dict of a .npy file (versions 1 to 3) and where its data starts.
fn npy_header(bytes: &[u8]) -> Result<(&str, usize)> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        bail!("not a .npy file");
    }
    let (header_len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => bail!(".npy format version {v} is not supported"),
    };
    let header = bytes
        .get(start..start + header_len)
        .context(".npy header truncated")?;
    let header = std::str::from_utf8(header).context(".npy header is not text")?;
    Ok((header, start + header_len))
}

/// A .npy element type rtk reads: float32 or float64, either byte order.
#[derive(Clone, Copy)]
struct NpyFloat {
    /// Bytes per value: 4 or 8.
    size: usize,
    little: bool,
}

impl NpyFloat {
    /// Value `i` of `body`, as f32.
    fn value(self, body: &[u8], i: usize) -> f32 {
        let o = i * self.size;
        if self.size == 4 {
            let b = [body[o], body[o + 1], body[o + 2], body[o + 3]];
            if self.little {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        } else {
            let mut b = [0u8; 8];
            b.copy_from_slice(&body[o..o + 8]);
            (if self.little {
                f64::from_le_bytes(b)
            } else {
                f64::from_be_bytes(b)
            }) as f32
        }
    }
}

/// The header's `descr`, when it is a type rtk reads.
fn npy_dtype(header: &str) -> Result<NpyFloat> {
    let descr = npy_value(header, "descr")?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    let (size, little) = match descr {
        "<f4" => (4, true),
        ">f4" => (4, false),
        "<f8" => (8, true),
        ">f8" => (8, false),
        d => bail!(".npy dtype `{d}` is not supported: float32 or float64"),
    };
    Ok(NpyFloat { size, little })
}

/// Height, width and channels from the header's `shape` text: (H, W, C)
/// with C = 1 or C >= 3, or (H, W).
fn npy_shape(shape_s: &str) -> Result<(u64, u64, usize)> {
    let shape: Vec<u64> = shape_s
        .trim_matches(|c| c == '(' || c == ')')
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<u64>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!(".npy shape `{shape_s}` is not a tuple of integers"))?;
    Ok(match shape[..] {
        [h, w] => (h, w, 1),
        [h, w, c] if c == 1 || c >= 3 => (h, w, c as usize),
        _ => bail!(".npy shape {shape_s}: expected (H, W, 3), (H, W, 1) or (H, W)"),
    })
}

/// The text of `'key': value` in a .npy header dict (up to the next `,` at
/// the top level or the closing brace).
fn npy_value<'a>(header: &'a str, key: &str) -> Result<&'a str> {
    let pat = format!("'{key}':");
    let at = header
        .find(&pat)
        .with_context(|| format!(".npy header has no `{key}`"))?;
    let rest = header[at + pat.len()..].trim_start();
    let mut depth = 0;
    let end = rest
        .char_indices()
        .find(|&(_, c)| match c {
            '(' => {
                depth += 1;
                false
            }
            ')' => {
                depth -= 1;
                false
            }
            ',' | '}' => depth == 0,
            _ => false,
        })
        .map_or(rest.len(), |(i, _)| i);
    Ok(rest[..end].trim())
}

/// Write a .npy: float32, little-endian, (H, W, 3), C order.
pub fn npy_bytes(img: &Image) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}, 3), }}",
        img.height, img.width
    );
    // Magic (6) + version (2) + length (2) + dict + padding + '\n' to a multiple of 64.
    let unpadded = 10 + dict.len() + 1;
    let pad = (64 - unpadded % 64) % 64;
    let header = format!("{dict}{}\n", " ".repeat(pad));
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in &img.data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Image {
        // 3x2, every value distinct, exactly representable.
        Image {
            width: 3,
            height: 2,
            data: (0..18).map(|i| i as f32 * 0.25 - 1.0).collect(),
        }
    }

    #[test]
    fn pfm_round_trips_with_rows_bottom_to_top() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.pfm");
        let img = sample();
        std::fs::write(&p, pfm_bytes(&img)).unwrap();
        assert_eq!(read(&p).unwrap(), img);
        // The first stored row is the image's bottom row.
        let bytes = pfm_bytes(&img);
        let body = &bytes[bytes.len() - 18 * 4..];
        assert_eq!(
            f32::from_le_bytes(body[..4].try_into().unwrap()),
            img.data[9]
        );
    }

    #[test]
    fn pfm_big_endian_and_grey() {
        // Pf, 2x1, big-endian (positive scale), two-line header variant.
        let mut b = b"Pf\n2\n1\n1.0\n".to_vec();
        b.extend_from_slice(&0.5f32.to_be_bytes());
        b.extend_from_slice(&2.0f32.to_be_bytes());
        let img = parse_pfm(&b).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        assert_eq!(img.data, vec![0.5, 0.5, 0.5, 2.0, 2.0, 2.0]);
    }

    #[test]
    fn pfm_errors() {
        assert!(parse_pfm(b"P6\n1 1\n255\n").is_err());
        let e = parse_pfm(b"PF\n2 2\n-1.0\n\0\0\0\0").unwrap_err();
        assert!(e.to_string().contains("48 bytes"), "{e}");
        assert!(parse_pfm(b"PF\n2 2\n0\n").is_err());
        assert!(parse_pfm(b"PF\n0 2\n-1\n").is_err());
    }

    #[test]
    fn npy_round_trips_row_zero_at_top() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npy");
        let img = sample();
        let bytes = npy_bytes(&img);
        assert_eq!((bytes.len() - 18 * 4) % 64, 0, "header padded to 64");
        std::fs::write(&p, &bytes).unwrap();
        assert_eq!(read(&p).unwrap(), img);
    }

    #[test]
    fn npy_float64_version2_and_errors() {
        let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (1, 2), }\n";
        let mut b = b"\x93NUMPY\x02\x00".to_vec();
        b.extend_from_slice(&(dict.len() as u32).to_le_bytes());
        b.extend_from_slice(dict.as_bytes());
        b.extend_from_slice(&1.5f64.to_le_bytes());
        b.extend_from_slice(&(-3.0f64).to_le_bytes());
        let img = parse_npy(&b).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        assert_eq!(img.data, vec![1.5, 1.5, 1.5, -3.0, -3.0, -3.0]);

        let mut bad = npy_bytes(&sample());
        let at = bad.windows(3).position(|w| w == b"<f4").unwrap();
        bad[at + 1] = b'i';
        let e = parse_npy(&bad).unwrap_err();
        assert!(e.to_string().contains("<i4"), "{e}");
        let truncated = &npy_bytes(&sample())[..100];
        assert!(parse_npy(truncated).is_err());
        assert!(parse_npy(b"not numpy").is_err());
    }

    #[test]
    fn exr_round_trips_and_png_decodes_srgb() {
        let dir = tempfile::tempdir().unwrap();
        let img = Image {
            width: 3,
            height: 2,
            data: (0..18).map(|i| i as f32 * 0.125).collect(),
        };
        let p = dir.path().join("a.exr");
        image::Rgb32FImage::from_raw(3, 2, img.data.clone())
            .unwrap()
            .save(&p)
            .unwrap();
        assert_eq!(read(&p).unwrap(), img);

        let p = dir.path().join("a.png");
        image::RgbImage::from_raw(1, 1, vec![0, 188, 255])
            .unwrap()
            .save(&p)
            .unwrap();
        let png = read(&p).unwrap();
        assert_eq!(png.data[0], 0.0);
        assert!((png.data[1] - 0.5).abs() < 0.003, "{}", png.data[1]);
        assert_eq!(png.data[2], 1.0);
    }

    #[test]
    fn unknown_extension_is_refused() {
        let e = read(Path::new("x.jpg")).unwrap_err();
        assert!(format!("{e:#}").contains("unsupported"), "{e:#}");
    }

    #[test]
    fn metrics_match_hand_computed_values() {
        // Differences 0.5 and 0 over two RGB pixels: squared 0.25 in 3 of 6 values.
        let a = [1.0f32, 1.0, 1.0, 0.0, 0.0, 0.0];
        let b = [0.5f32, 0.5, 0.5, 0.0, 0.0, 0.0];
        let m = metrics(&a, &b);
        assert!((m.rmse - (0.125f64).sqrt()).abs() < 1e-15);
        // 3 * 0.25 / (0.25 + 0.01) / 6
        assert!((m.relmse - 0.75 / 0.26 / 6.0).abs() < 1e-15);
        let same = metrics(&b, &b);
        assert_eq!((same.rmse, same.relmse), (0.0, 0.0));
        // f64 image against an f32 reference.
        let a64 = [0.0f64, 0.0, 0.0];
        let r = [0.1f32, 0.0, 0.0];
        let m = metrics(&a64, &r);
        let d = 0.1f32 as f64;
        assert!((m.rmse - (d * d / 3.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn size_check_names_both() {
        let e = check_same_size((2, 3), "A", (3, 2), "B").unwrap_err();
        assert_eq!(
            e.to_string(),
            "the images differ in size: A is 2x3, B is 3x2"
        );
    }

    #[test]
    fn uniform_image() {
        let u = Image::uniform(2, 1, [1.0, 2.0, 3.0]);
        assert_eq!(u.data, vec![1.0, 2.0, 3.0, 1.0, 2.0, 3.0]);
    }
}
