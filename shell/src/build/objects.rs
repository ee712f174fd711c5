//! Creating the DAG through the paper's steps: create (open) each reachable
//! definition once, instance each child with its bindings, prepare (close).
//! A definition instanced many times is created once; each transformed
//! instance gets an instance-transform object of its own around it.
//!
//! Camera-relative rendering (docs/numerics.md X3): the world is computed
//! about `[render] origin` (the camera's position by default). Definitions
//! reached from the root through untransformed instances are created
//! *shifted*: they subtract the origin from the world positions they read,
//! in f64, before rounding to f32. The first instance transform on a path
//! absorbs the shift instead (its matrix becomes `T(−origin)·M`, composed in
//! f64), and everything below it is created unshifted. A definition reached
//! both ways is created twice, once per kind.

use super::prepare::PrepareHost;
use crate::desc::defs::merge_attributes;
use crate::desc::{Def, Desc, Instance, ObjDef};
use crate::error::{ErrorKind, SceneError};
use crate::plugins::{Module, Registry};
use crate::tree::Node;
use rtk_handles::{Bulk, CallError, CreateArgs, Object, ObjectBuilder, Shader};
use rtk_kernel::abi::ObjectModuleRef;
use rtk_kernel::InstanceData;
use std::collections::{BTreeMap, HashMap};
use std::time::{Duration, Instant};

/// Which shader object an instance binding uses: the definition's own, or a
/// copy specialised by one instance's attribute block.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum ShaderKey {
    Plain(String),
    WithAttributes { shader: String, instance: String },
}

/// The state of one build.
pub(crate) struct Builder<'a> {
    pub desc: &'a Desc,
    pub registry: &'a Registry,
    pub scene_dir: String,
    /// The host's arrays by definition path ([`SceneFile::arrays`]).
    ///
    /// [`SceneFile::arrays`]: crate::SceneFile::arrays
    pub arrays: BTreeMap<String, Vec<Bulk<'a>>>,
    pub prepare_host: PrepareHost<'a>,
    /// Objects made, by (definition, shifted).
    made: HashMap<(String, bool), Object>,
    /// The aggregate class each primitive-set definition is wrapped in.
    pub accel: BTreeMap<String, String>,
    /// The wrapped objects, by (definition, shifted): one wrapper serves
    /// every instance.
    wrapped: HashMap<(String, bool), Object>,
    shader_ids: BTreeMap<ShaderKey, u32>,
    /// Shader definitions that emit: each instance binding them gets a
    /// shader id of its own and an area light (emitters.rs).
    emissive: std::collections::BTreeSet<String>,
    /// The area light of each emitting binding, by its shader id: numbered
    /// after the scene's lights, in the order the bindings are made.
    light_of_binding: BTreeMap<u32, u32>,
    pub shaders: Vec<Shader>,
    /// Path of each instance by its id (`InstanceData::id`): what a hit
    /// reports as its object (`LocalGeom::instance`).
    pub instances: Vec<String>,
    pub objects_created: usize,
    pub create_time: Duration,
    pub prepare_time: Duration,
    /// `prepare` time by class (an aggregate's build time is its `prepare`).
    pub prepare_by_class: BTreeMap<String, Duration>,
}

impl<'a> Builder<'a> {
    pub(crate) fn new(
        desc: &'a Desc,
        registry: &'a Registry,
        scene_dir: String,
        prepare_host: PrepareHost<'a>,
    ) -> Self {
        Builder {
            desc,
            registry,
            scene_dir,
            arrays: BTreeMap::new(),
            prepare_host,
            made: HashMap::new(),
            accel: BTreeMap::new(),
            wrapped: HashMap::new(),
            shader_ids: BTreeMap::new(),
            emissive: Default::default(),
            light_of_binding: BTreeMap::new(),
            shaders: Vec::new(),
            instances: Vec::new(),
            objects_created: 0,
            create_time: Duration::ZERO,
            prepare_time: Duration::ZERO,
            prepare_by_class: BTreeMap::new(),
        }
    }

