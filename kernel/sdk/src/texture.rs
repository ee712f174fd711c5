//! Textures for shader parameters: a colour that varies over the surface.
//!
//! A shader declares a parameter as [`TextureParam`] and builds it into a
//! [`Texture`] in `create`; the scene then gives either a constant colour or
//! a table:
//!
//! ```toml
//! albedo = [0.8, 0.7, 0.6]                                     # constant
//! albedo = { checker = { even = [0.9, 0.9, 0.9], odd = [0.1, 0.1, 0.1], scale = [8.0, 8.0] } }
//! albedo = { image_file = "textures/wood.png", scale = [2.0, 2.0] }
//! ```
//!
//! Textures are looked up at the hit's surface parameterisation
//! ([`LocalGeom::uv`]), scaled by `scale` and repeated outside [0, 1)².
//! An image texture may also say how uv finds its texels ([`Lookup`]):
//! `to_uv = [a, b, c, d, e, f]` (u' = a u + b v + c, v' = d u + e v + f),
//! `wrap = "repeat" | "mirror" | "clamp"`, `filter = "bilinear" |
//! "nearest"`, `v_origin = "bottom" | "top"` — Mitsuba's `bitmap`
//! options, with drjit's rules for wrapping texel indices.
//!
//! - **checker**: cell `(⌊u·su⌋, ⌊v·sv⌋)` takes `even` when the sum of its
//!   indices is even, else `odd`; `scale` defaults to [8, 8] (8 × 8 cells
//!   over the unit square).
//! - **image**: a PNG, JPEG, PNM or OpenEXR file, read once when the shader is created,
//!   its path relative to the scene file. Integer images (PNG, JPEG, PNM) are sRGB and
//!   decoded to linear (unless `raw = true`: data, value / 255); float images (EXR) are used as they are. Alpha is
//!   ignored. v = 0 is the image's bottom row (the OBJ and OpenGL
//!   convention); lookups are bilinear between texel centres, wrapping
//!   around the edges. `scale` defaults to [1, 1]. The file must be a
//!   regular file of at most 1 GiB and the image at most 65536 texels on a
//!   side and 2^26 texels in all.
//!
//! The key is named `image_file` so that `rtk render --safe` checks it as
//! it does every `file` / `*_file` parameter (it must stay inside the
//! scene's folder or the working directory).
//!
//! Every value, texels of float images included, passes the check the
//! shader names (for a reflectance, [`params::reflectance`]: finite, in
//! [0, 1]); errors name the key (`albedo.checker.odd`, `albedo.image_file`).

use super::{params, Env, PluginError};
use rtk_abi::{Color, LocalGeom};
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use std::fmt;
use std::io::Read;
use std::path::Path;

/// Largest texture file read.
pub const MAX_FILE_BYTES: u64 = 1 << 30;
/// Largest width or height of an image texture, in texels.
pub const MAX_SIDE: u32 = 65536;
/// Largest number of texels of an image texture (12 bytes each once decoded).
pub const MAX_TEXELS: u64 = 1 << 26;

/// A texture as the scene writes it: `[r, g, b]`, `{ checker = { ... } }`
/// or `{ image_file = "...", scale = [su, sv] }` (see the [module](self)).
#[derive(Clone, Debug, PartialEq)]
pub enum TextureParam {
    /// One colour everywhere.
    Constant([f32; 3]),
    /// A checkerboard in uv.
    Checker {
        /// Colour of cells whose index sum is even (the cell at the origin).
        even: [f32; 3],
        /// Colour of the other cells.
        odd: [f32; 3],
        /// Cells per unit of u and of v.
        scale: [f32; 2],
    },
    /// An image file.
    Image {
        /// Path, relative to the scene file's folder.
        file: String,
        /// Repetitions per unit of u and of v.
        scale: [f32; 2],
        /// How uv finds texels.
        lookup: Lookup,
    },
}

/// How an image texture maps uv to texels. The defaults are rtk's own
/// (and OpenGL's): bilinear, repeating, v = 0 at the bottom row; the
/// others are what Mitsuba's `bitmap` offers, so that `rtk import`
/// translates it exactly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    /// An affine map of uv applied before the lookup, row-major 2 x 3:
    /// u' = a u + b v + c, v' = d u + e v + f (Mitsuba's `to_uv`).
    pub to_uv: Option<[f32; 6]>,
    /// Outside [0, 1): repeat, mirror or clamp (to the edge texels).
    pub wrap: Wrap,
    /// Nearest texel, or bilinear between texel centres.
    pub nearest: bool,
    /// v = 0 at the image's top row (Mitsuba's convention) instead of its
    /// bottom row.
    pub v_top: bool,
    /// Integer images (PNG, JPEG, PNM) taken as stored, value / 255, not
    /// decoded from sRGB: data such as a height field (Mitsuba's `raw`).
    pub raw: bool,
}

