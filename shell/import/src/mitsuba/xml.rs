//! Mitsuba XML read into a tree of plugin objects and their properties,
//! with Mitsuba's own pre-processing done the way its parser does it
//! (`src/core/parser.cpp` in mitsuba-renderer/mitsuba3): `<default>` and
//! `$name` substitution in attribute values (`\$` escapes), `<include>`,
//! `<path>` search folders, `<ref>` and `<alias>`, transforms composed from
//! their steps, and version 0.x/1.x files upgraded (camelCase property
//! names to snake_case, `diffuse_reflectance` to `reflectance`).
//!
//! Every object and property keeps its location, so the translation can
//! say where each thing it refuses is.

use super::transform::Transform;
use crate::error::{ImportError, Loc};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

/// Largest scene file read (an XML scene names its bulk data by file).
pub const MAX_XML_BYTES: u64 = 64 << 20;

/// Deepest chain of `<include>`s.
pub const MAX_INCLUDE_DEPTH: usize = 16;

/// Deepest nesting of elements (a hostile file could nest millions).
const MAX_ELEMENT_DEPTH: usize = 64;

/// A property's value, as Mitsuba types it by its tag.
#[derive(Debug, Clone)]
pub enum Value {
    /// `<integer>`.
    Int(i64),
    /// `<float>`.
    Float(f64),
    /// `<boolean>`.
    Bool(bool),
    /// `<string>`.
    Str(String),
    /// `<rgb>`.
    Color([f64; 3]),
    /// `<spectrum value="v">`: uniform (its RGB depends on its use).
    UniformSpectrum(f64),
    /// `<spectrum value="λ:v, ...">`: wavelength (nm) and value pairs.
    Spectrum(Vec<(f64, f64)>),
    /// `<vector>`.
    Vector([f64; 3]),
    /// `<point>`.
    Point([f64; 3]),
    /// `<transform>`, composed, with its steps as written.
    Transform(Transform),
    /// A nested object given a `name` (a texture, a nested BSDF).
    Object(Rc<Obj>),
}

impl Value {
    /// The tag a value of this kind is written with, for messages.
    pub fn tag(&self) -> &'static str {
        match self {
            Value::Int(_) => "integer",
            Value::Float(_) => "float",
            Value::Bool(_) => "boolean",
            Value::Str(_) => "string",
            Value::Color(_) => "rgb",
            Value::UniformSpectrum(_) => "spectrum",
            Value::Spectrum(_) => "spectrum",
            Value::Vector(_) => "vector",
            Value::Point(_) => "point",
            Value::Transform(_) => "transform",
            Value::Object(_) => "object",
        }
    }
}

/// A named property of an object.
#[derive(Debug, Clone)]
pub struct Prop {
    /// Its name (snake_case, upgraded from older versions).
    pub name: String,
    /// Its value.
    pub value: Value,
    /// Where it is written.
    pub loc: Loc,
    /// The scene parameter whose whole value this is (`value="$spp"`):
    /// the translation keeps it a parameter where it maps one to one.
    pub param: Option<String>,
}

/// A plugin object: `<shape type="obj">`, `<bsdf type="diffuse">`, ...
#[derive(Debug)]
pub struct Obj {
    /// The tag: `shape`, `bsdf`, `emitter`, `sensor`, `film`, `rfilter`,
    /// `sampler`, `integrator`, `texture`, `medium`, ... (`scene` for the root).
    pub tag: String,
    /// The plugin type.
    pub ty: String,
    /// Its `id`, if it has one.
    pub id: Option<String>,
    /// Named properties, in order.
    pub props: Vec<Prop>,
    /// Objects nested without a name (a shape's BSDF and emitter, a
    /// sensor's film and sampler, the scene's contents), in order.
    pub children: Vec<Rc<Obj>>,
    /// Where it is written.
    pub loc: Loc,
}

