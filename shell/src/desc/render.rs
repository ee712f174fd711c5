//! `[render]`: image size, samples, seed, camera, root, integrator,
//! background, output.

use super::check::{integer, number, string, unknown_keys};
use super::defs::Def;
use super::instance::Instance;
use crate::error::SceneError;
use crate::tree::{Node, Origin, Val};
use std::collections::BTreeMap;

/// Default `[render] max_instances`: 2^24 leaf instances.
pub const DEFAULT_MAX_INSTANCES: u64 = 1 << 24;

/// Largest image, in pixels (the f64 film takes 28 bytes a pixel: sums and sample count).
pub const MAX_PIXELS: u64 = 1 << 28;

const KEYS: [&str; 14] = [
    "width",
    "height",
    "spp",
    "seed",
    "camera",
    "root",
    "integrator",
    "background",
    "output",
    "origin",
    "filter",
    "sampler",
    "shutter",
    "max_instances",
];
const OBJ: &str = "render";

/// `[render]` settings.
#[derive(Debug, Clone)]
pub struct Render {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the per-pixel random streams.
    pub seed: u64,
    /// Camera definition name.
    pub camera: String,
    /// Where `camera` was given (or the `[render]` table).
    pub camera_origin: Origin,
    /// The root instance.
    pub root: Instance,
    /// The integrator.
    pub integrator: Def,
    /// Radiance of rays that leave the scene.
    pub background: [f32; 3],
    /// Default output file.
    pub output: Option<String>,
    /// The world point the renderer computes about (`origin`): by default
    /// the camera's `eye`, so that what the camera sees has the precision
    /// of a scene at the origin (docs/numerics.md X3).
    pub origin: [f64; 3],
    /// The pixel filter, or `None` (not given): one sample looks through
    /// the pixel centre, more are spread uniformly over the pixel (a box).
    pub filter: Option<Filter>,
    /// Pixel positions stratified over an m×m grid (`sampler =
    /// "stratified"`, used when spp = m²), or independent (the default).
    pub stratified: bool,
    /// The shutter interval `[open, close]` ⊂ [0, 1]: each camera sample's
    /// time is uniform in it (motion blur); `[t, t]` freezes time at t.
    pub shutter: [f32; 2],
    /// Most leaf instances the object DAG may expand to (instancing
    /// multiplies: a DAG that doubles at each of 30 levels is 2^30).
    pub max_instances: u64,
}

/// A pixel filter, importance-sampled: each sample's film position is drawn
/// from the filter's own distribution and weighs 1, so a pixel is the plain
/// mean of its samples, and images do not depend on threads or tiles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Filter {
    /// Uniform over the pixel (radius 0.5): Mitsuba's `box`, the Cornell
    /// reference's convention.
    Box,
    /// A tent of radius 1 pixel.
    Tent,
    /// A Gaussian of standard deviation 0.5 pixel, cut at 3σ (1.5 pixels).
    Gaussian,
    /// Mitsuba 3's `gaussian` on its `hdrfilm`, exactly: σ = 0.5 pixel
    /// reaching 2 pixels, less its value there (so it falls to 0), per
    /// axis; and, as that film does without `sample_border`, it never looks
    /// outside the image (a pixel at the border weighs the part of its
    /// footprint inside). What `rtk import` translates Mitsuba's filter to.
    MitsubaGaussian,
}

impl Filter {
    /// The filter's name in the scene format.
    pub fn name(self) -> &'static str {
        match self {
            Filter::Box => "box",
            Filter::Tent => "tent",
            Filter::Gaussian => "gaussian",
            Filter::MitsubaGaussian => "mitsuba_gaussian",
        }
    }
}

/// `shutter = [open, close]`, 0 ≤ open ≤ close ≤ 1 (the `motion` class's
/// keyframes live in [0, 1], and aggregates bound their children over it).
fn shutter(r: &Node) -> Result<[f32; 2], SceneError> {
    let Some(n) = r.get("shutter") else {
        return Ok([0.0, 1.0]);
    };
    let bad = || {
        SceneError::invalid(
            &n.origin,
            OBJ,
            "shutter",
            "expected [open, close] with 0 <= open <= close <= 1",
        )
    };
    let Val::Arr(items) = &n.value else {
        return Err(bad());
    };
    let v: Vec<f64> = items
        .iter()
        .map(|i| number(i, OBJ, "shutter"))
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match v[..] {
        [a, b] if (0.0..=1.0).contains(&a) && (a..=1.0).contains(&b) => Ok([a as f32, b as f32]),
        _ => Err(bad()),
    }
}