impl Default for Lookup {
    fn default() -> Self {
        Lookup {
            to_uv: None,
            wrap: Wrap::Repeat,
            nearest: false,
            v_top: false,
            raw: false,
        }
    }
}

/// What an image texture shows outside [0, 1)².
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Tiled.
    Repeat,
    /// Tiled, every other tile mirrored.
    Mirror,
    /// The edge texels extended.
    Clamp,
}

impl Wrap {
    /// Texel index `i` of a row or column of `n`, wrapped into [0, n) —
    /// drjit's `tex_wrap`, the one Mitsuba's textures use.
    #[inline]
    fn index(self, i: i64, n: i64) -> i64 {
        match self {
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Mirror => {
                let (k, m) = (i.div_euclid(n), i.rem_euclid(n));
                if k & 1 == 0 {
                    m
                } else {
                    n - 1 - m
                }
            }
        }
    }
}

impl TextureParam {
    /// A constant colour (a parameter's default).
    pub const fn constant(c: [f32; 3]) -> Self {
        TextureParam::Constant(c)
    }

    /// Build the texture: check every value with `check` (which gets the
    /// key path of the value), read and decode an image file.
    pub fn build(
        &self,
        key: &str,
        env: &Env,
        check: impl Fn(&str, [f32; 3]) -> Result<Color, PluginError>,
    ) -> Result<Texture, PluginError> {
        let kind = match self {
            TextureParam::Constant(c) => Kind::Constant(check(key, *c)?),
            TextureParam::Checker { even, odd, scale } => {
                let k = format!("{key}.checker");
                Kind::Checker {
                    even: check(&format!("{k}.even"), *even)?,
                    odd: check(&format!("{k}.odd"), *odd)?,
                    scale: check_scale(&format!("{k}.scale"), *scale)?,
                }
            }
            TextureParam::Image {
                file,
                scale,
                lookup,
            } => {
                let scale = check_scale(&format!("{key}.scale"), *scale)?;
                if let Some(m) = &lookup.to_uv {
                    params::finite(&format!("{key}.to_uv"), m)?;
                }
                let k = format!("{key}.image_file");
                let path = env.resolve(file);
                let img = TexImage::load(&path, lookup.raw)
                    .map_err(|e| PluginError::key(&k, format!("`{file}`: {e}")))?;
                for (i, t) in img.texels.iter().enumerate() {
                    let (x, y) = (i as u32 % img.width, i as u32 / img.width);
                    check(&k, *t).map_err(|e| {
                        PluginError::key(&k, format!("texel ({x}, {y}) {:?}: {}", t, e.message))
                    })?;
                }
                Kind::Image {
                    img,
                    scale,
                    lookup: *lookup,
                }
            }
        };
        Ok(Texture { kind })
    }

    /// [`build`](Self::build) with [`params::reflectance`]: every value in
    /// [0, 1].
    pub fn reflectance(&self, key: &str, env: &Env) -> Result<Texture, PluginError> {
        self.build(key, env, params::reflectance)
    }

    /// [`build`](Self::build) with [`params::color`]: finite, not negative.
    pub fn color(&self, key: &str, env: &Env) -> Result<Texture, PluginError> {
        self.build(key, env, params::color)
    }
}

fn check_scale(key: &str, s: [f32; 2]) -> Result<[f32; 2], PluginError> {
    params::finite(key, &s)?;
    if s.iter().any(|&x| !(x > 0.0)) {
        return Err(PluginError::key(key, "components must be positive"));
    }
    Ok(s)
}

/// A built texture: what a shader evaluates at each hit.
#[derive(Clone, Debug)]
pub struct Texture {
    kind: Kind,
}

#[derive(Clone, Debug)]
enum Kind {
    Constant(Color),
    Checker {
        even: Color,
        odd: Color,
        scale: [f32; 2],
    },
    Image {
        img: TexImage,
        scale: [f32; 2],
        lookup: Lookup,
    },
}

impl Texture {
    /// One colour everywhere (not checked).
    pub const fn constant(c: Color) -> Self {
        Texture {
            kind: Kind::Constant(c),
        }
    }

    /// An image texture's width and height in texels (`None` for the
    /// others): what a projection that keeps the image's aspect needs.
    pub fn size(&self) -> Option<(u32, u32)> {
        match &self.kind {
            Kind::Image { img, .. } => Some((img.width, img.height)),
            _ => None,
        }
    }

    /// An image texture's texels, linear RGB, row by row from the top
    /// (`None` for the others): what a light that importance-samples its
    /// image needs.
    pub fn texels(&self) -> Option<(u32, u32, &[[f32; 3]])> {
        match &self.kind {
            Kind::Image { img, .. } => Some((img.width, img.height, &img.texels)),
            _ => None,
        }
    }

