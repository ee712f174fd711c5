//! Building the object DAG with the paper's open / create / instance / close
//! steps, loading only the plugins that what is reachable from the root needs.
//!
//! Order of work, so that errors come before any expensive step:
//! 1. walk the instances from the root (cycles and depth checked), collecting
//!    the definitions and shaders reachable;
//! 2. load exactly the classes they name (plus the camera, the integrator,
//!    the lights, and `transform` if a reachable instance has a transform);
//! 3. create the camera, integrator, lights and shaders;
//! 4. create each reachable object definition once, bottom-up: create it
//!    (open), add each child instance (instance), `prepare` (close). A
//!    definition instanced many times is created once (a DAG, not a tree);
//!    each transformed instance gets its own `transform` object.

use crate::desc::{Def, Desc, Instance, SceneFile};
use crate::error::{ErrorKind, SceneError};
use crate::plugins::{ClassError, Module, Plugin, Registry};
use crate::tree::Origin;
use rtk_kernel::abi::*;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ffi::c_void;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The host's thread pool, as `prepare` sees it.
pub trait Parallel: Sync {
    /// Number of threads queries may come from.
    fn max_threads(&self) -> u32;
    /// Run `f(i)` for every `i < n`, returning when all are done.
    fn run(&self, n: u64, f: &(dyn Fn(u64) + Sync));
}

/// Runs everything on the calling thread.
pub struct Sequential;

impl Parallel for Sequential {
    fn max_threads(&self) -> u32 {
        1
    }
    fn run(&self, n: u64, f: &(dyn Fn(u64) + Sync)) {
        (0..n).for_each(f)
    }
}

/// A created plugin instance of any kind other than object.
pub struct Created<M> {
    /// The plugin's module.
    pub module: M,
    /// The instance's data.
    pub this: *mut c_void,
    /// Definition path (`shaders.clay`).
    pub name: String,
    /// Plugin class.
    pub class: String,
}

/// How long each step of building took.
#[derive(Debug, Clone, Copy, Default)]
pub struct Timings {
    /// Loading and checking plugin libraries.
    pub load_plugins: Duration,
    /// `create` and `add_child` calls.
    pub create: Duration,
    /// `prepare` calls.
    pub prepare: Duration,
}

/// A built, prepared scene: everything the renderer needs. Objects are
/// immutable from here on; dropping the world destroys them, parents first.
pub struct World {
    /// The description it was built from.
    pub desc: Desc,
    /// The root object.
    pub root: ObjectRef,
    /// The root instance's bindings.
    pub root_inst: InstanceData,
    /// World bounds.
    pub bounds: Bounds3,
    /// The camera.
    pub camera: Created<CameraModuleRef>,
    /// The integrator.
    pub integrator: Created<IntegratorModuleRef>,
    /// The lights.
    pub lights: Vec<Created<LightModuleRef>>,
    /// The shaders, indexed by shader id.
    pub shaders: Vec<Created<ShaderModuleRef>>,
    objects: Vec<(ObjectModuleRef, *mut c_void)>,
    /// The plugins loaded for this scene.
    pub plugins: Vec<Arc<Plugin>>,
    /// Files plugins reported reading during `prepare`.
    pub files_read: Vec<String>,
    /// Timings of the build steps.
    pub timings: Timings,
}

// SAFETY: after building, every object, shader, light, camera and integrator
// is immutable and its class is `Send + Sync` (enforced by the SDK traits).
unsafe impl Send for World {}
// SAFETY: see above.
unsafe impl Sync for World {}

impl World {
    /// Number of objects created (transform wrappers included).
    pub fn objects_created(&self) -> usize {
        self.objects.len()
    }
}

impl Drop for World {
    fn drop(&mut self) {
        for (m, this) in self.objects.drain(..).rev() {
            (m.destroy())(this);
        }
        for s in self.shaders.drain(..) {
            (s.module.destroy())(s.this);
        }
        for l in self.lights.drain(..) {
            (l.module.destroy())(l.this);
        }
        (self.camera.module.destroy())(self.camera.this);
        (self.integrator.module.destroy())(self.integrator.this);
    }
}

