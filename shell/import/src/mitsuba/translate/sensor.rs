//! `<integrator>`, `<sensor>` and its `<film>`, `<rfilter>` and
//! `<sampler>`: rtk's `[render]` and its camera.

use super::{def, Props, Tx};
use crate::error::ImportError;
use crate::mitsuba::xml::{Obj, Value};
use crate::rtk_scene::{inline_table, vec3, Keys};
use toml::Value as T;

/// `<integrator>` → `[render] integrator`. Mitsuba's default is `path`.
pub fn integrator(tx: &mut Tx, scene: &Obj) -> Result<(), ImportError> {
    let mut all = scene.children_tagged("integrator");
    let keys = match all.next() {
        None => path_keys(None, 5),
        Some(i) => {
            if let Some(extra) = all.next() {
                return Err(ImportError::invalid(
                    &extra.loc,
                    "a second <integrator>: a Mitsuba scene has one",
                ));
            }
            one_integrator(tx, i)?
        }
    };
    tx.out
        .render
        .push(("integrator".into(), inline_table(keys)));
    Ok(())
}

fn path_keys(max_depth: Option<i64>, rr_depth: i64) -> Keys {
    let mut k = def("path");
    if let Some(d) = max_depth {
        k.push(("max_depth".into(), T::Integer(d)));
    }
    k.push(("rr_depth".into(), T::Integer(rr_depth)));
    k
}

/// One integrator's keys. `moment` only adds Mitsuba's variance output
/// (rtk's `--variance`), so it is its inner integrator; `direct` is
/// `path` of two segments (emitters seen directly and direct light, with
/// the same MIS of light and BSDF samples, one of each).
fn one_integrator(tx: &mut Tx, i: &Obj) -> Result<Keys, ImportError> {
    let mut p = Props::new(i);
    let refuse_hidden = "rtk's path shows emitters to camera rays; hiding them is not supported";
    let keys = match i.ty.as_str() {
        "moment" => {
            let inner: Vec<_> = i.children_tagged("integrator").collect();
            let [inner] = inner[..] else {
                return Err(ImportError::invalid(
                    &i.loc,
                    "<integrator type=\"moment\"> needs one nested integrator",
                ));
            };
            tx.warnings.push(format!(
                "note: {}: {}: Mitsuba's moment integrator only adds the variance; rtk writes it with `rtk render --variance FILE.exr`",
                i.loc,
                i.what()
            ));
            one_integrator(tx, inner)?
        }
        "direct" => {
            for n in ["emitter_samples", "bsdf_samples", "shading_samples"] {
                p.only_default(
                    tx,
                    n,
                    &Value::Int(1),
                    "rtk's path takes one light and one BSDF sample per vertex",
                )?;
            }
            p.only_default(tx, "hide_emitters", &Value::Bool(false), refuse_hidden)?;
            path_keys(Some(2), 5)
        }
        "path" => path_like(tx, &mut p, refuse_hidden)?,
        "volpath" | "volpathmis" => {
            // Without media these render as path does; with them, the
            // media themselves are refused where they are declared.
            tx.refuse(ImportError::unsupported(
                &i.loc,
                i.what(),
                "participating media are refused: rtk's importer does not translate media (docs/import.md); lenient, it is translated as path",
            ))?;
            path_like(tx, &mut p, refuse_hidden)?
        }
        _ => {
            return Err(ImportError::unsupported(
                &i.loc,
                i.what(),
                "rtk translates the integrators path, direct and moment",
            ))
        }
    };
    p.finish(tx)?;
    Ok(keys)
}

/// `path`'s keys from a path-like integrator's `max_depth`, `rr_depth`
/// and `hide_emitters`.
fn path_like(tx: &mut Tx, p: &mut Props, refuse_hidden: &str) -> Result<Keys, ImportError> {
    let max_depth = p.int("max_depth", -1)?;
    let rr_depth = p.int("rr_depth", 5)?;
    if max_depth == 0 || max_depth < -1 || rr_depth < 1 {
        return Err(ImportError::unsupported(
            &p.obj.loc,
            p.obj.what(),
            format!("max_depth = {max_depth}, rr_depth = {rr_depth}: rtk's path needs max_depth ≥ 1 (or -1, unlimited) and rr_depth ≥ 1"),
        ));
    }
    p.only_default(tx, "hide_emitters", &Value::Bool(false), refuse_hidden)?;
    Ok(path_keys((max_depth > 0).then_some(max_depth), rr_depth))
}

