//! The generic `extern "C"` shims between the ABI records and the safe traits.
//! All the SDK's `unsafe` is here: turning the raw pointers the host passes
//! back into references, under the ABI's contract that they are valid for the
//! call (and, for `this`, for the object's lifetime).

use super::*;
use abi_stable::library::{
    __call_root_module_loader, CheckTypeLayout, LibHeader, RootModule, RootModuleResult,
};
use abi_stable::prefix_type::PrefixTypeTrait;
use abi_stable::std_types::RStr;
use std::any::Any;
use std::marker::PhantomData;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};

/// What the export macro knows about a plugin: its class name, documentation
/// and crate version.
pub trait Decl: 'static {
    /// Class name used in scenes.
    const CLASS: &'static str;
    /// Documentation (parameter table and a TOML example).
    const DOC: &'static str;
    /// Plugin crate version.
    const VERSION: &'static str;
}

/// A type that can produce a plugin's abi_stable root module.
pub trait ModuleSource: 'static {
    /// The root module type.
    type Module: RootModule;
    /// Build the module.
    fn module() -> Self::Module;
}

extern "C" fn erased_module<S: ModuleSource>() -> RootModuleResult {
    __call_root_module_loader(S::module as fn() -> S::Module)
}

/// The library header abi_stable's loader looks for (what `#[export_root_module]` emits).
pub const fn lib_header<S: ModuleSource>() -> LibHeader {
    // SAFETY: `erased_module::<S>` returns the `PrefixRef` of an `S::Module`,
    // erased by abi_stable's own `__call_root_module_loader`, which is what
    // `from_constructor::<S::Module>` requires.
    unsafe { LibHeader::from_constructor::<S::Module>(erased_module::<S>, CheckTypeLayout::Yes) }
}

fn meta<D: Decl>() -> ModuleMeta {
    ModuleMeta {
        class_name: RStr::from_str(D::CLASS),
        doc: RStr::from_str(D::DOC),
        plugin_version: RStr::from_str(D::VERSION),
    }
}

fn panic_message(p: &(dyn Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".to_string()
    }
}

fn report(sink: &ErrSink, key: &str, msg: &str) {
    (sink.report)(sink.ctx, key.as_ptr(), key.len(), msg.as_ptr(), msg.len());
}

/// Run a cold-path call: errors and panics go to the sink as a status.
fn cold<D: Decl>(sink: &ErrSink, what: &str, f: impl FnOnce() -> Result<(), PluginError>) -> i32 {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => STATUS_OK,
        Ok(Err(e)) => {
            report(sink, &e.key, &e.message);
            STATUS_ERROR
        }
        Err(p) => {
            let msg = format!(
                "plugin '{}' panicked in {what}: {}",
                D::CLASS,
                panic_message(&*p)
            );
            report(sink, "", &msg);
            STATUS_PANIC
        }
    }
}

/// Run a hot-path call: a panic marks the render failed and yields `fallback`.
#[inline]
fn hot<D: Decl, R>(ctx: *mut TraceCtx, what: &str, fallback: R, f: impl FnOnce() -> R) -> R {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let msg = format!("panicked in {what}: {}", panic_message(&*p));
            // SAFETY: the host passes a valid, exclusive context for the call.
            let ctx = unsafe { &mut *ctx };
            ctx.failed = 1;
            (ctx.failure.report)(
                ctx.failure.ctx,
                D::CLASS.as_ptr(),
                D::CLASS.len(),
                msg.as_ptr(),
                msg.len(),
            );
            fallback
        }
    }
}

/// Decode the JSON parameters and the environment of a `create` call.
///
/// # Safety
/// `params` must point at `len` bytes and `env` at a valid [`CreateEnv`]
/// whose strings are valid for the call.
unsafe fn create_args<'a>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
) -> (&'a str, Env<'a>) {
    // SAFETY: guaranteed by the caller (the host's loader).
    let (bytes, env) = unsafe { (std::slice::from_raw_parts(params, len), &*env) };
    // SAFETY: as above; the strings come from Rust `&str`s in the host.
    let (dir, name) = unsafe {
        (
            std::slice::from_raw_parts(env.scene_dir, env.scene_dir_len),
            std::slice::from_raw_parts(env.name, env.name_len),
        )
    };
    (
        std::str::from_utf8(bytes).unwrap_or(""),
        Env {
            scene_dir: std::str::from_utf8(dir).unwrap_or("."),
            name: std::str::from_utf8(name).unwrap_or(""),
            image_width: env.image_width,
            image_height: env.image_height,
        },
    )
}

