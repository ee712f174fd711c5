//! The generic `unsafe extern "C"` shims between the records and the safe
//! traits: the SDK's side of each entry's signature (the record holds the
//! other). All of the plugin side's `unsafe` is here: turning the pointers the
//! host passes back into references, under the records' contract that they
//! are valid for the call (and, for `this`, for the object's life).

use super::*;
use crate::abi::*;
use abi_stable::library::{
    __call_root_module_loader, CheckTypeLayout, LibHeader, RootModule, RootModuleResult,
};
use abi_stable::prefix_type::PrefixTypeTrait;
use abi_stable::std_types::RStr;
use std::any::Any;
use std::ffi::c_void;
use std::marker::PhantomData;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

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

/// Turn a module value into the `'static` prefix reference the loader returns.
pub fn leak<M: PrefixTypeTrait>(m: M) -> M::PrefixRef {
    m.leak_into_prefix()
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
        "a panic with a non-string payload".to_string()
    }
}

fn report(sink: ErrSink, status: i32, key: &str, msg: &str) {
    // SAFETY: the host passes a sink valid for the call; the ranges are `&str`s.
    unsafe {
        (sink.report)(
            sink.ctx,
            status,
            key.as_ptr(),
            key.len(),
            msg.as_ptr(),
            msg.len(),
        )
    }
}

/// Run a cold call: an error or a panic goes to the sink, with a status.
fn cold(sink: ErrSink, f: impl FnOnce() -> Result<(), PluginError>) -> i32 {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => STATUS_OK,
        Ok(Err(e)) => {
            report(sink, STATUS_ERROR, &e.key, &e.message);
            STATUS_ERROR
        }
        Err(p) => {
            report(sink, STATUS_PANIC, "", &panic_message(&*p));
            STATUS_PANIC
        }
    }
}

/// Run a hot call: a panic is recorded in the context with the plugin's name
/// (and `fallback` returned). Nothing is checked on the success path.
///
/// # Safety
/// `ctx` must be valid and exclusive for the call.
#[inline(always)]
unsafe fn hot<D: Decl, R>(
    ctx: *mut TraceCtx,
    entry: &str,
    fallback: R,
    f: impl FnOnce(&mut TraceCtx) -> R,
) -> R {
    // SAFETY: guaranteed by the caller.
    let ctx = unsafe { &mut *ctx };
    let r = {
        let c = &mut *ctx;
        catch_unwind(AssertUnwindSafe(move || f(c)))
    };
    match r {
        Ok(v) => v,
        Err(p) => {
            let msg = format!("panicked in {entry}: {}", panic_message(&*p));
            ctx.record_failure(D::CLASS, &msg);
            fallback
        }
    }
}

/// Write an optional result to the entry's output record; true when there was one.
///
/// # Safety
/// `out` must be valid for writes.
#[inline(always)]
pub(crate) unsafe fn write_some<T>(out: *mut T, v: Option<T>) -> bool {
    match v {
        Some(v) => {
            // SAFETY: guaranteed by the caller.
            unsafe { *out = v };
            true
        }
        None => false,
    }
}

/// # Safety
/// `this` must be a live object of type `T` made by this plugin.
#[inline(always)]
unsafe fn obj<'a, T>(this: *const c_void) -> &'a T {
    // SAFETY: guaranteed by the caller.
    unsafe { &*(this as *const T) }
}

/// The one `create` of every kind.
unsafe extern "C" fn create<T: Plugin>(
    params: *const u8,
    len: usize,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    let mut out: *mut c_void = std::ptr::null_mut();
    cold(sink, || {
        // SAFETY: the host passes `len` bytes of parameter text and a valid environment.
        let (bytes, env) = unsafe { (std::slice::from_raw_parts(params, len), env_of(&*env)) };
        let json = std::str::from_utf8(bytes)
            .map_err(|_| PluginError::msg("the parameters are not UTF-8 text"))?;
        let obj = T::create(parse_params(json)?, &env)?;
        out = Box::into_raw(Box::new(obj)) as *mut c_void;
        Ok(())
    });
    out
}