    /// The arguments of a `create` for the definition at `path`, in the
    /// renderer's space (cameras, lights, shaders, shifted objects).
    pub(crate) fn args<'b>(&'b self, path: &'b str) -> CreateArgs<'b> {
        self.args_at(path, true)
    }

    /// [`Builder::args`] for an object created shifted or not.
    fn args_at<'b>(&'b self, path: &'b str, shifted: bool) -> CreateArgs<'b> {
        CreateArgs {
            scene_dir: &self.scene_dir,
            name: path,
            image_width: self.desc.render.width,
            image_height: self.desc.render.height,
            origin: if shifted {
                self.desc.render.origin
            } else {
                [0.0; 3]
            },
            arrays: self.arrays.get(path).map_or(&[], Vec::as_slice),
        }
    }

    /// The module of a class loaded in the loading step.
    pub(crate) fn module(&self, class: &str) -> Module {
        match self.registry.loaded_class(class) {
            Some(p) => p.module,
            None => unreachable!("class {class} was loaded before building"),
        }
    }

    fn object_class(&self, class: &str) -> ObjectModuleRef {
        match self.module(class) {
            Module::Object(m) => m,
            _ => unreachable!("kinds were checked when loading"),
        }
    }

    /// The object an instance puts in its parent: the definition's object
    /// (wrapped in its `accel` aggregate unless the parent flattens primitive
    /// sets and the instance has no transform), or an instance-transform
    /// object of its own around it. `shifted`: the instance's parent space is
    /// the renderer's (the module doc).
    pub(crate) fn instance(
        &mut self,
        inst: &Instance,
        parent_flattens: bool,
        shifted: bool,
    ) -> Result<Object, SceneError> {
        let flattened = parent_flattens && inst.transform.is_none();
        let child_shifted = shifted && inst.transform.is_none();
        let child = match self.accel.get(&inst.object) {
            Some(class) if !flattened => {
                let class = class.clone();
                self.wrapped(&inst.object, &class, child_shifted)?
            }
            _ => self.object(&inst.object, child_shifted)?,
        };
        let Some(m) = &inst.transform else {
            return Ok(child);
        };
        let origin = glam::DVec3::from(self.desc.render.origin);
        let shifted_m;
        let m = if shifted && origin != glam::DVec3::ZERO {
            shifted_m = glam::DAffine3::from_translation(-origin) * *m;
            &shifted_m
        } else {
            m
        };
        let class = rtk_kernel::classes::INSTANCE_TRANSFORM;
        let fail = |e: CallError| {
            SceneError::new(
                ErrorKind::PluginCall,
                &inst.origin,
                &inst.path,
                "transform",
                format!("plugin `{class}` refused it: {e}"),
            )
        };
        let t = Instant::now();
        let module = self.object_class(class);
        let mut b = ObjectBuilder::from_transform(module, m, &self.args_at(&inst.path, false))
            .map_err(fail)?;
        self.objects_created += 1;
        b.add_child(&child, InstanceData::NONE).map_err(fail)?;
        self.create_time += t.elapsed();
        self.prepared(b).map_err(fail)
    }

    /// The definition's object inside an aggregate of `class`, made once.
    fn wrapped(&mut self, name: &str, class: &str, shifted: bool) -> Result<Object, SceneError> {
        let key = (name.to_string(), shifted);
        if let Some(o) = self.wrapped.get(&key) {
            return Ok(o.clone());
        }
        let inner = self.object(name, shifted)?;
        let od = &self.desc.objects[name];
        let path = format!("{}.accel", od.def.path());
        let origin = od
            .accel
            .as_ref()
            .map_or(&od.def.class_origin, |a| &a.origin);
        let fail = |e: CallError| {
            SceneError::new(
                ErrorKind::PluginCall,
                origin,
                od.def.path(),
                "accel",
                format!("plugin `{class}` (its accel) {e}"),
            )
        };
        let t = Instant::now();
        let module = self.object_class(class);
        let mut b =
            ObjectBuilder::create(module, "{}", &self.args_at(&path, shifted)).map_err(fail)?;
        self.objects_created += 1;
        b.add_child(&inner, InstanceData::NONE).map_err(fail)?;
        self.create_time += t.elapsed();
        let o = self.prepared(b).map_err(fail)?;
        self.wrapped.insert(key, o.clone());
        Ok(o)
    }