    /// The colour when it is the same everywhere.
    pub fn as_constant(&self) -> Option<Color> {
        match self.kind {
            Kind::Constant(c) => Some(c),
            _ => None,
        }
    }

    /// The colour at the hit: at its [`LocalGeom::uv`].
    #[inline]
    pub fn at(&self, g: &LocalGeom) -> Color {
        self.eval(g.uv)
    }

    /// The colour at `uv`.
    #[inline]
    pub fn eval(&self, uv: [f32; 2]) -> Color {
        match &self.kind {
            Kind::Constant(c) => *c,
            Kind::Checker { even, odd, scale } => {
                let cu = (uv[0] * scale[0]).floor();
                let cv = (uv[1] * scale[1]).floor();
                // `as` saturates (NaN: 0), and the parity of each alone
                // cannot overflow.
                if ((cu as i64) ^ (cv as i64)) & 1 == 0 {
                    *even
                } else {
                    *odd
                }
            }
            Kind::Image { img, scale, lookup } if *lookup == Lookup::default() => {
                img.bilinear(uv[0] * scale[0], uv[1] * scale[1])
            }
            Kind::Image { img, scale, lookup } => {
                let (u, v) = (uv[0] * scale[0], uv[1] * scale[1]);
                let (u, v) = match lookup.to_uv {
                    Some(m) => (m[0] * u + m[1] * v + m[2], m[3] * u + m[4] * v + m[5]),
                    None => (u, v),
                };
                img.lookup(u, v, lookup)
            }
        }
    }
}

/// Mitsuba's luminance weights (linear sRGB primaries, `luminance()`).
const LUMINANCE: [f32; 3] = [0.212671, 0.715160, 0.072169];

impl Texture {
    /// ∂L/∂u and ∂L/∂v of the luminance `L` of [`Texture::eval`] at `uv`:
    /// the slope a bump map needs. Exact for the bilinear lookup within
    /// its cell (Mitsuba's `eval_1_grad`); 0 for constants, checkers and
    /// nearest-texel images, which are flat almost everywhere.
    pub fn gradient(&self, uv: [f32; 2]) -> [f32; 2] {
        let Kind::Image { img, scale, lookup } = &self.kind else {
            return [0.0; 2];
        };
        if lookup.nearest {
            return [0.0; 2];
        }
        let (u, v) = (uv[0] * scale[0], uv[1] * scale[1]);
        let m = lookup.to_uv.unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let (gu, gv) = img.slope(
            m[0] * u + m[1] * v + m[2],
            m[3] * u + m[4] * v + m[5],
            lookup,
        );
        // Through the affine map (its transpose) and the scale.
        [
            (m[0] * gu + m[3] * gv) * scale[0],
            (m[1] * gu + m[4] * gv) * scale[1],
        ]
    }
}

/// A decoded image: linear RGB, row 0 at the top.
#[derive(Clone, Debug)]
struct TexImage {
    width: u32,
    height: u32,
    texels: Vec<[f32; 3]>,
}

/// The sRGB transfer function, decoded: encoded value in [0, 1] to linear.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// `x` in [0, 1): the fraction that wraps a texture around (0 for non-finite x).
#[inline]
fn wrap(x: f32) -> f32 {
    let f = x - x.floor();
    if f.is_finite() && f < 1.0 {
        f
    } else {
        0.0
    }
}

impl TexImage {
    /// Read and decode an image file, within the limits of the module;
    /// `raw`: integer images not decoded from sRGB.
    fn load(path: &Path, raw: bool) -> Result<TexImage, String> {
        let bytes = read_limited(path, MAX_FILE_BYTES)?;
        let reader = || {
            image::ImageReader::new(std::io::Cursor::new(bytes.as_slice()))
                .with_guessed_format()
                .map_err(|e| e.to_string())
        };
        let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE || w as u64 * h as u64 > MAX_TEXELS {
            return Err(format!(
                "a {w} x {h} image: textures are 1 to {MAX_SIDE} texels on a side and at most 2^26 texels in all"
            ));
        }
        let mut reader = reader()?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_SIDE);
        limits.max_image_height = Some(MAX_SIDE);
        limits.max_alloc = Some(2 << 30);
        reader.limits(limits);
        let img = reader.decode().map_err(|e| e.to_string())?;
        let linear = raw
            || matches!(
                img,
                image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
            );
        let rgb = img.into_rgb32f();
        let (width, height) = rgb.dimensions();
        let texels = rgb
            .pixels()
            .map(|p| if linear { p.0 } else { p.0.map(srgb_to_linear) })
            .collect();
        Ok(TexImage {
            width,
            height,
            texels,
        })
    }

    #[inline]
    fn texel(&self, x: i64, y: i64) -> [f32; 3] {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        self.texels[y * self.width as usize + x]
    }

    /// Bilinear between texel centres, wrapping; `v` = 0 at the bottom row.
    fn bilinear(&self, u: f32, v: f32) -> Color {
        let x = wrap(u) * self.width as f32 - 0.5;
        let y = (1.0 - wrap(v)) * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut c = [0.0f32; 3];
        for (dx, dy, w) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let t = self.texel(x0 + dx, y0 + dy);
            for k in 0..3 {
                c[k] += w * t[k];
            }
        }
        Color::from_array(c)
    }
}

