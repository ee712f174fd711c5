//! The plugin side's shims: the record of each kind, generated from its
//! declaration (`rtk_abi::entries`) by [`__shims!`](crate::__shims), and
//! the helpers every generated shim uses — `catch_unwind` around each call,
//! failures into the trace context or the error sink, `create` and
//! `destroy`. The plugin side's `unsafe` is here and in the generated code:
//! turning the pointers the host passes back into references, under the
//! records' contract that they are valid for the call (and, for `this`, for
//! the object's life).

use super::*;
use abi_stable::library::{
    __call_root_module_loader, CheckTypeLayout, LibHeader, RootModule, RootModuleResult,
};
use abi_stable::prefix_type::PrefixTypeTrait;
use abi_stable::std_types::RStr;
use rtk_abi::*;
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

/// The metadata every record starts with.
pub fn meta<D: Decl>() -> ModuleMeta {
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
pub fn cold(sink: ErrSink, f: impl FnOnce() -> Result<(), PluginError>) -> i32 {
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
pub unsafe fn hot<D: Decl, R>(
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
pub unsafe fn write_some<T>(out: *mut T, v: Option<T>) -> bool {
    match v {
        Some(v) => {
            // SAFETY: guaranteed by the caller.
            unsafe { *out = v };
            true
        }
        None => false,
    }
}

/// `this` as the object it is.
///
/// # Safety
/// `this` must be a live object of type `T` made by this plugin.
#[inline(always)]
pub unsafe fn obj<'a, T>(this: *const c_void) -> &'a T {
    // SAFETY: guaranteed by the caller.
    unsafe { &*(this as *const T) }
}

/// `this` as the object it is, exclusively.
///
/// # Safety
/// `this` must be a live object of type `T` made by this plugin, and the
/// caller must have it to itself (building: `add_child`, `prepare`).
#[inline(always)]
pub unsafe fn obj_mut<'a, T>(this: *mut c_void) -> &'a mut T {
    // SAFETY: guaranteed by the caller.
    unsafe { &mut *(this as *mut T) }
}

/// The one `create` of every kind.
///
/// # Safety
/// `params` is valid UTF-8 bytes (or not: that is refused) for the call,
/// `env` a valid environment.
pub unsafe extern "C" fn create<T: Plugin>(
    params: Span<u8>,
    env: *const CreateEnv,
    sink: ErrSink,
) -> *mut c_void {
    let mut out: *mut c_void = std::ptr::null_mut();
    cold(sink, || {
        // SAFETY: the host passes the parameter text and a valid environment.
        let (bytes, env) = unsafe { (params.as_slice(), env_of(&*env)) };
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
/// The environment's strings and arrays must be valid for `'a`.
pub unsafe fn env_of<'a>(env: &'a CreateEnv) -> Env<'a> {
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
        // SAFETY: the caller's contract covers the arrays: the host builds
        // each record from bytes it holds for the whole call.
        arrays: unsafe { crate::bulk::Arrays::from_raw(env.arrays.as_slice()) },
    }
}

/// The one `destroy` of every kind.
///
/// # Safety
/// `this` is null or came from this plugin's `create` (or a `ctor`) for a
/// `T`, and is destroyed once.
pub unsafe extern "C" fn destroy<T>(this: *mut c_void) {
    if !this.is_null() {
        // A panic in a destructor is dropped: there is nothing left to report it to.
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: `this` came from `Box::into_raw` in `create` and is destroyed once.
            drop(unsafe { Box::from_raw(this as *mut T) })
        }));
    }
}

/// Fills the optional entries of a capability a plugin names in its export
/// macro (`capabilities = [PrimitiveSet]`): each method is named after its
/// trait and exists only when the type implements it (the methods are
/// generated with the records, one per capability group).
pub struct Install<T, D>(PhantomData<(T, D)>);

rtk_abi::object_entries!(crate::__shims, object);
rtk_abi::shader_entries!(crate::__shims, shader);
rtk_abi::integrator_entries!(crate::__shims, integrator);
rtk_abi::camera_entries!(crate::__shims, camera);
rtk_abi::light_entries!(crate::__shims, light);

/// Tell the host a file was read.
pub(crate) fn note_file(env: &PrepareEnv, path: &str) {
    // SAFETY: the host's environment is valid during `prepare`; the range is a `&str`.
    unsafe { (env.note_file)(env.host, path.as_ptr(), path.len()) }
}

/// `Prepare::parallel_for`: hand each index to the host's pool; catch panics
/// per task (unwinding into the host would abort) and re-raise the first here.
pub(crate) fn parallel_for<F: Fn(u64) + Sync>(env: &PrepareEnv, n: u64, f: F) {
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
