//! `<emitter>`s outside shapes → `[lights.*]`. Mitsuba's RGB variants
//! use an `<rgb>` radiance or intensity as it is, so the values carry
//! over unchanged.

use super::{def, Props, Tx};
use crate::error::ImportError;
use crate::mitsuba::spectrum::Role;
use crate::mitsuba::xml::Obj;
use crate::rtk_scene::vec3;

/// One light.
pub fn light(tx: &mut Tx, e: &Obj) -> Result<(), ImportError> {
    let mut p = Props::new(e);
    let keys = match e.ty.as_str() {
        "directional" => {
            let mut k = def("directional");
            let dir =
                match p.transform("to_world")? {
                    Some(t) if p.obj.prop("direction").is_none() => t.vector([0.0, 0.0, 1.0]),
                    Some(_) => return Err(ImportError::invalid(
                        &e.loc,
                        "<emitter type=\"directional\">: give `direction` or `to_world`, not both",
                    )),
                    None => p.vec3("direction", [0.0, 0.0, 1.0])?,
                };
            k.push(("direction".into(), vec3(dir)));
            let irr = p
                .color(tx, "irradiance", Role::Emission)?
                .unwrap_or(vec3([1.0; 3]));
            k.push(("irradiance".into(), irr));
            k
        }
        "point" => {
            let mut k = def("point");
            let pos = match p.transform("to_world")? {
                Some(t) => t.point([0.0; 3]),
                None => p.vec3("position", [0.0; 3])?,
            };
            k.push(("position".into(), vec3(pos)));
            let i = p
                .color(tx, "intensity", Role::Emission)?
                .unwrap_or(vec3([1.0; 3]));
            k.push(("intensity".into(), i));
            k
        }
        "constant" => {
            let mut k = def("constant");
            let r = p
                .color(tx, "radiance", Role::Emission)?
                .unwrap_or(vec3([1.0; 3]));
            k.push(("radiance".into(), r));
            k
        }
        "projector" => projector(tx, &mut p)?,
        "envmap" => envmap(tx, &mut p)?,
        "area" => {
            return Err(ImportError::invalid(
                &e.loc,
                "an area emitter belongs inside the <shape> that emits",
            ))
        }
        _ => return tx.refuse_plugin(
            e,
            "rtk translates the emitters directional, point, constant, envmap, projector and area",
        ),
    };
    p.finish(tx)?;
    let name = tx.out.fresh_name(e.id.as_deref().unwrap_or(&e.ty));
    tx.out.lights.push((name, keys));
    Ok(())
}

/// `projector` → rtk's `projector`, which reproduces Mitsuba's projection
/// and normalisation; its texture is looked up at Mitsuba's own uv.
fn projector(tx: &mut Tx, p: &mut Props) -> Result<crate::rtk_scene::Keys, ImportError> {
    let mut k = def("projector");
    let m = match p.transform("to_world")? {
        Some(t) => t.m,
        None => super::super::transform::Transform::identity().m,
    };
    let flat: Vec<toml::Value> = m.iter().flatten().map(|x| toml::Value::Float(*x)).collect();
    k.push(("to_world".into(), toml::Value::Array(flat)));
    if p.obj.prop("focal_length").is_some() {
        return Err(ImportError::unsupported(
            &p.obj.loc,
            format!("{} parameter `focal_length`", p.obj.what()),
            "rtk's projector takes `fov` (or Mitsuba's default 50mm, when neither is given)",
        ));
    }
    if p.obj.prop("fov").is_some() {
        k.push(("fov".into(), toml::Value::Float(p.float("fov", 0.0)?)));
        k.push((
            "fov_axis".into(),
            toml::Value::String(p.string("fov_axis", "x")?),
        ));
    }
    tx.uv_source = Some(super::UvSource::Same);
    let irr = p
        .color(tx, "irradiance", Role::Emission)?
        .unwrap_or(vec3([1.0; 3]));
    k.push(("irradiance".into(), irr));
    k.push(("scale".into(), toml::Value::Float(p.float("scale", 1.0)?)));
    Ok(k)
}

/// `envmap` → rtk's `envmap`, which evaluates the map as Mitsuba does
/// (bilinear between texel centres, periodic in φ, poles at the first and
/// last rows); its own sampling gives the same mean.
fn envmap(tx: &mut Tx, p: &mut Props) -> Result<crate::rtk_scene::Keys, ImportError> {
    let mut k = def("envmap");
    let Some(loc) = p.obj.prop("filename").map(|f| f.loc.clone()) else {
        return Err(ImportError::invalid(
            &p.obj.loc,
            format!("{}: `filename` is required", p.obj.what()),
        ));
    };
    let name = p.string("filename", "")?;
    let file = tx.file(&loc, &name)?;
    k.push((
        "radiance".into(),
        crate::rtk_scene::inline_table(vec![("image_file".into(), toml::Value::String(file))]),
    ));
    k.push(("scale".into(), toml::Value::Float(p.float("scale", 1.0)?)));
    if let Some(t) = p.transform("to_world")? {
        let flat: Vec<toml::Value> =
            t.m.iter()
                .flatten()
                .map(|x| toml::Value::Float(*x))
                .collect();
        k.push(("to_world".into(), toml::Value::Array(flat)));
    }
    // Mitsuba's MIS compensation changes its sampling only, not the mean.
    p.ignore(&["mis_compensation"]);
    Ok(k)
}
