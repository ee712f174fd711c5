//! The scene description: the TOML file read and checked, before any plugin
//! is loaded. Everything the shell itself owns — `[render]`, definitions'
//! `class`, `children`, instances, transforms, references — is validated here
//! with errors that name file, line, column, object and key. Plugin
//! parameters are converted to JSON (refusing NaN and infinities) and checked
//! by the plugins themselves at `create`.

use crate::error::{ErrorKind, SceneError};
use crate::tree::{self, Node, Origin, Val};
use glam::DAffine3;
use rtk_kernel::xform;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The sections of a scene file, in the order they are documented.
pub const SECTIONS: [&str; 5] = ["render", "cameras", "lights", "shaders", "objects"];

/// A scene file: its text and its spanned tree.
#[derive(Debug, Clone)]
pub struct SceneFile {
    /// Path as given.
    pub path: PathBuf,
    /// Text.
    pub src: String,
    /// Parsed tree.
    pub root: Node,
}

impl SceneFile {
    /// Read and parse a scene file.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let src = std::fs::read_to_string(path).map_err(|e| SceneError {
            kind: ErrorKind::Io,
            file: path.to_path_buf(),
            place: crate::error::Place::Unknown,
            object: String::new(),
            key: String::new(),
            message: format!("cannot read the scene file: {e}"),
            notes: vec![],
        })?;
        Self::parse(path, src)
    }

    /// Parse scene text (the path is for messages and relative files).
    pub fn parse(path: &Path, src: String) -> Result<Self, SceneError> {
        match tree::parse(&src) {
            Ok(root) => Ok(SceneFile {
                path: path.to_path_buf(),
                src,
                root,
            }),
            Err((msg, span)) => {
                let origin = Origin::File(span.unwrap_or(0..0));
                let msg = msg.trim_end().to_string();
                Err(SceneError::at(
                    ErrorKind::Syntax,
                    path,
                    &src,
                    &origin,
                    "",
                    "",
                    msg,
                ))
            }
        }
    }

    /// Apply `--set key.path=value` overrides.
    pub fn apply_overrides(&mut self, sets: &[String]) -> Result<(), SceneError> {
        for s in sets {
            let Some((key, value)) = s.split_once('=') else {
                return Err(self.err(
                    ErrorKind::Invalid,
                    &Origin::CommandLine(s.clone()),
                    "",
                    "",
                    "expected --set key.path=value",
                ));
            };
            let keys: Vec<&str> = key.trim().split('.').collect();
            if keys.iter().any(|k| k.is_empty()) || !SECTIONS.contains(&keys[0]) {
                return Err(self.err(
                    ErrorKind::Invalid,
                    &Origin::CommandLine(s.clone()),
                    "",
                    key,
                    format!(
                        "the key path must start with one of {}",
                        SECTIONS.join(", ")
                    ),
                ));
            }
            let node = tree::parse_override_value(s, value.trim());
            if let Err(m) = self.root.set_path(&keys, node) {
                return Err(self.err(
                    ErrorKind::Invalid,
                    &Origin::CommandLine(s.clone()),
                    "",
                    key,
                    m,
                ));
            }
        }
        Ok(())
    }

    /// An error at an origin of this file.
    pub fn err(
        &self,
        kind: ErrorKind,
        origin: &Origin,
        object: &str,
        key: &str,
        msg: impl Into<String>,
    ) -> SceneError {
        SceneError::at(kind, &self.path, &self.src, origin, object, key, msg)
    }

    /// The folder relative file parameters resolve against.
    pub fn dir(&self) -> PathBuf {
        match self.path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }
}

/// Largest image, in pixels (the f64 film takes 24 bytes a pixel).
pub const MAX_PIXELS: u64 = 1 << 28;

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
}

/// A plugin definition: `[cameras.X]`, `[lights.X]`, `[shaders.X]`,
/// `[objects.X]`, or the integrator.
#[derive(Debug, Clone)]
pub struct Def {
    /// Section (`objects`...).
    pub section: &'static str,
    /// Name within the section.
    pub name: String,
    /// Class name.
    pub class: String,
    /// Where the class is named.
    pub class_origin: Origin,
    /// The definition's table (for locating plugin errors by key path).
    pub node: Node,
    /// Parameters for the plugin, as JSON text.
    pub params: String,
}

impl Def {
    /// `section.name`, as errors name it.
    pub fn path(&self) -> String {
        if self.name.is_empty() {
            self.section.to_string()
        } else {
            format!("{}.{}", self.section, self.name)
        }
    }
}

