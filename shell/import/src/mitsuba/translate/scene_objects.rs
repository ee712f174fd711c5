//! `<shape>`s → `[objects.*]` and instances of the root, their `<bsdf>`s
//! and area `<emitter>`s → `[shaders.*]`.
//!
//! Mitsuba's `diffuse` is one-sided: black seen from behind the shading
//! normal, unless wrapped in `twosided`. rtk's `lambert` says which with
//! `two_sided`, so both translate exactly.

use super::{def, steps, Props, Tx, UvSource};
use crate::error::ImportError;
use crate::mitsuba::spectrum::Role;
use crate::mitsuba::transform::Transform;
use crate::mitsuba::xml::{Obj, Value};
use crate::rtk_scene::{inline_table, vec3, Keys};
use std::rc::Rc;
use toml::Value as T;

/// One shape: its object, its shader and its instance in `children`.
pub fn shape(tx: &mut Tx, s: &Rc<Obj>, children: &mut Vec<T>) -> Result<(), ImportError> {
    let mut p = Props::new(s);
    let (keys, to_world, center) = match s.ty.as_str() {
        "obj" | "ply" => (mesh(tx, &mut p)?, p.transform("to_world")?, None),
        "sphere" => {
            let mut k = def("sphere");
            k.push(("radius".into(), T::Float(p.float("radius", 1.0)?)));
            let c = p.vec3("center", [0.0; 3])?;
            (k, p.transform("to_world")?, Some(c))
        }
        "rectangle" => {
            let mut k = def("polygon");
            let corners = [
                [-1.0, -1.0, 0.0],
                [1.0, -1.0, 0.0],
                [1.0, 1.0, 0.0],
                [-1.0, 1.0, 0.0],
            ];
            k.push((
                "points".into(),
                T::Array(corners.iter().map(|c| vec3(*c)).collect()),
            ));
            (k, p.transform("to_world")?, None)
        }
        _ => {
            return tx.refuse_plugin(
                s,
                "rtk translates the shapes obj, ply, sphere and rectangle",
            )
        }
    };
    p.only_default(
        tx,
        "flip_normals",
        &Value::Bool(false),
        "rtk does not flip a shape's normals",
    )?;
    p.finish(tx)?;
    tx.uv_source = uv_source(s);
    let shader = shape_shader(tx, s)?;
    let hint =
        s.id.clone()
            .unwrap_or_else(|| file_stem(s).unwrap_or_else(|| s.ty.clone()));
    let name = tx.out.fresh_name(&hint);
    tx.out.objects.push((name.clone(), keys));
    let mut inst = vec![
        ("object".into(), T::String(name)),
        ("shader".into(), T::String(shader)),
    ];
    let mut t = Transform::identity();
    if let Some(c) = center.filter(|c| *c != [0.0; 3]) {
        t.translate(c);
    }
    if let Some(w) = to_world {
        for st in &w.steps {
            t.steps.push(st.clone());
        }
    }
    if !t.steps.is_empty() {
        inst.push(("transform".into(), steps(&t)));
    }
    children.push(inline_table(inst));
    Ok(())
}

/// `obj`/`ply` → `mesh`. Mitsuba uses the file's vertex normals, or
/// computes them, unless `face_normals`; rtk's `vertex` does the same.
fn mesh(tx: &mut Tx, p: &mut Props) -> Result<Keys, ImportError> {
    let mut k = def("mesh");
    let Some(f) = p.get("filename") else {
        return Err(ImportError::invalid(
            &p.obj.loc,
            format!("{} needs `filename`", p.obj.what()),
        ));
    };
    let Value::Str(name) = &f.value else {
        return Err(ImportError::invalid(&f.loc, "`filename` is a <string>"));
    };
    k.push(("file".into(), T::String(tx.file(&f.loc, name)?)));
    let face = p.bool("face_normals", false)?;
    k.push((
        "normals".into(),
        T::String(if face { "face" } else { "vertex" }.into()),
    ));
    // Read by `uv_source`, for the textures.
    p.ignore(&["flip_tex_coords"]);
    Ok(k)
}

/// Does object `o`, or one nested in it, hold a texture?
fn has_texture(o: &Obj) -> bool {
    let nested = o.props.iter().filter_map(|p| match &p.value {
        Value::Object(c) => Some(c.as_ref()),
        _ => None,
    });
    o.tag == "texture"
        || nested
            .chain(o.children.iter().map(|c| c.as_ref()))
            .any(has_texture)
}

/// How shape `s` gives its uv against Mitsuba (textures on it are
/// translated for that; `None`: refused).
fn uv_source(s: &Obj) -> Option<UvSource> {
    match s.ty.as_str() {
        "obj" => {
            let flip = !matches!(
                s.prop("flip_tex_coords").map(|p| &p.value),
                Some(Value::Bool(false))
            );
            Some(if flip {
                UvSource::FlippedV
            } else {
                UvSource::Same
            })
        }
        "ply" | "rectangle" => Some(UvSource::Same),
        _ => None,
    }
}

fn file_stem(s: &Obj) -> Option<String> {
    match &s.prop("filename")?.value {
        Value::Str(f) => std::path::Path::new(f)
            .file_stem()
            .map(|x| x.to_string_lossy().into_owned()),
        _ => None,
    }
}