/// The first `<sensor>` → `[cameras.*]` and the film's `[render]` keys.
pub fn sensor(tx: &mut Tx, scene: &Obj) -> Result<(), ImportError> {
    let sensors: Vec<_> = scene.children_tagged("sensor").collect();
    let Some(s) = sensors.first() else {
        return Err(ImportError::invalid(
            &scene.loc,
            "the scene has no <sensor>: rtk needs a camera",
        ));
    };
    for extra in &sensors[1..] {
        tx.refuse_plugin(extra, "a second sensor: rtk renders the first")?;
    }
    if s.ty != "perspective" {
        return Err(ImportError::unsupported(
            &s.loc,
            s.what(),
            "rtk translates the perspective sensor",
        ));
    }
    let (width, height) = film(tx, s)?;
    sampler(tx, s)?;
    let mut p = Props::new(s);
    let aspect = width as f64 / height as f64;
    let fov_x = fov(&mut p, aspect, s)?;
    let fov_y = 2.0
        * ((0.5 * fov_x.to_radians()).tan() / aspect)
            .atan()
            .to_degrees();
    let near = p.float("near_clip", 1e-2)?;
    let far = p.float("far_clip", 1e4)?;
    for n in ["principal_point_offset_x", "principal_point_offset_y"] {
        p.only_default(
            tx,
            n,
            &Value::Float(0.0),
            "rtk's pinhole looks through the image centre",
        )?;
    }
    let mut cam = def("pinhole");
    let t = p.transform("to_world")?;
    let (eye, look_at, up) = match t {
        None => MITSUBA_POSE,
        Some(t) => match camera_frame(t) {
            Ok(pose) => pose,
            Err(m) => {
                let what = format!("{} parameter `to_world`", s.what());
                let at = s.prop("to_world").map_or(&s.loc, |q| &q.loc);
                tx.refuse(ImportError::unsupported(at, what, m))?;
                MITSUBA_POSE
            }
        },
    };
    cam.push(("eye".into(), vec3(eye)));
    cam.push(("look_at".into(), vec3(look_at)));
    cam.push(("up".into(), vec3(up)));
    cam.push(("fov_y".into(), T::Float(fov_y)));
    // Mitsuba always clips (its defaults too): so does the translation.
    cam.push(("near_clip".into(), T::Float(near)));
    cam.push(("far_clip".into(), T::Float(far)));
    p.finish(tx)?;
    let name = tx.out.fresh_name(s.id.as_deref().unwrap_or("camera"));
    tx.out.cameras.push((name.clone(), cam));
    tx.out.render.push(("camera".into(), T::String(name)));
    for c in &s.children {
        if !matches!(c.tag.as_str(), "film" | "sampler") {
            tx.refuse_plugin(c, "not translated inside a sensor")?;
        }
    }
    Ok(())
}

/// The horizontal field of view, as Mitsuba's `parse_fov`
/// (`src/render/sensor.cpp`): `fov` along `fov_axis` (x by default), or a
/// 35 mm camera's `focal_length` (50mm by default) on the diagonal.
fn fov(p: &mut Props, aspect: f64, s: &Obj) -> Result<f64, ImportError> {
    let bad = |m: String| ImportError::invalid(&s.loc, format!("{}: {m}", s.what()));
    let has_fov = p.obj.prop("fov").is_some();
    let (fov, axis) = if has_fov {
        if p.obj.prop("focal_length").is_some() {
            return Err(bad("give either `fov` or `focal_length`".into()));
        }
        let fov = p.float("fov", 0.0)?;
        let axis = p.string("fov_axis", "x")?.to_ascii_lowercase();
        let axis = match axis.as_str() {
            "smaller" if aspect > 1.0 => "y".to_string(),
            "smaller" => "x".to_string(),
            "larger" if aspect > 1.0 => "x".to_string(),
            "larger" => "y".to_string(),
            _ => axis,
        };
        (fov, axis)
    } else {
        let f = p.string("focal_length", "50mm")?;
        let mm: f64 = f
            .trim()
            .trim_end_matches("mm")
            .parse()
            .map_err(|_| bad(format!("focal_length = \"{f}\": expected <x>mm")))?;
        let fov = 2.0
            * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * mm))
                .atan()
                .to_degrees();
        (fov, "diagonal".to_string())
    };
    let half = (0.5 * fov.to_radians()).tan();
    let x = match axis.as_str() {
        "x" => fov,
        "y" => 2.0 * (half * aspect).atan().to_degrees(),
        "diagonal" => {
            let width = 2.0 * half / (1.0 + 1.0 / (aspect * aspect)).sqrt();
            2.0 * (0.5 * width).atan().to_degrees()
        }
        other => {
            return Err(bad(format!(
                "fov_axis = \"{other}\": expected x, y, diagonal, smaller or larger"
            )))
        }
    };
    if !(x > 0.0 && x < 180.0) {
        return Err(bad(format!(
            "the horizontal field of view is {x}°: it must lie in (0, 180)"
        )));
    }
    Ok(x)
}