/// An object definition with its instances.
#[derive(Debug, Clone)]
pub struct ObjDef {
    /// The definition.
    pub def: Def,
    /// Its children (empty for primitives).
    pub children: Vec<Instance>,
    /// Where `children` was given, if it was.
    pub children_origin: Option<Origin>,
}

/// An instance: an object placed with its own transform, shader and attributes.
#[derive(Debug, Clone)]
pub struct Instance {
    /// Name of the object definition.
    pub object: String,
    /// Bound shader definition, if any.
    pub shader: Option<String>,
    /// Attribute block: parameters that override the shader's for this instance.
    pub attributes: Option<Node>,
    /// Composed transform (f64), if any.
    pub transform: Option<DAffine3>,
    /// Where the instance is written.
    pub origin: Origin,
    /// Where its `object` key is written.
    pub object_origin: Origin,
    /// Path of the instance for messages (`objects.world.children[2]`).
    pub path: String,
}

/// A checked scene description.
#[derive(Debug, Clone)]
pub struct Desc {
    /// `[render]`.
    pub render: Render,
    /// `[cameras.*]`.
    pub cameras: BTreeMap<String, Def>,
    /// `[lights.*]`.
    pub lights: BTreeMap<String, Def>,
    /// `[shaders.*]`.
    pub shaders: BTreeMap<String, Def>,
    /// `[objects.*]`.
    pub objects: BTreeMap<String, ObjDef>,
}

struct Ctx<'a> {
    file: &'a SceneFile,
}

