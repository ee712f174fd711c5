//! pbrt-v4 directives to rtk definitions (docs/import.md has the table).

use super::lexer::{Tok, Token};
use super::params::{self, Params};
use crate::error::{ImportError, Loc};
use crate::rtk_scene::{inline_table, vec3, Keys, RtkScene};
use crate::{Imported, Options};
use glam::{DMat4, DVec3};
use std::path::Path;
use toml::Value as T;

/// pbrt's graphics state: what `AttributeBegin` saves.
#[derive(Clone)]
struct State {
    ctm: DMat4,
    /// The current material: its shader's name and keys.
    material: Option<(String, Keys)>,
    /// The current area light's emission, and where it was declared.
    area: Option<(T, Loc)>,
    reverse: bool,
}

/// The camera, kept until the film's size is known.
struct Camera {
    world_from_camera: DMat4,
    fov: f64,
    loc: Loc,
}

struct Tx<'a> {
    opts: &'a Options,
    dir: &'a Path,
    out: RtkScene,
    warnings: Vec<String>,
    st: State,
    saved: Vec<State>,
    named: Vec<(String, (String, Keys))>,
    camera: Option<Camera>,
    size: (i64, i64),
    filter: Option<String>,
    children: Vec<T>,
}

impl Tx<'_> {
    fn refuse(&mut self, e: ImportError) -> Result<(), ImportError> {
        if self.opts.lenient {
            self.warnings
                .push(format!("warning: {e} (dropped: --lenient)"));
            Ok(())
        } else {
            Err(e)
        }
    }

    /// Refuse every parameter of `p` the translation did not read.
    fn finish(&mut self, what: &str, p: &Params) -> Result<(), ImportError> {
        for q in p.unread() {
            let e = ImportError::unsupported(
                &q.loc,
                format!("{what} parameter `{}`", q.name),
                "rtk's translation has no equivalent",
            );
            self.refuse(e)?;
        }
        Ok(())
    }
}

/// Translate the (includes expanded) tokens of `path`.
pub fn scene(toks: &[Token], path: &Path, opts: &Options) -> Result<Imported, ImportError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut tx = Tx {
        opts,
        dir,
        out: RtkScene::default(),
        warnings: Vec::new(),
        st: State {
            ctm: DMat4::IDENTITY,
            material: None,
            area: None,
            reverse: false,
        },
        saved: Vec::new(),
        named: Vec::new(),
        camera: None,
        size: (1280, 720),
        filter: None,
        children: Vec::new(),
    };
    tx.out.header.push(format!(
        "Imported by `rtk import` from {} (pbrt-v4).",
        path.display()
    ));
    let mut i = 0;
    while i < toks.len() {
        let t = &toks[i];
        let Tok::Word(w) = &t.tok else {
            return Err(ImportError::invalid(
                &t.loc,
                "expected a directive (Shape, Camera, ...)",
            ));
        };
        i += 1;
        directive(&mut tx, w, &t.loc, toks, &mut i)?;
    }
    finish_scene(tx, path)
}

/// `n` numbers after a directive: bare, or in brackets.
fn numbers(
    toks: &[Token],
    i: &mut usize,
    n: usize,
    at: &Loc,
    what: &str,
) -> Result<Vec<f64>, ImportError> {
    let bracket = matches!(toks.get(*i).map(|t| &t.tok), Some(Tok::Open));
    if bracket {
        *i += 1;
    }
    let mut v = Vec::with_capacity(n);
    while v.len() < n {
        match toks.get(*i).map(|t| &t.tok) {
            Some(Tok::Word(w)) => match w.parse::<f64>() {
                Ok(x) if x.is_finite() => {
                    v.push(x);
                    *i += 1;
                }
                _ => break,
            },
            _ => break,
        }
    }
    if bracket {
        if !matches!(toks.get(*i).map(|t| &t.tok), Some(Tok::Close)) {
            return Err(ImportError::invalid(
                at,
                format!("{what}: expected {n} numbers in [ ]"),
            ));
        }
        *i += 1;
    }
    if v.len() != n {
        return Err(ImportError::invalid(
            at,
            format!("{what}: expected {n} numbers, found {}", v.len()),
        ));
    }
    Ok(v)
}