/// The safe view of a [`CreateEnv`].
///
/// # Safety
/// The environment's strings must be valid for `'a`.
unsafe fn env_of<'a>(env: &'a CreateEnv) -> Env<'a> {
    // SAFETY: guaranteed by the caller; the host builds them from `&str`s.
    let (dir, name) = unsafe {
        (
            std::slice::from_raw_parts(env.scene_dir, env.scene_dir_len),
            std::slice::from_raw_parts(env.name, env.name_len),
        )
    };
    Env {
        scene_dir: std::str::from_utf8(dir).unwrap_or("."),
        name: std::str::from_utf8(name).unwrap_or(""),
        image_width: env.image_width,
        image_height: env.image_height,
        origin: env.origin,
    }
}

unsafe extern "C" fn destroy<T>(this: *mut c_void) {
    if !this.is_null() {
        // A panic in a destructor is dropped: there is nothing left to report it to.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: `this` came from `Box::into_raw` in `create` and is destroyed once.
            drop(unsafe { Box::from_raw(this as *mut T) })
        }));
    }
}

// ---------------------------------------------------------------- objects

/// The root module of an object class, before capabilities are installed.
pub fn object_module<T: Object, D: Decl>() -> ObjectModule {
    ObjectModule {
        meta: meta::<D>(),
        create: create::<T>,
        destroy: destroy::<T>,
        add_child: obj_add_child::<T>,
        prepare: obj_prepare::<T>,
        bounds: obj_bounds::<T>,
        intersect: obj_intersect::<T, D>,
        occluded: obj_occluded::<T, D>,
        local_geom: obj_local_geom::<T, D>,
        from_transform: None,
        prim_count: None,
        prim_bounds: None,
        intersect_prims: None,
        occluded_prims: None,
        triangles: None,
        flattens_primitives: false,
        sample_surface: None,
        inq_bounds: None,
    }
}

unsafe extern "C" fn obj_add_child<T: Object>(
    this: *mut c_void,
    child: ObjectRef,
    inst: *const InstanceData,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the host passes the live object, exclusively, a prepared
        // child that outlives it, and valid instance data.
        let (me, child) = unsafe { (&mut *(this as *mut T), Child::new(child, *inst)) };
        me.add_child(child)
    })
}

unsafe extern "C" fn obj_prepare<T: Object>(
    this: *mut c_void,
    env: *const PrepareEnv,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the host passes the live object, exclusively, and a valid environment.
        let (me, env) = unsafe { (&mut *(this as *mut T), &*env) };
        me.prepare(&Prepare { env })
    })
}

unsafe extern "C" fn obj_bounds<T: Object>(
    this: *const c_void,
    t0: f32,
    t1: f32,
    out: *mut Bounds3,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the host passes the live object and a valid output record.
        unsafe { *out = obj::<T>(this).bounds(t0, t1) };
        Ok(())
    })
}

unsafe extern "C" fn obj_intersect<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    hit: *mut Hit,
    level: u32,
) -> bool {
    // SAFETY: the caller passes the live object and valid, exclusive records.
    unsafe {
        hot::<D, _>(ctx, "intersect", false, |ctx| {
            obj::<T>(this).intersect(ctx, &*ray, &mut *hit, level)
        })
    }
}

unsafe extern "C" fn obj_occluded<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    level: u32,
) -> bool {
    // SAFETY: the caller passes the live object and valid, exclusive records.
    unsafe {
        hot::<D, _>(ctx, "occluded", false, |ctx| {
            obj::<T>(this).occluded(ctx, &*ray, level)
        })
    }
}

unsafe extern "C" fn obj_local_geom<T: Object, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    hit: *const Hit,
    level: u32,
    mask: u32,
    out: *mut LocalGeom,
) {
    // SAFETY: the caller passes the live object and valid, exclusive records.
    unsafe {
        hot::<D, _>(ctx, "local_geom", (), |ctx| {
            obj::<T>(this).local_geom(ctx, &*ray, &*hit, level, mask, &mut *out)
        })
    }
}