impl Ctx<'_> {
    fn err(&self, origin: &Origin, object: &str, key: &str, msg: impl Into<String>) -> SceneError {
        self.file.err(ErrorKind::Invalid, origin, object, key, msg)
    }

    fn table<'n>(
        &self,
        n: &'n Node,
        object: &str,
        key: &str,
    ) -> Result<&'n [(String, Origin, Node)], SceneError> {
        match &n.value {
            Val::Table(t) => Ok(t),
            v => Err(self.err(
                &n.origin,
                object,
                key,
                format!("expected a table, found {}", v.type_name()),
            )),
        }
    }

    fn string(&self, n: &Node, object: &str, key: &str) -> Result<String, SceneError> {
        match &n.value {
            Val::Str(s) => Ok(s.clone()),
            v => Err(self.err(
                &n.origin,
                object,
                key,
                format!("expected a string, found {}", v.type_name()),
            )),
        }
    }

    fn uint(
        &self,
        n: &Node,
        object: &str,
        key: &str,
        min: i64,
        max: i64,
    ) -> Result<i64, SceneError> {
        match &n.value {
            Val::Int(i) if (min..=max).contains(i) => Ok(*i),
            Val::Int(i) => Err(self.err(
                &n.origin,
                object,
                key,
                format!("must be between {min} and {max}, got {i}"),
            )),
            v => Err(self.err(
                &n.origin,
                object,
                key,
                format!("expected an integer, found {}", v.type_name()),
            )),
        }
    }

    fn number(&self, n: &Node, object: &str, key: &str) -> Result<f64, SceneError> {
        let v = match &n.value {
            Val::Int(i) => *i as f64,
            Val::Float(f) => *f,
            v => {
                return Err(self.err(
                    &n.origin,
                    object,
                    key,
                    format!("expected a number, found {}", v.type_name()),
                ))
            }
        };
        if !v.is_finite() {
            return Err(self.err(
                &n.origin,
                object,
                key,
                format!("must be a finite number, got {v}"),
            ));
        }
        Ok(v)
    }

    fn unknown_keys(&self, n: &Node, object: &str, allowed: &[&str]) -> Result<(), SceneError> {
        for (k, ko, _) in self.table(n, object, "")? {
            if !allowed.contains(&k.as_str()) {
                return Err(self.err(
                    ko,
                    object,
                    k,
                    format!("unknown key; expected one of: {}", allowed.join(", ")),
                ));
            }
        }
        Ok(())
    }

    /// Convert a plugin's parameter table to JSON, leaving out the shell's keys.
    fn params_json(&self, n: &Node, object: &str, skip: &[&str]) -> Result<String, SceneError> {
        let mut map = serde_json::Map::new();
        for (k, _, v) in self.table(n, object, "")? {
            if skip.contains(&k.as_str()) {
                continue;
            }
            map.insert(k.clone(), self.json(v, object, k)?);
        }
        Ok(serde_json::Value::Object(map).to_string())
    }

    fn json(&self, n: &Node, object: &str, key: &str) -> Result<serde_json::Value, SceneError> {
        use serde_json::Value as J;
        Ok(match &n.value {
            Val::Str(s) => J::String(s.clone()),
            Val::Int(i) => J::from(*i),
            Val::Bool(b) => J::Bool(*b),
            Val::Float(f) => match serde_json::Number::from_f64(*f) {
                Some(x) if f.is_finite() => J::Number(x),
                _ => {
                    return Err(self.err(
                        &n.origin,
                        object,
                        key,
                        format!("must be a finite number, got {f}"),
                    ))
                }
            },
            Val::Datetime => {
                return Err(self.err(&n.origin, object, key, "date-times are not used by rtk"))
            }
            Val::Arr(a) => J::Array(
                a.iter()
                    .enumerate()
                    .map(|(i, c)| self.json(c, object, &format!("{key}[{i}]")))
                    .collect::<Result<_, _>>()?,
            ),
            Val::Table(t) => {
                let mut m = serde_json::Map::new();
                for (k, _, v) in t {
                    m.insert(k.clone(), self.json(v, object, &format!("{key}.{k}"))?);
                }
                J::Object(m)
            }
        })
    }

    fn def(
        &self,
        section: &'static str,
        name: &str,
        n: &Node,
        skip: &[&str],
    ) -> Result<Def, SceneError> {
        let object = format!("{section}.{name}");
        self.table(n, &object, "")?;
        let Some(cn) = n.get("class") else {
            return Err(self.err(
                &n.origin,
                &object,
                "class",
                "missing key `class` (the plugin to use)",
            ));
        };
        let class = self.string(cn, &object, "class")?;
        if !crate::plugins::is_identifier(&class) {
            return Err(self.err(
                &cn.origin,
                &object,
                "class",
                format!("`{class}` is not a class name: use a plain identifier (letters, digits, _), never a path"),
            ));
        }
        let mut skip_all = vec!["class"];
        skip_all.extend_from_slice(skip);
        Ok(Def {
            section,
            name: name.to_string(),
            class,
            class_origin: cn.origin.clone(),
            node: n.clone(),
            params: self.params_json(n, &object, &skip_all)?,
        })
    }

    fn instance(&self, n: &Node, path: &str) -> Result<Instance, SceneError> {
        let (obj_node, table_node) = match &n.value {
            Val::Str(_) => (n, None),
            Val::Table(_) => {
                self.unknown_keys(n, path, &["object", "shader", "transform", "attributes"])?;
                match n.get("object") {
                    Some(o) => (o, Some(n)),
                    None => {
                        return Err(self.err(
                            &n.origin,
                            path,
                            "object",
                            "missing key `object` (the definition to instance)",
                        ))
                    }
                }
            }
            v => {
                return Err(self.err(
                    &n.origin,
                    path,
                    "",
                    format!(
                        "an instance is an object name or a table {{ object = ... }}, found {}",
                        v.type_name()
                    ),
                ))
            }
        };
        let object = self.string(obj_node, path, "object")?;
        let mut inst = Instance {
            object,
            shader: None,
            attributes: None,
            transform: None,
            origin: n.origin.clone(),
            object_origin: obj_node.origin.clone(),
            path: path.to_string(),
        };
        let Some(t) = table_node else { return Ok(inst) };
        if let Some(s) = t.get("shader") {
            inst.shader = Some(self.string(s, path, "shader")?);
        }
        if let Some(a) = t.get("attributes") {
            self.table(a, path, "attributes")?;
            if inst.shader.is_none() {
                return Err(self.err(
                    &a.origin,
                    path,
                    "attributes",
                    "attributes override a shader's parameters: bind a `shader` too",
                ));
            }
            inst.attributes = Some(a.clone());
        }
        if let Some(tr) = t.get("transform") {
            inst.transform = Some(self.transform(tr, path)?);
        }
        Ok(inst)
    }

    fn transform(&self, n: &Node, path: &str) -> Result<DAffine3, SceneError> {
        let steps = match &n.value {
            Val::Arr(_) => n.clone(),
            Val::Table(_) => Node {
                origin: n.origin.clone(),
                value: Val::Arr(vec![n.clone()]),
            },
            v => {
                return Err(self.err(
                    &n.origin,
                    path,
                    "transform",
                    format!(
                        "expected a list of steps such as [{{ translate = [1, 0, 0] }}], found {}",
                        v.type_name()
                    ),
                ))
            }
        };
        let json = self.json(&steps, path, "transform")?;
        let parsed: Vec<xform::Step> = match rtk_kernel::parse_params(&json.to_string()) {
            Ok(s) => s,
            Err(e) => {
                let key = format!(
                    "transform{}",
                    if e.key.starts_with('[') {
                        e.key.clone()
                    } else {
                        String::new()
                    }
                );
                let origin = steps.locate_origin(&e.key);
                return Err(self.err(&origin, path, &key, e.message));
            }
        };
        xform::compose("", &parsed).map_err(|e| {
            let origin = steps.locate_origin(&e.key);
            self.err(&origin, path, &format!("transform{}", e.key), e.message)
        })
    }
}