impl TexImage {
    /// The general lookup ([`Lookup`]): texel coordinates x = u·w (− ½
    /// for bilinear), y likewise from the top or the bottom, indices
    /// wrapped one by one, as drjit's textures do.
    fn lookup(&self, u: f32, v: f32, l: &Lookup) -> Color {
        let (w, h) = (self.width as i64, self.height as i64);
        let v = if l.v_top { v } else { 1.0 - v };
        let at = |x: i64, y: i64| {
            let (x, y) = (l.wrap.index(x, w), l.wrap.index(y, h));
            self.texels[(y * w + x) as usize]
        };
        // Far outside [0, 1) (or NaN) the index saturates; wrapped, it
        // still names a texel.
        let (x, y) = (u * w as f32, v * h as f32);
        if l.nearest {
            return Color::from_array(at(x.floor() as i64, y.floor() as i64));
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut c = [0.0f32; 3];
        for (dx, dy, wt) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let t = at(x0.saturating_add(dx), y0.saturating_add(dy));
            for k in 0..3 {
                c[k] += wt * t[k];
            }
        }
        Color::from_array(c)
    }
}

impl TexImage {
    /// ∂L/∂u, ∂L/∂v of the bilinear [`TexImage::lookup`] (luminance) at
    /// (u, v) after any `to_uv`: the derivative of the interpolation
    /// within the cell of four texels, times the resolution.
    fn slope(&self, u: f32, v: f32, l: &Lookup) -> (f32, f32) {
        let (w, h) = (self.width as i64, self.height as i64);
        let (v, dv) = if l.v_top { (v, 1.0) } else { (1.0 - v, -1.0) };
        let lum = |x: i64, y: i64| {
            let t = self.texels[(l.wrap.index(y, h) * w + l.wrap.index(x, w)) as usize];
            t[0] * LUMINANCE[0] + t[1] * LUMINANCE[1] + t[2] * LUMINANCE[2]
        };
        let (x, y) = (u * w as f32 - 0.5, v * h as f32 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let f00 = lum(x0, y0);
        let f10 = lum(x0.saturating_add(1), y0);
        let f01 = lum(x0, y0.saturating_add(1));
        let f11 = lum(x0.saturating_add(1), y0.saturating_add(1));
        let dx = (1.0 - fy) * (f10 - f00) + fy * (f11 - f01);
        let dy = (1.0 - fx) * (f01 - f00) + fx * (f11 - f10);
        (dx * w as f32, dy * h as f32 * dv)
    }
}

/// Read a whole regular file of at most `max` bytes (a FIFO or a device is
/// refused before it is opened, a file that grows is cut off and refused).
fn read_limited(path: &Path, max: u64) -> Result<Vec<u8>, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    if meta.len() > max {
        return Err(format!("{} bytes: at most {max} are read", meta.len()));
    }
    let f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    f.take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > max {
        return Err(format!("more than {max} bytes"));
    }
    Ok(bytes)
}

impl<'de> Deserialize<'de> for TextureParam {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(TextureVisitor)
    }
}

struct TextureVisitor;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Table {
    checker: Option<CheckerTable>,
    image_file: Option<String>,
    scale: Option<[f32; 2]>,
    to_uv: Option<[f32; 6]>,
    wrap: Option<String>,
    filter: Option<String>,
    v_origin: Option<String>,
    raw: Option<bool>,
}