    fn prepared(&mut self, b: ObjectBuilder) -> Result<Object, CallError> {
        let class = b.class_name();
        let t = Instant::now();
        let r = b.prepare(&self.prepare_host);
        let dt = t.elapsed();
        self.prepare_time += dt;
        *self.prepare_by_class.entry(class.to_string()).or_default() += dt;
        r
    }

    /// Create (once per kind) and prepare an object definition and its
    /// children.
    fn object(&mut self, name: &str, shifted: bool) -> Result<Object, SceneError> {
        let key = (name.to_string(), shifted);
        if let Some(o) = self.made.get(&key) {
            return Ok(o.clone());
        }
        let desc = self.desc;
        let od = &desc.objects[name];
        let def = &od.def;
        let t = Instant::now();
        let module = self.object_class(&def.class);
        let path = def.path();
        let created = ObjectBuilder::create(module, &def.params, &self.args_at(&path, shifted));
        self.create_time += t.elapsed();
        let mut b = created.map_err(|e| call_error(def, None, "its parameters", e))?;
        self.objects_created += 1;
        let flattens = module.flattens_primitives();
        // A transform or motion object places its child by its matrix,
        // which absorbs the shift (its plugin subtracts the origin it is given).
        let children_shifted =
            shifted && !rtk_kernel::classes::PLACE_THEIR_CHILD.contains(&def.class.as_str());
        for inst in expand_groups(desc, &od.children) {
            let child = self.instance(&inst, flattens, children_shifted)?;
            let bound = self.bindings(&inst)?;
            let data = self.named(bound, &inst);
            let t = Instant::now();
            let added = b.add_child(&child, data);
            self.create_time += t.elapsed();
            added.map_err(|e| child_refused(od, &inst, e))?;
        }
        let o = self
            .prepared(b)
            .map_err(|e| call_error(def, None, "to build", e))?;
        self.made.insert(key, o.clone());
        Ok(o)
    }

    /// The object made for a definition (not its acceleration wrapper).
    pub(crate) fn made_object(&self, name: &str, shifted: bool) -> Option<Object> {
        self.made.get(&(name.to_string(), shifted)).cloned()
    }

    /// An instance's bindings: the id of its shader (created, or specialised
    /// by its attribute block, on first use).
    pub(crate) fn bindings(&mut self, inst: &Instance) -> Result<InstanceData, SceneError> {
        let Some(s) = &inst.shader else {
            return Ok(InstanceData::NONE);
        };
        let own = ShaderKey::WithAttributes {
            shader: s.clone(),
            instance: inst.path.clone(),
        };
        let key = if inst.attributes.is_some() || self.emissive.contains(s) {
            own.clone()
        } else {
            ShaderKey::Plain(s.clone())
        };
        if let Some(&id) = self.shader_ids.get(&key) {
            return Ok(self.binding(id));
        }
        let desc = self.desc;
        let def = &desc.shaders[s];
        let shader = self.create_shader(def, inst.attributes.as_ref())?;
        let emits = shader.lobes() & rtk_kernel::lobe::EMISSION != 0;
        let id = self.shaders.len() as u32;
        self.shaders.push(shader);
        if emits {
            self.emissive.insert(s.clone());
            self.shader_ids.insert(own, id);
            let light = (desc.lights.len() + self.light_of_binding.len()) as u32;
            self.light_of_binding.insert(id, light);
        } else {
            self.shader_ids.insert(key, id);
        }
        Ok(self.binding(id))
    }

    /// `data` with the next instance id, which names `inst`.
    pub(crate) fn named(&mut self, data: InstanceData, inst: &Instance) -> InstanceData {
        let id = self.instances.len() as u32;
        self.instances.push(inst.path.clone());
        InstanceData { id, ..data }
    }