/// The quoted argument of a directive (`Shape "sphere"`).
fn word(toks: &[Token], i: &mut usize, at: &Loc, what: &str) -> Result<String, ImportError> {
    match toks.get(*i) {
        Some(Token {
            tok: Tok::Str(s), ..
        }) => {
            *i += 1;
            Ok(s.clone())
        }
        _ => Err(ImportError::invalid(
            at,
            format!("{what} needs a quoted name"),
        )),
    }
}

fn directive(
    tx: &mut Tx,
    w: &str,
    at: &Loc,
    toks: &[Token],
    i: &mut usize,
) -> Result<(), ImportError> {
    match w {
        "Identity" => tx.st.ctm = DMat4::IDENTITY,
        "Translate" => {
            let v = numbers(toks, i, 3, at, w)?;
            tx.st.ctm *= DMat4::from_translation(DVec3::new(v[0], v[1], v[2]));
        }
        "Scale" => {
            let v = numbers(toks, i, 3, at, w)?;
            tx.st.ctm *= DMat4::from_scale(DVec3::new(v[0], v[1], v[2]));
        }
        "Rotate" => {
            let v = numbers(toks, i, 4, at, w)?;
            let axis = DVec3::new(v[1], v[2], v[3]);
            if axis.length_squared() == 0.0 {
                return Err(ImportError::invalid(at, "Rotate: the axis is zero"));
            }
            tx.st.ctm *= DMat4::from_axis_angle(axis.normalize(), v[0].to_radians());
        }
        "LookAt" => {
            let v = numbers(toks, i, 9, at, w)?;
            tx.st.ctm *= look_at(&v).ok_or_else(|| {
                ImportError::invalid(
                    at,
                    "LookAt: a degenerate view (eye on the target, or up along the view)",
                )
            })?;
        }
        "Transform" | "ConcatTransform" => {
            let v = numbers(toks, i, 16, at, w)?;
            // Column by column, as pbrt reads them.
            let m = DMat4::from_cols_slice(&v);
            tx.st.ctm = if w == "Transform" { m } else { tx.st.ctm * m };
        }
        "AttributeBegin" | "TransformBegin" => tx.saved.push(tx.st.clone()),
        "AttributeEnd" | "TransformEnd" => {
            let Some(s) = tx.saved.pop() else {
                return Err(ImportError::invalid(at, format!("{w} without its Begin")));
            };
            if w == "TransformEnd" {
                tx.st.ctm = s.ctm;
            } else {
                tx.st = s;
            }
        }
        "ReverseOrientation" => tx.st.reverse = !tx.st.reverse,
        "WorldBegin" => tx.st.ctm = DMat4::IDENTITY,
        "Camera" => camera(tx, toks, i, at)?,
        "Film" | "Sampler" | "PixelFilter" | "Integrator" => options(tx, w, toks, i, at)?,
        "Material" | "MakeNamedMaterial" | "NamedMaterial" => material(tx, w, toks, i, at)?,
        "LightSource" => light(tx, toks, i, at)?,
        "AreaLightSource" => area_light(tx, toks, i, at)?,
        "Shape" => shape(tx, toks, i, at)?,
        _ => {
            // Skip the directive's arguments, then refuse it.
            while matches!(
                toks.get(*i).map(|t| &t.tok),
                Some(Tok::Str(_) | Tok::Open | Tok::Close)
            ) || matches!(toks.get(*i).map(|t| &t.tok), Some(Tok::Word(x)) if x.parse::<f64>().is_ok() || x == "true" || x == "false")
            {
                *i += 1;
            }
            tx.refuse(ImportError::unsupported(
                at,
                format!("the directive `{w}`"),
                "not translated by rtk's pbrt importer (docs/import.md)",
            ))?;
        }
    }
    Ok(())
}

