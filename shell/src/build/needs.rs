//! Loading exactly the plugins the reachable scene names, each checked to be
//! of the kind its use needs.

use super::reach::Reach;
use crate::desc::Desc;
use crate::error::{ErrorKind, SceneError};
use crate::plugins::{library_file_name, ClassError, Module, Plugin, Registry};
use crate::tree::Origin;
use rtk_kernel::abi::PluginKind;
use std::collections::BTreeMap;
use std::sync::Arc;

/// One class the scene needs, and where it asks for it.
struct Need {
    class: String,
    kind: PluginKind,
    origin: Origin,
    /// The definition (or instance) path naming it.
    object: String,
}

/// The classes needed: the camera, the integrator, every light, and the
/// shaders and objects reachable from the root (plus the instance-transform
/// class when a reachable instance has a transform).
fn needs(desc: &Desc, reach: &Reach) -> Vec<Need> {
    let def_need = |d: &crate::desc::Def, kind| Need {
        class: d.class.clone(),
        kind,
        origin: d.class_origin.clone(),
        object: d.path(),
    };
    let mut out = vec![
        def_need(&desc.cameras[&desc.render.camera], PluginKind::Camera),
        Need {
            object: "render.integrator".into(),
            ..def_need(&desc.render.integrator, PluginKind::Integrator)
        },
    ];
    out.extend(desc.lights.values().map(|l| def_need(l, PluginKind::Light)));
    out.extend(
        reach
            .shaders
            .iter()
            .map(|s| def_need(&desc.shaders[s], PluginKind::Shader)),
    );
    out.extend(
        reach
            .objects
            .iter()
            .filter(|o| desc.objects[*o].def.class != rtk_kernel::classes::GROUP)
            .map(|o| def_need(&desc.objects[o].def, PluginKind::Object)),
    );
    if let Some(inst) = &reach.first_transform {
        out.push(Need {
            class: rtk_kernel::classes::INSTANCE_TRANSFORM.into(),
            kind: PluginKind::Object,
            origin: inst.origin.clone(),
            object: inst.path.clone(),
        });
    }
    out
}

/// What loading decided: the plugins, and the aggregate class the shell
/// wraps each primitive-set definition in (by definition name).
pub(crate) struct Loaded {
    pub plugins: Vec<Arc<Plugin>>,
    pub accel: BTreeMap<String, String>,
}

/// Load the plugins the reachable scene needs (each once), then the
/// aggregate classes over the definitions whose class offers primitives.
pub(crate) fn load(
    desc: &Desc,
    reach: &Reach,
    registry: &mut Registry,
) -> Result<Loaded, SceneError> {
    let mut plugins: Vec<Arc<Plugin>> = Vec::new();
    load_needs(needs(desc, reach), registry, &mut plugins)?;
    let (accel, accel_needs) = accel_needs(desc, reach, registry)?;
    load_needs(accel_needs, registry, &mut plugins)?;
    Ok(Loaded { plugins, accel })
}

/// The aggregate each reachable primitive-set definition is wrapped in: its
/// `accel` key, else the kernel's default. `accel` on a class without
/// primitives is refused.
fn accel_needs(
    desc: &Desc,
    reach: &Reach,
    registry: &Registry,
) -> Result<(BTreeMap<String, String>, Vec<Need>), SceneError> {
    let (mut accel, mut needs) = (BTreeMap::new(), Vec::new());
    for o in &reach.objects {
        let od = &desc.objects[o];
        if od.def.class == rtk_kernel::classes::GROUP {
            continue;
        }
        let offers = matches!(
            registry.loaded_class(&od.def.class).map(|p| p.module),
            Some(Module::Object(m)) if m.prim_count().is_some()
        );
        let (class, origin) = match (&od.accel, offers) {
            (Some(a), false) if a.class.is_some() => {
                return Err(SceneError::invalid(
                    &a.origin,
                    od.def.path(),
                    "accel",
                    format!(
                        "class `{}` has no primitives to build an aggregate over (it offers no primitive set)",
                        od.def.class
                    ),
                ))
            }
            (None, true) => (
                rtk_kernel::classes::DEFAULT_ACCEL.to_string(),
                od.def.class_origin.clone(),
            ),
            (Some(a), true) => match &a.class {
                Some(c) => (c.clone(), a.origin.clone()),
                None => continue,
            },
            _ => continue,
        };
        needs.push(Need {
            class: class.clone(),
            kind: PluginKind::Object,
            origin,
            object: format!("{}.accel", od.def.path()),
        });
        accel.insert(o.clone(), class);
    }
    Ok((accel, needs))
}

fn load_needs(
    needs: Vec<Need>,
    registry: &mut Registry,
    plugins: &mut Vec<Arc<Plugin>>,
) -> Result<(), SceneError> {
    for n in needs {
        let p = registry.get(&n.class).map_err(|e| class_error(e, &n))?;
        if p.kind != n.kind {
            return Err(SceneError::new(
                ErrorKind::Plugin,
                &n.origin,
                &n.object,
                "class",
                format!(
                    "class `{}` is {} plugin, but {} is needed here",
                    n.class,
                    with_article(p.kind.name()),
                    with_article(n.kind.name())
                ),
            ));
        }
        if !plugins.iter().any(|q| Arc::ptr_eq(q, &p)) {
            plugins.push(p);
        }
    }
    Ok(())
}

/// "an object", "a camera".
fn with_article(word: &str) -> String {
    match word.starts_with(['a', 'e', 'i', 'o', 'u']) {
        true => format!("an {word}"),
        false => format!("a {word}"),
    }
}

fn class_error(e: ClassError, n: &Need) -> SceneError {
    class_refused(e, &n.class, &n.origin, &n.object, "class")
}

/// Why `class` could not be had, at the `key` of `object` written at `origin`.
pub(crate) fn class_refused(
    e: ClassError,
    class: &str,
    origin: &Origin,
    object: &str,
    key: &str,
) -> SceneError {
    let err = |msg: String| SceneError::new(ErrorKind::Plugin, origin, object, key, msg);
    match e {
        ClassError::BadName => err(format!(
            "`{class}` is not a class name: use a plain identifier, never a path"
        )),
        ClassError::NotFound {
            searched,
            available,
        } => {
            let mut e = err(format!(
                "unknown class `{class}`: no {} on the plugin path",
                library_file_name(class)
            ))
            .note("folders searched (--plugin-path, RTK_PLUGIN_PATH, <exe>/plugins, <exe dir>):");
            for d in searched {
                e = e.note(format!("  {}", d.display()));
            }
            e.note(if available.is_empty() {
                "classes found there: none".to_string()
            } else {
                format!("classes found there: {}", available.join(", "))
            })
        }
        ClassError::Refused(le) => err(le.to_string()),
    }
}
