//! Each Mitsuba plugin mapped to rtk's (docs/import.md has the table).
//!
//! Every object is read through `Props`, which marks the properties the
//! translation used: whatever is left is refused by name at the end, so a
//! parameter this code does not know can never be dropped silently. A
//! parameter that only restates rtk's behaviour (Mitsuba's default) is
//! accepted; any other value of it is refused.

use super::spectrum::{self, Role};
use super::transform::{Step, Transform};
use super::xml::{Document, Obj, Prop, Value};
use crate::error::{ImportError, Loc};
use crate::rtk_scene::{inline_table, vec3, Keys, RtkScene};
use crate::{Imported, Options};
use std::path::Path;
use std::rc::Rc;
use toml::Value as T;

mod bsdfs;
mod emitters;
mod scene_objects;
mod sensor;
mod textures;

pub(super) use textures::UvSource;

/// The translation's state: the scene being built and what was dropped.
pub(super) struct Tx<'a> {
    pub doc: &'a Document,
    pub opts: &'a Options,
    pub out: RtkScene,
    pub warnings: Vec<String>,
    /// BSDFs already translated (by object identity and the uv of the
    /// shapes they are on, which their textures depend on) and their shader.
    pub shaders: Vec<((*const Obj, Option<UvSource>), String)>,
    /// Scene parameters referenced as `$name` in the output, with their
    /// values as the translation typed them.
    pub used_params: Vec<(String, T)>,
    /// How the shape being translated gives its uv (`None`: not as
    /// Mitsuba does, so its textures are refused).
    pub uv_source: Option<UvSource>,
}

impl Tx<'_> {
    /// Refuse `e`, or (lenient) record it as dropped.
    pub fn refuse(&mut self, e: ImportError) -> Result<(), ImportError> {
        if self.opts.lenient {
            self.warnings
                .push(format!("warning: {e} (dropped: --lenient)"));
            Ok(())
        } else {
            Err(e)
        }
    }

    /// Refuse the whole object `o` (a plugin rtk has no translation for).
    pub fn refuse_plugin(&mut self, o: &Obj, why: &str) -> Result<(), ImportError> {
        self.refuse(ImportError::unsupported(&o.loc, o.what(), why))
    }

    /// `v`, or `"$name"` when the property was written as a whole
    /// parameter and `v` is its value unchanged.
    pub fn param_or(&mut self, p: &Prop, v: T) -> T {
        match &p.param {
            Some(name) => {
                if !self.used_params.iter().any(|(n, _)| n == name) {
                    self.used_params.push((name.clone(), v));
                }
                T::String(format!("${name}"))
            }
            None => v,
        }
    }

    /// A file named in the scene, as the TOML should name it: relative to
    /// the TOML's folder where both resolve, else absolute.
    pub fn file(&self, at: &Loc, name: &str) -> Result<String, ImportError> {
        let p = self.doc.resolve(at, name);
        if !p.is_file() {
            return Err(ImportError::invalid(
                at,
                format!(
                    "the file `{name}` does not exist (looked for {} and in the <path> folders)",
                    p.display()
                ),
            ));
        }
        Ok(crate::rtk_scene::file_name(&p, &self.opts.out_dir))
    }
}

/// An object's properties, each marked when the translation reads it.
pub(super) struct Props<'o> {
    pub obj: &'o Obj,
    used: Vec<bool>,
}

impl<'o> Props<'o> {
    pub fn new(obj: &'o Obj) -> Self {
        Props {
            obj,
            used: vec![false; obj.props.len()],
        }
    }