/// pbrt's `LookAt`: the camera-from-world transform of an eye at v[0..3]
/// looking at v[3..6] with up v[6..9] (`right = up × dir`, left-handed).
fn look_at(v: &[f64]) -> Option<DMat4> {
    let (pos, look, up) = (
        DVec3::new(v[0], v[1], v[2]),
        DVec3::new(v[3], v[4], v[5]),
        DVec3::new(v[6], v[7], v[8]),
    );
    let dir = (look - pos).try_normalize()?;
    let right = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        pos.extend(1.0),
    );
    Some(world_from_camera.inverse())
}

fn camera(tx: &mut Tx, toks: &[Token], i: &mut usize, at: &Loc) -> Result<(), ImportError> {
    let ty = word(toks, i, at, "Camera")?;
    let p = params::read(toks, i)?;
    if ty != "perspective" {
        return tx.refuse(ImportError::unsupported(
            at,
            format!("Camera \"{ty}\""),
            "rtk translates the perspective camera",
        ));
    }
    let fov = p.float("fov", 90.0)?;
    if p.float("lensradius", 0.0)? != 0.0 {
        tx.refuse(ImportError::unsupported(
            at,
            "Camera \"perspective\" parameter `lensradius`",
            "a thin lens is not translated yet",
        ))?;
    }
    p.get("focaldistance");
    tx.finish("Camera \"perspective\"", &p)?;
    let world_from_camera = tx.st.ctm.inverse();
    tx.camera = Some(Camera {
        world_from_camera,
        fov,
        loc: at.clone(),
    });
    Ok(())
}

/// `Film`, `Sampler`, `PixelFilter`, `Integrator`: `[render]` keys.
fn options(
    tx: &mut Tx,
    w: &str,
    toks: &[Token],
    i: &mut usize,
    at: &Loc,
) -> Result<(), ImportError> {
    let ty = word(toks, i, at, w)?;
    let p = params::read(toks, i)?;
    let what = format!("{w} \"{ty}\"");
    match (w, ty.as_str()) {
        ("Film", "rgb") => {
            tx.size = (
                p.float("xresolution", 1280.0)? as i64,
                p.float("yresolution", 720.0)? as i64,
            );
            p.get("filename");
            p.get("savefp16");
        }
        ("Sampler", s) => {
            let spp = if s == "stratified" {
                let jitter = p.bool("jitter", true)?;
                if !jitter {
                    tx.refuse(ImportError::unsupported(
                        at,
                        format!("{what} parameter `jitter`"),
                        "rtk's stratified sampler jitters",
                    ))?;
                }
                p.float("xsamples", 4.0)? * p.float("ysamples", 4.0)?
            } else {
                p.get("seed");
                p.get("randomization");
                p.float("pixelsamples", 16.0)?
            };
            let sampler = if s == "stratified" {
                "stratified"
            } else {
                "independent"
            };
            if !matches!(s, "stratified" | "independent") {
                tx.warnings.push(format!("note: {at}: {what}: rtk samples independently: the same expected image, another variance"));
            }
            tx.out.render.push(("spp".into(), T::Integer(spp as i64)));
            tx.out
                .render
                .push(("sampler".into(), T::String(sampler.into())));
        }
        ("PixelFilter", "box") => {
            for r in ["xradius", "yradius"] {
                if p.float(r, 0.5)? != 0.5 {
                    tx.refuse(ImportError::unsupported(
                        at,
                        format!("{what} parameter `{r}`"),
                        "rtk's box filter is one pixel wide",
                    ))?;
                }
            }
            tx.filter = Some("box".into());
        }
        ("Integrator", "path" | "volpath") => {
            let depth = p.float("maxdepth", 5.0)? as i64;
            if p.bool("regularize", false)? {
                tx.refuse(ImportError::unsupported(
                    at,
                    format!("{what} parameter `regularize`"),
                    "rtk's path does not regularise",
                ))?;
            }
            p.get("lightsampler");
            integrator(tx, depth);
        }
        _ => {
            return tx.refuse(ImportError::unsupported(
                at,
                what,
                "not translated by rtk's pbrt importer (docs/import.md)",
            ))
        }
    }
    tx.finish(&what, &p)
}

