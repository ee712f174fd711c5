//! Building the object DAG, loading only the plugins what is reachable from
//! the root needs. Errors come before any expensive step:
//! 1. `reach`: walk the instances from the root (cycles and depth checked),
//!    collecting the definitions and shaders reachable;
//! 2. `needs`: load exactly the classes they name (plus the camera, the
//!    integrator, the lights, and the instance-transform class if a reachable
//!    instance has a transform);
//! 3. create the camera, integrator and lights;
//! 4. `objects`: create each reachable object definition once, bottom-up.

mod emitters;
mod needs;
mod objects;
mod prepare;
mod reach;

pub use emitters::Emitter;
pub use prepare::{Parallel, Sequential};

use crate::desc::{Def, Desc, Instance};
use crate::error::{ErrorKind, SceneError};
use crate::file::SceneFile;
use crate::plugins::{Module, Plugin, Registry};
use objects::{call_error, Builder};
use prepare::PrepareHost;
use rtk_handles::{Camera, Integrator, Light, Object, Shader};
use rtk_kernel::{Bounds3, InstanceData};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How long each step of building took.
#[derive(Debug, Clone, Default)]
pub struct Timings {
    /// Loading and checking plugin libraries.
    pub load_plugins: Duration,
    /// `create` and `add_child` calls.
    pub create: Duration,
    /// `prepare` calls.
    pub prepare: Duration,
    /// `prepare` calls by class: an aggregate's build time is its `prepare`
    /// (a mesh's is reading its file).
    pub prepare_by_class: std::collections::BTreeMap<String, Duration>,
}

/// A built, prepared scene: everything the renderer needs. Objects are
/// immutable from here on; dropping the world destroys them, parents first.
pub struct World {
    /// The description it was built from.
    pub desc: Desc,
    /// The root object.
    pub root: Object,
    /// The root instance's bindings.
    pub root_inst: InstanceData,
    /// World bounds over the shutter interval.
    pub bounds: Bounds3,
    /// The camera.
    pub camera: Camera,
    /// The integrator.
    pub integrator: Integrator,
    /// The lights: those the scene lists (`[lights]`), then one area light
    /// per emitting instance (the light a hit on it reports, `LocalGeom::light`).
    pub lights: Vec<Light>,
    /// Index in `lights` of the environment light, if there is one.
    pub environment: Option<usize>,
    /// The shaders, indexed by shader id.
    pub shaders: Vec<Shader>,
    /// Each instance's path (`objects.world.children[2]`, `render.root`) by
    /// its id, the `LocalGeom::instance` a hit on it reports (the innermost
    /// instance wins; a definition instanced twice reports its children's
    /// ids for both).
    pub instances: Vec<String>,
    /// The plugins loaded for this scene.
    pub plugins: Vec<Arc<Plugin>>,
    /// Files plugins reported reading during `prepare`.
    pub files_read: Vec<String>,
    /// Timings of the build steps.
    pub timings: Timings,
    /// Objects created (instance transforms included).
    pub objects_created: usize,
}

/// Build a scene: load the plugins it needs, create and prepare its objects.
pub fn build(
    file: &SceneFile,
    desc: Desc,
    registry: &mut Registry,
    parallel: &dyn Parallel,
) -> Result<World, SceneError> {
    build_world(file, desc, registry, parallel).map_err(|e| e.in_file(&file.text))
}

fn build_world(
    file: &SceneFile,
    desc: Desc,
    registry: &mut Registry,
    parallel: &dyn Parallel,
) -> Result<World, SceneError> {
    refuse_group_root(&desc)?;
    let reach = reach::Reach::walk(&desc)?;
    let t0 = Instant::now();
    let loaded = needs::load(&desc, &reach, registry)?;
    let load_plugins = t0.elapsed();
    let (mut world, emitters) = create_world(file, desc, registry, parallel, loaded)?;
    world.timings.load_plugins = load_plugins;
    add_area_lights(&mut world, registry, file, &emitters)?;
    Ok(world)
}

/// A group is expanded into the object instancing it, so it cannot be the
/// root.
fn refuse_group_root(desc: &Desc) -> Result<(), SceneError> {
    let root = &desc.render.root;
    if desc
        .objects
        .get(&root.object)
        .is_some_and(|o| o.def.class == rtk_kernel::classes::GROUP)
    {
        return Err(SceneError::invalid(
            &root.object_origin,
            &root.path,
            "object",
            format!(
                "`{}` is a group, which is expanded into the object instancing it: the root \
                 must be an object (a `list` or an aggregate over the group)",
                root.object
            ),
        ));
    }
    Ok(())
}

