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
        SceneError::invalid(
            &steps.locate_origin(&e.key),
            path,
            key,
            crate::plain::plain_message(&e.message),
        )
    })?;
    let m = xform::compose("", &parsed).map_err(|e| {
        SceneError::invalid(
            &steps.locate_origin(&e.key),
            path,
            format!("transform{}", e.key),
            e.message,
        )
    })?;
    check_range(&steps, &parsed, path)?;
    Ok(m)
}

/// Largest translation and scale of an instance transform, and the inverse
/// of the smallest scale: beyond them the f32 transform of a ray loses the
/// instance (it silently vanishes from the image) or overflows.
const MAX_TRANSFORM: f64 = super::check::MAX_COORDINATE;

/// Refuse, naming the first step that goes out of range, a transform
/// whose translation or scale leaves what f32 can trace ([`MAX_TRANSFORM`]).
/// The steps were checked one by one already, so composing them cannot fail.
fn check_range(steps: &Node, parsed: &[xform::Step], path: &str) -> Result<(), SceneError> {
    let mut m = DAffine3::IDENTITY;
    for (i, s) in parsed.iter().enumerate() {
        let Ok(one) = xform::compose("", std::slice::from_ref(s)) else {
            continue;
        };
        m = one * m;
        if let Some(why) = out_of_range(&m) {
            let key = format!("[{i}].{}", step_key(s));
            return Err(SceneError::invalid(
                &steps.locate_origin(&key),
                path,
                format!("transform{key}"),
                why,
            ));
        }
    }
    Ok(())
}

/// Why a composed transform is out of range, if it is.
fn out_of_range(m: &DAffine3) -> Option<String> {
    let largest = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let t = m.translation.to_array();
    if let Some(axis) = (0..3).find(|&i| t[i].abs() > MAX_TRANSFORM) {
        return Some(format!(
            "moves the instance by {:e} along {}, beyond ±{MAX_TRANSFORM:e}: f32 intersection cannot trace it there",
            t[axis],
            ["x", "y", "z"][axis]
        ));
    }
    if largest(&m.matrix3.to_cols_array()) > MAX_TRANSFORM {
        return Some(format!(
            "scales by more than {MAX_TRANSFORM:e}: f32 intersection cannot trace the result"
        ));
    }
    if largest(&m.matrix3.inverse().to_cols_array()) > MAX_TRANSFORM {
        return Some(format!(
            "scales by less than {:e}: f32 intersection cannot trace the result",
            1.0 / MAX_TRANSFORM
        ));
    }
    None
}

/// The key of a step (each step has exactly one, checked already).
fn step_key(s: &xform::Step) -> &'static str {
    match s {
        xform::Step {
            translate: Some(_), ..
        } => "translate",
        xform::Step { scale: Some(_), .. } => "scale",
        xform::Step {
            rotate_x: Some(_), ..
        } => "rotate_x",
        xform::Step {
            rotate_y: Some(_), ..
        } => "rotate_y",
        xform::Step {
            rotate_z: Some(_), ..
        } => "rotate_z",
        xform::Step {
            rotate: Some(_), ..
        } => "rotate",
        _ => "matrix",
    }
}