/// rtk's `path` for pbrt's `maxdepth` bounces: one segment more.
fn integrator(tx: &mut Tx, maxdepth: i64) {
    tx.out.render.retain(|(k, _)| k != "integrator");
    let mut k = vec![("class".into(), T::String("path".into()))];
    k.push(("max_depth".into(), T::Integer(maxdepth.max(0) + 1)));
    tx.out.render.push(("integrator".into(), inline_table(k)));
}

/// A pbrt `diffuse` material's lambert keys.
fn diffuse_keys(tx: &mut Tx, what: &str, p: &Params) -> Result<Keys, ImportError> {
    let r = p.three("reflectance", &["rgb"], [0.5; 3])?;
    tx.finish(what, p)?;
    Ok(vec![
        ("class".into(), T::String("lambert".into())),
        ("albedo".into(), vec3(r)),
    ])
}

fn material(
    tx: &mut Tx,
    w: &str,
    toks: &[Token],
    i: &mut usize,
    at: &Loc,
) -> Result<(), ImportError> {
    let name = word(toks, i, at, w)?;
    if w == "NamedMaterial" {
        let Some((_, m)) = tx.named.iter().find(|(n, _)| *n == name) else {
            return Err(ImportError::invalid(
                at,
                format!("NamedMaterial \"{name}\": no MakeNamedMaterial of that name before it"),
            ));
        };
        tx.st.material = Some(m.clone());
        return Ok(());
    }
    let p = params::read(toks, i)?;
    let ty = if w == "Material" {
        name.clone()
    } else {
        p.string("type", "")?
    };
    let what = format!("{w} \"{name}\"");
    if ty != "diffuse" {
        tx.refuse(ImportError::unsupported(
            at,
            format!("the material \"{ty}\""),
            "rtk translates pbrt's diffuse material so far",
        ))?;
        return Ok(());
    }
    let keys = diffuse_keys(tx, &what, &p)?;
    let shader = tx
        .out
        .fresh_name(if w == "Material" { "material" } else { &name });
    tx.out.shaders.push((shader.clone(), keys.clone()));
    if w == "Material" {
        tx.st.material = Some((shader, keys));
    } else {
        tx.named.retain(|(n, _)| *n != name);
        tx.named.push((name, (shader, keys)));
    }
    Ok(())
}

fn light(tx: &mut Tx, toks: &[Token], i: &mut usize, at: &Loc) -> Result<(), ImportError> {
    let ty = word(toks, i, at, "LightSource")?;
    let p = params::read(toks, i)?;
    let what = format!("LightSource \"{ty}\"");
    let scale = p.float("scale", 1.0)?;
    let m = tx.st.ctm;
    let keys = match ty.as_str() {
        "point" => {
            let from = m.transform_point3(DVec3::from(p.three(
                "from",
                &["point3", "point"],
                [0.0; 3],
            )?));
            let c = p.three("I", &["rgb"], [1.0; 3])?.map(|x| x * scale);
            vec![
                ("class".into(), T::String("point".into())),
                ("position".into(), vec3(from.into())),
                ("intensity".into(), vec3(c)),
            ]
        }
        "distant" => {
            let from = DVec3::from(p.three("from", &["point3", "point"], [0.0; 3])?);
            let to = DVec3::from(p.three("to", &["point3", "point"], [0.0, 0.0, 1.0])?);
            let d = m.transform_vector3(to - from);
            let c = p.three("L", &["rgb"], [1.0; 3])?.map(|x| x * scale);
            vec![
                ("class".into(), T::String("directional".into())),
                ("direction".into(), vec3(d.into())),
                ("irradiance".into(), vec3(c)),
            ]
        }
        "infinite" if p.get("filename").is_none() => {
            let c = p.three("L", &["rgb"], [1.0; 3])?.map(|x| x * scale);
            vec![
                ("class".into(), T::String("constant".into())),
                ("radiance".into(), vec3(c)),
            ]
        }
        _ => {
            return tx.refuse(ImportError::unsupported(
                at,
                what,
                "rtk translates the point, distant and (uniform) infinite lights",
            ))
        }
    };
    tx.finish(&what, &p)?;
    let name = tx.out.fresh_name(&ty);
    tx.out.lights.push((name, keys));
    Ok(())
}