/// A pinhole's eye, look-at point and up.
type Pose = ([f64; 3], [f64; 3], [f64; 3]);

/// A Mitsuba camera's pose without `to_world`: at the origin, looking
/// along +z, +y up.
const MITSUBA_POSE: Pose = ([0.0; 3], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]);

/// Eye, look-at point and up of a camera-to-world transform: Mitsuba's
/// camera looks along +z with +y up and +x to the left, so a rigid
/// transform (any translation and rotation, a uniform scale) is a pinhole
/// pose; a mirror or a shear is not.
fn camera_frame(t: &crate::mitsuba::transform::Transform) -> Result<Pose, String> {
    let cols: Vec<[f64; 3]> = (0..3)
        .map(|k| {
            let mut e = [0.0; 3];
            e[k] = 1.0;
            t.vector(e)
        })
        .collect();
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let len: Vec<f64> = cols.iter().map(|c| dot(*c, *c).sqrt()).collect();
    let ortho =
        (0..3).all(|i| (i + 1..3).all(|j| dot(cols[i], cols[j]).abs() <= 1e-6 * len[i] * len[j]));
    let uniform = len.iter().all(|l| (l - len[0]).abs() <= 1e-6 * len[0]);
    if !ortho || !uniform || len[0] == 0.0 {
        return Err("a camera transform with a shear or a non-uniform scale: rtk's pinhole needs a rigid pose".into());
    }
    if t.det() < 0.0 {
        return Err("a camera transform that mirrors the image (negative determinant): rtk's pinhole cannot".into());
    }
    let eye = t.point([0.0; 3]);
    let d = cols[2];
    let look_at = [
        eye[0] + d[0] / len[2],
        eye[1] + d[1] / len[2],
        eye[2] + d[2] / len[2],
    ];
    let up = cols[1].map(|x| x / len[1]);
    Ok((eye, look_at, up))
}

/// `<film type="hdrfilm">` and its `<rfilter>` → `[render]` width,
/// height, filter. Returns the size.
fn film(tx: &mut Tx, s: &Obj) -> Result<(u32, u32), ImportError> {
    let films: Vec<_> = s.children_tagged("film").collect();
    let (mut w, mut h) = (768, 576);
    // hdrfilm's default filter.
    let mut filter = "mitsuba_gaussian".to_string();
    if let Some(f) = films.first() {
        if f.ty != "hdrfilm" {
            tx.refuse_plugin(f, "rtk translates the hdrfilm film")?;
        }
        let mut p = Props::new(f);
        w = p.int("width", 768)?;
        h = p.int("height", 576)?;
        p.ignore(&["file_format", "pixel_format", "component_format", "banner"]);
        p.only_default(
            tx,
            "sample_border",
            &Value::Bool(false),
            "rtk's pixels take only their own samples",
        )?;
        for c in ["crop_offset_x", "crop_offset_y"] {
            p.only_default(tx, c, &Value::Int(0), "use `rtk render --crop`")?;
        }
        for (c, full) in [("crop_width", w), ("crop_height", h)] {
            p.only_default(tx, c, &Value::Int(full), "use `rtk render --crop`")?;
        }
        p.finish(tx)?;
        if let Some(r) = f.children_tagged("rfilter").next() {
            filter = rfilter(tx, r)?;
        }
        for c in f.children.iter().filter(|c| c.tag != "rfilter") {
            tx.refuse_plugin(c, "not translated inside a film")?;
        }
    }
    if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
        return Err(ImportError::invalid(
            &s.loc,
            format!("a film of {w}x{h} pixels: rtk renders 1 to 65536 a side"),
        ));
    }
    tx.out.render.push(("filter".into(), T::String(filter)));
    tx.out.render.insert(0, ("height".into(), T::Integer(h)));
    tx.out.render.insert(0, ("width".into(), T::Integer(w)));
    Ok((w as u32, h as u32))
}