/// The shared body of every kind's `create`.
fn create_with<D: Decl, T>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
    make: impl FnOnce(&str, &Env) -> Result<T, PluginError>,
) -> *mut c_void {
    let mut out: *mut c_void = std::ptr::null_mut();
    cold::<D>(&sink, "create", || {
        // SAFETY: the host passes valid parameter text and environment.
        let (json, env) = unsafe { create_args(params, len, env) };
        let obj = make(json, &env)?;
        out = Box::into_raw(Box::new(obj)) as *mut c_void;
        Ok(())
    });
    out
}

extern "C" fn destroy<T>(this: *mut c_void) {
    if !this.is_null() {
        // SAFETY: `this` came from `Box::into_raw` in `create` and is destroyed once.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            drop(unsafe { Box::from_raw(this as *mut T) })
        }));
    }
}

/// # Safety
/// `this` must be a live object of type `T` made by this plugin's `create`.
#[inline]
unsafe fn obj<'a, T>(this: *const c_void) -> &'a T {
    // SAFETY: guaranteed by the caller.
    unsafe { &*(this as *const T) }
}

// ---------------------------------------------------------------- objects

/// Marker tying an [`Object`] type to its declaration.
pub struct ObjectSource<T, D>(PhantomData<(T, D)>);

impl<T: Object, D: Decl> ModuleSource for ObjectSource<T, D> {
    type Module = ObjectModuleRef;
    fn module() -> ObjectModuleRef {
        object_module::<T, D>()
    }
}

/// The root module of an object class.
pub fn object_module<T: Object, D: Decl>() -> ObjectModuleRef {
    ObjectModule {
        meta: meta::<D>(),
        create: obj_create::<T, D>,
        destroy: destroy::<T>,
        add_child: obj_add_child::<T, D>,
        prepare: obj_prepare::<T, D>,
        fns: object_fns::<T, D>(),
    }
    .leak_into_prefix()
}

fn object_fns<T: Object, D: Decl>() -> ObjectFns {
    ObjectFns {
        intersect: obj_intersect::<T, D>,
        occluded: obj_occluded::<T, D>,
        local_geom: obj_local_geom::<T, D>,
        bounds: obj_bounds::<T>,
        bounding_sphere: T::HAS_BOUNDING_SPHERE.then_some(obj_bounding_sphere::<T> as _),
        hull_points: None,
        slab_bounds: None,
        in_interior: T::HAS_INTERIOR.then_some(obj_in_interior::<T, D> as _),
        sample_surface: T::HAS_SURFACE_SAMPLING.then_some(obj_sample_surface::<T, D> as _),
        area: T::HAS_SURFACE_SAMPLING.then_some(obj_area::<T> as _),
        prim_count: T::HAS_PRIM_SET.then_some(obj_prim_count::<T> as _),
        prim_bounds: T::HAS_PRIM_SET.then_some(obj_prim_bounds::<T> as _),
        intersect_prims: T::HAS_PRIM_SET.then_some(obj_intersect_prims::<T, D> as _),
        occluded_prims: T::HAS_PRIM_SET.then_some(obj_occluded_prims::<T, D> as _),
        reorder_prims: None,
    }
}

extern "C" fn obj_create<T: Object, D: Decl>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    create_with::<D, T>(params, len, env, sink, |json, env| {
        T::create(parse_params(json)?, env)
    })
}

extern "C" fn obj_add_child<T: Object, D: Decl>(
    this: *mut c_void,
    child: ObjectRef,
    inst: *const InstanceData,
    sink: ErrSink,
) -> i32 {
    cold::<D>(&sink, "add_child", || {
        // SAFETY: the host passes the live object, exclusively, and valid instance data.
        let (me, inst) = unsafe { (&mut *(this as *mut T), *inst) };
        me.add_child(Child::new(child, inst))
    })
}

extern "C" fn obj_prepare<T: Object, D: Decl>(
    this: *mut c_void,
    env: *const PrepareEnv,
    sink: ErrSink,
) -> i32 {
    cold::<D>(&sink, "prepare", || {
        // SAFETY: the host passes the live object, exclusively, and a valid environment.
        let (me, env) = unsafe { (&mut *(this as *mut T), &*env) };
        me.prepare(&Prepare { env })
    })
}

extern "C" fn obj_intersect<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    hit: *mut Hit,
    level: u32,
) -> bool {
    hot::<D, _>(ctx, "intersect", false, || {
        // SAFETY: the caller passes the live object and valid, exclusive query records.
        unsafe { obj::<T>(this).intersect(&mut *ctx, &*ray, &mut *hit, level) }
    })
}