/// The shader of shape `s`: its BSDF's (Mitsuba's default, a one-sided
/// `diffuse` of 0.5, when it has none or lenient dropped it), with the
/// emission of its area emitter (none when lenient dropped it).
fn shape_shader(tx: &mut Tx, s: &Obj) -> Result<String, ImportError> {
    let bsdfs: Vec<_> = s.children_tagged("bsdf").collect();
    let emitters: Vec<_> = s.children_tagged("emitter").collect();
    for c in s
        .children
        .iter()
        .filter(|c| c.tag != "bsdf" && c.tag != "emitter")
    {
        tx.refuse_plugin(c, "not translated inside a shape")?;
    }
    if bsdfs.len() > 1 {
        return Err(ImportError::invalid(&bsdfs[1].loc, "a shape has one BSDF"));
    }
    let mut area = None;
    for e in emitters {
        if e.ty != "area" || area.is_some() {
            tx.refuse_plugin(e, "a shape carries one area emitter")?;
        } else if s.ty == "rectangle" {
            tx.refuse_plugin(
                e,
                "rtk's polygon (a rectangle's translation) cannot sample its surface, so it cannot be an area light; give the rectangle as an OBJ or PLY mesh",
            )?;
        } else {
            area = Some(e);
        }
    }
    let Some(e) = area else {
        return Ok(match bsdfs.first() {
            Some(b) => bsdf_shader(tx, b)?,
            None => default_diffuse(tx),
        });
    };
    // An emitter: its own shader, the BSDF's keys with the emission.
    let keys = match bsdfs.first() {
        Some(b) => bsdf_keys(tx, b)?,
        None => None,
    };
    let mut keys = keys.unwrap_or_else(|| diffuse_keys(vec3([0.5; 3]), false));
    let mut p = Props::new(e);
    let radiance = p
        .color(tx, "radiance", Role::Emission)?
        .unwrap_or(vec3([1.0; 3]));
    p.finish(tx)?;
    keys.push(("emission".into(), radiance));
    let name = tx
        .out
        .fresh_name(&format!("{}_emitter", s.id.as_deref().unwrap_or("area")));
    tx.out.shaders.push((name.clone(), keys));
    Ok(name)
}

pub(super) fn diffuse_keys(albedo: T, two_sided: bool) -> Keys {
    let mut k = def("lambert");
    k.push(("albedo".into(), albedo));
    if !two_sided {
        k.push(("two_sided".into(), T::Boolean(false)));
    }
    k
}

/// The shader for shapes without a BSDF.
fn default_diffuse(tx: &mut Tx) -> String {
    let name = "mitsuba_default_diffuse";
    if !tx.out.shaders.iter().any(|(n, _)| n == name) {
        tx.out
            .shaders
            .push((name.into(), diffuse_keys(vec3([0.5; 3]), false)));
    }
    name.into()
}

/// The shader of BSDF `b`, translated (or, lenient, dropped for the
/// default) once however many shapes use it.
fn bsdf_shader(tx: &mut Tx, b: &Rc<Obj>) -> Result<String, ImportError> {
    // A BSDF's translation depends on its shape's uv only through a
    // texture: without one, every shape shares one shader.
    let uv = if has_texture(b) { tx.uv_source } else { None };
    let key = (Rc::as_ptr(b), uv);
    if let Some((_, n)) = tx.shaders.iter().find(|(p, _)| *p == key) {
        return Ok(n.clone());
    }
    let name = match bsdf_keys(tx, b)? {
        Some(keys) => {
            let name = tx.out.fresh_name(b.id.as_deref().unwrap_or(&b.ty));
            tx.out.shaders.push((name.clone(), keys));
            name
        }
        None => default_diffuse(tx),
    };
    tx.shaders.push((key, name.clone()));
    Ok(name)
}

/// A BSDF's shader keys; `None` when lenient dropped it.
pub(super) fn bsdf_keys(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let two_sided = b.ty == "twosided";
    let inner: &Obj = if two_sided {
        let nested: Vec<_> = b.children_tagged("bsdf").collect();
        let [one] = nested[..] else {
            tx.refuse_plugin(
                b,
                "a twosided BSDF with two different sides is not translated",
            )?;
            return Ok(None);
        };
        Props::new(b).finish(tx)?;
        one
    } else {
        b
    };
    match inner.ty.as_str() {
        "diffuse" => {}
        "roughplastic" if !two_sided => return super::bsdfs::roughplastic(tx, inner),
        "bumpmap" if !two_sided => return super::bsdfs::bumpmap(tx, inner),
        "normalmap" if !two_sided => return super::bsdfs::normalmap(tx, inner),
        "plastic" if !two_sided => return super::bsdfs::plastic(tx, inner),
        "conductor" if !two_sided => return super::bsdfs::conductor(tx, inner),
        "mask" if !two_sided => return super::bsdfs::mask(tx, inner),
        "dielectric" if !two_sided => return super::bsdfs::dielectric(tx, inner),
        "roughdielectric" if !two_sided => return super::bsdfs::roughdielectric(tx, inner),
        "roughconductor" if !two_sided => return super::bsdfs::roughconductor(tx, inner),
        _ => {
            tx.refuse_plugin(
                inner,
                "rtk translates the BSDFs diffuse, twosided(diffuse), plastic, roughplastic, conductor, roughconductor, dielectric, roughdielectric, bumpmap(diffuse), normalmap(diffuse) and mask(diffuse) so far",
            )?;
            return Ok(None);
        }
    }
    Ok(Some(diffuse_keys(diffuse_albedo(tx, inner)?, two_sided)))
}

/// A `diffuse` BSDF's albedo (Mitsuba's default 0.5, also where lenient
/// dropped its texture).
pub(super) fn diffuse_albedo(tx: &mut Tx, d: &Obj) -> Result<T, ImportError> {
    let mut p = Props::new(d);
    let albedo = p
        .color(tx, "reflectance", Role::Reflectance)?
        .unwrap_or(vec3([0.5; 3]));
    p.finish(tx)?;
    Ok(albedo)
}