    /// The property `name`, marked read.
    pub fn get(&mut self, name: &str) -> Option<&'o Prop> {
        let i = self.obj.props.iter().position(|p| p.name == name)?;
        self.used[i] = true;
        Some(&self.obj.props[i])
    }

    fn wrong(&self, p: &Prop, want: &str) -> ImportError {
        ImportError::invalid(
            &p.loc,
            format!(
                "{}: `{}` is a <{}>, expected {want}",
                self.obj.what(),
                p.name,
                p.value.tag()
            ),
        )
    }

    /// A number (`<float>` or `<integer>`), or `default`.
    pub fn float(&mut self, name: &str, default: f64) -> Result<f64, ImportError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(f) => Ok(f),
                Value::Int(i) => Ok(i as f64),
                _ => Err(self.wrong(p, "a <float>")),
            },
        }
    }

    /// An `<integer>`, or `default`.
    pub fn int(&mut self, name: &str, default: i64) -> Result<i64, ImportError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Int(i) => Ok(i),
                _ => Err(self.wrong(p, "an <integer>")),
            },
        }
    }

    /// A `<boolean>`, or `default`.
    pub fn bool(&mut self, name: &str, default: bool) -> Result<bool, ImportError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Bool(b) => Ok(b),
                _ => Err(self.wrong(p, "a <boolean>")),
            },
        }
    }

    /// A `<string>`, or `default`.
    pub fn string(&mut self, name: &str, default: &str) -> Result<String, ImportError> {
        match self.get(name) {
            None => Ok(default.to_string()),
            Some(p) => match &p.value {
                Value::Str(s) => Ok(s.clone()),
                _ => Err(self.wrong(p, "a <string>")),
            },
        }
    }

    /// A `<vector>` or `<point>`, or `default`.
    pub fn vec3(&mut self, name: &str, default: [f64; 3]) -> Result<[f64; 3], ImportError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Vector(v) | Value::Point(v) => Ok(v),
                _ => Err(self.wrong(p, "a <vector> or <point>")),
            },
        }
    }

    /// A `<transform>`, if given.
    pub fn transform(&mut self, name: &str) -> Result<Option<&'o Transform>, ImportError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::Transform(t) => Ok(Some(t)),
                _ => Err(self.wrong(p, "a <transform>")),
            },
        }
    }

    /// A colour: `<rgb>`, a `<spectrum>` (reduced to RGB as Mitsuba's RGB
    /// variants do for its `role`), a `<float>` (grey) or a texture. `None`
    /// when absent.
    pub fn color(&mut self, tx: &mut Tx, name: &str, role: Role) -> Result<Option<T>, ImportError> {
        let Some(p) = self.get(name) else {
            return Ok(None);
        };
        let v = match &p.value {
            Value::Color(c) => vec3(*c),
            Value::Float(f) => vec3([*f; 3]),
            Value::Int(i) => vec3([*i as f64; 3]),
            Value::UniformSpectrum(v) => vec3(spectrum::uniform_to_srgb(*v, role)),
            Value::Spectrum(pairs) => match spectrum::list_to_srgb(pairs, role) {
                Some(c) => vec3(c),
                None => {
                    return Err(ImportError::invalid(
                        &p.loc,
                        format!(
                            "{}: `{name}`: the wavelengths of a <spectrum> must increase",
                            self.obj.what()
                        ),
                    ))
                }
            },
            Value::Object(o) if o.tag == "texture" => return textures::texture(tx, o, name),
            _ => return Err(self.wrong(p, "a colour (<rgb>, <spectrum> or <float>)")),
        };
        Ok(Some(tx.param_or(p, v)))
    }

    /// Accept `name` if it is absent or equal to `default` (rtk's own
    /// behaviour); otherwise refuse it, saying `why`.
    pub fn only_default(
        &mut self,
        tx: &mut Tx,
        name: &str,
        default: &Value,
        why: &str,
    ) -> Result<(), ImportError> {
        let Some(p) = self.get(name) else {
            return Ok(());
        };
        let same = match (&p.value, default) {
            (Value::Bool(a), Value::Bool(b)) => a == b,
            (Value::Int(a), Value::Int(b)) => a == b,
            (Value::Float(a), Value::Float(b)) => a == b,
            (Value::Int(a), Value::Float(b)) => *a as f64 == *b,
            (Value::Float(a), Value::Int(b)) => *a == *b as f64,
            (Value::Str(a), Value::Str(b)) => a.eq_ignore_ascii_case(b),
            _ => false,
        };
        if same {
            return Ok(());
        }
        tx.refuse(ImportError::unsupported(
            &p.loc,
            format!("{} parameter `{name}`", self.obj.what()),
            why.to_string(),
        ))
    }

    /// Accept `names` whatever their values: they do not change the image
    /// rtk computes (an output file format, a Mitsuba-only optimisation).
    pub fn ignore(&mut self, names: &[&str]) {
        for n in names {
            self.get(n);
        }
    }

    /// Refuse every property not read.
    pub fn finish(self, tx: &mut Tx) -> Result<(), ImportError> {
        for (p, used) in self.obj.props.iter().zip(&self.used) {
            if !used {
                tx.refuse(ImportError::unsupported(
                    &p.loc,
                    format!("{} parameter `{}`", self.obj.what(), p.name),
                    "rtk's translation of this plugin has no such parameter",
                ))?;
            }
        }
        Ok(())
    }
}