extern "C" fn obj_occluded<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    level: u32,
) -> bool {
    hot::<D, _>(ctx, "occluded", false, || {
        // SAFETY: the caller passes the live object and valid, exclusive query records.
        unsafe { obj::<T>(this).occluded(&mut *ctx, &*ray, level) }
    })
}

extern "C" fn obj_local_geom<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    hit: *const Hit,
    level: u32,
    mask: u32,
    out: *mut LocalGeom,
) {
    hot::<D, _>(ctx, "local_geom", (), || {
        // SAFETY: the caller passes the live object and valid, exclusive query records.
        unsafe { obj::<T>(this).local_geom(&mut *ctx, &*ray, &*hit, level, mask, &mut *out) }
    })
}

extern "C" fn obj_bounds<T: Object>(this: *const c_void, t0: f32, t1: f32, out: *mut Bounds3) {
    let r = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live object.
        unsafe { obj::<T>(this) }.bounds(t0, t1)
    }));
    // A panic here leaves an empty box; the caller sees the object as empty.
    // SAFETY: the caller passes a valid output record.
    unsafe { *out = r.unwrap_or(Bounds3::EMPTY) };
}

extern "C" fn obj_bounding_sphere<T: Object>(
    this: *const c_void,
    t0: f32,
    t1: f32,
    out: *mut BoundingSphere,
) -> bool {
    catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live object and a valid output record.
        unsafe { *out = obj::<T>(this).bounding_sphere(t0, t1) };
    }))
    .is_ok()
}

extern "C" fn obj_in_interior<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    p: *const Float3,
    time: f32,
) -> bool {
    hot::<D, _>(ctx, "in_interior", false, || {
        // SAFETY: the caller passes the live object and valid records.
        unsafe { obj::<T>(this).in_interior(&mut *ctx, *p, time) }
    })
}

extern "C" fn obj_sample_surface<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    u: *const [f32; 3],
    time: f32,
    out: *mut SurfaceSample,
) -> bool {
    hot::<D, _>(ctx, "sample_surface", false, || {
        // SAFETY: the caller passes the live object and valid records.
        match unsafe { obj::<T>(this).sample_surface(&mut *ctx, *u, time) } {
            Some(s) => {
                // SAFETY: valid output record.
                unsafe { *out = s };
                true
            }
            None => false,
        }
    })
}

extern "C" fn obj_area<T: Object>(this: *const c_void, time: f32) -> f32 {
    // SAFETY: the caller passes the live object.
    catch_unwind(AssertUnwindSafe(|| unsafe { obj::<T>(this) }.area(time))).unwrap_or(0.0)
}

extern "C" fn obj_prim_count<T: Object>(this: *const c_void) -> u32 {
    // SAFETY: the caller passes the live object.
    catch_unwind(AssertUnwindSafe(|| unsafe { obj::<T>(this) }.prim_count())).unwrap_or(0)
}

extern "C" fn obj_prim_bounds<T: Object>(
    this: *const c_void,
    first: u32,
    n: u32,
    out: *mut Bounds3,
) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live object and room for `n` boxes.
        let (me, out) = unsafe {
            (
                obj::<T>(this),
                std::slice::from_raw_parts_mut(out, n as usize),
            )
        };
        me.prim_bounds(first, out)
    }));
}

extern "C" fn obj_intersect_prims<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    ids: *const u32,
    n: u32,
    hit: *mut Hit,
    level: u32,
) -> bool {
    hot::<D, _>(ctx, "intersect_prims", false, || {
        // SAFETY: the caller passes the live object, `n` ids and valid, exclusive records.
        unsafe {
            let ids = std::slice::from_raw_parts(ids, n as usize);
            obj::<T>(this).intersect_prims(&mut *ctx, &*ray, ids, &mut *hit, level)
        }
    })
}

extern "C" fn obj_occluded_prims<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    ids: *const u32,
    n: u32,
    level: u32,
) -> bool {
    hot::<D, _>(ctx, "occluded_prims", false, || {
        // SAFETY: the caller passes the live object, `n` ids and valid, exclusive records.
        unsafe {
            let ids = std::slice::from_raw_parts(ids, n as usize);
            obj::<T>(this).occluded_prims(&mut *ctx, &*ray, ids, level)
        }
    })
}

