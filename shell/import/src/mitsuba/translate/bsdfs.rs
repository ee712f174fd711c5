//! BSDFs beyond `diffuse`: Mitsuba's parameters mapped onto the rtk shader
//! that implements the same model, refusing what that shader lacks.

use super::{def, Props, Tx};
use crate::error::ImportError;
use crate::mitsuba::spectrum::Role;
use crate::mitsuba::xml::{Obj, Value};
use crate::rtk_scene::{vec3, Keys};
use toml::Value as T;

/// Mitsuba's named indices of refraction (`include/mitsuba/render/ior.h`,
/// stored as f32 there, so given here as the f32 values print).
const IOR: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// An index of refraction: a `<float>`, or a `<string>` naming one of
/// Mitsuba's materials (case-insensitive), or `default`.
fn ior(p: &mut Props, name: &str, default: &str) -> Result<f64, ImportError> {
    let what = p.obj.what();
    let (text, loc) = match p.get(name) {
        None => (default.to_string(), p.obj.loc.clone()),
        Some(prop) => match &prop.value {
            Value::Float(f) => return Ok(*f),
            Value::Int(i) => return Ok(*i as f64),
            Value::Str(s) => (s.clone(), prop.loc.clone()),
            _ => {
                return Err(ImportError::invalid(
                    &prop.loc,
                    format!("{what}: `{name}` must be a <float> or a <string> naming a material"),
                ))
            }
        },
    };
    let lower = text.to_lowercase();
    match IOR.iter().find(|(n, _)| *n == lower) {
        // Through the f32's shortest decimal, so that 1.5046 stays 1.5046.
        Some((_, v)) => Ok(v.to_string().parse().unwrap_or(*v as f64)),
        None => Err(ImportError::invalid(
            &loc,
            format!(
                "{what}: `{name}` = \"{text}\" is not one of Mitsuba's named indices ({})",
                IOR.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        )),
    }
}

/// `roughplastic` → rtk's `roughplastic` (the same model and tables, GGX
/// or Beckmann).
/// `None` when lenient dropped it.
pub(super) fn roughplastic(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let mut p = Props::new(b);
    // Mitsuba's default is Beckmann (rtk's is GGX: always written).
    let dist = distribution(b, &mut p)?;
    // Sampling only: the image's mean is the same either way.
    p.ignore(&["sample_visible"]);
    let mut k = def("roughplastic");
    k.push(("distribution".into(), T::String(dist)));
    k.push(("alpha".into(), T::Float(p.float("alpha", 0.1)?)));
    if !coat(tx, b, &mut p, &mut k)? {
        return Ok(None);
    }
    p.finish(tx)?;
    Ok(Some(k))
}

/// `plastic` → rtk's `plastic` (the same model and Fresnel fits). `None`
/// when lenient dropped it.
pub(super) fn plastic(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let mut p = Props::new(b);
    let mut k = def("plastic");
    if !coat(tx, b, &mut p, &mut k)? {
        return Ok(None);
    }
    p.finish(tx)?;
    Ok(Some(k))
}

/// The keys a plastic's coat and base share (indices, colours,
/// `nonlinear`), pushed onto `k`; false when lenient dropped the BSDF.
fn coat(tx: &mut Tx, b: &Obj, p: &mut Props, k: &mut Keys) -> Result<bool, ImportError> {
    k.push((
        "int_ior".into(),
        T::Float(ior(p, "int_ior", "polypropylene")?),
    ));
    k.push(("ext_ior".into(), T::Float(ior(p, "ext_ior", "air")?)));
    let rho = p
        .color(tx, "diffuse_reflectance", Role::Reflectance)?
        .unwrap_or(vec3([0.5; 3]));
    k.push(("diffuse_reflectance".into(), rho));
    if !tint(tx, b, p, k, "specular_reflectance", "specular_reflectance")? {
        return Ok(false);
    }
    if p.bool("nonlinear", false)? {
        k.push(("nonlinear".into(), T::Boolean(true)));
    }
    Ok(true)
}

/// `bumpmap` around a `diffuse` → `lambert` with `bump_map` and
/// `bump_scale` (the same tilt and shadowing term). `None` when lenient
/// dropped it.
pub(super) fn bumpmap(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let nested: Vec<_> = b.children_tagged("bsdf").collect();
    let inner = match nested[..] {
        [one] if one.ty == "diffuse" => one,
        _ => {
            tx.refuse_plugin(b, "rtk translates a bumpmap around one diffuse BSDF")?;
            return Ok(None);
        }
    };
    let mut p = Props::new(b);
    let scale = p.float("scale", 1.0)?;
    for flag in ["use_shadowing_function", "flip_invalid_normals"] {
        p.only_default(
            tx,
            flag,
            &Value::Bool(true),
            "rtk's bump map always applies Mitsuba's default rule",
        )?;
    }
    // Mitsuba takes the first texture among the properties, whatever its name.
    let height = b.props.iter().find_map(|q| match &q.value {
        Value::Object(o) if o.tag == "texture" => Some((q.name.clone(), o.clone())),
        _ => None,
    });
    let Some((name, tex)) = height else {
        return Err(ImportError::invalid(
            &b.loc,
            format!("{}: needs a height <texture>", b.what()),
        ));
    };
    p.get(&name);
    let Some(map) = super::textures::texture(tx, &tex, &name)? else {
        return Ok(None);
    };
    p.finish(tx)?;
    let albedo = super::scene_objects::diffuse_albedo(tx, inner)?;
    let mut k = super::scene_objects::diffuse_keys(albedo, false);
    k.push(("bump_map".into(), map));
    k.push(("bump_scale".into(), T::Float(scale)));
    Ok(Some(k))
}

/// `conductor` → rtk's `conductor`: Mitsuba's Fresnel term for the complex
/// index (`eta`, `k`, or a named `material`'s spectra), one-sided. `None`
/// when lenient dropped it.
pub(super) fn conductor(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let mut p = Props::new(b);
    let mut k = def("conductor");
    let Some(index) = complex_index(tx, b, &mut p)? else {
        return Ok(None);
    };
    if let Some((eta, kk)) = index {
        k.push(("eta".into(), eta));
        k.push(("k".into(), kk));
    }
    if !tint(tx, b, &mut p, &mut k, "specular_reflectance", "reflectance")? {
        return Ok(None);
    }
    k.push(("two_sided".into(), T::Boolean(false)));
    p.finish(tx)?;
    Ok(Some(k))
}

/// A conductor's complex index as RGB `eta` and `k`: given, or read from
/// the named `material`'s `ior/NAME.eta.spd` and `.k.spd` and reduced as
/// Mitsuba's RGB variants reduce them (unweighted, unclipped above).
/// `Some(None)`: Mitsuba's `none`, a perfect mirror; `None`: dropped.
fn complex_index(
    tx: &mut Tx,
    b: &Obj,
    p: &mut Props,
) -> Result<Option<Option<(T, T)>>, ImportError> {
    let material = p.string("material", "none")?;
    let given = b.props.iter().any(|q| q.name == "eta" || q.name == "k");
    if given && material != "none" {
        return Err(ImportError::invalid(
            &b.loc,
            format!(
                "{}: give either `eta` and `k` or `material`, not both",
                b.what()
            ),
        ));
    }
    if material == "none" && !given {
        return Ok(Some(None));
    }
    if given {
        let eta = p
            .color(tx, "eta", Role::Unbounded)?
            .unwrap_or(vec3([0.0; 3]));
        let k = p.color(tx, "k", Role::Unbounded)?.unwrap_or(vec3([1.0; 3]));
        if !matches!((&eta, &k), (T::Array(_), T::Array(_))) {
            tx.refuse_plugin(b, "a textured `eta` or `k` is not translated")?;
            return Ok(None);
        }
        return Ok(Some(Some((eta, k))));
    }
    let [eta, k] = ["eta", "k"].map(|part| material_spectrum(tx, b, &material, part));
    Ok(Some(Some((eta?, k?))))
}

/// `ior/MATERIAL.PART.spd` (PART `eta` or `k`), looked for in the
/// `<path>` folders and in the scene file's folder and each folder above
/// it (where Mitsuba's test data keeps `ior/`), reduced to RGB.
fn material_spectrum(tx: &Tx, b: &Obj, material: &str, part: &str) -> Result<T, ImportError> {
    let name = format!("{material}.{part}.spd");
    let above = b.loc.file.ancestors().skip(1).map(|d| d.to_path_buf());
    let dirs: Vec<_> = tx.doc.search.iter().cloned().chain(above).collect();
    let Some(path) = dirs
        .iter()
        .map(|d| d.join("ior").join(&name))
        .find(|f| f.is_file())
    else {
        return Err(ImportError::invalid(
            &b.loc,
            format!(
                "{}: material `{material}`: no ior/{name} in the <path> folders or beside the scene (Mitsuba ships these spectra; copy its `ior` folder next to the scene)",
                b.what()
            ),
        ));
    };
    let Value::Spectrum(pairs) = crate::mitsuba::xml::spectrum_file(&path, &b.loc)? else {
        unreachable!("spectrum_file returns a list");
    };
    match crate::mitsuba::spectrum::list_to_srgb(&pairs, Role::Unbounded) {
        Some(c) => Ok(vec3(c)),
        None => Err(ImportError::invalid(
            &b.loc,
            format!("{}: the wavelengths must increase", path.display()),
        )),
    }
}

/// `roughconductor` → rtk's `roughconductor` in Mitsuba's form: its
/// distribution (Beckmann by default), separable masking, the complex
/// index, one-sided. Anisotropic roughness is refused. `None` when
/// lenient dropped it.
pub(super) fn roughconductor(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let mut p = Props::new(b);
    let dist = distribution(b, &mut p)?;
    p.ignore(&["sample_visible"]);
    let mut k = def("roughconductor");
    let alpha = p.float("alpha", 0.1)?;
    let aniso = match (p.get("alpha_u").is_some(), p.get("alpha_v").is_some()) {
        (false, false) => None,
        _ => Some((p.float("alpha_u", alpha)?, p.float("alpha_v", alpha)?)),
    };
    if aniso.is_some_and(|(u, v)| u != v) && dist != "ggx" {
        tx.refuse_plugin(b, "rtk's anisotropic roughconductor is GGX only")?;
        return Ok(None);
    }
    k.push(("distribution".into(), T::String(dist)));
    k.push(("masking".into(), T::String("separable".into())));
    match aniso {
        Some((u, v)) if u != v => {
            k.push(("alpha_u".into(), T::Float(u)));
            k.push(("alpha_v".into(), T::Float(v)));
        }
        Some((u, _)) => k.push(("alpha".into(), T::Float(u))),
        None => k.push(("alpha".into(), T::Float(alpha))),
    }
    let Some(index) = complex_index(tx, b, &mut p)? else {
        return Ok(None);
    };
    if let Some((eta, kk)) = index {
        k.push(("eta".into(), eta));
        k.push(("k".into(), kk));
    }
    if !tint(tx, b, &mut p, &mut k, "specular_reflectance", "reflectance")? {
        return Ok(None);
    }
    k.push(("two_sided".into(), T::Boolean(false)));
    p.finish(tx)?;
    Ok(Some(k))
}

/// `mask` around a `diffuse` or a `twosided` `diffuse` → `lambert` with
/// `opacity` (Mitsuba's default opacity is 0.5). `None` when lenient
/// dropped it.
pub(super) fn mask(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let nested: Vec<_> = b.children_tagged("bsdf").collect();
    let inner = match nested[..] {
        [one] if one.ty == "diffuse" => Some((one, false)),
        [one] if one.ty == "twosided" => {
            match one.children_tagged("bsdf").collect::<Vec<_>>()[..] {
                [d] if d.ty == "diffuse" => {
                    Props::new(one).finish(tx)?;
                    Some((d, true))
                }
                _ => None,
            }
        }
        _ => None,
    };
    let Some((diffuse, two_sided)) = inner else {
        tx.refuse_plugin(
            b,
            "rtk translates a mask around one diffuse or twosided(diffuse) BSDF",
        )?;
        return Ok(None);
    };
    let mut p = Props::new(b);
    let opacity = p
        .color(tx, "opacity", Role::Reflectance)?
        .unwrap_or(vec3([0.5; 3]));
    p.finish(tx)?;
    let albedo = super::scene_objects::diffuse_albedo(tx, diffuse)?;
    let mut k = super::scene_objects::diffuse_keys(albedo, two_sided);
    k.push(("opacity".into(), opacity));
    Ok(Some(k))
}

/// `dielectric` → rtk's `dielectric`: η = int_ior / ext_ior, Mitsuba's
/// radiance scaling across the interface. `None` when lenient dropped it.
pub(super) fn dielectric(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let mut p = Props::new(b);
    let eta = ior(&mut p, "int_ior", "bk7")? / ior(&mut p, "ext_ior", "air")?;
    let mut k = def("dielectric");
    k.push(("eta".into(), T::Float(eta)));
    for (theirs, ours) in [
        ("specular_reflectance", "reflectance"),
        ("specular_transmittance", "transmittance"),
    ] {
        if !tint(tx, b, &mut p, &mut k, theirs, ours)? {
            return Ok(None);
        }
    }
    k.push(("scale_radiance".into(), T::Boolean(true)));
    p.finish(tx)?;
    Ok(Some(k))
}

/// `roughdielectric` → rtk's `roughdielectric`: its distribution
/// (Beckmann by default), η = int_ior / ext_ior, Mitsuba's radiance
/// scaling. Anisotropic roughness is refused. `None` when lenient dropped it.
pub(super) fn roughdielectric(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let mut p = Props::new(b);
    let dist = distribution(b, &mut p)?;
    p.ignore(&["sample_visible"]);
    let mut k = def("roughdielectric");
    k.push(("distribution".into(), T::String(dist)));
    k.push(("alpha".into(), T::Float(p.float("alpha", 0.1)?)));
    let eta = ior(&mut p, "int_ior", "bk7")? / ior(&mut p, "ext_ior", "air")?;
    k.push(("eta".into(), T::Float(eta)));
    for (theirs, ours) in [
        ("specular_reflectance", "reflectance"),
        ("specular_transmittance", "transmittance"),
    ] {
        if !tint(tx, b, &mut p, &mut k, theirs, ours)? {
            return Ok(None);
        }
    }
    k.push(("scale_radiance".into(), T::Boolean(true)));
    p.finish(tx)?;
    Ok(Some(k))
}

/// `normalmap` around a `diffuse` → `lambert` with `normal_map` (the same
/// frame, flips and shadowing term). `None` when lenient dropped it.
pub(super) fn normalmap(tx: &mut Tx, b: &Obj) -> Result<Option<Keys>, ImportError> {
    let nested: Vec<_> = b.children_tagged("bsdf").collect();
    if let ([one], true) = (&nested[..], is_identity_map(b)) {
        // (0.5, 0.5, 1) is the unperturbed normal: the frame, the flips and
        // the shadowing term (1 for an untilted normal) change nothing.
        let mut p = Props::new(b);
        p.ignore(&[
            "normalmap",
            "use_shadowing_function",
            "flip_invalid_normals",
        ]);
        p.finish(tx)?;
        return super::scene_objects::bsdf_keys(tx, one);
    }
    let inner = match nested[..] {
        [one] if one.ty == "diffuse" => one,
        _ => {
            tx.refuse_plugin(b, "rtk translates a normalmap around one diffuse BSDF")?;
            return Ok(None);
        }
    };
    let mut p = Props::new(b);
    for flag in ["use_shadowing_function", "flip_invalid_normals"] {
        p.only_default(
            tx,
            flag,
            &Value::Bool(true),
            "rtk's normal map always applies Mitsuba's default rule",
        )?;
    }
    let Some(prop) = p.get("normalmap") else {
        return Err(ImportError::invalid(
            &b.loc,
            format!("{}: needs a `normalmap` <texture>", b.what()),
        ));
    };
    let Value::Object(tex) = &prop.value else {
        return Err(ImportError::invalid(
            &prop.loc,
            format!("{}: `normalmap` must be a <texture>", b.what()),
        ));
    };
    let Some(map) = super::textures::texture(tx, tex, "normalmap")? else {
        return Ok(None);
    };
    p.finish(tx)?;
    let albedo = super::scene_objects::diffuse_albedo(tx, inner)?;
    let mut k = super::scene_objects::diffuse_keys(albedo, false);
    k.push(("normal_map".into(), map));
    Ok(Some(k))
}

/// Is `b`'s `normalmap` a `rawconstant` of (0.5, 0.5, 1): every normal the
/// shading normal itself?
fn is_identity_map(b: &Obj) -> bool {
    let Some(prop) = b.props.iter().find(|p| p.name == "normalmap") else {
        return false;
    };
    let Value::Object(t) = &prop.value else {
        return false;
    };
    t.ty == "rawconstant"
        && t.props.iter().any(|q| {
            q.name == "value"
                && matches!(q.value, Value::Vector(v) | Value::Point(v) if v == [0.5, 0.5, 1.0])
        })
}

/// The microfacet `distribution`, Mitsuba's default (Beckmann) if absent.
fn distribution(b: &Obj, p: &mut Props) -> Result<String, ImportError> {
    let dist = p.string("distribution", "beckmann")?.to_ascii_lowercase();
    if dist != "ggx" && dist != "beckmann" {
        return Err(ImportError::invalid(
            &b.loc,
            format!(
                "{}: distribution `{dist}`: Mitsuba's are ggx and beckmann",
                b.what()
            ),
        ));
    }
    Ok(dist)
}

/// Mitsuba's colour `theirs` as rtk's `ours` on `k`, if given; false when
/// it is a texture (refused: rtk's tints are colours) and lenient dropped
/// the BSDF.
fn tint(
    tx: &mut Tx,
    b: &Obj,
    p: &mut Props,
    k: &mut Keys,
    theirs: &str,
    ours: &str,
) -> Result<bool, ImportError> {
    if let Some(c) = p.color(tx, theirs, Role::Reflectance)? {
        if !matches!(c, T::Array(_)) {
            tx.refuse_plugin(b, &format!("a textured {theirs} is not translated"))?;
            return Ok(false);
        }
        k.push((ours.into(), c));
    }
    Ok(true)
}