    /// The bindings of shader id `id`: the shader, and its area light when it emits.
    fn binding(&self, id: u32) -> InstanceData {
        InstanceData {
            shader: id,
            light: self
                .light_of_binding
                .get(&id)
                .copied()
                .unwrap_or(rtk_kernel::NONE_ID),
            ..InstanceData::NONE
        }
    }

    /// Number of area lights the bindings made call for.
    pub(crate) fn area_light_count(&self) -> usize {
        self.light_of_binding.len()
    }

    fn create_shader(&mut self, def: &Def, attrs: Option<&Node>) -> Result<Shader, SceneError> {
        let Module::Shader(module) = self.module(&def.class) else {
            unreachable!("kinds were checked when loading")
        };
        let params = match attrs {
            Some(a) => merge_attributes(&def.params, a, &def.path())?,
            None => def.params.clone(),
        };
        let t = Instant::now();
        let s = Shader::create(module, &params, &self.args(&def.path()));
        self.create_time += t.elapsed();
        s.map_err(|e| call_error(def, attrs, "its parameters", e))
    }
}

/// `children` with every instance of a macro group (class
/// [`GROUP`](rtk_kernel::classes::GROUP)) replaced by the group's own
/// children, recursively: each member's transform composed after the
/// instance's (`M_instance · M_member`, in f64), the instance's shader (and
/// attributes) bound where the member binds none (the innermost binding
/// wins), and a path that names both (`objects.a.children[1] > objects.g.children[0]`).
pub(crate) fn expand_groups(desc: &Desc, children: &[Instance]) -> Vec<Instance> {
    let mut out = Vec::with_capacity(children.len());
    for inst in children {
        let od = &desc.objects[&inst.object];
        if od.def.class != rtk_kernel::classes::GROUP {
            out.push(inst.clone());
            continue;
        }
        for m in expand_groups(desc, &od.children) {
            let transform = match (inst.transform, m.transform) {
                (Some(a), Some(b)) => Some(a * b),
                (a, b) => a.or(b),
            };
            let (shader, attributes) = match &m.shader {
                Some(_) => (m.shader.clone(), m.attributes.clone()),
                None => (inst.shader.clone(), inst.attributes.clone()),
            };
            out.push(Instance {
                transform,
                shader,
                attributes,
                path: format!("{} > {}", inst.path, m.path),
                ..m
            });
        }
    }
    out
}

/// A plugin's error mapped back to the definition's table (or to an attribute
/// block that overrides it): an unknown key points at the key, any other
/// error at the value, an error without a key at the class.
pub(crate) fn call_error(def: &Def, attrs: Option<&Node>, what: &str, e: CallError) -> SceneError {
    let class = &def.class;
    let first_key = e.key.split(['.', '[']).next().unwrap_or("");
    let (node, object) = match attrs {
        Some(a) if !e.key.is_empty() && a.get(first_key).is_some() => {
            (a, format!("{} (attributes)", def.path()))
        }
        _ => (&def.node, def.path()),
    };
    let origin = if e.key.is_empty() {
        def.class_origin.clone()
    } else if e.message.starts_with("unknown field") {
        node.locate_origin(&e.key)
    } else {
        node.locate(&e.key).origin.clone()
    };
    let msg = if e.panicked {
        format!("plugin `{class}` {e}")
    } else {
        format!(
            "plugin `{class}` refused {what}: {}",
            crate::plain::plain_message(&e.message)
        )
    };
    SceneError::new(ErrorKind::PluginCall, &origin, object, e.key, msg)
}

fn child_refused(od: &ObjDef, inst: &Instance, e: CallError) -> SceneError {
    let origin = match (&od.children_origin, e.key.as_str()) {
        (Some(o), "children") => o.clone(),
        _ => inst.origin.clone(),
    };
    SceneError::new(
        ErrorKind::PluginCall,
        &origin,
        od.def.path(),
        "children",
        if e.panicked {
            // As other entries' panics read: the plugin, then the entry.
            format!(
                "plugin `{}` {e} (adding child `{}`)",
                od.def.class, inst.object
            )
        } else {
            format!(
                "plugin `{}` refused child `{}`: {}",
                od.def.class,
                inst.object,
                crate::plain::plain_message(&e.message)
            )
        },
    )
}