/// Collects the message a plugin reports through an [`ErrSink`].
#[derive(Default)]
struct Collected {
    key: String,
    msg: String,
}

extern "C" fn collect(ctx: *mut c_void, key: *const u8, klen: usize, msg: *const u8, mlen: usize) {
    // SAFETY: `ctx` is the `Collected` passed with the sink, alive for the call;
    // the plugin passes valid UTF-8 byte ranges (lossily decoded regardless).
    unsafe {
        let c = &mut *(ctx as *mut Collected);
        c.key = String::from_utf8_lossy(std::slice::from_raw_parts(key, klen)).into_owned();
        c.msg = String::from_utf8_lossy(std::slice::from_raw_parts(msg, mlen)).into_owned();
    }
}

fn sink(c: &mut Collected) -> ErrSink {
    ErrSink {
        ctx: c as *mut Collected as *mut c_void,
        report: collect,
    }
}

/// What `prepare`'s host pointer refers to.
struct PrepareHost<'a> {
    par: &'a dyn Parallel,
    files: Mutex<Vec<String>>,
}

struct SendPtr(*const c_void);
// SAFETY: the pointer is the SDK's job record, which is `Sync` by construction
// (it holds a `&F` with `F: Sync` and an atomic flag).
unsafe impl Sync for SendPtr {}

impl SendPtr {
    fn get(&self) -> *const c_void {
        self.0
    }
}

extern "C" fn host_parallel_for(
    host: *const c_void,
    n: u64,
    body: ParallelBody,
    user: *const c_void,
) {
    // SAFETY: `host` is the `PrepareHost` passed in the `PrepareEnv`, alive for `prepare`.
    let h = unsafe { &*(host as *const PrepareHost) };
    let user = SendPtr(user);
    h.par.run(n, &|i| (body.func)(user.get(), i));
}

extern "C" fn host_note_file(host: *const c_void, path: *const u8, len: usize) {
    // SAFETY: `host` is the live `PrepareHost`; the plugin passes a valid byte range.
    let (h, bytes) = unsafe {
        (
            &*(host as *const PrepareHost),
            std::slice::from_raw_parts(path, len),
        )
    };
    if let Ok(mut f) = h.files.lock() {
        f.push(String::from_utf8_lossy(bytes).into_owned());
    }
}

struct Builder<'a> {
    file: &'a SceneFile,
    desc: &'a Desc,
    registry: &'a mut Registry,
    scene_dir: String,
    objects: Vec<(ObjectModuleRef, *mut c_void)>,
    made: HashMap<String, ObjectRef>,
    prepare_host: PrepareHost<'a>,
    max_threads: u32,
    shader_ids: BTreeMap<String, u32>,
    shaders: Vec<Created<ShaderModuleRef>>,
    create_time: Duration,
    prepare_time: Duration,
}

