//! Instances: an object placed in its parent with its own transform, shader
//! and attribute block.

use super::check::{json, string, table, unknown_keys};
use crate::error::SceneError;
use crate::tree::{Node, Origin, Val};
use glam::DAffine3;
use rtk_kernel::xform;

/// An instance: an object placed with its own transform, shader and attributes.
#[derive(Debug, Clone)]
pub struct Instance {
    /// Name of the object definition.
    pub object: String,
    /// Bound shader definition, if any.
    pub shader: Option<String>,
    /// Attribute block: parameters that override the shader's for this instance.
    pub attributes: Option<Node>,
    /// Composed transform (f64, checked), if any.
    pub transform: Option<DAffine3>,
    /// Where the instance is written.
    pub origin: Origin,
    /// Where its `object` key is written.
    pub object_origin: Origin,
    /// Path of the instance for messages (`objects.world.children[2]`).
    pub path: String,
}

impl Instance {
    /// Read an instance: an object name, or a table `{ object = ..., ... }`.
    pub(crate) fn read(n: &Node, path: &str) -> Result<Instance, SceneError> {
        let (obj_node, table_node) = match &n.value {
            Val::Str(_) => (n, None),
            Val::Table(_) => {
                unknown_keys(n, path, &["object", "shader", "transform", "attributes"])?;
                match n.get("object") {
                    Some(o) => (o, Some(n)),
                    None => {
                        return Err(SceneError::invalid(
                            &n.origin,
                            path,
                            "object",
                            "missing key `object` (the definition to instance)",
                        ))
                    }
                }
            }
            v => {
                return Err(SceneError::invalid(
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
        let mut inst = Instance {
            object: string(obj_node, path, "object")?,
            shader: None,
            attributes: None,
            transform: None,
            origin: n.origin.clone(),
            object_origin: obj_node.origin.clone(),
            path: path.to_string(),
        };
        if let Some(t) = table_node {
            inst.read_bindings(t)?;
        }
        Ok(inst)
    }

    fn read_bindings(&mut self, t: &Node) -> Result<(), SceneError> {
        let path = self.path.clone();
        if let Some(s) = t.get("shader") {
            self.shader = Some(string(s, &path, "shader")?);
        }
        if let Some(a) = t.get("attributes") {
            table(a, &path, "attributes")?;
            if self.shader.is_none() {
                return Err(SceneError::invalid(
                    &a.origin,
                    &path,
                    "attributes",
                    "attributes override a shader's parameters: bind a `shader` too",
                ));
            }
            self.attributes = Some(a.clone());
        }
        if let Some(tr) = t.get("transform") {
            self.transform = Some(transform(tr, &path)?);
        }
        Ok(())
    }
}

/// A `transform` value (a list of steps, or one step as a table), composed
/// in f64 and checked by the kernel's `xform`.
fn transform(n: &Node, path: &str) -> Result<DAffine3, SceneError> {
    let steps = match &n.value {
        Val::Arr(_) => n.clone(),
        Val::Table(_) => Node {
            origin: n.origin.clone(),
            value: Val::Arr(vec![n.clone()]),
        },
        v => {
            return Err(SceneError::invalid(
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
    let text = json(&steps, path, "transform")?.to_string();
    let parsed: Vec<xform::Step> = rtk_kernel::parse_params(&text).map_err(|e| {
        let key = if e.key.starts_with('[') {
            format!("transform{}", e.key)
        } else {
            "transform".to_string()
        };
        SceneError::invalid(&steps.locate_origin(&e.key), path, key, e.message)
    })?;
    xform::compose("", &parsed).map_err(|e| {
        SceneError::invalid(
            &steps.locate_origin(&e.key),
            path,
            format!("transform{}", e.key),
            e.message,
        )
    })
}
