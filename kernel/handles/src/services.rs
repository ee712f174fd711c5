//! What the host offers plugins, as safe traits the host implements; the
//! shims generated from the services' declaration (`rtk_abi::scene_entries`)
//! turn them into the records ([`PrepareEnv`], [`SceneRef`]).

use glam::Vec3;
use rtk_abi::*;
use rtk_sdk::Scene;
use std::ffi::c_void;
use std::marker::PhantomData;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The host's thread pool and file accounting, as `prepare` sees them.
pub trait PrepareServices: Sync {
    /// Number of threads queries may come from (`TraceCtx::thread_index` bound).
    fn max_threads(&self) -> u32;
    /// Run `f(i)` for every `i < n`, returning when all are done.
    fn parallel_for(&self, n: u64, f: &(dyn Fn(u64) + Sync));
    /// A plugin read this file (for `--stats`).
    fn note_file(&self, path: &str);
}

/// Call `f` with a [`PrepareEnv`] built over `services`, valid for the call.
pub(super) fn prepare_env<R>(
    services: &dyn PrepareServices,
    f: impl FnOnce(&PrepareEnv) -> R,
) -> R {
    let host: &dyn PrepareServices = services;
    let env = PrepareEnv {
        max_threads: services.max_threads(),
        host: &host as *const &dyn PrepareServices as *const c_void,
        parallel_for: prepare_parallel_for,
        note_file: prepare_note_file,
    };
    f(&env)
}

/// A task context pointer the pool's threads share.
struct SharedPtr(*const c_void);
// SAFETY: it points at the SDK's job record, which is `Sync` (a `&F` with
// `F: Sync` and a mutex), alive until `parallel_for` returns.
unsafe impl Sync for SharedPtr {}

unsafe extern "C" fn prepare_parallel_for(
    host: *const c_void,
    n: u64,
    body: ParallelBody,
    user: *const c_void,
) {
    // SAFETY: `host` is the `&dyn PrepareServices` of `prepare_env`, alive for `prepare`.
    let h = unsafe { *(host as *const &dyn PrepareServices) };
    let user = SharedPtr(user);
    let user = &user;
    // The task bodies catch their own panics (the SDK's job record); a panic
    // of the host's pool itself must not unwind into the plugin.
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the SDK's task body with its job record, valid for the call.
        h.parallel_for(n, &|i| unsafe { (body.func)(user.0, i) })
    }));
}

unsafe extern "C" fn prepare_note_file(host: *const c_void, path: *const u8, len: usize) {
    // SAFETY: `host` as above; the plugin passes a valid byte range.
    let (h, bytes) = unsafe {
        (
            *(host as *const &dyn PrepareServices),
            std::slice::from_raw_parts(path, len),
        )
    };
    let _ = catch_unwind(AssertUnwindSafe(|| {
        h.note_file(&String::from_utf8_lossy(bytes))
    }));
}

