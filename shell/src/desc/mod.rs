//! The scene description: the TOML file checked before any plugin is loaded.
//! Everything the shell itself owns — `[render]`, definitions' `class`,
//! `children`, instances, transforms, references — is validated here, each
//! error naming its origin, object and key. Plugin parameters are converted to
//! JSON (refusing NaN and infinities) and checked by the plugins at `create`.
//!
//! - [`render`]: the `[render]` settings;
//! - [`defs`]: plugin definitions and their parameters;
//! - [`instance`]: instances and their transforms;
//! - [`params`]: the `[params]` table and its `$name` references.

pub(crate) mod check;
pub mod defs;
pub mod instance;
pub mod params;
pub mod render;

pub use defs::{Accel, Def, ObjDef};
pub use instance::Instance;
pub use render::{Render, MAX_PIXELS};

use crate::error::{ErrorKind, SceneError};
use crate::file::{SceneFile, SECTIONS};
use crate::tree::{Node, Val};
use std::collections::BTreeMap;

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

impl Desc {
    /// Check a scene file and build its description.
    pub fn from_file(file: &SceneFile) -> Result<Desc, SceneError> {
        Self::read(&file.root).map_err(|e| e.in_file(&file.text))
    }

    fn read(root: &Node) -> Result<Desc, SceneError> {
        let root = &params::substituted(root)?;
        check::unknown_keys(root, "", &SECTIONS)?;
        check_instance_count(root)?;
        let cameras = defs_of(root, "cameras")?;
        let lights = defs_of(root, "lights")?;
        let shaders = defs_of(root, "shaders")?;
        let objects = entries(root, "objects")?
            .iter()
            .map(|(name, n)| Ok((name.clone(), ObjDef::read(name, n)?)))
            .collect::<Result<_, SceneError>>()?;
        let desc = Desc {
            render: Render::read(root, &cameras)?,
            cameras,
            lights,
            shaders,
            objects,
        };
        desc.check_references()?;
        Ok(desc)
    }

    /// Every name refers to a definition of the right section (checked for
    /// all definitions: it needs no plugin).
    fn check_references(&self) -> Result<(), SceneError> {
        if !self.cameras.contains_key(&self.render.camera) {
            return Err(SceneError::new(
                ErrorKind::UnknownReference,
                &self.render.camera_origin,
                "render",
                "camera",
                format!("no camera named `{}`", self.render.camera),
            )
            .note(format!("cameras defined: {}", names(&self.cameras))));
        }
        let instances = std::iter::once(&self.render.root)
            .chain(self.objects.values().flat_map(|o| o.children.iter()));
        for inst in instances {
            if !self.objects.contains_key(&inst.object) {
                return Err(SceneError::new(
                    ErrorKind::UnknownReference,
                    &inst.object_origin,
                    &inst.path,
                    "object",
                    format!("no object named `{}`", inst.object),
                )
                .note(format!("objects defined: {}", names(&self.objects))));
            }
            match &inst.shader {
                Some(s) if !self.shaders.contains_key(s) => {
                    return Err(SceneError::new(
                        ErrorKind::UnknownReference,
                        &inst.origin,
                        &inst.path,
                        "shader",
                        format!("no shader named `{s}`"),
                    )
                    .note(format!("shaders defined: {}", names(&self.shaders))));
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// Most instances a scene may have: entries of `children` arrays, over all
/// definitions. Reading a transformed instance takes about 4 KB at the peak
/// (most of it the TOML parser's own tree), so a scene at the limit needs
/// about 4.5 GB; refusing above it is better than being killed for memory.
pub const MAX_INSTANCES: usize = 1 << 20;

/// Refuse a scene with more than [`MAX_INSTANCES`] instances, before any
/// instance is read.
fn check_instance_count(root: &Node) -> Result<(), SceneError> {
    let Some(Val::Table(objects)) = root.get("objects").map(|o| &o.value) else {
        return Ok(());
    };
    let mut total = 0usize;
    for (name, _, def) in objects {
        let Some(c) = def.get("children") else {
            continue;
        };
        if let Val::Arr(items) = &c.value {
            total += items.len();
            if total > MAX_INSTANCES {
                return Err(SceneError::invalid(
                    &c.origin,
                    format!("objects.{name}"),
                    "children",
                    format!("the scene has more than {MAX_INSTANCES} instances, rtk's limit: instance a group of instances instead (a DAG), or split the scene"),
                ));
            }
        }
    }
    Ok(())
}

/// The `(name, table)` entries of a section (empty when absent).
fn entries(root: &Node, section: &str) -> Result<Vec<(String, Node)>, SceneError> {
    match root.get(section) {
        None => Ok(Vec::new()),
        Some(n) => Ok(check::table(n, section, "")?
            .iter()
            .map(|(name, _, v)| (name.clone(), v.clone()))
            .collect()),
    }
}

/// The definitions of a plugin section.
fn defs_of(root: &Node, section: &'static str) -> Result<BTreeMap<String, Def>, SceneError> {
    entries(root, section)?
        .iter()
        .map(|(name, n)| Ok((name.clone(), Def::read(section, name, n, &[])?)))
        .collect()
}

fn names<V>(m: &BTreeMap<String, V>) -> String {
    m.keys().cloned().collect::<Vec<_>>().join(", ")
}