impl Obj {
    /// `<tag type="ty">`, for messages.
    pub fn what(&self) -> String {
        format!("<{} type=\"{}\">", self.tag, self.ty)
    }

    /// The property `name`, if given.
    pub fn prop(&self, name: &str) -> Option<&Prop> {
        self.props.iter().find(|p| p.name == name)
    }

    /// Nested objects with tag `tag`.
    pub fn children_tagged<'a>(&'a self, tag: &'a str) -> impl Iterator<Item = &'a Rc<Obj>> + 'a {
        self.children.iter().filter(move |c| c.tag == tag)
    }
}

/// A scene parameter: a `<default>` (or one given on the command line).
#[derive(Debug, Clone)]
pub struct Param {
    /// Its name.
    pub name: String,
    /// Its value as text (Mitsuba's parameters are text).
    pub value: String,
    /// Where its `<default>` is, if the scene declares it.
    pub loc: Option<Loc>,
}

/// A Mitsuba scene read from XML.
#[derive(Debug)]
pub struct Document {
    /// The `<scene>` element and everything in it (includes merged).
    pub scene: Rc<Obj>,
    /// The parameters in effect, in declaration order: the command line's
    /// values, then the `<default>`s not overridden.
    pub params: Vec<Param>,
    /// The `version` of the top-level file.
    pub version: (u32, u32, u32),
    /// Where file names are looked for, in order: the `<path>` folders
    /// (the last declared first), then the top-level file's folder.
    pub search: Vec<PathBuf>,
}

/// Read `path` with parameters `given` (name, value), as `mitsuba -D`.
pub fn read(path: &Path, given: &[(String, String)]) -> Result<Document, ImportError> {
    let mut p = Parser {
        params: given
            .iter()
            .map(|(n, v)| Param {
                name: n.clone(),
                value: v.clone(),
                loc: None,
            })
            .collect(),
        ids: HashMap::new(),
        search: vec![path.parent().unwrap_or(Path::new(".")).to_path_buf()],
        stack: Vec::new(),
        version: (3, 0, 0),
    };
    let top = p.read_file(path, None)?;
    let version = p.version;
    let mut scene = Obj {
        tag: "scene".into(),
        ty: "scene".into(),
        id: None,
        props: Vec::new(),
        children: Vec::new(),
        loc: Loc::file_start(path),
    };
    p.scene_contents(&top, &mut scene)?;
    Ok(Document {
        scene: Rc::new(scene),
        params: p.params,
        version,
        search: p.search,
    })
}

/// One file's text and parsed tree, kept while its elements are read.
struct FileDoc {
    path: Arc<PathBuf>,
    text: String,
    version: (u32, u32, u32),
}

struct Parser {
    params: Vec<Param>,
    ids: HashMap<String, Rc<Obj>>,
    search: Vec<PathBuf>,
    stack: Vec<PathBuf>,
    version: (u32, u32, u32),
}