/// Build a scene: load the plugins it needs, create and prepare its objects.
pub fn build(
    file: &SceneFile,
    desc: Desc,
    registry: &mut Registry,
    parallel: &dyn Parallel,
) -> Result<World, SceneError> {
    let reach = Reach::walk(file, &desc)?;

    // Load exactly the plugins the reachable scene names.
    let t0 = Instant::now();
    let mut wanted: Vec<(String, &'static str, Origin, String, PluginKind)> = vec![
        {
            let c = &desc.cameras[&desc.render.camera];
            (
                c.class.clone(),
                "camera",
                c.class_origin.clone(),
                c.path(),
                PluginKind::Camera,
            )
        },
        (
            desc.render.integrator.class.clone(),
            "integrator",
            desc.render.integrator.class_origin.clone(),
            "render.integrator".into(),
            PluginKind::Integrator,
        ),
    ];
    for l in desc.lights.values() {
        wanted.push((
            l.class.clone(),
            "light",
            l.class_origin.clone(),
            l.path(),
            PluginKind::Light,
        ));
    }
    for s in &reach.shaders {
        let d = &desc.shaders[s];
        wanted.push((
            d.class.clone(),
            "shader",
            d.class_origin.clone(),
            d.path(),
            PluginKind::Shader,
        ));
    }
    for o in &reach.objects {
        let d = &desc.objects[o].def;
        wanted.push((
            d.class.clone(),
            "object",
            d.class_origin.clone(),
            d.path(),
            PluginKind::Object,
        ));
    }
    if let Some(inst) = &reach.first_transform {
        wanted.push((
            "transform".into(),
            "object",
            inst.origin.clone(),
            inst.path.clone(),
            PluginKind::Object,
        ));
    }
    let mut plugins: Vec<Arc<Plugin>> = Vec::new();
    for (class, what, origin, object, kind) in &wanted {
        let p = registry
            .get(class)
            .map_err(|e| class_error(file, e, class, origin, object))?;
        if p.kind != *kind {
            return Err(file.err(
                ErrorKind::Plugin,
                origin,
                object,
                "class",
                format!(
                    "class `{class}` is a {} plugin, but a {what} is needed here",
                    p.kind.name()
                ),
            ));
        }
        if !plugins.iter().any(|q| Arc::ptr_eq(q, &p)) {
            plugins.push(p);
        }
    }
    let load_plugins = t0.elapsed();

    let mut b = Builder {
        file,
        desc: &desc,
        registry,
        scene_dir: file.dir().to_string_lossy().into_owned(),
        objects: Vec::new(),
        made: HashMap::new(),
        prepare_host: PrepareHost {
            par: parallel,
            files: Mutex::new(Vec::new()),
        },
        max_threads: parallel.max_threads(),
        shader_ids: BTreeMap::new(),
        shaders: Vec::new(),
        create_time: Duration::ZERO,
        prepare_time: Duration::ZERO,
    };
    let t1 = Instant::now();
    let camera_def = &desc.cameras[&desc.render.camera];
    let camera = b.create_other(camera_def, None, |m| match m {
        Module::Camera(c) => Some((c, c.create())),
        _ => None,
    })?;
    let integrator = b.create_other(&desc.render.integrator, None, |m| match m {
        Module::Integrator(c) => Some((c, c.create())),
        _ => None,
    })?;
    let mut lights = Vec::new();
    for l in desc.lights.values() {
        lights.push(b.create_other(l, None, |m| match m {
            Module::Light(c) => Some((c, c.create())),
            _ => None,
        })?);
    }
    b.create_time += t1.elapsed();

    let root_inst = desc.render.root.clone();
    let root = b.instance_ref(&root_inst)?;
    let root_bind = b.bindings(&root_inst)?;
    let mut bounds = Bounds3::EMPTY;
    (root.fns.bounds)(root.this, 0.0, 1.0, &mut bounds);
    for l in &lights {
        if let Some(pre) = l.module.preprocess() {
            pre(l.this, &bounds);
        }
    }
    let files_read = b
        .prepare_host
        .files
        .lock()
        .map(|f| f.clone())
        .unwrap_or_default();
    let timings = Timings {
        load_plugins,
        create: b.create_time,
        prepare: b.prepare_time,
    };
    let objects = std::mem::take(&mut b.objects);
    let shaders = std::mem::take(&mut b.shaders);
    drop(b);
    Ok(World {
        desc,
        root,
        root_inst: root_bind,
        bounds,
        camera,
        integrator,
        lights,
        shaders,
        objects,
        plugins,
        files_read,
        timings,
    })
}

fn class_error(
    file: &SceneFile,
    e: ClassError,
    class: &str,
    origin: &Origin,
    object: &str,
) -> SceneError {
    match e {
        ClassError::BadName => file.err(
            ErrorKind::Plugin,
            origin,
            object,
            "class",
            format!("`{class}` is not a class name: use a plain identifier, never a path"),
        ),
        ClassError::NotFound {
            searched,
            available,
        } => {
            let mut err = file.err(
                ErrorKind::Plugin,
                origin,
                object,
                "class",
                format!(
                    "unknown class `{class}`: no {} on the plugin path",
                    crate::plugins::library_file_name(class)
                ),
            );
            err = err.note(
                "folders searched (--plugin-path, RTK_PLUGIN_PATH, <exe>/plugins, <exe dir>):",
            );
            for d in searched {
                err = err.note(format!("  {}", d.display()));
            }
            err.note(if available.is_empty() {
                "classes found there: none".to_string()
            } else {
                format!("classes found there: {}", available.join(", "))
            })
        }
        ClassError::Refused(le) => {
            file.err(ErrorKind::Plugin, origin, object, "class", le.to_string())
        }
    }
}