/// `Prepare::parallel_for`: hand each index to the host's pool; catch panics
/// per task (unwinding into the host would abort) and re-raise one here.
pub(super) fn parallel_for<F: Fn(u64) + Sync>(env: &PrepareEnv, n: u64, f: F) {
    struct Job<'a, F> {
        f: &'a F,
        panicked: AtomicBool,
    }
    extern "C" fn body<F: Fn(u64) + Sync>(user: *const c_void, i: u64) {
        // SAFETY: `user` is the `Job` below, alive until `parallel_for` returns.
        let job = unsafe { &*(user as *const Job<F>) };
        if catch_unwind(AssertUnwindSafe(|| (job.f)(i))).is_err() {
            job.panicked.store(true, Ordering::Relaxed);
        }
    }
    let job = Job {
        f: &f,
        panicked: AtomicBool::new(false),
    };
    (env.parallel_for)(
        env.host,
        n,
        ParallelBody { func: body::<F> },
        &job as *const Job<F> as *const c_void,
    );
    if job.panicked.load(Ordering::Relaxed) {
        panic!("a parallel_for task panicked");
    }
}

// ---------------------------------------------------------------- shaders

/// Marker tying a [`Shader`] type to its declaration.
pub struct ShaderSource<T, D>(PhantomData<(T, D)>);

impl<T: Shader, D: Decl> ModuleSource for ShaderSource<T, D> {
    type Module = ShaderModuleRef;
    fn module() -> ShaderModuleRef {
        shader_module::<T, D>()
    }
}

/// The root module of a shader.
pub fn shader_module<T: Shader, D: Decl>() -> ShaderModuleRef {
    ShaderModule {
        meta: meta::<D>(),
        create: sh_create::<T, D>,
        destroy: destroy::<T>,
        eval: sh_eval::<T, D>,
        sample: sh_sample::<T, D>,
        pdf: sh_pdf::<T>,
        emitted: T::EMITS.then_some(sh_emitted::<T> as _),
        shade: T::SHADES.then_some(sh_shade::<T, D> as _),
    }
    .leak_into_prefix()
}

extern "C" fn sh_create<T: Shader, D: Decl>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    create_with::<D, T>(params, len, env, sink, |json, env| {
        T::create(parse_params(json)?, env)
    })
}

extern "C" fn sh_eval<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    wi: *const Float3,
) -> Color {
    hot::<D, _>(ctx, "eval", Color::BLACK, || {
        // SAFETY: the caller passes the live shader and valid records.
        unsafe { obj::<T>(this).eval(&mut *ctx, &*geom, (*wo).v(), (*wi).v()) }
    })
}

extern "C" fn sh_sample<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    u: *const [f32; 2],
    out: *mut BsdfSample,
) -> bool {
    hot::<D, _>(ctx, "sample", false, || {
        // SAFETY: the caller passes the live shader and valid records.
        match unsafe { obj::<T>(this).sample(&mut *ctx, &*geom, (*wo).v(), *u) } {
            Some(s) => {
                // SAFETY: valid output record.
                unsafe { *out = s };
                true
            }
            None => false,
        }
    })
}

extern "C" fn sh_pdf<T: Shader>(
    this: *const c_void,
    geom: *const LocalGeom,
    wo: *const Float3,
    wi: *const Float3,
) -> f32 {
    catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live shader and valid records.
        unsafe { obj::<T>(this).pdf(&*geom, (*wo).v(), (*wi).v()) }
    }))
    .unwrap_or(0.0)
}

extern "C" fn sh_emitted<T: Shader>(
    this: *const c_void,
    geom: *const LocalGeom,
    wo: *const Float3,
) -> Color {
    catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live shader and valid records.
        unsafe { obj::<T>(this).emitted(&*geom, (*wo).v()) }
    }))
    .unwrap_or(Color::BLACK)
}

extern "C" fn sh_shade<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    scene: *const SceneApi,
    ray: *const Ray,
    geom: *const LocalGeom,
) -> Color {
    hot::<D, _>(ctx, "shade", Color::BLACK, || {
        // SAFETY: the caller passes the live shader and valid records.
        unsafe { obj::<T>(this).shade(&mut *ctx, &Scene::new(&*scene), &*ray, &*geom) }
    })
}

// ---------------------------------------------------------------- integrators

/// Marker tying an [`Integrator`] type to its declaration.
pub struct IntegratorSource<T, D>(PhantomData<(T, D)>);

impl<T: Integrator, D: Decl> ModuleSource for IntegratorSource<T, D> {
    type Module = IntegratorModuleRef;
    fn module() -> IntegratorModuleRef {
        integrator_module::<T, D>()
    }
}

/// The root module of an integrator.
pub fn integrator_module<T: Integrator, D: Decl>() -> IntegratorModuleRef {
    IntegratorModule {
        meta: meta::<D>(),
        create: int_create::<T, D>,
        destroy: destroy::<T>,
        max_depth: int_max_depth::<T>,
        li: int_li::<T, D>,
    }
    .leak_into_prefix()
}