/// Fills the optional entries of a capability a plugin names in its export
/// macro (`capabilities = [PrimitiveSet]`): each method is named after its
/// trait and exists only when the type implements it.
pub struct Install<T, D>(PhantomData<(T, D)>);

#[allow(non_snake_case)]
impl<T: PrimitiveSet, D: Decl> Install<T, D> {
    /// Offer the primitive-set protocol.
    pub fn PrimitiveSet(m: &mut ObjectModule) {
        m.prim_count = Some(obj_prim_count::<T>);
        m.prim_bounds = Some(obj_prim_bounds::<T>);
        m.intersect_prims = Some(obj_intersect_prims::<T, D>);
        m.occluded_prims = Some(obj_occluded_prims::<T, D>);
    }
}

#[allow(non_snake_case)]
impl<T: Triangles, D: Decl> Install<T, D> {
    /// Lend triangles as data.
    pub fn Triangles(m: &mut ObjectModule) {
        m.triangles = Some(obj_triangles::<T>);
    }
}

#[allow(non_snake_case)]
impl<T: FlattensPrimitives, D: Decl> Install<T, D> {
    /// Say that the aggregate flattens primitive sets.
    pub fn FlattensPrimitives(m: &mut ObjectModule) {
        m.flattens_primitives = true;
    }
}

#[allow(non_snake_case)]
impl<T: BoundingVolumes, D: Decl> Install<T, D> {
    /// Answer `inq_bounds` for spheres, hull points and slabs.
    pub fn BoundingVolumes(m: &mut ObjectModule) {
        m.inq_bounds = Some(obj_inq_bounds::<T>);
    }
}

unsafe extern "C" fn obj_inq_bounds<T: BoundingVolumes>(
    this: *const c_void,
    kind: u32,
    t0: f32,
    t1: f32,
    out: *mut BoundingVolume,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the host passes the live object and a valid, exclusive
        // record whose `hull` has room for `hull_cap` points.
        let (o, out) = unsafe { (obj::<T>(this), &mut *out) };
        out.written = false;
        match kind {
            bound_kind::SPHERE => {
                if let Some(s) = o.bound_sphere(t0, t1) {
                    out.sphere = s;
                    out.written = true;
                }
            }
            bound_kind::SLABS => {
                if let Some(s) = o.slabs(t0, t1) {
                    out.slabs = s;
                    out.written = true;
                }
            }
            bound_kind::HULL => {
                if let Some(pts) = o.hull_points(t0, t1) {
                    let n = u32::try_from(pts.len())
                        .map_err(|_| PluginError::msg("more than 2^32 hull points"))?;
                    let copy = n.min(out.hull_cap) as usize;
                    if copy > 0 {
                        // SAFETY: the caller's buffer holds `hull_cap` points.
                        unsafe { std::slice::from_raw_parts_mut(out.hull, copy) }
                            .copy_from_slice(&pts[..copy]);
                    }
                    out.hull_len = n;
                    out.written = true;
                }
            }
            _ => {}
        }
        Ok(())
    })
}

#[allow(non_snake_case)]
impl<T: SampleSurface, D: Decl> Install<T, D> {
    /// Offer points on the surface (area lights).
    pub fn SampleSurface(m: &mut ObjectModule) {
        m.sample_surface = Some(obj_sample_surface::<T, D>);
    }
}

unsafe extern "C" fn obj_sample_surface<T: SampleSurface, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    u: *const [f32; 2],
    out: *mut SurfaceSample,
) -> bool {
    // SAFETY: the caller passes the live object and valid records.
    unsafe {
        hot::<D, _>(ctx, "sample_surface", false, |_| {
            let o = obj::<T>(this);
            let area = o.area();
            let s = o.sample_surface(*u).map(|(p, n)| SurfaceSample {
                p: p.into(),
                n: n.into(),
                area,
            });
            write_some(out, s.filter(|_| area > 0.0))
        })
    }
}

#[allow(non_snake_case)]
impl<T: Environment, D: Decl> Install<T, D> {
    /// Say the light surrounds the scene.
    pub fn Environment(m: &mut LightModule) {
        m.le = Some(light_le::<T, D>);
        m.pdf_li = Some(light_pdf_li::<T, D>);
    }
}

