//! Plugin definitions: `[cameras.X]`, `[lights.X]`, `[shaders.X]`,
//! `[objects.X]` and the integrator: a class name and the parameters the
//! plugin checks itself.

use super::check::{json, string, table};
use super::instance::Instance;
use crate::error::SceneError;
use crate::tree::{Node, Origin, Val};

/// A plugin definition.
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
    /// The definition's table (plugin errors are located in it by key path).
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

    /// Read a definition: its `class` and its parameters, leaving out the
    /// shell's own keys (`skip`).
    pub(crate) fn read(
        section: &'static str,
        name: &str,
        n: &Node,
        skip: &[&str],
    ) -> Result<Def, SceneError> {
        let object = format!("{section}.{name}");
        table(n, &object, "")?;
        let Some(cn) = n.get("class") else {
            return Err(SceneError::invalid(
                &n.origin,
                &object,
                "class",
                "missing key `class` (the plugin to use)",
            ));
        };
        let class = string(cn, &object, "class")?;
        if !crate::plugins::is_identifier(&class) {
            return Err(SceneError::invalid(
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
            node: without_children(n),
            params: params_json(n, &object, &skip_all)?,
        })
    }

    /// A definition made by the shell (the default integrator), with no parameters.
    pub(crate) fn implicit(section: &'static str, class: &str, origin: &Origin) -> Def {
        Def {
            section,
            name: String::new(),
            class: class.to_string(),
            class_origin: origin.clone(),
            node: Node {
                origin: origin.clone(),
                value: Val::Table(vec![]),
            },
            params: "{}".into(),
        }
    }
}

/// A definition's table for locating its plugin's errors, with `children`
/// emptied: a plugin's error never lies inside the instances, and copying
/// them would double the memory of a scene with many instances.
fn without_children(n: &Node) -> Node {
    let Val::Table(t) = &n.value else {
        return n.clone();
    };
    let entries = t
        .iter()
        .map(|(k, ko, v)| match k.as_str() {
            "children" => (
                k.clone(),
                ko.clone(),
                Node {
                    origin: v.origin.clone(),
                    value: Val::Arr(Vec::new()),
                },
            ),
            _ => (k.clone(), ko.clone(), v.clone()),
        })
        .collect();
    Node {
        origin: n.origin.clone(),
        value: Val::Table(entries),
    }
}

/// A plugin's parameter table as JSON text, without the shell's keys.
fn params_json(n: &Node, object: &str, skip: &[&str]) -> Result<String, SceneError> {
    let mut map = serde_json::Map::new();
    for (k, _, v) in table(n, object, "")? {
        if !skip.contains(&k.as_str()) {
            map.insert(k.clone(), json(v, object, k)?);
        }
    }
    Ok(serde_json::Value::Object(map).to_string())
}

/// The `accel` key of an object definition.
#[derive(Debug, Clone)]
pub struct Accel {
    /// The aggregate class, or `None` for `"none"` (test every primitive).
    pub class: Option<String>,
    /// Where it was given.
    pub origin: Origin,
}

/// An object definition with its instances.
#[derive(Debug, Clone)]
pub struct ObjDef {
    /// The definition.
    pub def: Def,
    /// The aggregate built over its primitives where no parent flattens them
    /// (`None`: the default, [`DEFAULT_ACCEL`](rtk_kernel::classes::DEFAULT_ACCEL)).
    pub accel: Option<Accel>,
    /// Its children (empty for primitives).
    pub children: Vec<Instance>,
    /// Where `children` was given, if it was.
    pub children_origin: Option<Origin>,
}

impl ObjDef {
    /// Read `[objects.NAME]`: the definition and its `children` instances.
    pub(crate) fn read(name: &str, n: &Node) -> Result<ObjDef, SceneError> {
        let def = Def::read("objects", name, n, &["children", "accel"])?;
        if def.class == rtk_kernel::classes::GROUP {
            // A macro group is the shell's: nothing for a plugin to read.
            let extra = match &n.value {
                Val::Table(t) => t.iter().find(|(k, _, _)| k != "class" && k != "children"),
                _ => None,
            };
            if let Some((key, origin, _)) = extra {
                return Err(SceneError::invalid(
                    origin,
                    def.path(),
                    key.as_str(),
                    "a group takes only `children` (it is expanded into each parent that \
                     instances it)",
                ));
            }
        }
        let accel = n
            .get("accel")
            .map(|a| {
                let class = string(a, &def.path(), "accel")?;
                if class != "none" && !crate::plugins::is_identifier(&class) {
                    return Err(SceneError::invalid(
                        &a.origin,
                        def.path(),
                        "accel",
                        format!(
                            "`{class}` is not a class name: name an aggregate class, or \"none\""
                        ),
                    ));
                }
                Ok(Accel {
                    class: (class != "none").then_some(class),
                    origin: a.origin.clone(),
                })
            })
            .transpose()?;
        let Some(c) = n.get("children") else {
            return Ok(ObjDef {
                def,
                accel,
                children: Vec::new(),
                children_origin: None,
            });
        };
        let Val::Arr(items) = &c.value else {
            return Err(SceneError::invalid(
                &c.origin,
                def.path(),
                "children",
                format!(
                    "expected an array of instances, found {}",
                    c.value.type_name()
                ),
            ));
        };
        let children = items
            .iter()
            .enumerate()
            .map(|(i, it)| Instance::read(it, &format!("objects.{name}.children[{i}]")))
            .collect::<Result<_, _>>()?;
        Ok(ObjDef {
            def,
            accel,
            children,
            children_origin: Some(c.origin.clone()),
        })
    }
}

/// A shader's parameters with an instance's attribute block laid over them.
pub(crate) fn merge_attributes(
    base: &str,
    attrs: &Node,
    object: &str,
) -> Result<String, SceneError> {
    let mut v: serde_json::Value =
        serde_json::from_str(base).unwrap_or_else(|_| serde_json::json!({}));
    for (k, ko, n) in table(attrs, object, "attributes")? {
        if k == "class" {
            return Err(SceneError::invalid(
                ko,
                object,
                "attributes.class",
                "attributes cannot change the shader's class",
            ));
        }
        v[k] = json(n, object, k)?;
    }
    Ok(v.to_string())
}