/// `sampler = "independent" | "stratified"`: whether pixel positions are
/// stratified.
fn sampler(r: &Node) -> Result<bool, SceneError> {
    let Some(n) = r.get("sampler") else {
        return Ok(false);
    };
    match string(n, OBJ, "sampler")?.as_str() {
        "independent" => Ok(false),
        "stratified" => Ok(true),
        other => Err(SceneError::invalid(
            &n.origin,
            OBJ,
            "sampler",
            format!("unknown sampler `{other}`: use \"independent\" or \"stratified\""),
        )),
    }
}

/// `filter = "box" | "tent" | "gaussian"`.
fn filter(r: &Node) -> Result<Option<Filter>, SceneError> {
    let Some(n) = r.get("filter") else {
        return Ok(None);
    };
    let name = string(n, OBJ, "filter")?;
    match name.as_str() {
        "box" => Ok(Some(Filter::Box)),
        "tent" => Ok(Some(Filter::Tent)),
        "gaussian" => Ok(Some(Filter::Gaussian)),
        "mitsuba_gaussian" => Ok(Some(Filter::MitsubaGaussian)),
        other => Err(SceneError::invalid(
            &n.origin,
            OBJ,
            "filter",
            format!("unknown pixel filter `{other}`: use \"box\", \"tent\", \"gaussian\" or \"mitsuba_gaussian\""),
        )),
    }
}

impl Render {
    /// Read `[render]` (the cameras are needed to pick the default one).
    pub(crate) fn read(root: &Node, cameras: &BTreeMap<String, Def>) -> Result<Render, SceneError> {
        let Some(r) = root.get("render") else {
            return Err(SceneError::invalid(
                &root.origin,
                "",
                "render",
                "missing section [render] (at least `root = \"...\"`)",
            ));
        };
        unknown_keys(r, OBJ, &KEYS)?;
        let int = |k: &str, d: i64, min: i64, max: i64| -> Result<i64, SceneError> {
            r.get(k).map_or(Ok(d), |n| integer(n, OBJ, k, min, max))
        };
        let (width, height) = (
            int("width", 512, 1, 65536)? as u32,
            int("height", 384, 1, 65536)? as u32,
        );
        if width as u64 * height as u64 > MAX_PIXELS {
            return Err(SceneError::invalid(
                &r.get("width").unwrap_or(r).origin,
                OBJ,
                "width",
                format!("{width}x{height} is more than rtk's limit of {MAX_PIXELS} pixels; render it in crops"),
            ));
        }
        let camera = camera(r, cameras)?;
        let origin = origin(r, cameras.get(&camera.name))?;
        let Some(rn) = r.get("root") else {
            return Err(SceneError::invalid(
                &r.origin,
                OBJ,
                "root",
                "missing key `root` (the object to render)",
            ));
        };
        Ok(Render {
            width,
            height,
            spp: int("spp", 1, 1, 1 << 24)? as u32,
            seed: int("seed", 0, 0, i64::MAX)? as u64,
            camera: camera.name,
            camera_origin: camera.origin,
            root: Instance::read(rn, "render.root")?,
            integrator: integrator(r)?,
            background: background(r)?,
            output: r
                .get("output")
                .map(|n| string(n, OBJ, "output"))
                .transpose()?,
            origin,
            filter: filter(r)?,
            stratified: sampler(r)?,
            shutter: shutter(r)?,
            max_instances: int("max_instances", DEFAULT_MAX_INSTANCES as i64, 1, i64::MAX)? as u64,
        })
    }
}

/// `origin`: `"camera"` (the default: the camera's `eye` parameter, or the
/// world's origin for a camera without one), `"world"`, or a point.
fn origin(r: &Node, camera: Option<&Def>) -> Result<[f64; 3], SceneError> {
    let eye = || {
        camera
            .and_then(|c| serde_json::from_str::<serde_json::Value>(&c.params).ok())
            .and_then(|p| serde_json::from_value::<[f64; 3]>(p.get("eye")?.clone()).ok())
            .filter(|e| e.iter().all(|x| x.is_finite()))
            .unwrap_or([0.0; 3])
    };
    let Some(n) = r.get("origin") else {
        return Ok(eye());
    };
    let bad = || {
        SceneError::invalid(
            &n.origin,
            OBJ,
            "origin",
            "expected \"camera\", \"world\" or a point [x, y, z]",
        )
    };
    match &n.value {
        Val::Str(s) if s == "camera" => Ok(eye()),
        Val::Str(s) if s == "world" => Ok([0.0; 3]),
        Val::Arr(a) if a.len() == 3 => {
            let mut p = [0.0; 3];
            for (i, c) in a.iter().enumerate() {
                p[i] = number(c, OBJ, &format!("origin[{i}]"))?;
                if p[i].abs() > 1e12 {
                    return Err(SceneError::invalid(
                        &c.origin,
                        OBJ,
                        format!("origin[{i}]"),
                        "must be within 1e12 of the world's origin",
                    ));
                }
            }
            Ok(p)
        }
        _ => Err(bad()),
    }
}