unsafe extern "C" fn light_le<T: Environment, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    dir: *const Float3,
) -> Color {
    // SAFETY: the caller passes the live light and valid records.
    unsafe {
        hot::<D, _>(ctx, "le", Color::BLACK, |ctx| {
            obj::<T>(this).le(ctx, (*dir).v())
        })
    }
}

unsafe extern "C" fn light_pdf_li<T: Environment, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    p: *const Float3,
    wi: *const Float3,
) -> f32 {
    // SAFETY: the caller passes the live light and valid records.
    unsafe {
        hot::<D, _>(ctx, "pdf_li", 0.0, |ctx| {
            obj::<T>(this).pdf_li(ctx, (*p).v(), (*wi).v())
        })
    }
}

#[allow(non_snake_case)]
impl<T: FromTransform, D: Decl> Install<T, D> {
    /// Offer creation from a composed transform.
    pub fn FromTransform(m: &mut ObjectModule) {
        m.from_transform = Some(obj_from_transform::<T>);
    }
}

#[allow(non_snake_case)]
impl<T: Shade, D: Decl> Install<T, D> {
    /// Offer whole shading.
    pub fn Shade(m: &mut ShaderModule) {
        m.shade = Some(sh_shade::<T, D>);
    }
}

unsafe extern "C" fn obj_from_transform<T: FromTransform>(
    m: *const Affine3x4,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    let mut out: *mut c_void = std::ptr::null_mut();
    cold(sink, || {
        // SAFETY: the host passes a valid matrix and environment.
        let (m, env) = unsafe { (*m, env_of(&*env)) };
        let obj = T::from_transform(m.to_daffine(), &env)?;
        out = Box::into_raw(Box::new(obj)) as *mut c_void;
        Ok(())
    });
    out
}

unsafe extern "C" fn obj_triangles<T: Triangles>(
    this: *const c_void,
    out: *mut TriangleData,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the caller passes the live object and a valid output; the
        // slices live as long as the object, which is immutable after `prepare`.
        let t = unsafe { obj::<T>(this) }.triangles();
        let nv = t.positions.len();
        if let Some(bad) = t.indices.iter().flatten().find(|&&i| i as usize >= nv) {
            return Err(PluginError::msg(format!(
                "triangle index {bad} is beyond the {nv} vertices"
            )));
        }
        let (vertex_count, triangle_count) = (
            u32::try_from(nv).map_err(|_| PluginError::msg("too many vertices"))?,
            u32::try_from(t.indices.len()).map_err(|_| PluginError::msg("too many triangles"))?,
        );
        // SAFETY: valid output record.
        unsafe {
            *out = TriangleData {
                positions: t.positions.as_ptr(),
                vertex_count,
                indices: t.indices.as_ptr(),
                triangle_count,
            }
        };
        Ok(())
    })
}

unsafe extern "C" fn obj_prim_count<T: PrimitiveSet>(
    this: *const c_void,
    out: *mut u32,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the caller passes the live object and a valid output.
        unsafe { *out = obj::<T>(this).prim_count() };
        Ok(())
    })
}

unsafe extern "C" fn obj_prim_bounds<T: PrimitiveSet>(
    this: *const c_void,
    first: u32,
    n: u32,
    out: *mut Bounds3,
    sink: ErrSink,
) -> i32 {
    cold(sink, || {
        // SAFETY: the caller passes the live object and room for `n` boxes.
        let (me, out) = unsafe {
            (
                obj::<T>(this),
                std::slice::from_raw_parts_mut(out, n as usize),
            )
        };
        let total = me.prim_count() as u64;
        if first as u64 + n as u64 > total {
            return Err(PluginError::msg(format!(
                "asked for the boxes of primitives {first}..{} of {total}",
                first as u64 + n as u64
            )));
        }
        me.prim_bounds(first, out);
        Ok(())
    })
}