impl Desc {
    /// Check a scene file and build its description.
    pub fn from_file(file: &SceneFile) -> Result<Desc, SceneError> {
        let cx = Ctx { file };
        let root = &file.root;
        cx.unknown_keys(root, "", &SECTIONS)?;

        let mut sections: BTreeMap<&str, Vec<(String, Node)>> = BTreeMap::new();
        for sec in &SECTIONS[1..] {
            let mut defs = Vec::new();
            if let Some(n) = root.get(sec) {
                for (name, _, v) in cx.table(n, sec, "")? {
                    defs.push((name.clone(), v.clone()));
                }
            }
            sections.insert(sec, defs);
        }
        let mut cameras = BTreeMap::new();
        for (name, n) in &sections["cameras"] {
            cameras.insert(name.clone(), cx.def("cameras", name, n, &[])?);
        }
        let mut lights = BTreeMap::new();
        for (name, n) in &sections["lights"] {
            lights.insert(name.clone(), cx.def("lights", name, n, &[])?);
        }
        let mut shaders = BTreeMap::new();
        for (name, n) in &sections["shaders"] {
            shaders.insert(name.clone(), cx.def("shaders", name, n, &[])?);
        }
        let mut objects = BTreeMap::new();
        for (name, n) in &sections["objects"] {
            let def = cx.def("objects", name, n, &["children"])?;
            let mut children = Vec::new();
            let mut children_origin = None;
            if let Some(c) = n.get("children") {
                children_origin = Some(c.origin.clone());
                let Val::Arr(items) = &c.value else {
                    return Err(cx.err(
                        &c.origin,
                        &def.path(),
                        "children",
                        format!(
                            "expected an array of instances, found {}",
                            c.value.type_name()
                        ),
                    ));
                };
                for (i, it) in items.iter().enumerate() {
                    children.push(cx.instance(it, &format!("objects.{name}.children[{i}]"))?);
                }
            }
            objects.insert(
                name.clone(),
                ObjDef {
                    def,
                    children,
                    children_origin,
                },
            );
        }

        let render = Self::render(&cx, root, &cameras)?;
        let desc = Desc {
            render,
            cameras,
            lights,
            shaders,
            objects,
        };
        desc.check_references(&cx)?;
        Ok(desc)
    }