/// Everything but the area lights, with the plugins `loaded`: the camera,
/// the integrator and the scene's lights, then the objects reachable from
/// the root, each created once and prepared; and the emitting instances
/// the area lights will stand for.
fn create_world(
    file: &SceneFile,
    desc: Desc,
    registry: &mut Registry,
    parallel: &dyn Parallel,
    loaded: needs::Loaded,
) -> Result<(World, Vec<Emitter>), SceneError> {
    let host = PrepareHost {
        par: parallel,
        files: Mutex::new(Vec::new()),
    };
    let mut b = Builder::new(
        &desc,
        registry,
        file.dir().to_string_lossy().into_owned(),
        host,
    );
    b.arrays = attached_arrays(file);
    b.accel = loaded.accel;
    let t1 = Instant::now();
    let Others {
        camera,
        integrator,
        lights,
    } = create_others(&b, &desc)?;
    b.create_time += t1.elapsed();
    let root_inst = &desc.render.root;
    let root = b.instance(root_inst, false, true)?;
    let root_bind = b.bindings(root_inst)?;
    let root_bind = b.named(root_bind, root_inst);
    let emitters = b.emitters(root_inst)?;
    let environment = environment(&desc, &lights)?;
    let bounds = root_bounds(&root, root_inst)?;
    if b.area_light_count() != emitters.len() {
        return Err(SceneError::invalid(
            &root_inst.origin,
            "render",
            "root",
            "an emitting binding has no instance to stand for (a bug in rtk)",
        ));
    }
    let files_read = b
        .prepare_host
        .files
        .lock()
        .map(|f| f.clone())
        .unwrap_or_default();
    let timings = Timings {
        load_plugins: Duration::ZERO,
        create: b.create_time,
        prepare: b.prepare_time,
        prepare_by_class: std::mem::take(&mut b.prepare_by_class),
    };
    let (shaders, objects_created) = (std::mem::take(&mut b.shaders), b.objects_created);
    let instances = std::mem::take(&mut b.instances);
    drop(b);
    let world = World {
        desc,
        root,
        root_inst: root_bind,
        bounds,
        camera,
        integrator,
        lights,
        environment,
        shaders,
        instances,
        plugins: loaded.plugins,
        files_read,
        timings,
        objects_created,
    };
    Ok((world, emitters))
}

/// The world bounds over the shutter interval, as the root reports them.
fn root_bounds(root: &Object, root_inst: &Instance) -> Result<Bounds3, SceneError> {
    root.bounds(0.0, 1.0).map_err(|e| {
        SceneError::new(
            ErrorKind::PluginCall,
            &root_inst.origin,
            "render",
            "root",
            format!("plugin `{}` {e}", root.class_name()),
        )
    })
}

/// One area light per emitting instance, after the scene's own lights
/// (their time counts as creation).
fn add_area_lights(
    world: &mut World,
    registry: &mut Registry,
    file: &SceneFile,
    emitters: &[Emitter],
) -> Result<(), SceneError> {
    let t2 = Instant::now();
    let (area, area_plugin) = emitters::area_lights(
        registry,
        &world.desc,
        &file.dir().to_string_lossy(),
        world.lights.len(),
        emitters,
        &world.shaders,
    )?;
    world.lights.extend(area);
    world.plugins.extend(area_plugin);
    world.timings.create += t2.elapsed();
    Ok(())
}

/// The environment light's index: at most one light may surround the scene,
/// and then `[render] background` must be left black (a ray that leaves the
/// scene finds the environment; two sources would be two answers).
fn environment(desc: &Desc, lights: &[Light]) -> Result<Option<usize>, SceneError> {
    let defs: Vec<_> = desc.lights.values().collect();
    let envs: Vec<usize> = (0..lights.len())
        .filter(|&i| lights[i].is_environment())
        .collect();
    match envs[..] {
        [] => Ok(None),
        [i] => {
            if desc.render.background != [0.0; 3] {
                let d = defs[i];
                return Err(SceneError::invalid(
                    &d.class_origin,
                    d.path(),
                    "class",
                    "an environment light and `[render] background` both say what rays that leave the scene find; remove the background",
                ));
            }
            Ok(Some(i))
        }
        [_, j, ..] => {
            let d = defs[j];
            Err(SceneError::invalid(
                &d.class_origin,
                d.path(),
                "class",
                "a scene has at most one environment light",
            ))
        }
    }
}

/// What a scene has besides objects and shaders.
struct Others {
    camera: Camera,
    integrator: Integrator,
    lights: Vec<Light>,
}

/// The camera, the integrator and the lights.
fn create_others(b: &Builder, desc: &Desc) -> Result<Others, SceneError> {
    let camera = create_def(b, &desc.cameras[&desc.render.camera], |m, p, a| match m {
        Module::Camera(c) => Some(Camera::create(c, p, a)),
        _ => None,
    })?;
    let integrator = create_def(b, &desc.render.integrator, |m, p, a| match m {
        Module::Integrator(c) => Some(Integrator::create(c, p, a)),
        _ => None,
    })?;
    let lights = desc
        .lights
        .values()
        .map(|l| {
            create_def(b, l, |m, p, a| match m {
                Module::Light(c) => Some(Light::create(c, p, a)),
                _ => None,
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Others {
        camera,
        integrator,
        lights,
    })
}

/// Create a camera, integrator or light from its definition; `make` picks
/// the module of the right kind (the kind was checked when loading).
fn create_def<T>(
    b: &Builder,
    def: &Def,
    make: impl FnOnce(
        Module,
        &str,
        &rtk_handles::CreateArgs,
    ) -> Option<Result<T, rtk_handles::CallError>>,
) -> Result<T, SceneError> {
    let path = def.path();
    match make(b.module(&def.class), &def.params, &b.args(&path)) {
        Some(r) => r.map_err(|e| call_error(def, None, "its parameters", e)),
        None => unreachable!("kinds were checked when loading"),
    }
}

/// The host's arrays of `file` as the views `create` lends by pointer.
fn attached_arrays(file: &SceneFile) -> BTreeMap<String, Vec<rtk_handles::Bulk<'_>>> {
    file.arrays
        .iter()
        .map(|(path, list)| {
            let views = list
                .iter()
                .map(|a| rtk_handles::Bulk {
                    name: &a.name,
                    dtype: a.dtype,
                    rows: a.rows,
                    cols: a.cols,
                    data: &a.data,
                })
                .collect();
            (path.clone(), views)
        })
        .collect()
}