fn area_light(tx: &mut Tx, toks: &[Token], i: &mut usize, at: &Loc) -> Result<(), ImportError> {
    let ty = word(toks, i, at, "AreaLightSource")?;
    let p = params::read(toks, i)?;
    let what = format!("AreaLightSource \"{ty}\"");
    if ty != "diffuse" {
        return tx.refuse(ImportError::unsupported(
            at,
            what,
            "rtk translates the diffuse area light",
        ));
    }
    let scale = p.float("scale", 1.0)?;
    let l = p.three("L", &["rgb"], [1.0; 3])?.map(|x| x * scale);
    if p.bool("twosided", false)? {
        tx.refuse(ImportError::unsupported(
            at,
            format!("{what} parameter `twosided`"),
            "rtk's emitters emit from their front side only",
        ))?;
    }
    tx.finish(&what, &p)?;
    tx.st.area = Some((vec3(l), at.clone()));
    Ok(())
}

fn shape(tx: &mut Tx, toks: &[Token], i: &mut usize, at: &Loc) -> Result<(), ImportError> {
    let ty = word(toks, i, at, "Shape")?;
    let p = params::read(toks, i)?;
    let what = format!("Shape \"{ty}\"");
    let mut hint = ty.clone();
    let keys = match ty.as_str() {
        "plymesh" => {
            let f = p.string("filename", "")?;
            if let Some(stem) = Path::new(&f).file_stem() {
                hint = stem.to_string_lossy().into_owned();
            }
            let path = tx.dir.join(&f);
            if f.is_empty() || !path.is_file() {
                return Err(ImportError::invalid(at, format!("{what}: the file `{f}` does not exist ({})", path.display())));
            }
            let file = crate::rtk_scene::file_name(&path, &tx.opts.out_dir);
            vec![("class".into(), T::String("mesh".into())), ("file".into(), T::String(file))]
        }
        "sphere" => {
            let r = p.float("radius", 1.0)?;
            vec![("class".into(), T::String("sphere".into())), ("radius".into(), T::Float(r))]
        }
        _ => return tx.refuse(ImportError::unsupported(at, what, "rtk translates the plymesh and sphere shapes so far (an inline trianglemesh: write it as a PLY file)")),
    };
    tx.finish(&what, &p)?;
    let Some(shader) = shape_shader(tx)? else {
        return Ok(());
    };
    let name = tx.out.fresh_name(&hint);
    tx.out.objects.push((name.clone(), keys));
    let mut inst = vec![
        ("object".into(), T::String(name)),
        ("shader".into(), T::String(shader)),
    ];
    if tx.st.ctm != DMat4::IDENTITY {
        let rows: Vec<T> = tx
            .st
            .ctm
            .transpose()
            .to_cols_array()
            .iter()
            .map(|x| T::Float(*x))
            .collect();
        inst.push((
            "transform".into(),
            T::Array(vec![inline_table(vec![("matrix".into(), T::Array(rows))])]),
        ));
    }
    tx.children.push(inline_table(inst));
    Ok(())
}