/// The camera a render uses, and where the choice was made.
struct CameraChoice {
    name: String,
    origin: Origin,
}

/// The camera named, or the only one defined.
fn camera(r: &Node, cameras: &BTreeMap<String, Def>) -> Result<CameraChoice, SceneError> {
    if let Some(n) = r.get("camera") {
        return Ok(CameraChoice {
            name: string(n, OBJ, "camera")?,
            origin: n.origin.clone(),
        });
    }
    match cameras.len() {
        1 => Ok(CameraChoice {
            name: cameras.keys().next().cloned().unwrap_or_default(),
            origin: r.origin.clone(),
        }),
        0 => Err(SceneError::invalid(
            &r.origin,
            OBJ,
            "camera",
            "the scene defines no camera: add a [cameras.NAME] table",
        )),
        _ => Err(SceneError::invalid(
            &r.origin,
            OBJ,
            "camera",
            format!(
                "several cameras are defined ({}): say which with `camera = \"...\"`",
                cameras.keys().cloned().collect::<Vec<_>>().join(", ")
            ),
        )),
    }
}

/// `integrator = "class"` or `integrator = { class = "...", ... }`, by default
/// the kernel's [`DEFAULT_INTEGRATOR`](rtk_kernel::classes::DEFAULT_INTEGRATOR).
fn integrator(r: &Node) -> Result<Def, SceneError> {
    let Some(n) = r.get("integrator") else {
        return Ok(Def::implicit(
            OBJ,
            rtk_kernel::classes::DEFAULT_INTEGRATOR,
            &r.origin,
        ));
    };
    match &n.value {
        Val::Str(_) => {
            let table = Node {
                origin: n.origin.clone(),
                value: Val::Table(vec![("class".into(), n.origin.clone(), n.clone())]),
            };
            Def::read(OBJ, "integrator", &table, &[])
        }
        Val::Table(_) => Def::read(OBJ, "integrator", n, &[]),
        v => Err(SceneError::invalid(
            &n.origin,
            OBJ,
            "integrator",
            format!(
                "expected a class name or a table {{ class = \"...\", ... }}, found {}",
                v.type_name()
            ),
        )),
    }
}

/// Largest background radiance: the limit the plugins' colours have
/// ([`rtk_kernel::params::color`]); larger values overflow f32 once scaled.
const MAX_RADIANCE: f64 = super::check::MAX_COORDINATE;

/// `background = [r, g, b]`, finite, not negative, at most [`MAX_RADIANCE`];
/// black by default.
fn background(r: &Node) -> Result<[f32; 3], SceneError> {
    let Some(n) = r.get("background") else {
        return Ok([0.0; 3]);
    };
    let Val::Arr(a) = &n.value else {
        return Err(SceneError::invalid(
            &n.origin,
            OBJ,
            "background",
            "expected [r, g, b]",
        ));
    };
    if a.len() != 3 {
        return Err(SceneError::invalid(
            &n.origin,
            OBJ,
            "background",
            "expected [r, g, b]",
        ));
    }
    let mut out = [0.0f32; 3];
    for (i, c) in a.iter().enumerate() {
        let key = format!("background[{i}]");
        let v = number(c, OBJ, &key)?;
        if v < 0.0 {
            return Err(SceneError::invalid(
                &c.origin,
                OBJ,
                key,
                "must not be negative",
            ));
        }
        if v > MAX_RADIANCE {
            return Err(SceneError::invalid(
                &c.origin,
                OBJ,
                key,
                format!("{v:e} is too large: radiance must be at most {MAX_RADIANCE:e}, as for the plugins' colours (f32 arithmetic overflows beyond)"),
            ));
        }
        out[i] = v as f32;
    }
    Ok(out)
}