/// What is reachable from the root.
struct Reach {
    objects: BTreeSet<String>,
    shaders: BTreeSet<String>,
    first_transform: Option<Instance>,
}

impl Reach {
    fn walk(file: &SceneFile, desc: &Desc) -> Result<Reach, SceneError> {
        let mut r = Reach {
            objects: BTreeSet::new(),
            shaders: BTreeSet::new(),
            first_transform: None,
        };
        let mut depth_memo: HashMap<String, usize> = HashMap::new();
        let mut stack: Vec<String> = Vec::new();
        let root = &desc.render.root;
        let d = r.visit(file, desc, root, &mut stack, &mut depth_memo)?;
        if d > HIT_STACK_DEPTH {
            return Err(file.err(
                ErrorKind::Cycle,
                &root.origin,
                "render",
                "root",
                format!("the object DAG is {d} levels deep (transforms count as a level); rtk traces at most {HIT_STACK_DEPTH}"),
            ));
        }
        Ok(r)
    }

    /// Visit an instance; returns the number of levels it occupies.
    fn visit(
        &mut self,
        file: &SceneFile,
        desc: &Desc,
        inst: &Instance,
        stack: &mut Vec<String>,
        memo: &mut HashMap<String, usize>,
    ) -> Result<usize, SceneError> {
        if let Some(s) = &inst.shader {
            self.shaders.insert(s.clone());
        }
        let extra = if inst.transform.is_some() {
            if self.first_transform.is_none() {
                self.first_transform = Some(inst.clone());
            }
            1
        } else {
            0
        };
        if let Some(pos) = stack.iter().position(|s| *s == inst.object) {
            let mut cycle: Vec<String> = stack[pos..].to_vec();
            cycle.push(inst.object.clone());
            return Err(file.err(
                ErrorKind::Cycle,
                &inst.object_origin,
                &inst.path,
                "object",
                format!("instancing cycle: {}", cycle.join(" -> ")),
            ));
        }
        if let Some(d) = memo.get(&inst.object) {
            return Ok(d + extra);
        }
        self.objects.insert(inst.object.clone());
        stack.push(inst.object.clone());
        let mut deepest = 0;
        for c in &desc.objects[&inst.object].children {
            deepest = deepest.max(self.visit(file, desc, c, stack, memo)?);
        }
        stack.pop();
        let d = 1 + deepest;
        memo.insert(inst.object.clone(), d);
        Ok(d + extra)
    }
}