/// The shader of the next shape: the current material's (pbrt's default,
/// diffuse 0.5, when none), with the current area light's emission.
fn shape_shader(tx: &mut Tx) -> Result<Option<String>, ImportError> {
    let (name, keys) = match &tx.st.material {
        Some(m) => m.clone(),
        None => {
            let name = "pbrt_default_diffuse".to_string();
            let keys = vec![
                ("class".into(), T::String("lambert".into())),
                ("albedo".into(), vec3([0.5; 3])),
            ];
            if !tx.out.shaders.iter().any(|(n, _)| *n == name) {
                tx.out.shaders.push((name.clone(), keys.clone()));
            }
            (name, keys)
        }
    };
    let Some((emission, loc)) = tx.st.area.clone() else {
        return Ok(Some(name));
    };
    if tx.st.reverse || tx.st.ctm.determinant() < 0.0 {
        tx.refuse(ImportError::unsupported(
            &loc,
            "AreaLightSource \"diffuse\" on a reversed or mirrored shape",
            "which side emits follows pbrt's orientation rules, not rtk's",
        ))?;
        return Ok(Some(name));
    }
    let mut keys = keys;
    keys.push(("emission".into(), emission));
    let em = tx.out.fresh_name(&format!("{name}_emitter"));
    tx.out.shaders.push((em.clone(), keys));
    Ok(Some(em))
}

/// `[render]` and the camera, once everything is read.
fn finish_scene(mut tx: Tx, path: &Path) -> Result<Imported, ImportError> {
    let Some(cam) = tx.camera.take() else {
        return Err(ImportError::invalid(
            &Loc::file_start(path),
            "the scene has no Camera",
        ));
    };
    let (w, h) = tx.size;
    if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
        return Err(ImportError::invalid(
            &cam.loc,
            format!("a film of {w}x{h} pixels: rtk renders 1 to 65536 a side"),
        ));
    }
    let Some(filter) = tx.filter.clone() else {
        return Err(ImportError::unsupported(&Loc::file_start(path), "pbrt's default PixelFilter \"gaussian\"", "its footprint (radius 1.5, σ 0.5, less its value at the radius) is not rtk's: give PixelFilter \"box\""));
    };
    let m = cam.world_from_camera;
    let (eye, fwd, up, right) = (
        m.transform_point3(DVec3::ZERO),
        m.transform_vector3(DVec3::Z),
        m.transform_vector3(DVec3::Y),
        m.transform_vector3(DVec3::X),
    );
    // rtk's image right is forward × up; pbrt's is the camera's +x.
    if fwd.normalize().cross(up.normalize()).dot(right.normalize()) < 0.999_999 {
        return Err(ImportError::unsupported(&cam.loc, "Camera \"perspective\" transform", "pbrt's view here is left-handed (its image mirrors rtk's): mirror it, e.g. `Scale -1 1 1` before LookAt"));
    }
    let fov_y = if w >= h {
        cam.fov
    } else {
        2.0 * ((0.5 * cam.fov.to_radians()).tan() * h as f64 / w as f64)
            .atan()
            .to_degrees()
    };
    let look = eye + fwd.normalize();
    tx.out.cameras.push((
        "camera".into(),
        vec![
            ("class".into(), T::String("pinhole".into())),
            ("eye".into(), vec3(eye.into())),
            ("look_at".into(), vec3(look.into())),
            ("up".into(), vec3(up.normalize().into())),
            ("fov_y".into(), T::Float(fov_y)),
        ],
    ));
    if !tx.out.render.iter().any(|(k, _)| k == "integrator") {
        integrator(&mut tx, 5);
    }
    if !tx.out.render.iter().any(|(k, _)| k == "spp") {
        tx.out.render.push(("spp".into(), T::Integer(16)));
    }
    let mut head = vec![
        ("width".into(), T::Integer(w)),
        ("height".into(), T::Integer(h)),
        ("filter".into(), T::String(filter)),
    ];
    head.append(&mut tx.out.render);
    tx.out.render = head;
    tx.out
        .render
        .push(("camera".into(), T::String("camera".into())));
    if tx.children.is_empty() {
        return Err(ImportError::invalid(
            &Loc::file_start(path),
            "the scene has no shape rtk can render",
        ));
    }
    let root = tx.out.fresh_name("scene");
    tx.out.render.push(("root".into(), T::String(root.clone())));
    let children = std::mem::take(&mut tx.children);
    tx.out.objects.push((
        root,
        vec![
            ("class".into(), T::String("bvh".into())),
            ("children".into(), T::Array(children)),
        ],
    ));
    Ok(Imported {
        toml: tx.out.to_toml(),
        warnings: tx.warnings,
    })
}