/// Read a scene file's text (a regular file of at most [`MAX_XML_BYTES`],
/// UTF-8): Mitsuba's and pbrt's alike.
pub(crate) fn read_text(path: &Path) -> Result<String, ImportError> {
    let err = |message: String| ImportError::Read {
        path: path.to_path_buf(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| err(format!("cannot read it: {e}")))?;
    if !meta.is_file() {
        return Err(err("not a regular file".into()));
    }
    if meta.len() > MAX_XML_BYTES {
        return Err(err(format!(
            "{} bytes: larger than the {} MiB a scene file may be",
            meta.len(),
            MAX_XML_BYTES >> 20
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| err(format!("cannot read it: {e}")))?;
    String::from_utf8(bytes).map_err(|e| {
        err(format!(
            "not UTF-8 text (byte {} is not valid)",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// The location of byte `pos` of `doc`.
fn loc_at(f: &FileDoc, pos: usize) -> Loc {
    let before = &f.text[..pos.min(f.text.len())];
    let line = before.matches('\n').count() as u32 + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) as u32 + 1;
    Loc {
        file: f.path.clone(),
        line,
        col,
    }
}

/// roxmltree's error `e` in `f`, located.
fn syntax_error(f: &FileDoc, e: roxmltree::Error) -> ImportError {
    let p = e.pos();
    let at = Loc {
        file: f.path.clone(),
        line: p.row,
        col: p.col,
    };
    match e {
        // roxmltree says where the document starts.
        roxmltree::Error::DtdDetected => ImportError::Syntax {
            loc: f.text.find("<!DOCTYPE").map_or(at, |i| loc_at(f, i)),
            message: "a <!DOCTYPE> (DTD): rtk reads no DTD and expands no entities (Mitsuba scenes have none)".into(),
        },
        e => ImportError::Syntax {
            loc: at,
            message: e.to_string(),
        },
    }
}

/// A version attribute `a.b.c` as numbers.
fn parse_version(s: &str) -> Option<(u32, u32, u32)> {
    let mut it = s.trim().split('.').map(|p| p.parse::<u32>());
    let a = it.next()?.ok()?;
    let b = it.next().unwrap_or(Ok(0)).ok()?;
    let c = it.next().unwrap_or(Ok(0)).ok()?;
    Some((a, b, c))
}

impl Parser {
    /// Parse `path` (named at `at`, for an include) and check its root.
    fn read_file(&mut self, path: &Path, at: Option<&Loc>) -> Result<FileDoc, ImportError> {
        let text = read_text(path).map_err(|e| match (e, at) {
            (ImportError::Read { path, message }, Some(at)) => ImportError::invalid(
                at,
                format!("the included file {}: {message}", path.display()),
            ),
            (e, _) => e,
        })?;
        let mut f = FileDoc {
            path: Arc::new(path.to_path_buf()),
            text,
            version: (3, 0, 0),
        };
        let opts = roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        };
        let version = {
            let doc = roxmltree::Document::parse_with_options(&f.text, opts)
                .map_err(|e| syntax_error(&f, e))?;
            let root = doc.root_element();
            let loc = loc_at(&f, root.range().start);
            if root.tag_name().name() != "scene" {
                return Err(ImportError::invalid(
                    &loc,
                    format!(
                        "the root element is <{}>: a Mitsuba scene is a <scene>",
                        root.tag_name().name()
                    ),
                ));
            }
            match root.attribute("version") {
                Some(v) => parse_version(v).ok_or_else(|| {
                    ImportError::invalid(&loc, format!("version=\"{v}\" is not a version a.b.c"))
                })?,
                None => {
                    return Err(ImportError::invalid(
                        &loc,
                        "<scene> needs a version attribute (Mitsuba refuses a scene without one)",
                    ))
                }
            }
        };
        f.version = version;
        if self.stack.is_empty() {
            self.version = version;
        }
        Ok(f)
    }

    /// The contents of `f`'s `<scene>` into `scene`.
    fn scene_contents(&mut self, f: &FileDoc, scene: &mut Obj) -> Result<(), ImportError> {
        self.stack.push(canonical(&f.path));
        let opts = roxmltree::ParsingOptions {
            allow_dtd: false,
            ..Default::default()
        };
        let doc =
            roxmltree::Document::parse_with_options(&f.text, opts).expect("parsed once already");
        for node in doc.root_element().children().filter(|n| n.is_element()) {
            let loc = loc_at(f, node.range().start);
            match node.tag_name().name() {
                "default" => self.default(node, &loc)?,
                "path" => {
                    let v = self.attr(node, "value", &loc)?.0;
                    let dir = relative_to(&f.path, &v);
                    let dir = if dir.is_dir() {
                        Some(dir)
                    } else {
                        find(&self.search, &v)
                    };
                    match dir.filter(|d| d.is_dir()) {
                        Some(d) => self.search.insert(0, d),
                        None => {
                            return Err(ImportError::invalid(
                                &loc,
                                format!("<path value=\"{v}\">: no such folder"),
                            ))
                        }
                    }
                }
                "include" => self.include(f, node, &loc, scene)?,
                "alias" => {
                    let id = self.attr(node, "id", &loc)?.0;
                    let to = self.attr(node, "as", &loc)?.0;
                    let o = self.lookup(&id, &loc)?;
                    self.ids.insert(to, o);
                }
                _ => {
                    let child = self.element(f, node, &loc, 1)?;
                    match child {
                        Item::Object(o) => scene.children.push(o),
                        Item::Prop(p) => scene.props.push(*p),
                    }
                }
            }
        }
        self.stack.pop();
        Ok(())
    }

    fn default(&mut self, node: roxmltree::Node, loc: &Loc) -> Result<(), ImportError> {
        let name = self.attr(node, "name", loc)?.0;
        let value = self.attr(node, "value", loc)?.0;
        if !self.params.iter().any(|p| p.name == name) {
            self.params.push(Param {
                name,
                value,
                loc: Some(loc.clone()),
            });
        } else if let Some(p) = self.params.iter_mut().find(|p| p.name == name) {
            p.loc.get_or_insert(loc.clone());
        }
        Ok(())
    }

    fn include(
        &mut self,
        f: &FileDoc,
        node: roxmltree::Node,
        loc: &Loc,
        scene: &mut Obj,
    ) -> Result<(), ImportError> {
        let name = self.attr(node, "filename", loc)?.0;
        let path = self.resolve(&f.path, &name);
        let key = canonical(&path);
        if let Some(i) = self.stack.iter().position(|p| *p == key) {
            let chain: Vec<String> = self.stack[i..]
                .iter()
                .chain(std::iter::once(&key))
                .map(|p| p.display().to_string())
                .collect();
            return Err(ImportError::invalid(
                loc,
                format!("include cycle: {}", chain.join(" -> ")),
            ));
        }
        if self.stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(ImportError::invalid(
                loc,
                format!("includes nested more than {MAX_INCLUDE_DEPTH} deep"),
            ));
        }
        let inner = self.read_file(&path, Some(loc))?;
        self.scene_contents(&inner, scene)
    }

    fn lookup(&self, id: &str, loc: &Loc) -> Result<Rc<Obj>, ImportError> {
        self.ids.get(id).cloned().ok_or_else(|| {
            ImportError::invalid(
                loc,
                format!("<ref id=\"{id}\">: no object with this id is declared before it"),
            )
        })
    }

    /// Attribute `name` of `node`, parameters substituted; with the
    /// parameter it was whole, if it was one (`"$spp"`).
    fn attr(
        &self,
        node: roxmltree::Node,
        name: &str,
        loc: &Loc,
    ) -> Result<(String, Option<String>), ImportError> {
        match node.attribute(name) {
            Some(v) => self.substitute(v, loc),
            None => Err(ImportError::invalid(
                loc,
                format!("<{}> needs the attribute `{name}`", node.tag_name().name()),
            )),
        }
    }

    fn opt_attr(
        &self,
        node: roxmltree::Node,
        name: &str,
        loc: &Loc,
    ) -> Result<Option<(String, Option<String>)>, ImportError> {
        node.attribute(name)
            .map(|v| self.substitute(v, loc))
            .transpose()
    }

    /// Mitsuba's substitution: every `$name` of a parameter replaced (the
    /// longest names first), `\$` kept as a literal `$`, any other `$name`
    /// an error.
    fn substitute(&self, v: &str, loc: &Loc) -> Result<(String, Option<String>), ImportError> {
        if !v.contains('$') {
            return Ok((v.to_string(), None));
        }
        let mut out = String::with_capacity(v.len());
        let mut whole = None;
        let mut rest = v;
        while let Some(i) = rest.find('$') {
            let escaped = rest[..i].ends_with('\\');
            out.push_str(&rest[..i - escaped as usize]);
            let after = &rest[i + 1..];
            let n = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            if escaped {
                out.push('$');
                rest = after;
                continue;
            }
            // The longest parameter name that prefixes what follows.
            let name = &after[..n];
            let p = (self.params.iter())
                .filter(|p| name.starts_with(p.name.as_str()) && !p.name.is_empty())
                .max_by_key(|p| p.name.len());
            let Some(p) = p else {
                return Err(ImportError::invalid(
                    loc,
                    format!("undefined parameter: ${name} (declare it with <default name=\"{name}\" value=\"...\"/> or pass it with -D {name}=...)"),
                ));
            };
            if v == format!("${}", p.name) {
                whole = Some(p.name.clone());
            }
            out.push_str(&p.value);
            rest = &after[p.name.len()..];
        }
        out.push_str(rest);
        Ok((out, whole))
    }

    /// A `<spectrum>`'s value: its `filename`'s `.spd` pairs (found as a
    /// plugin's file is), or its `value` (with the parameter it names).
    fn spectrum_value(
        &self,
        node: roxmltree::Node,
        loc: &Loc,
    ) -> Result<(Value, Option<String>), ImportError> {
        if let Some((name, _)) = self.opt_attr(node, "filename", loc)? {
            let path = find(&self.search, &name).unwrap_or_else(|| relative_to(&loc.file, &name));
            return Ok((spectrum_file(&path, loc)?, None));
        }
        let (v, param) = self.attr(node, "value", loc)?;
        Ok((spectrum(&v, loc)?, param))
    }

    /// An `<include>`d file name resolved as Mitsuba does: beside the
    /// including file, then beside each file including that one, then as
    /// any file name ([`Document::resolve`]).
    fn resolve(&self, from: &Path, name: &str) -> PathBuf {
        let mut dirs = vec![from.parent().unwrap_or(Path::new(".")).to_path_buf()];
        let parents = self.stack.iter().rev().filter_map(|p| p.parent());
        dirs.extend(parents.map(Path::to_path_buf));
        dirs.extend(self.search.iter().cloned());
        find(&dirs, name).unwrap_or_else(|| relative_to(from, name))
    }
}

/// What an element inside an object is.
enum Item {
    Object(Rc<Obj>),
    Prop(Box<Prop>),
}

impl Parser {
    /// Any element inside `<scene>` or an object, `depth` deep.
    fn element(
        &mut self,
        f: &FileDoc,
        node: roxmltree::Node,
        loc: &Loc,
        depth: usize,
    ) -> Result<Item, ImportError> {
        if depth > MAX_ELEMENT_DEPTH {
            return Err(ImportError::invalid(
                loc,
                format!("elements nested more than {MAX_ELEMENT_DEPTH} deep"),
            ));
        }
        let tag = node.tag_name().name();
        let name = self
            .opt_attr(node, "name", loc)?
            .map(|n| upgrade_name(&n.0, f.version));
        let prop = |value: Value, param: Option<String>| -> Result<Item, ImportError> {
            let name = name.clone().ok_or_else(|| {
                ImportError::invalid(loc, format!("<{tag}> needs the attribute `name`"))
            })?;
            Ok(Item::Prop(Box::new(Prop {
                name,
                value,
                loc: loc.clone(),
                param,
            })))
        };
        match tag {
            "integer" | "float" | "boolean" | "string" => {
                let (v, param) = self.attr(node, "value", loc)?;
                prop(scalar(tag, &v, loc)?, param)
            }
            "rgb" => {
                let (v, param) = self.attr(node, "value", loc)?;
                prop(Value::Color(color(&v, loc)?), param)
            }
            "spectrum" if node.attribute("type").is_none() => {
                let (v, param) = self.spectrum_value(node, loc)?;
                prop(v, param)
            }
            "vector" | "point" => {
                let v = self.xyz(node, loc, 0.0)?;
                prop(
                    if tag == "vector" {
                        Value::Vector(v)
                    } else {
                        Value::Point(v)
                    },
                    None,
                )
            }
            "transform" => prop(Value::Transform(self.transform(node, loc)?), None),
            "ref" => {
                let id = self.attr(node, "id", loc)?.0;
                let o = self.lookup(&id, loc)?;
                match name {
                    Some(_) => prop(Value::Object(o), None),
                    None => Ok(Item::Object(o)),
                }
            }
            "default" | "path" | "include" | "alias" => Err(ImportError::invalid(
                loc,
                format!("<{tag}> belongs directly inside <scene>"),
            )),
            _ => {
                let o = Rc::new(self.object(f, node, loc, depth)?);
                if let Some(id) = &o.id {
                    self.ids.insert(id.clone(), o.clone());
                }
                match name {
                    Some(_) => prop(Value::Object(o), None),
                    None => Ok(Item::Object(o)),
                }
            }
        }
    }

    /// A plugin object and its contents.
    fn object(
        &mut self,
        f: &FileDoc,
        node: roxmltree::Node,
        loc: &Loc,
        depth: usize,
    ) -> Result<Obj, ImportError> {
        let tag = node.tag_name().name().to_string();
        let ty = match self.opt_attr(node, "type", loc)? {
            Some((t, _)) => t,
            None => {
                return Err(ImportError::invalid(
                    loc,
                    format!("<{tag}> is neither a property nor a plugin object with a `type`"),
                ))
            }
        };
        let id = self.opt_attr(node, "id", loc)?.map(|i| i.0);
        let mut o = Obj {
            tag,
            ty,
            id,
            props: Vec::new(),
            children: Vec::new(),
            loc: loc.clone(),
        };
        for child in node.children().filter(|n| n.is_element()) {
            let cloc = loc_at(f, child.range().start);
            match self.element(f, child, &cloc, depth + 1)? {
                Item::Object(c) => o.children.push(c),
                Item::Prop(p) => {
                    if o.props.iter().any(|q| q.name == p.name) {
                        return Err(ImportError::invalid(
                            &cloc,
                            format!("{}: the property `{}` is given twice", o.what(), p.name),
                        ));
                    }
                    o.props.push(*p)
                }
            }
        }
        if f.version < (2, 0, 0) && o.ty == "diffuse" {
            for p in &mut o.props {
                if p.name == "diffuse_reflectance" {
                    p.name = "reflectance".into();
                }
            }
        }
        Ok(o)
    }

    /// A vector from `value="x, y, z"` or the `x`, `y`, `z` attributes
    /// (missing ones `default`).
    fn xyz(&self, node: roxmltree::Node, loc: &Loc, default: f64) -> Result<[f64; 3], ImportError> {
        if let Some((v, _)) = self.opt_attr(node, "value", loc)? {
            let n = numbers(&v, loc)?;
            return match n[..] {
                [a] => Ok([a; 3]),
                [a, b, c] => Ok([a, b, c]),
                _ => Err(ImportError::invalid(
                    loc,
                    format!("value=\"{v}\": expected 3 numbers (or 1)"),
                )),
            };
        }
        let mut out = [default; 3];
        for (k, a) in ["x", "y", "z"].iter().enumerate() {
            if let Some((v, _)) = self.opt_attr(node, a, loc)? {
                out[k] = number(&v, loc)?;
            }
        }
        Ok(out)
    }

    /// A `<transform>`: its steps composed, each applied after the ones
    /// before it.
    fn transform(&self, node: roxmltree::Node, loc: &Loc) -> Result<Transform, ImportError> {
        let mut t = Transform::identity();
        for step in node.children().filter(|n| n.is_element()) {
            let tag = step.tag_name().name();
            match tag {
                "translate" => t.translate(self.xyz(step, loc, 0.0)?),
                "scale" => t.scale(self.xyz(step, loc, 1.0)?),
                "rotate" => {
                    let axis = self.xyz(step, loc, 0.0)?;
                    let angle = match self.opt_attr(step, "angle", loc)? {
                        Some((a, _)) => number(&a, loc)?,
                        None => 0.0,
                    };
                    t.rotate(axis, angle)
                        .map_err(|m| ImportError::invalid(loc, format!("<rotate>: {m}")))?;
                }
                "matrix" => {
                    let (v, _) = self
                        .opt_attr(step, "value", loc)?
                        .ok_or_else(|| ImportError::invalid(loc, "<matrix> needs `value`"))?;
                    t.matrix(&numbers(&v, loc)?)
                        .map_err(|m| ImportError::invalid(loc, format!("<matrix>: {m}")))?;
                }
                "lookat" => {
                    let get = |a: &str| -> Result<Option<[f64; 3]>, ImportError> {
                        match self.opt_attr(step, a, loc)? {
                            Some((v, _)) => match numbers(&v, loc)?[..] {
                                [x, y, z] => Ok(Some([x, y, z])),
                                _ => Err(ImportError::invalid(
                                    loc,
                                    format!("<lookat {a}=\"{v}\">: expected 3 numbers"),
                                )),
                            },
                            None => Ok(None),
                        }
                    };
                    let origin = get("origin")?.unwrap_or([0.0; 3]);
                    let target = get("target")?.unwrap_or([0.0, 0.0, 1.0]);
                    t.look_at(origin, target, get("up")?)
                        .map_err(|m| ImportError::invalid(loc, format!("<lookat>: {m}")))?;
                }
                other => {
                    return Err(ImportError::invalid(
                        loc,
                        format!("<{other}> is not a transform step (translate, scale, rotate, matrix, lookat)"),
                    ))
                }
            }
        }
        Ok(t)
    }
}

/// Mitsuba's upgrade of a property name from a version before 2.0:
/// camelCase to snake_case (`toWorld` → `to_world`, `maxDepth` →
/// `max_depth`, `intIOR` → `int_ior`).
pub fn upgrade_name(name: &str, version: (u32, u32, u32)) -> String {
    if version >= (2, 0, 0) {
        return name.to_string();
    }
    let c: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < c.len() {
        if i > 0 && c[i - 1].is_ascii_lowercase() && c[i].is_ascii_uppercase() {
            out.push('_');
            out.push(c[i].to_ascii_lowercase());
            while i + 1 < c.len() && c[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(c[i].to_ascii_lowercase());
            }
        } else {
            out.push(c[i]);
        }
        i += 1;
    }
    out
}

fn scalar(tag: &str, v: &str, loc: &Loc) -> Result<Value, ImportError> {
    let bad = |what: &str| ImportError::invalid(loc, format!("<{tag} value=\"{v}\">: not {what}"));
    Ok(match tag {
        "integer" => Value::Int(v.trim().parse().map_err(|_| bad("an integer"))?),
        "float" => Value::Float(number(v, loc)?),
        "boolean" => match v.trim().to_ascii_lowercase().as_str() {
            "true" => Value::Bool(true),
            "false" => Value::Bool(false),
            _ => return Err(bad("true or false")),
        },
        _ => Value::Str(v.to_string()),
    })
}

/// One finite number.
pub fn number(v: &str, loc: &Loc) -> Result<f64, ImportError> {
    match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(ImportError::invalid(
            loc,
            format!("`{v}` is not a finite number"),
        )),
    }
}

/// Numbers separated by commas and/or white space.
fn numbers(v: &str, loc: &Loc) -> Result<Vec<f64>, ImportError> {
    v.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| number(s, loc))
        .collect()
}

fn color(v: &str, loc: &Loc) -> Result<[f64; 3], ImportError> {
    match numbers(v, loc)?[..] {
        [a] => Ok([a; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => Err(ImportError::invalid(
            loc,
            format!("<rgb value=\"{v}\">: expected 3 numbers (or 1)"),
        )),
    }
}

/// `<spectrum value="0.5">` (uniform) or `value="400:0.1, 500:0.2"`.
fn spectrum(v: &str, loc: &Loc) -> Result<Value, ImportError> {
    if !v.contains(':') {
        return Ok(Value::UniformSpectrum(number(v, loc)?));
    }
    let pairs = v
        .split(',')
        .map(|pair| {
            let (l, x) = pair.split_once(':').ok_or_else(|| {
                ImportError::invalid(loc, format!("<spectrum>: `{pair}` is not wavelength:value"))
            })?;
            Ok((number(l, loc)?, number(x, loc)?))
        })
        .collect::<Result<Vec<_>, ImportError>>()?;
    Ok(Value::Spectrum(pairs))
}

/// A `<spectrum filename="...">`: Mitsuba's `.spd` format
/// (`spectrum_from_file` in `src/core/spectrum.cpp`), lines of a wavelength
/// in nm and a value, `#` starting a comment to the end of its line.
pub fn spectrum_file(path: &Path, loc: &Loc) -> Result<Value, ImportError> {
    let shown = path.display();
    if path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        != Some("spd".into())
    {
        return Err(ImportError::invalid(
            loc,
            format!("<spectrum>: {shown}: a spectrum file must be a `.spd` file, as Mitsuba's"),
        ));
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| ImportError::invalid(loc, format!("<spectrum>: cannot read {shown}: {e}")))?;
    let mut pairs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let data = line.split('#').next().unwrap_or("");
        let fields: Vec<&str> = data.split_whitespace().collect();
        let bad = |what: &str| {
            ImportError::invalid(loc, format!("<spectrum>: {shown}:{}: {what}", i + 1))
        };
        match fields.as_slice() {
            [] => {}
            [l, v] => {
                let parse = |t: &str| t.parse::<f64>().ok().filter(|x| x.is_finite());
                match (parse(l), parse(v)) {
                    (Some(l), Some(v)) => pairs.push((l, v)),
                    _ => return Err(bad("expected a wavelength and a value")),
                }
            }
            _ => return Err(bad("expected two numbers on the line")),
        }
    }
    if pairs.is_empty() {
        return Err(ImportError::invalid(
            loc,
            format!("<spectrum>: {shown} holds no wavelength–value pairs"),
        ));
    }
    Ok(Value::Spectrum(pairs))
}

fn relative_to(file: &Path, name: &str) -> PathBuf {
    let p = Path::new(name);
    if p.is_absolute() {
        return p.to_path_buf();
    }
    file.parent().unwrap_or(Path::new(".")).join(p)
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

impl Document {
    /// A file name a plugin gives (a mesh, a texture), resolved as
    /// Mitsuba's file resolver does when the scene is instantiated: in the
    /// `<path>` folders, the last declared first, then the top-level
    /// file's folder; failing those, beside the file that names it.
    pub fn resolve(&self, from: &Loc, name: &str) -> PathBuf {
        find(&self.search, name).unwrap_or_else(|| relative_to(&from.file, name))
    }
}

/// The first of `dirs` holding `name` (or `name` itself when absolute).
fn find(dirs: &[PathBuf], name: &str) -> Option<PathBuf> {
    if Path::new(name).is_absolute() {
        return Some(PathBuf::from(name));
    }
    dirs.iter().map(|d| d.join(name)).find(|p| p.exists())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_names_upgrade_as_mitsubas_rules_say() {
        let v1 = (0, 5, 0);
        for (old, new) in [
            ("toWorld", "to_world"),
            ("maxDepth", "max_depth"),
            ("intIOR", "int_ior"),
            ("sampleCount", "sample_count"),
            ("fovAxis", "fov_axis"),
            ("diffuseReflectance", "diffuse_reflectance"),
            ("radius", "radius"),
            ("uvscale", "uvscale"),
        ] {
            assert_eq!(upgrade_name(old, v1), new);
        }
        assert_eq!(upgrade_name("toWorld", (3, 0, 0)), "toWorld");
    }
}