extern "C" fn int_create<T: Integrator, D: Decl>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    create_with::<D, T>(params, len, env, sink, |json, env| {
        T::create(parse_params(json)?, env)
    })
}

extern "C" fn int_max_depth<T: Integrator>(this: *const c_void) -> u32 {
    // SAFETY: the caller passes the live integrator.
    catch_unwind(AssertUnwindSafe(|| unsafe { obj::<T>(this) }.max_depth())).unwrap_or(0)
}

extern "C" fn int_li<T: Integrator, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    scene: *const SceneApi,
    ray: *const Ray,
) -> Color {
    hot::<D, _>(ctx, "li", Color::BLACK, || {
        // SAFETY: the caller passes the live integrator and valid records.
        unsafe { obj::<T>(this).li(&mut *ctx, &Scene::new(&*scene), &*ray) }
    })
}

// ---------------------------------------------------------------- cameras

/// Marker tying a [`Camera`] type to its declaration.
pub struct CameraSource<T, D>(PhantomData<(T, D)>);

impl<T: Camera, D: Decl> ModuleSource for CameraSource<T, D> {
    type Module = CameraModuleRef;
    fn module() -> CameraModuleRef {
        camera_module::<T, D>()
    }
}

/// The root module of a camera.
pub fn camera_module<T: Camera, D: Decl>() -> CameraModuleRef {
    CameraModule {
        meta: meta::<D>(),
        create: cam_create::<T, D>,
        destroy: destroy::<T>,
        generate_ray: cam_generate_ray::<T>,
    }
    .leak_into_prefix()
}

extern "C" fn cam_create<T: Camera, D: Decl>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    create_with::<D, T>(params, len, env, sink, |json, env| {
        T::create(parse_params(json)?, env)
    })
}

extern "C" fn cam_generate_ray<T: Camera>(
    this: *const c_void,
    sample: *const CameraSample,
    out: *mut Ray,
) -> f32 {
    catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live camera and valid records.
        let (ray, w) = unsafe { obj::<T>(this).generate_ray(&*sample) };
        // SAFETY: valid output record.
        unsafe { *out = ray };
        w
    }))
    // A NaN weight tells the host the camera failed.
    .unwrap_or(f32::NAN)
}

// ---------------------------------------------------------------- lights

/// Marker tying a [`Light`] type to its declaration.
pub struct LightSource<T, D>(PhantomData<(T, D)>);

impl<T: Light, D: Decl> ModuleSource for LightSource<T, D> {
    type Module = LightModuleRef;
    fn module() -> LightModuleRef {
        light_module::<T, D>()
    }
}

/// The root module of a light.
pub fn light_module<T: Light, D: Decl>() -> LightModuleRef {
    LightModule {
        meta: meta::<D>(),
        create: light_create::<T, D>,
        destroy: destroy::<T>,
        flags: light_flags::<T>,
        preprocess: Some(light_preprocess::<T>),
        sample_li: light_sample_li::<T, D>,
        pdf_li: None,
        le: T::HAS_LE.then_some(light_le::<T> as _),
    }
    .leak_into_prefix()
}

extern "C" fn light_create<T: Light, D: Decl>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    create_with::<D, T>(params, len, env, sink, |json, env| {
        T::create(parse_params(json)?, env)
    })
}

extern "C" fn light_flags<T: Light>(this: *const c_void) -> u32 {
    // SAFETY: the caller passes the live light.
    catch_unwind(AssertUnwindSafe(|| unsafe { obj::<T>(this) }.flags())).unwrap_or(0)
}

extern "C" fn light_preprocess<T: Light>(this: *mut c_void, world: *const Bounds3) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live light, exclusively, and valid bounds.
        unsafe { (*(this as *mut T)).preprocess(&*world) }
    }));
}

extern "C" fn light_sample_li<T: Light, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    p: *const Float3,
    u: *const [f32; 2],
    time: f32,
    out: *mut LightSample,
) -> bool {
    hot::<D, _>(ctx, "sample_li", false, || {
        // SAFETY: the caller passes the live light and valid records.
        match unsafe { obj::<T>(this).sample_li(&mut *ctx, (*p).v(), *u, time) } {
            Some(s) => {
                // SAFETY: valid output record.
                unsafe { *out = s };
                true
            }
            None => false,
        }
    })
}

extern "C" fn light_le<T: Light>(this: *const c_void, ray: *const Ray) -> Color {
    catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the caller passes the live light and a valid ray.
        unsafe { obj::<T>(this).le(&*ray) }
    }))
    .unwrap_or(Color::BLACK)
}