/// `<rfilter>`: box, and Mitsuba's gaussian (rtk's `mitsuba_gaussian`).
fn rfilter(tx: &mut Tx, r: &Obj) -> Result<String, ImportError> {
    let mut p = Props::new(r);
    let name = match r.ty.as_str() {
        "box" => "box",
        "tent" => {
            return Err(ImportError::unsupported(
                &r.loc,
                r.what(),
                "rtk's tent looks past the image's border, Mitsuba's film without sample_border does not: border pixels differ",
            ))
        }
        "gaussian" => {
            p.only_default(
                tx,
                "stddev",
                &Value::Float(0.5),
                "rtk has Mitsuba's gaussian of σ = 0.5 pixel (`mitsuba_gaussian`)",
            )?;
            "mitsuba_gaussian"
        }
        _ => {
            return Err(ImportError::unsupported(
                &r.loc,
                r.what(),
                "rtk translates Mitsuba's box and gaussian filters",
            ))
        }
    };
    p.finish(tx)?;
    Ok(name.to_string())
}

/// The least square ≥ `n` (Mitsuba's stratified sample count).
fn square_up(n: i64) -> i64 {
    let mut r = (n as f64).sqrt() as i64;
    while r * r < n {
        r += 1;
    }
    while r > 1 && (r - 1) * (r - 1) >= n {
        r -= 1;
    }
    r * r
}

/// `<sampler>` → `[render]` spp, sampler, seed. Every unbiased sampler
/// gives the same expected image, but their variances differ, so only the
/// two rtk has are translated.
fn sampler(tx: &mut Tx, s: &Obj) -> Result<(), ImportError> {
    let Some(smp) = s.children_tagged("sampler").next() else {
        tx.out.render.push(("spp".into(), T::Integer(4)));
        return Ok(());
    };
    let mut p = Props::new(smp);
    let kind = match smp.ty.as_str() {
        "independent" => "independent",
        "stratified" => {
            p.only_default(
                tx,
                "jitter",
                &Value::Bool(true),
                "rtk's stratified sampler jitters",
            )?;
            "stratified"
        }
        _ => {
            return Err(ImportError::unsupported(
                &smp.loc,
                smp.what(),
                "rtk has the independent and stratified samplers",
            ))
        }
    };
    let spp = sample_count(tx, &mut p, kind)?;
    tx.out.render.push(("spp".into(), spp));
    tx.out
        .render
        .push(("sampler".into(), T::String(kind.into())));
    if let Some(prop) = p.get("seed") {
        match prop.value {
            Value::Int(n) if n >= 0 => tx.out.render.push(("seed".into(), T::Integer(n))),
            _ => {
                return Err(ImportError::invalid(
                    &prop.loc,
                    "seed must be a non-negative <integer>",
                ))
            }
        }
    }
    p.finish(tx)
}

/// `sample_count` (Mitsuba's default 4), as `[render] spp`.
fn sample_count(tx: &mut Tx, p: &mut Props, kind: &str) -> Result<T, ImportError> {
    Ok(match p.get("sample_count") {
        None => T::Integer(4),
        Some(prop) => match prop.value {
            Value::Int(n) if !(1..=u32::MAX as i64).contains(&n) => {
                return Err(ImportError::invalid(
                    &prop.loc,
                    "sample_count must be a positive <integer> (Mitsuba's is 32 bits)",
                ))
            }
            Value::Int(n) if kind == "stratified" && square_up(n) != n => {
                // Mitsuba's stratified sampler takes the next square.
                let m = square_up(n);
                tx.warnings.push(format!(
                    "note: {}: {}: sample_count = {n} is not a square: Mitsuba's stratified sampler takes {m} samples a pixel, and so does the translation",
                    prop.loc,
                    p.obj.what()
                ));
                T::Integer(m)
            }
            Value::Int(n) => tx.param_or(prop, T::Integer(n)),
            _ => {
                return Err(ImportError::invalid(
                    &prop.loc,
                    "sample_count must be a positive <integer>",
                ))
            }
        },
    })
}