impl Builder<'_> {
    fn env(&self, name: &str) -> (CreateEnv, String) {
        let name = name.to_string();
        (
            CreateEnv {
                scene_dir: self.scene_dir.as_ptr(),
                scene_dir_len: self.scene_dir.len(),
                name: name.as_ptr(),
                name_len: name.len(),
                image_width: self.desc.render.width,
                image_height: self.desc.render.height,
            },
            name,
        )
    }

    fn plugin(&mut self, class: &str) -> Arc<Plugin> {
        // Every class was loaded in step 2; this cannot fail.
        match self.registry.get(class) {
            Ok(p) => p,
            Err(_) => unreachable!("class {class} was loaded before building"),
        }
    }

    /// A plugin error mapped back to the definition's table (or to an
    /// attribute block that overrides it).
    fn call_error(
        &self,
        def: &Def,
        attrs: Option<&crate::tree::Node>,
        what: &str,
        c: &Collected,
    ) -> SceneError {
        let class = &def.class;
        let (node, object) = match attrs {
            Some(a)
                if !c.key.is_empty()
                    && a.get(c.key.split(['.', '[']).next().unwrap_or(""))
                        .is_some() =>
            {
                (a, format!("{} (attributes)", def.path()))
            }
            _ => (&def.node, def.path()),
        };
        // An unknown key points at the key; any other error at the value.
        let origin = if c.key.is_empty() {
            def.class_origin.clone()
        } else if c.msg.starts_with("unknown field") {
            node.locate_origin(&c.key)
        } else {
            node.locate(&c.key).origin.clone()
        };
        // A panic's message already names the plugin and the entry point.
        let msg = if c.msg.starts_with("plugin '") {
            c.msg.clone()
        } else {
            format!("plugin `{class}` refused {what}: {}", c.msg)
        };
        self.file
            .err(ErrorKind::PluginCall, &origin, &object, &c.key, msg)
    }

    fn create_other<M: Copy>(
        &mut self,
        def: &Def,
        attrs: Option<&crate::tree::Node>,
        pick: impl Fn(
            Module,
        ) -> Option<(
            M,
            extern "C" fn(*const u8, usize, *const CreateEnv, ErrSink) -> *mut c_void,
        )>,
    ) -> Result<Created<M>, SceneError> {
        let p = self.plugin(&def.class);
        let Some((module, create)) = pick(p.module) else {
            unreachable!("kinds were checked when loading")
        };
        let params = match attrs {
            Some(a) => merge_params(&def.params, a, self.file, &def.path())?,
            None => def.params.clone(),
        };
        let (env, _name) = self.env(&def.path());
        let mut c = Collected::default();
        let this = create(params.as_ptr(), params.len(), &env, sink(&mut c));
        if this.is_null() {
            return Err(self.call_error(def, attrs, "its parameters", &c));
        }
        Ok(Created {
            module,
            this,
            name: def.path(),
            class: def.class.clone(),
        })
    }

    /// Shader id of an instance's binding (creating the shader, or an
    /// attribute-specialised copy, on first use).
    fn bindings(&mut self, inst: &Instance) -> Result<InstanceData, SceneError> {
        let Some(s) = &inst.shader else {
            return Ok(InstanceData::NONE);
        };
        let key = match &inst.attributes {
            Some(_) => format!("{s}@{}", inst.path),
            None => s.clone(),
        };
        if let Some(id) = self.shader_ids.get(&key) {
            return Ok(InstanceData {
                shader: *id,
                ..InstanceData::NONE
            });
        }
        let def = self.desc.shaders[s].clone();
        let t = Instant::now();
        let mut created = self.create_other(&def, inst.attributes.as_ref(), |m| match m {
            Module::Shader(c) => Some((c, c.create())),
            _ => None,
        })?;
        self.create_time += t.elapsed();
        if inst.attributes.is_some() {
            created.name = format!("{} (attributes of {})", created.name, inst.path);
        }
        let id = self.shaders.len() as u32;
        self.shaders.push(created);
        self.shader_ids.insert(key, id);
        Ok(InstanceData {
            shader: id,
            ..InstanceData::NONE
        })
    }

    /// The object an instance puts in its parent: the definition's object, or
    /// a `transform` object of its own around it.
    fn instance_ref(&mut self, inst: &Instance) -> Result<ObjectRef, SceneError> {
        let child = self.object(&inst.object)?;
        let Some(m) = inst.transform else {
            return Ok(child);
        };
        let cols = m.matrix3.to_cols_array();
        let t = m.translation;
        let rows = [
            cols[0], cols[3], cols[6], t.x, cols[1], cols[4], cols[7], t.y, cols[2], cols[5],
            cols[8], t.z,
        ];
        let params = serde_json::json!({ "matrix": rows }).to_string();
        let p = self.plugin("transform");
        let Module::Object(module, fns) = p.module else {
            unreachable!("kinds were checked when loading")
        };
        let (env, _n) = self.env(&inst.path);
        let t0 = Instant::now();
        let mut c = Collected::default();
        let this = (module.create())(params.as_ptr(), params.len(), &env, sink(&mut c));
        let fail = |b: &Self, c: &Collected| {
            b.file.err(
                ErrorKind::PluginCall,
                &inst.origin,
                &inst.path,
                "transform",
                format!("plugin `transform` refused it: {}", c.msg),
            )
        };
        if this.is_null() {
            return Err(fail(self, &c));
        }
        self.objects.push((module, this));
        if (module.add_child())(this, child, &InstanceData::NONE, sink(&mut c)) != STATUS_OK {
            return Err(fail(self, &c));
        }
        self.create_time += t0.elapsed();
        self.prepare(module, this, &|b, c| fail(b, c))?;
        Ok(ObjectRef { this, fns })
    }

    fn prepare(
        &mut self,
        module: ObjectModuleRef,
        this: *mut c_void,
        fail: &dyn Fn(&Self, &Collected) -> SceneError,
    ) -> Result<(), SceneError> {
        let env = PrepareEnv {
            max_threads: self.max_threads,
            host: &self.prepare_host as *const PrepareHost as *const c_void,
            parallel_for: host_parallel_for,
            note_file: host_note_file,
        };
        let t = Instant::now();
        let mut c = Collected::default();
        let st = (module.prepare())(this, &env, sink(&mut c));
        self.prepare_time += t.elapsed();
        if st != STATUS_OK {
            return Err(fail(self, &c));
        }
        Ok(())
    }

    /// Create (once) and prepare an object definition and its children.
    fn object(&mut self, name: &str) -> Result<ObjectRef, SceneError> {
        if let Some(r) = self.made.get(name) {
            return Ok(*r);
        }
        let od = self.desc.objects[name].clone();
        let def = &od.def;
        let p = self.plugin(&def.class);
        let Module::Object(module, fns) = p.module else {
            unreachable!("kinds were checked when loading")
        };
        // open / create
        let (env, _n) = self.env(&def.path());
        let t = Instant::now();
        let mut c = Collected::default();
        let this = (module.create())(def.params.as_ptr(), def.params.len(), &env, sink(&mut c));
        self.create_time += t.elapsed();
        if this.is_null() {
            return Err(self.call_error(def, None, "its parameters", &c));
        }
        self.objects.push((module, this));
        // instance each child
        for inst in &od.children {
            let child = self.instance_ref(inst)?;
            let data = self.bindings(inst)?;
            let t = Instant::now();
            let st = (module.add_child())(this, child, &data, sink(&mut c));
            self.create_time += t.elapsed();
            if st != STATUS_OK {
                let origin = if c.key == "children" {
                    od.children_origin.clone().unwrap_or(inst.origin.clone())
                } else {
                    inst.origin.clone()
                };
                return Err(self.file.err(
                    ErrorKind::PluginCall,
                    &origin,
                    &def.path(),
                    "children",
                    format!(
                        "plugin `{}` refused child `{}`: {}",
                        def.class, inst.object, c.msg
                    ),
                ));
            }
        }
        // close
        let d2 = def.clone();
        self.prepare(module, this, &move |b, c| {
            b.call_error(&d2, None, "to build", c)
        })?;
        let r = ObjectRef { this, fns };
        self.made.insert(name.to_string(), r);
        Ok(r)
    }
}

/// A shader's parameters with an instance's attribute block laid over them.
fn merge_params(
    base: &str,
    attrs: &crate::tree::Node,
    file: &SceneFile,
    object: &str,
) -> Result<String, SceneError> {
    let mut v: serde_json::Value =
        serde_json::from_str(base).unwrap_or_else(|_| serde_json::json!({}));
    let crate::tree::Val::Table(t) = &attrs.value else {
        return Ok(base.to_string());
    };
    for (k, ko, n) in t {
        if k == "class" {
            return Err(file.err(
                ErrorKind::Invalid,
                ko,
                object,
                "attributes.class",
                "attributes cannot change the shader's class",
            ));
        }
        let j = crate::desc::node_json(file, n, object, k)?;
        v[k] = j;
    }
    Ok(v.to_string())
}