impl Table {
    /// The image lookup the table asks for (defaults: [`Lookup::default`]).
    fn lookup<E: de::Error>(&self) -> Result<Lookup, E> {
        let wrap = match self.wrap.as_deref() {
            None | Some("repeat") => Wrap::Repeat,
            Some("mirror") => Wrap::Mirror,
            Some("clamp") => Wrap::Clamp,
            Some(o) => {
                return Err(E::custom(format!(
                    "wrap `{o}`: use \"repeat\", \"mirror\" or \"clamp\""
                )))
            }
        };
        let nearest = match self.filter.as_deref() {
            None | Some("bilinear") => false,
            Some("nearest") => true,
            Some(o) => {
                return Err(E::custom(format!(
                    "filter `{o}`: use \"bilinear\" or \"nearest\""
                )))
            }
        };
        let v_top = match self.v_origin.as_deref() {
            None | Some("bottom") => false,
            Some("top") => true,
            Some(o) => {
                return Err(E::custom(format!(
                    "v_origin `{o}`: use \"bottom\" or \"top\""
                )))
            }
        };
        Ok(Lookup {
            to_uv: self.to_uv,
            wrap,
            nearest,
            v_top,
            raw: self.raw.unwrap_or(false),
        })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CheckerTable {
    #[serde(default = "light")]
    even: [f32; 3],
    #[serde(default = "dark")]
    odd: [f32; 3],
    #[serde(default = "eight")]
    scale: [f32; 2],
}

fn light() -> [f32; 3] {
    [0.8; 3]
}
fn dark() -> [f32; 3] {
    [0.2; 3]
}
fn eight() -> [f32; 2] {
    [8.0; 2]
}

impl<'de> Visitor<'de> for TextureVisitor {
    type Value = TextureParam;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(
            "a colour [r, g, b] or a texture table ({ checker = { even = [r, g, b], odd = [r, g, b], scale = [su, sv] } } or { image_file = \"file.png\", scale = [su, sv] })",
        )
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
        let c = <[f32; 3]>::deserialize(de::value::SeqAccessDeserializer::new(seq))?;
        Ok(TextureParam::Constant(c))
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        let t = Table::deserialize(de::value::MapAccessDeserializer::new(map))?;
        let image_only = t.to_uv.is_some()
            || t.wrap.is_some()
            || t.filter.is_some()
            || t.v_origin.is_some()
            || t.raw.is_some();
        if t.checker.is_some() && image_only {
            return Err(de::Error::custom(
                "`to_uv`, `wrap`, `filter`, `v_origin` and `raw` belong to an `image_file` texture",
            ));
        }
        let lookup = t.lookup()?;
        match (t.checker, t.image_file) {
            (Some(c), None) => {
                if t.scale.is_some() {
                    return Err(de::Error::custom(
                        "a checker's `scale` goes inside it: { checker = { scale = [su, sv] } }",
                    ));
                }
                Ok(TextureParam::Checker {
                    even: c.even,
                    odd: c.odd,
                    scale: c.scale,
                })
            }
            (None, Some(file)) => Ok(TextureParam::Image {
                file,
                scale: t.scale.unwrap_or([1.0, 1.0]),
                lookup,
            }),
            (Some(_), Some(_)) => Err(de::Error::custom(
                "a texture is either a `checker` or an `image_file`, not both",
            )),
            (None, None) => Err(de::Error::custom(
                "a texture table needs `checker = { ... }` or `image_file = \"...\"`",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_params;

    #[derive(Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    struct P {
        albedo: TextureParam,
    }

    fn env(dir: &str) -> Env<'_> {
        Env {
            scene_dir: dir,
            name: "shaders.test",
            image_width: 1,
            image_height: 1,
            origin: [0.0; 3],
            arrays: Default::default(),
        }
    }

    fn close(a: Color, b: [f32; 3], tol: f32) -> bool {
        a.to_array()
            .iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= tol)
    }

    #[test]
    fn constant_and_checker_parse_and_evaluate() {
        let p: P = parse_params(r#"{"albedo": [0.1, 0.2, 0.3]}"#).unwrap();
        let t = p.albedo.reflectance("albedo", &env(".")).unwrap();
        assert_eq!(t.as_constant(), Some(Color::new(0.1, 0.2, 0.3)));
        assert_eq!(t.eval([0.7, -3.0]), Color::new(0.1, 0.2, 0.3));

        let p: P = parse_params(
            r#"{"albedo": {"checker": {"even": [1, 1, 1], "odd": [0, 0.5, 0], "scale": [4, 2]}}}"#,
        )
        .unwrap();
        let t = p.albedo.reflectance("albedo", &env(".")).unwrap();
        let (e, o) = (Color::splat(1.0), Color::new(0.0, 0.5, 0.0));
        // Cells of 1/4 in u and 1/2 in v; (0, 0) is even.
        assert_eq!(t.eval([0.1, 0.1]), e);
        assert_eq!(t.eval([0.3, 0.1]), o);
        assert_eq!(t.eval([0.3, 0.6]), e);
        assert_eq!(t.eval([0.1, 0.6]), o);
        assert_eq!(t.eval([0.6, 0.4]), e);
        // Repeats through negative coordinates: u in [-0.25, 0) is cell -1.
        assert_eq!(t.eval([-0.1, 0.1]), o);
        assert_eq!(t.eval([-0.1, -0.1]), e);
        assert_eq!(t.eval([f32::NAN, 0.1]), e, "NaN counts as cell 0");
        assert!(t.as_constant().is_none());

        // Defaults: 8 x 8 cells of 0.8 and 0.2.
        let p: P = parse_params(r#"{"albedo": {"checker": {}}}"#).unwrap();
        let t = p.albedo.reflectance("albedo", &env(".")).unwrap();
        assert_eq!(t.eval([0.01, 0.01]), Color::splat(0.8));
        assert_eq!(t.eval([0.13, 0.01]), Color::splat(0.2));
    }

    #[test]
    fn errors_name_the_key() {
        let e = parse_params::<P>(r#"{"albedo": {"checker": {"even": [1, 1]}}}"#).unwrap_err();
        assert_eq!(e.key, "albedo.checker.even");
        let e = parse_params::<P>(r#"{"albedo": {"checker": {"evn": [1, 1, 1]}}}"#).unwrap_err();
        assert_eq!(e.key, "albedo.checker.evn");
        let e = parse_params::<P>(r#"{"albedo": {"image": "a.png"}}"#).unwrap_err();
        assert_eq!(e.key, "albedo.image");
        let e = parse_params::<P>(r#"{"albedo": {}}"#).unwrap_err();
        assert_eq!(e.key, "albedo");
        assert!(e.message.contains("checker"), "{e}");
        let e = parse_params::<P>(r#"{"albedo": 0.5}"#).unwrap_err();
        assert_eq!(e.key, "albedo");
        assert!(e.message.contains("[r, g, b]"), "{e}");

        let p: P = parse_params(r#"{"albedo": {"checker": {"odd": [0, 1.5, 0]}}}"#).unwrap();
        let e = p.albedo.reflectance("albedo", &env(".")).unwrap_err();
        assert_eq!(e.key, "albedo.checker.odd");
        assert!(e.message.contains("[0, 1]"), "{e}");
        let p: P = parse_params(r#"{"albedo": {"checker": {"scale": [0, 1]}}}"#).unwrap();
        let e = p.albedo.reflectance("albedo", &env(".")).unwrap_err();
        assert_eq!(e.key, "albedo.checker.scale");
        let p: P = parse_params(r#"{"albedo": [-1, 0, 0]}"#).unwrap();
        assert_eq!(
            p.albedo.reflectance("albedo", &env(".")).unwrap_err().key,
            "albedo"
        );
        let p: P = parse_params(r#"{"albedo": {"image_file": "missing.png"}}"#).unwrap();
        let e = p
            .albedo
            .reflectance("albedo", &env("/nonexistent"))
            .unwrap_err();
        assert_eq!(e.key, "albedo.image_file");
        assert!(e.message.contains("missing.png"), "{e}");
    }

    /// A 2 x 2 PNG: sRGB decoded to linear, v = 0 at the bottom, bilinear
    /// between texel centres, wrapping around.
    #[test]
    fn image_texture_from_a_png() {
        let dir = tempfile::tempdir().unwrap();
        // Top row: red, green; bottom row: blue, white (sRGB 8-bit).
        let mut img = image::RgbImage::new(2, 2);
        img.put_pixel(0, 0, image::Rgb([255, 0, 0]));
        img.put_pixel(1, 0, image::Rgb([0, 255, 0]));
        img.put_pixel(0, 1, image::Rgb([0, 0, 255]));
        img.put_pixel(1, 1, image::Rgb([188, 188, 188]));
        img.save(dir.path().join("t.png")).unwrap();
        let dir_s = dir.path().to_str().unwrap();
        let p: P = parse_params(r#"{"albedo": {"image_file": "t.png"}}"#).unwrap();
        let t = p.albedo.reflectance("albedo", &env(dir_s)).unwrap();
        let grey = srgb_to_linear(188.0 / 255.0);
        assert!((grey - 0.5).abs() < 0.01, "{grey}");
        // Texel centres: u, v in {0.25, 0.75}, v up.
        assert!(close(t.eval([0.25, 0.75]), [1.0, 0.0, 0.0], 1e-6));
        assert!(close(t.eval([0.75, 0.75]), [0.0, 1.0, 0.0], 1e-6));
        assert!(close(t.eval([0.25, 0.25]), [0.0, 0.0, 1.0], 1e-6));
        assert!(close(t.eval([0.75, 0.25]), [grey; 3], 1e-6));
        // The centre is the mean of the four.
        let m = [(1.0 + grey) / 4.0, (1.0 + grey) / 4.0, (1.0 + grey) / 4.0];
        assert!(close(t.eval([0.5, 0.5]), m, 1e-6));
        // Halfway between red and green along the top row.
        assert!(close(t.eval([0.5, 0.75]), [0.5, 0.5, 0.0], 1e-6));
        // Wrapping: u = 0 is halfway between the right and left columns,
        // and a whole period further is the same.
        assert!(close(t.eval([0.0, 0.75]), [0.5, 0.5, 0.0], 1e-6));
        assert!(close(t.eval([3.25, -1.25]), [1.0, 0.0, 0.0], 1e-5));
        // Scale repeats the image: u·2 = 0.5 is the first texel's centre.
        let p: P = parse_params(r#"{"albedo": {"image_file": "t.png", "scale": [2, 2]}}"#).unwrap();
        let t = p.albedo.reflectance("albedo", &env(dir_s)).unwrap();
        assert!(close(t.eval([0.125, 0.375]), [1.0, 0.0, 0.0], 1e-6));
        assert!(close(t.eval([0.625, 0.875]), [1.0, 0.0, 0.0], 1e-6));

        // Not an image, not a regular file.
        std::fs::write(dir.path().join("bad.png"), b"not a png").unwrap();
        let p: P = parse_params(r#"{"albedo": {"image_file": "bad.png"}}"#).unwrap();
        let e = p.albedo.reflectance("albedo", &env(dir_s)).unwrap_err();
        assert_eq!(e.key, "albedo.image_file");
        let p: P = parse_params(r#"{"albedo": {"image_file": "."}}"#).unwrap();
        let e = p.albedo.reflectance("albedo", &env(dir_s)).unwrap_err();
        assert!(e.message.contains("not a regular file"), "{e}");
    }

    /// Mitsuba's lookups on a 4 x 1 row of greys 0.1, 0.2, 0.3, 0.4
    /// (linear, EXR): nearest and bilinear, repeat, mirror and clamp
    /// (drjit's rules), `to_uv`, and v from the top.
    #[test]
    fn wrap_modes_filters_and_to_uv_follow_drjit() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = image::Rgb32FImage::new(4, 2);
        for x in 0..4 {
            let g = 0.1 * (x + 1) as f32;
            img.put_pixel(x, 0, image::Rgb([g; 3]));
            img.put_pixel(x, 1, image::Rgb([0.9; 3]));
        }
        image::DynamicImage::ImageRgb32F(img)
            .save(dir.path().join("row.exr"))
            .unwrap();
        let dir_s = dir.path().to_str().unwrap();
        let tex = |extra: &str| {
            let json = format!(r#"{{"albedo": {{"image_file": "row.exr"{extra}}}}}"#);
            let p: P = parse_params(&json).unwrap();
            p.albedo.reflectance("albedo", &env(dir_s)).unwrap()
        };
        let g = |t: &Texture, u: f32, v: f32| t.eval([u, v]).to_array()[0];
        // Nearest, v from the top: row 0 for v in [0, 0.5).
        let t = tex(r#", "filter": "nearest", "v_origin": "top", "wrap": "clamp""#);
        assert!((g(&t, 0.3, 0.25) - 0.2).abs() < 1e-6);
        assert!(
            (g(&t, -0.3, 0.25) - 0.1).abs() < 1e-6,
            "clamped to the first texel"
        );
        assert!((g(&t, 1.7, 0.25) - 0.4).abs() < 1e-6);
        let t = tex(r#", "filter": "nearest", "v_origin": "top", "wrap": "mirror""#);
        // u = -0.1 → texel -1 → mirrored to 0; u = 1.1 → texel 4 → 3.
        assert!((g(&t, -0.1, 0.25) - 0.1).abs() < 1e-6);
        assert!((g(&t, 1.1, 0.25) - 0.4).abs() < 1e-6);
        assert!((g(&t, 1.3, 0.25) - 0.3).abs() < 1e-6, "texel 5 → 2");
        let t = tex(r#", "filter": "nearest", "v_origin": "top", "wrap": "repeat""#);
        assert!((g(&t, -0.1, 0.25) - 0.4).abs() < 1e-6);
        // Bilinear, clamp: at u = 0 (x = -0.5) both taps are texel 0.
        let t = tex(r#", "v_origin": "top", "wrap": "clamp""#);
        assert!((g(&t, 0.0, 0.25) - 0.1).abs() < 1e-6);
        assert!(
            (g(&t, 0.25, 0.25) - 0.15).abs() < 1e-6,
            "halfway between 0.1 and 0.2"
        );
        // Bilinear, mirror: at u = 0 the taps are texels -1 → 0 and 0.
        let t = tex(r#", "v_origin": "top", "wrap": "mirror""#);
        assert!((g(&t, 0.0, 0.25) - 0.1).abs() < 1e-6);
        // to_uv: u' = 2u − 0.5, so u = 0.4 looks at u' = 0.3 (texel 1).
        let t = tex(r#", "filter": "nearest", "v_origin": "top", "to_uv": [2, 0, -0.5, 0, 1, 0]"#);
        assert!((g(&t, 0.4, 0.25) - 0.2).abs() < 1e-6);
        // The default orientation: v = 0.25 is the bottom row.
        let t = tex(r#", "filter": "nearest""#);
        assert!((g(&t, 0.3, 0.25) - 0.9).abs() < 1e-6);
        // Misspelt modes are refused, naming the key.
        let e = parse_params::<P>(r#"{"albedo": {"image_file": "row.exr", "wrap": "tile"}}"#)
            .unwrap_err();
        assert!(e.message.contains("wrap `tile`"), "{e}");
        let e = parse_params::<P>(r#"{"albedo": {"checker": {}, "wrap": "clamp"}}"#).unwrap_err();
        assert!(e.message.contains("belong to an `image_file`"), "{e}");
    }

    /// `gradient` is the derivative of `eval`'s luminance: central
    /// differences inside bilinear cells agree, through `to_uv`, `scale`
    /// and either v origin; `raw` keeps integer texels as stored.
    #[test]
    fn gradient_is_the_slope_of_the_lookup_and_raw_skips_srgb() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = image::RgbImage::new(5, 4);
        for (x, y, p) in img.enumerate_pixels_mut() {
            *p = image::Rgb([
                (40 * x + 25 * y) as u8,
                (7 * x * y) as u8,
                200 - (30 * y) as u8,
            ]);
        }
        img.save(dir.path().join("h.png")).unwrap();
        let dir_s = dir.path().to_str().unwrap();
        let tex = |extra: &str| {
            let json = format!(r#"{{"albedo": {{"image_file": "h.png"{extra}}}}}"#);
            let p: P = parse_params(&json).unwrap();
            p.albedo.color("albedo", &env(dir_s)).unwrap()
        };
        let raw = tex(r#", "raw": true, "filter": "nearest", "v_origin": "top""#);
        let c = raw.eval([0.5 / 5.0, 0.5 / 4.0]).to_array();
        assert!((c[2] - 200.0 / 255.0).abs() < 1e-6, "{c:?}");
        assert_eq!(raw.gradient([0.3, 0.3]), [0.0, 0.0], "nearest is flat");
        let lum = |t: &Texture, u: f32, v: f32| {
            let c = t.eval([u, v]).to_array();
            (0..3).map(|k| c[k] * LUMINANCE[k]).sum::<f32>()
        };
        for extra in [
            r#", "raw": true"#,
            r#", "v_origin": "top", "wrap": "mirror""#,
            r#", "raw": true, "to_uv": [1.5, 0.5, 0.1, -0.3, 2.0, 0.2], "scale": [1.25, 0.8]"#,
        ] {
            let t = tex(extra);
            for (u, v) in [(0.31f32, 0.47f32), (0.62, 0.18), (0.13, 0.83)] {
                let h = 1e-3;
                let du = (lum(&t, u + h, v) - lum(&t, u - h, v)) / (2.0 * h);
                let dv = (lum(&t, u, v + h) - lum(&t, u, v - h)) / (2.0 * h);
                let g = t.gradient([u, v]);
                assert!(
                    (g[0] - du).abs() < 2e-2 * (1.0 + du.abs())
                        && (g[1] - dv).abs() < 2e-2 * (1.0 + dv.abs()),
                    "{extra} at ({u}, {v}): {g:?} vs ({du}, {dv})"
                );
            }
        }
        let e = parse_params::<P>(r#"{"albedo": {"checker": {}, "raw": true}}"#).unwrap_err();
        assert!(e.message.contains("belong to an `image_file`"), "{e}");
    }

    #[test]
    fn float_images_are_linear_and_checked() {
        let dir = tempfile::tempdir().unwrap();
        let mut img = image::Rgb32FImage::new(1, 1);
        img.put_pixel(0, 0, image::Rgb([0.25, 2.0, 0.5]));
        image::DynamicImage::ImageRgb32F(img)
            .save(dir.path().join("t.exr"))
            .unwrap();
        let dir_s = dir.path().to_str().unwrap();
        let p: P = parse_params(r#"{"albedo": {"image_file": "t.exr"}}"#).unwrap();
        // As a colour it is used unchanged...
        let t = p.albedo.color("albedo", &env(dir_s)).unwrap();
        assert!(
            close(t.eval([0.3, 0.3]), [0.25, 2.0, 0.5], 1e-6),
            "{:?}",
            t.eval([0.3, 0.3])
        );
        // ...as a reflectance, 2.0 is refused, naming the texel.
        let e = p.albedo.reflectance("albedo", &env(dir_s)).unwrap_err();
        assert_eq!(e.key, "albedo.image_file");
        assert!(e.message.contains("texel (0, 0)"), "{e}");
    }
}