    fn render(
        cx: &Ctx,
        root: &Node,
        cameras: &BTreeMap<String, Def>,
    ) -> Result<Render, SceneError> {
        let obj = "render";
        let Some(r) = root.get("render") else {
            return Err(cx.err(
                &root.origin,
                "",
                "render",
                "missing section [render] (at least `root = \"...\"`)",
            ));
        };
        cx.unknown_keys(
            r,
            obj,
            &[
                "width",
                "height",
                "spp",
                "seed",
                "camera",
                "root",
                "integrator",
                "background",
                "output",
            ],
        )?;
        let int = |k: &str, d: i64, min: i64, max: i64| -> Result<i64, SceneError> {
            r.get(k).map_or(Ok(d), |n| cx.uint(n, obj, k, min, max))
        };
        let width = int("width", 512, 1, 65536)? as u32;
        let height = int("height", 384, 1, 65536)? as u32;
        let spp = int("spp", 1, 1, 1 << 24)? as u32;
        if width as u64 * height as u64 > MAX_PIXELS {
            return Err(cx.err(
                &r.get("width").unwrap_or(r).origin,
                obj,
                "width",
                format!("{width}x{height} is more than rtk's limit of {MAX_PIXELS} pixels; render it in crops"),
            ));
        }
        let seed = int("seed", 0, 0, i64::MAX)? as u64;
        let (camera, camera_origin) = match r.get("camera") {
            Some(n) => (cx.string(n, obj, "camera")?, n.origin.clone()),
            None => match cameras.len() {
                1 => (
                    cameras.keys().next().cloned().unwrap_or_default(),
                    r.origin.clone(),
                ),
                0 => {
                    return Err(cx.err(
                        &r.origin,
                        obj,
                        "camera",
                        "the scene defines no camera: add a [cameras.NAME] table",
                    ))
                }
                _ => {
                    return Err(cx.err(
                        &r.origin,
                        obj,
                        "camera",
                        format!(
                            "several cameras are defined ({}): say which with `camera = \"...\"`",
                            cameras.keys().cloned().collect::<Vec<_>>().join(", ")
                        ),
                    ))
                }
            },
        };
        let Some(rn) = r.get("root") else {
            return Err(cx.err(
                &r.origin,
                obj,
                "root",
                "missing key `root` (the object to render)",
            ));
        };
        let root_inst = cx.instance(rn, "render.root")?;
        let integrator = match r.get("integrator") {
            None => Def {
                section: "render",
                name: String::new(),
                class: "whitted".into(),
                class_origin: r.origin.clone(),
                node: Node {
                    origin: r.origin.clone(),
                    value: Val::Table(vec![]),
                },
                params: "{}".into(),
            },
            Some(
                n @ Node {
                    value: Val::Str(_), ..
                },
            ) => {
                let class = cx.string(n, obj, "integrator")?;
                let table = Node {
                    origin: n.origin.clone(),
                    value: Val::Table(vec![("class".into(), n.origin.clone(), n.clone())]),
                };
                let mut d = cx.def("render", "integrator", &table, &[])?;
                d.class = class;
                d
            }
            Some(
                n @ Node {
                    value: Val::Table(_),
                    ..
                },
            ) => cx.def("render", "integrator", n, &[])?,
            Some(n) => {
                return Err(cx.err(
                    &n.origin,
                    obj,
                    "integrator",
                    format!(
                        "expected a class name or a table {{ class = \"...\", ... }}, found {}",
                        n.value.type_name()
                    ),
                ))
            }
        };
        let background = match r.get("background") {
            None => [0.0; 3],
            Some(n) => {
                let Val::Arr(a) = &n.value else {
                    return Err(cx.err(&n.origin, obj, "background", "expected [r, g, b]"));
                };
                if a.len() != 3 {
                    return Err(cx.err(&n.origin, obj, "background", "expected [r, g, b]"));
                }
                let mut out = [0.0f32; 3];
                for (i, c) in a.iter().enumerate() {
                    let v = cx.number(c, obj, &format!("background[{i}]"))?;
                    if v < 0.0 {
                        return Err(cx.err(
                            &c.origin,
                            obj,
                            &format!("background[{i}]"),
                            "must not be negative",
                        ));
                    }
                    out[i] = v as f32;
                }
                out
            }
        };
        let output = r
            .get("output")
            .map(|n| cx.string(n, obj, "output"))
            .transpose()?;
        Ok(Render {
            width,
            height,
            spp,
            seed,
            camera,
            camera_origin,
            root: root_inst,
            integrator,
            background,
            output,
        })
    }

    /// Every name refers to a definition of the right section (checked for
    /// all definitions: it needs no plugin).
    fn check_references(&self, cx: &Ctx) -> Result<(), SceneError> {
        let names = |m: Vec<&String>| m.into_iter().cloned().collect::<Vec<_>>().join(", ");
        if !self.cameras.contains_key(&self.render.camera) {
            return Err(cx
                .file
                .err(
                    ErrorKind::UnknownReference,
                    &self.render.camera_origin,
                    "render",
                    "camera",
                    format!("no camera named `{}`", self.render.camera),
                )
                .note(format!(
                    "cameras defined: {}",
                    names(self.cameras.keys().collect())
                )));
        }
        let mut all: Vec<&Instance> = vec![&self.render.root];
        for o in self.objects.values() {
            all.extend(o.children.iter());
        }
        for inst in all {
            if !self.objects.contains_key(&inst.object) {
                return Err(cx
                    .file
                    .err(
                        ErrorKind::UnknownReference,
                        &inst.object_origin,
                        &inst.path,
                        "object",
                        format!("no object named `{}`", inst.object),
                    )
                    .note(format!(
                        "objects defined: {}",
                        names(self.objects.keys().collect())
                    )));
            }
            if let Some(s) = &inst.shader {
                if !self.shaders.contains_key(s) {
                    return Err(cx
                        .file
                        .err(
                            ErrorKind::UnknownReference,
                            &inst.origin,
                            &inst.path,
                            "shader",
                            format!("no shader named `{s}`"),
                        )
                        .note(format!(
                            "shaders defined: {}",
                            names(self.shaders.keys().collect())
                        )));
                }
            }
        }
        Ok(())
    }
}

/// A value of the tree as JSON (NaN and infinities refused), for plugin parameters.
pub fn node_json(
    file: &SceneFile,
    n: &Node,
    object: &str,
    key: &str,
) -> Result<serde_json::Value, SceneError> {
    Ctx { file }.json(n, object, key)
}