/// What the host offers integrators and shaders while rendering: the
/// kernel's `Trace`, the root's queries, the lights and the bound materials,
/// one method per entry of the services record. Every method may be called
/// from many threads at once. The shims add no `catch_unwind`: host code is
/// pure dispatch, and a panic in it is a bug in rtk, which aborts with its
/// message rather than unwinding into a plugin's frame.
pub trait Services: Sync + Sized {
    /// `Trace(ray) -> color`: the integrator's radiance along `ray`.
    fn trace(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32) -> Color;
    /// Nearest hit of the root.
    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32, hit: &mut Hit) -> bool;
    /// Any hit of the root.
    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool;
    /// Local geometry of a root hit, into `out` (which starts as [`LocalGeom::EMPTY`]).
    fn local_geom(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &Hit, mask: u32, out: &mut LocalGeom);
    /// Radiance of a ray leaving the scene.
    fn background(&self, ctx: &mut TraceCtx, ray: &Ray) -> Color;
    /// Number of lights.
    fn light_count(&self) -> u32;
    /// The [`light_flag`] bits of light `index`.
    fn light_flags(&self, index: u32) -> u32;
    /// Sample light `index` from `p`.
    fn sample_light(
        &self,
        ctx: &mut TraceCtx,
        index: u32,
        p: Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample>;
    /// Density (solid angle, per light) with which sampling the light that
    /// `ray` found from `p` gives its direction: `geom` is the ray's hit on
    /// an emitting surface, `None` when it left the scene.
    fn light_pdf(&self, ctx: &mut TraceCtx, p: Vec3, ray: &Ray, geom: Option<&LocalGeom>) -> f32;
    /// The shader with id `shader`, as the record a plugin queries.
    fn material(&self, shader: u32) -> Option<ShaderRef>;

    /// Nearest hits of the root for a batch of rays (ray streams); the
    /// default asks [`intersect`](Services::intersect) ray by ray.
    fn intersect_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        kind: u32,
        hits: &mut [Hit],
        active: u64,
    ) -> u64 {
        let mut found = 0;
        for i in rtk_sdk::batch::lanes(active, rays.len().min(hits.len())) {
            if self.intersect(ctx, &rays[i], kind, &mut hits[i]) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Any hit of the root for each active ray of a batch; the default
    /// asks [`occluded`](Services::occluded) ray by ray.
    fn occluded_batch(&self, ctx: &mut TraceCtx, rays: &[Ray], active: u64) -> u64 {
        let mut found = 0;
        for i in rtk_sdk::batch::lanes(active, rays.len()) {
            if self.occluded(ctx, &rays[i]) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Local geometry of each active root hit of a batch; the default asks
    /// [`local_geom`](Services::local_geom) hit by hit.
    fn local_geom_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &[Hit],
        active: u64,
        mask: u32,
        out: &mut [LocalGeom],
    ) {
        for i in rtk_sdk::batch::lanes(active, rays.len().min(hits.len()).min(out.len())) {
            self.local_geom(ctx, &rays[i], &hits[i], mask, &mut out[i]);
        }
    }

    /// `sample_light` for each active point of a batch; the default asks
    /// point by point.
    #[allow(clippy::too_many_arguments)]
    fn sample_light_batch(
        &self,
        ctx: &mut TraceCtx,
        index: &[u32],
        p: &[Float3],
        u: &[[f32; 2]],
        time: &[f32],
        active: u64,
        out: &mut [LightSample],
    ) -> u64 {
        let n = index
            .len()
            .min(p.len())
            .min(u.len())
            .min(time.len())
            .min(out.len());
        let mut got = 0;
        for i in rtk_sdk::batch::lanes(active, n) {
            if let Some(s) = self.sample_light(ctx, index[i], p[i].v(), u[i], time[i]) {
                out[i] = s;
                got |= 1 << i;
            }
        }
        got
    }
}

rtk_abi::scene_entries!(rtk_sdk::__host_shims, shims);

/// The scene-services record for host type `H`, built once per render.
pub struct ServicesTable<H> {
    r: SceneServicesRef,
    _host: PhantomData<fn(&H)>,
}

impl<H> Clone for ServicesTable<H> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<H> Copy for ServicesTable<H> {}

impl<H: Services> ServicesTable<H> {
    /// Build the record (a few hundred bytes, leaked: records are `'static`).
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        use abi_stable::prefix_type::PrefixTypeTrait;
        ServicesTable {
            r: shims::module::<H>().leak_into_prefix(),
            _host: PhantomData,
        }
    }

    /// The record bound to `host`, valid while `host` is borrowed.
    pub fn bind<'h>(&self, host: &'h H) -> SceneRecord<'h> {
        SceneRecord {
            r: SceneRef {
                host: host as *const H as *const c_void,
                services: self.r,
            },
            _host: PhantomData,
        }
    }
}

/// The scene services bound to a live host: what an integrator receives.
pub struct SceneRecord<'h> {
    r: SceneRef,
    _host: PhantomData<&'h ()>,
}

impl SceneRecord<'_> {
    /// The record as the [`Scene`] a plugin receives (a shader's `shade`,
    /// tools that call plugins directly).
    pub fn scene(&self) -> &Scene {
        super::handles::scene_of(&self.r)
    }
}