/// rtk's transform steps for `t` (`transform = [...]` of an instance).
pub(super) fn steps(t: &Transform) -> T {
    let items = t
        .steps
        .iter()
        .map(|s| match s {
            Step::Translate(v) => inline_table(vec![("translate".into(), vec3(*v))]),
            Step::Scale(v) if v[0] == v[1] && v[1] == v[2] => {
                inline_table(vec![("scale".into(), T::Float(v[0]))])
            }
            Step::Scale(v) => inline_table(vec![("scale".into(), vec3(*v))]),
            Step::Rotate { axis, angle } => inline_table(vec![(
                "rotate".into(),
                inline_table(vec![
                    ("axis".into(), vec3(*axis)),
                    ("angle".into(), T::Float(*angle)),
                ]),
            )]),
            Step::Matrix(m) => inline_table(vec![(
                "matrix".into(),
                T::Array(m.iter().map(|x| T::Float(*x)).collect()),
            )]),
        })
        .collect();
    T::Array(items)
}

/// Translate the whole document.
pub fn scene(doc: &Document, path: &Path, opts: &Options) -> Result<Imported, ImportError> {
    let mut tx = Tx {
        doc,
        opts,
        out: RtkScene::default(),
        warnings: Vec::new(),
        shaders: Vec::new(),
        used_params: Vec::new(),
        uv_source: None,
    };
    let scene = &doc.scene;
    let (major, minor, patch) = doc.version;
    tx.out.header.push(format!(
        "Imported by `rtk import` from {} (Mitsuba scene version {major}.{minor}.{patch}).",
        path.display()
    ));
    sensor::integrator(&mut tx, scene)?;
    sensor::sensor(&mut tx, scene)?;
    let mut children = Vec::new();
    for c in &scene.children {
        top_level(&mut tx, c, &mut children)?;
    }
    if children.is_empty() {
        return Err(ImportError::invalid(
            &scene.loc,
            "the scene has no shape rtk can render",
        ));
    }
    let root = tx.out.fresh_name("scene");
    tx.out.render.push(("root".into(), T::String(root.clone())));
    tx.out.objects.push((
        root,
        vec![
            ("class".into(), T::String("bvh".into())),
            ("children".into(), T::Array(children)),
        ],
    ));
    declare_params(&mut tx);
    let toml = tx.out.to_toml();
    Ok(Imported {
        toml,
        warnings: tx.warnings,
    })
}

/// One child of `<scene>`: shapes become instances of the root, emitters
/// lights; BSDFs and textures with an id wait for their references.
fn top_level(tx: &mut Tx, c: &Rc<Obj>, children: &mut Vec<T>) -> Result<(), ImportError> {
    match c.tag.as_str() {
        "shape" => scene_objects::shape(tx, c, children),
        "emitter" => emitters::light(tx, c),
        "sensor" | "integrator" => Ok(()),
        "bsdf" | "texture" | "spectrum" if c.id.is_some() => Ok(()),
        "medium" | "phase" | "volume" => tx.refuse_plugin(
            c,
            "participating media are not supported by rtk's importer (issue 23 refuses them)",
        ),
        _ => tx.refuse_plugin(c, "no rtk translation for this plugin"),
    }
}

/// `[params]`: the parameters the output refers to, with their values
/// as the elements that used them typed them; the others are noted in the
/// header as fixed at import.
fn declare_params(tx: &mut Tx) {
    let mut fixed = Vec::new();
    for p in &tx.doc.params {
        match tx.used_params.iter().find(|(n, _)| *n == p.name) {
            Some((n, v)) => tx.out.params.push((n.clone(), v.clone())),
            None => fixed.push(format!("{} = {}", p.name, p.value)),
        }
    }
    if !fixed.is_empty() {
        tx.out.header.push(format!(
            "Mitsuba parameters fixed at import (they are not one value here): {}.",
            fixed.join(", ")
        ));
    }
}

/// Keys of a definition: `class` first.
pub(super) fn def(class: &str) -> Keys {
    vec![("class".into(), T::String(class.into()))]
}