unsafe extern "C" fn obj_intersect_prims<T: PrimitiveSet, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    ids: *const u32,
    n: u32,
    hit: *mut Hit,
    level: u32,
) -> bool {
    // SAFETY: the caller passes the live object, `n` ids and valid, exclusive records.
    unsafe {
        hot::<D, _>(ctx, "intersect_prims", false, |ctx| {
            let ids = std::slice::from_raw_parts(ids, n as usize);
            obj::<T>(this).intersect_prims(ctx, &*ray, ids, &mut *hit, level)
        })
    }
}

unsafe extern "C" fn obj_occluded_prims<T: PrimitiveSet, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    ids: *const u32,
    n: u32,
    level: u32,
) -> bool {
    // SAFETY: the caller passes the live object, `n` ids and valid, exclusive records.
    unsafe {
        hot::<D, _>(ctx, "occluded_prims", false, |ctx| {
            let ids = std::slice::from_raw_parts(ids, n as usize);
            obj::<T>(this).occluded_prims(ctx, &*ray, ids, level)
        })
    }
}

/// Tell the host a file was read.
pub(super) fn note_file(env: &PrepareEnv, path: &str) {
    // SAFETY: the host's environment is valid during `prepare`; the range is a `&str`.
    unsafe { (env.note_file)(env.host, path.as_ptr(), path.len()) }
}

/// `Prepare::parallel_for`: hand each index to the host's pool; catch panics
/// per task (unwinding into the host would abort) and re-raise the first here.
pub(super) fn parallel_for<F: Fn(u64) + Sync>(env: &PrepareEnv, n: u64, f: F) {
    struct Job<'a, F> {
        f: &'a F,
        panicked: Mutex<Option<String>>,
    }
    unsafe extern "C" fn body<F: Fn(u64) + Sync>(user: *const c_void, i: u64) {
        // SAFETY: `user` is the `Job` below, alive until `parallel_for` returns.
        let job = unsafe { &*(user as *const Job<F>) };
        if let Err(p) = catch_unwind(AssertUnwindSafe(|| (job.f)(i))) {
            if let Ok(mut first) = job.panicked.lock() {
                first.get_or_insert_with(|| panic_message(&*p));
            }
        }
    }
    let job = Job {
        f: &f,
        panicked: Mutex::new(None),
    };
    // SAFETY: the environment is valid during `prepare`; `job` outlives the
    // call, which returns only when every task has run.
    unsafe {
        (env.parallel_for)(
            env.host,
            n,
            ParallelBody { func: body::<F> },
            &job as *const Job<F> as *const c_void,
        )
    };
    if let Some(msg) = job.panicked.into_inner().ok().flatten() {
        panic!("a parallel_for task panicked: {msg}");
    }
}

// ---------------------------------------------------------------- shaders

/// The root module of a shader, before capabilities are installed.
pub fn shader_module<T: Shader, D: Decl>() -> ShaderModule {
    ShaderModule {
        meta: meta::<D>(),
        create: create::<T>,
        destroy: destroy::<T>,
        lobes: sh_lobes::<T>,
        eval: sh_eval::<T, D>,
        sample: sh_sample::<T, D>,
        shade: None,
        pdf: Some(sh_pdf::<T, D>),
        emitted: Some(sh_emitted::<T, D>),
    }
}

/// `pdf`'s answer when the shader cannot tell ([`Shader::pdf`] is `None`).
pub const PDF_UNKNOWN: f32 = -1.0;

unsafe extern "C" fn sh_pdf<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    wi: *const Float3,
    lobes: u32,
) -> f32 {
    // SAFETY: the caller passes the live shader and valid records.
    unsafe {
        hot::<D, _>(ctx, "pdf", PDF_UNKNOWN, |ctx| {
            obj::<T>(this)
                .pdf(ctx, &*geom, (*wo).v(), (*wi).v(), lobes)
                .unwrap_or(PDF_UNKNOWN)
        })
    }
}

unsafe extern "C" fn sh_emitted<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
) -> Color {
    // SAFETY: the caller passes the live shader and valid records.
    unsafe {
        hot::<D, _>(ctx, "emitted", Color::BLACK, |ctx| {
            obj::<T>(this).emitted(ctx, &*geom, (*wo).v())
        })
    }
}

unsafe extern "C" fn sh_lobes<T: Shader>(this: *const c_void, out: *mut u32, sink: ErrSink) -> i32 {
    cold(sink, || {
        // SAFETY: the caller passes the live shader and a valid output.
        unsafe { *out = obj::<T>(this).lobes() };
        Ok(())
    })
}

unsafe extern "C" fn sh_eval<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    wi: *const Float3,
) -> Color {
    // SAFETY: the caller passes the live shader and valid records.
    unsafe {
        hot::<D, _>(ctx, "eval", Color::BLACK, |ctx| {
            obj::<T>(this).eval(ctx, &*geom, (*wo).v(), (*wi).v())
        })
    }
}

unsafe extern "C" fn sh_sample<T: Shader, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    u: *const [f32; 2],
    lobes: u32,
    out: *mut BsdfSample,
) -> bool {
    // SAFETY: the caller passes the live shader and valid records.
    unsafe {
        hot::<D, _>(ctx, "sample", false, |ctx| {
            write_some(
                out,
                obj::<T>(this).sample(ctx, &*geom, (*wo).v(), *u, lobes),
            )
        })
    }
}

unsafe extern "C" fn sh_shade<T: Shade, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    scene: *const SceneRef,
    ray: *const Ray,
    geom: *const LocalGeom,
) -> Color {
    // SAFETY: the caller passes the live shader, a live scene record and valid records.
    unsafe {
        hot::<D, _>(ctx, "shade", Color::BLACK, |ctx| {
            obj::<T>(this).shade(ctx, &Scene::new(&*scene), &*ray, &*geom)
        })
    }
}

// ---------------------------------------------------------------- integrators

/// The root module of an integrator.
pub fn integrator_module<T: Integrator, D: Decl>() -> IntegratorModule {
    IntegratorModule {
        meta: meta::<D>(),
        create: create::<T>,
        destroy: destroy::<T>,
        li: int_li::<T, D>,
    }
}

unsafe extern "C" fn int_li<T: Integrator, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    scene: *const SceneRef,
    ray: *const Ray,
) -> Color {
    // SAFETY: the caller passes the live integrator, a live scene record and valid records.
    unsafe {
        hot::<D, _>(ctx, "li", Color::BLACK, |ctx| {
            obj::<T>(this).li(ctx, &Scene::new(&*scene), &*ray)
        })
    }
}

// ---------------------------------------------------------------- cameras

/// The root module of a camera.
pub fn camera_module<T: Camera, D: Decl>() -> CameraModule {
    CameraModule {
        meta: meta::<D>(),
        create: create::<T>,
        destroy: destroy::<T>,
        generate_ray: cam_generate_ray::<T, D>,
    }
}

unsafe extern "C" fn cam_generate_ray<T: Camera, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    sample: *const CameraSample,
    out: *mut Ray,
) -> f32 {
    // SAFETY: the caller passes the live camera and valid records.
    unsafe {
        hot::<D, _>(ctx, "generate_ray", 0.0, |_| {
            let (ray, w) = obj::<T>(this).generate_ray(&*sample);
            *out = ray;
            w
        })
    }
}

// ---------------------------------------------------------------- lights

/// The root module of a light.
pub fn light_module<T: Light, D: Decl>() -> LightModule {
    LightModule {
        meta: meta::<D>(),
        create: create::<T>,
        destroy: destroy::<T>,
        sample_li: light_sample_li::<T, D>,
        le: None,
        pdf_li: None,
    }
}

unsafe extern "C" fn light_sample_li<T: Light, D: Decl>(
    this: *const c_void,
    ctx: *mut TraceCtx,
    p: *const Float3,
    u: *const [f32; 2],
    time: f32,
    out: *mut LightSample,
) -> bool {
    // SAFETY: the caller passes the live light and valid records.
    unsafe {
        hot::<D, _>(ctx, "sample_li", false, |ctx| {
            write_some(out, obj::<T>(this).sample_li(ctx, (*p).v(), *u, time))
        })
    }
}
