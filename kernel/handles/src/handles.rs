//! Owned handles to plugin objects. Each holds its object's [`Live*`]
//! handle (the generated safe callers, which it dereferences to) and
//! destroys the object when the last count goes: objects, shaders and
//! lights are counted (`Arc`) because plugins may hold them too — an
//! aggregate its children, an area light its emitter's object and shader —
//! through the [`KeepAlive`] the host hands out with them.
//!
//! [`Live*`]: rtk_sdk::LiveObject

use super::services::{prepare_env, PrepareServices, SceneRecord};
use crate::{CallError, Collected};
use rtk_abi::*;
use rtk_sdk::{LiveCamera, LiveIntegrator, LiveLight, LiveObject, LiveShader, Scene};
use std::ffi::c_void;
use std::sync::Arc;

/// A named array a host hands to `create` by pointer ([`BulkArray`]): a
/// C-order `rows × cols` block of [`bulk_dtype`] elements. The host owns the
/// bytes; they need only outlive the `create` call.
#[derive(Debug, Clone, Copy)]
pub struct Bulk<'a> {
    /// The parameter it stands for (`vertices`, `indices`).
    pub name: &'a str,
    /// A [`bulk_dtype`].
    pub dtype: u32,
    /// Number of rows.
    pub rows: u64,
    /// Number of columns.
    pub cols: u64,
    /// `rows * cols` elements, native byte order.
    pub data: &'a [u8],
}

/// What `create` receives besides the parameters.
#[derive(Debug, Clone, Copy)]
pub struct CreateArgs<'a> {
    /// Folder of the scene file (relative file parameters resolve against it).
    pub scene_dir: &'a str,
    /// Path of the definition (`objects.ball`), for the plugin's messages.
    pub name: &'a str,
    /// Image width in pixels.
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
    /// The world point the renderer computes about ([`CreateEnv::origin`]).
    pub origin: [f64; 3],
    /// Arrays passed by pointer (meshes from NumPy); empty for a scene file.
    pub arrays: &'a [Bulk<'a>],
}

impl CreateArgs<'_> {
    /// The arrays' records, which `raw` points at.
    fn raw_arrays(&self) -> Vec<BulkArray> {
        self.arrays
            .iter()
            .map(|b| BulkArray {
                name: Span::of(b.name.as_bytes()),
                dtype: b.dtype,
                rows: b.rows,
                cols: b.cols,
                data: b.data.as_ptr(),
            })
            .collect()
    }

    /// The record; its pointers are valid while `self` and `arrays` are borrowed.
    fn raw(&self, arrays: &[BulkArray]) -> CreateEnv {
        CreateEnv {
            arrays: Span::of(arrays),
            scene_dir: self.scene_dir.as_ptr(),
            scene_dir_len: self.scene_dir.len(),
            name: self.name.as_ptr(),
            name_len: self.name.len(),
            image_width: self.image_width,
            image_height: self.image_height,
            origin: self.origin,
        }
    }
}

/// Run a `create`-like entry: `call(env, sink)` returns the new object or null.
fn created(
    args: &CreateArgs,
    entry: &'static str,
    class: &'static str,
    call: impl FnOnce(&CreateEnv, ErrSink) -> *mut c_void,
) -> Result<*mut c_void, CallError> {
    let arrays = args.raw_arrays();
    let env = args.raw(&arrays);
    let mut c = Collected::default();
    let this = call(&env, c.sink());
    if this.is_null() {
        // A null object is a refusal even if the plugin forgot to say why.
        return Err(c.result(STATUS_ERROR, entry, class).unwrap_err());
    }
    Ok(this)
}

/// Release a count an `Arc<T>` handed out with [`counted`].
///
/// # Safety
/// `owner` came from [`counted`] for this `T`, and this count is released once.
unsafe extern "C" fn release<T>(owner: *const c_void) {
    // SAFETY: guaranteed by the caller: one count of a live `Arc<T>`.
    unsafe { Arc::decrement_strong_count(owner as *const T) }
}

/// Add a count to an `Arc<T>` handed out with [`counted`].
///
/// # Safety
/// `owner` came from [`counted`] for this `T` and a count on it is held.
unsafe extern "C" fn retain<T>(owner: *const c_void) {
    // SAFETY: guaranteed by the caller: a count is held, so the `Arc` is alive.
    unsafe { Arc::increment_strong_count(owner as *const T) }
}

/// One count on `arc`, for a plugin to own.
fn counted<T>(arc: &Arc<T>) -> KeepAlive {
    let owner = Arc::into_raw(arc.clone()) as *const c_void;
    KeepAlive {
        owner,
        retain: retain::<T>,
        release: release::<T>,
    }
}

// ---------------------------------------------------------------- objects

struct ObjectInner {
    live: LiveObject,
}

impl Drop for ObjectInner {
    fn drop(&mut self) {
        // SAFETY: `this` was made by this class's `create` and is destroyed
        // once, when the last count (the host's or a plugin's) goes.
        unsafe { (self.live.raw_class().destroy())(self.live.raw_this()) }
    }
}

/// A created object before `prepare`: children may still be added. Only its
/// owner can reach it (the paper's open object).
pub struct ObjectBuilder {
    inner: ObjectInner,
}

/// A prepared object: immutable, shared, safe to query from many threads.
/// Its methods are those of [`LiveObject`] (one per entry of the object
/// record), plus the root's queries at level 0 and a few conveniences.
#[derive(Clone)]
pub struct Object {
    inner: Arc<ObjectInner>,
}

impl ObjectBuilder {
    /// Create an object of `class` from its parameters (JSON text).
    pub fn create(
        class: ObjectModuleRef,
        params: &str,
        args: &CreateArgs,
    ) -> Result<Self, CallError> {
        let name = class.meta().class_name.as_str();
        let this = created(args, "create", name, |env, sink| {
            // SAFETY: the text, environment and sink are valid for the call.
            unsafe { (class.create())(Span::of(params.as_bytes()), env, sink) }
        })?;
        Ok(Self::own(this, class))
    }

    /// Create an object of `class` from a transform (the class must offer
    /// `from_transform`; see `rtk_abi::classes::INSTANCE_TRANSFORM`).
    pub fn from_transform(
        class: ObjectModuleRef,
        m: &glam::DAffine3,
        args: &CreateArgs,
    ) -> Result<Self, CallError> {
        let name = class.meta().class_name.as_str();
        let Some(f) = class.from_transform() else {
            return Err(CallError {
                entry: "from_transform",
                class: name,
                panicked: false,
                key: String::new(),
                message: format!("class `{name}` cannot be made from a transform"),
            });
        };
        let m = Affine3x4::from_daffine(m);
        // SAFETY: the matrix, environment and sink are valid for the call.
        let this = created(args, "from_transform", name, |env, sink| unsafe {
            f(&m, env, sink)
        })?;
        Ok(Self::own(this, class))
    }

    fn own(this: *mut c_void, class: ObjectModuleRef) -> Self {
        ObjectBuilder {
            inner: ObjectInner {
                // SAFETY: `this` is the object `class` just made; the
                // builder owns it alone until `prepare`, and destroys it on drop.
                live: unsafe { LiveObject::new(this, class) },
            },
        }
    }

    /// The object's class name.
    pub fn class_name(&self) -> &'static str {
        self.inner.live.class_name()
    }

    /// The paper's "instance": add a prepared child with its bindings. The
    /// child gets a count, which the parent's plugin owns from now on.
    pub fn add_child(&mut self, child: &Object, inst: InstanceData) -> Result<(), CallError> {
        self.inner.live.add_child(child.child_ref(inst))
    }

    /// The paper's "close": build, and become immutable and shareable.
    pub fn prepare(mut self, services: &dyn PrepareServices) -> Result<Object, CallError> {
        prepare_env(services, |env| self.inner.live.prepare(env))?;
        Ok(Object {
            inner: Arc::new(self.inner),
        })
    }
}

/// A copy of an object's triangles: vertex positions and index triples.
pub type OwnedTriangles = (Vec<[f32; 3]>, Vec<[u32; 3]>);

impl std::ops::Deref for Object {
    type Target = LiveObject;
    #[inline(always)]
    fn deref(&self) -> &LiveObject {
        &self.inner.live
    }
}

impl Object {
    /// The object as a child with `inst`'s bindings, carrying one count.
    pub fn child_ref(&self, inst: InstanceData) -> ChildRef {
        ChildRef {
            obj: ObjectRef {
                this: self.inner.live.raw_this(),
                class: self.inner.live.raw_class(),
            },
            inst,
            keep: counted(&self.inner),
        }
    }

    /// Nearest hit, recorded from level 0 (the root's query).
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit) -> bool {
        self.inner.live.intersect(ctx, ray, hit, 0)
    }

    /// Any hit (the root's query).
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool {
        self.inner.live.occluded(ctx, ray, 0)
    }

    /// Local geometry of a hit found by [`intersect`](Self::intersect).
    #[inline]
    pub fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        self.inner.live.local_geom(ctx, ray, hit, 0, mask, out)
    }

    /// Nearest hits of a batch of rays from level 0 (ray streams), ray by
    /// ray when the class predates the entry; the mask of those that hit.
    #[inline]
    pub fn intersect_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &mut [Hit],
        active: u64,
    ) -> u64 {
        let live = &self.inner.live;
        if live.raw_class().intersect_batch().is_some() {
            return live
                .intersect_batch(ctx, rays, hits, active, 0)
                .unwrap_or(0);
        }
        let mut found = 0;
        for i in rtk_sdk::batch::lanes(active, rays.len().min(hits.len())) {
            if live.intersect(ctx, &rays[i], &mut hits[i], 0) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Any hit for each active ray of a batch, from level 0.
    #[inline]
    pub fn occluded_stream(&self, ctx: &mut TraceCtx, rays: &[Ray], active: u64) -> u64 {
        let live = &self.inner.live;
        if let Some(m) = live.occluded_batch(ctx, rays, active, 0) {
            return m;
        }
        let mut found = 0;
        for i in rtk_sdk::batch::lanes(active, rays.len()) {
            if live.occluded(ctx, &rays[i], 0) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Local geometry of each active hit of a batch found from level 0.
    #[inline]
    pub fn local_geom_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &[Hit],
        active: u64,
        mask: u32,
        out: &mut [LocalGeom],
    ) {
        let live = &self.inner.live;
        if live
            .local_geom_batch(ctx, rays, hits, active, 0, mask, out)
            .is_none()
        {
            for i in rtk_sdk::batch::lanes(active, rays.len().min(hits.len()).min(out.len())) {
                live.local_geom(ctx, &rays[i], &hits[i], 0, mask, &mut out[i]);
            }
        }
    }

    /// A copy of the triangles the object lends as data (positions, index
    /// triples; `None` when its class lends none), checked: every index is
    /// within the positions.
    pub fn triangles(&self) -> Result<Option<OwnedTriangles>, CallError> {
        let Some(d) = self.inner.live.triangles() else {
            return Ok(None);
        };
        let d = d?;
        // SAFETY: the entry succeeded, so `d` points into the object's
        // immutable data with its counts, valid while the object lives
        // (`self`); copied before returning.
        let (p, t) = unsafe {
            (
                Span {
                    ptr: d.positions,
                    len: d.vertex_count as usize,
                }
                .as_slice()
                .to_vec(),
                Span {
                    ptr: d.indices,
                    len: d.triangle_count as usize,
                }
                .as_slice()
                .to_vec(),
            )
        };
        if t.iter().flatten().any(|&i| i as usize >= p.len()) {
            return Err(CallError {
                entry: "triangles",
                class: self.class_name(),
                key: String::new(),
                message: "a triangle index is beyond the vertices".into(),
                panicked: false,
            });
        }
        Ok(Some((p, t)))
    }

    /// A sphere containing the object over `[time0, time1]` (`inq_bounds`,
    /// derived from its hull points or box when it offers none).
    pub fn bound_sphere(&self, time0: f32, time1: f32) -> Result<BoundSphere, CallError> {
        rtk_sdk::volumes::sphere(&self.inner.live, (time0, time1))
    }

    /// Points whose convex hull contains the object (its box's corners when
    /// it offers none).
    pub fn hull_points(&self, time0: f32, time1: f32) -> Result<Vec<[f32; 3]>, CallError> {
        rtk_sdk::volumes::hull_points(&self.inner.live, (time0, time1))
    }

    /// Kay–Kajiya slabs containing the object (from its hull points when it
    /// offers none).
    pub fn slabs(&self, time0: f32, time1: f32) -> Result<SlabBounds, CallError> {
        rtk_sdk::volumes::slabs(&self.inner.live, (time0, time1))
    }

    /// Whether the class answers `inq_bounds` itself.
    pub fn offers_volumes(&self) -> bool {
        self.inner.live.raw_class().inq_bounds().is_some()
    }

    /// Whether the class can sample its surface (be an area light).
    pub fn samples_surface(&self) -> bool {
        self.inner.live.raw_class().sample_surface().is_some()
    }
}

// ---------------------------------------------------------------- other kinds

macro_rules! handle {
    ($(#[$doc:meta])* $name:ident, $inner:ident, $live:ident, $module:ident) => {
        struct $inner {
            live: $live,
            /// The [`lobe`] kinds a shader reported when it was created (0 for other kinds).
            #[allow(dead_code)]
            lobes: u32,
        }

        impl Drop for $inner {
            fn drop(&mut self) {
                // SAFETY: made by this class's `create`, destroyed once, when
                // the last count goes.
                unsafe { (self.live.raw_class().destroy())(self.live.raw_this()) }
            }
        }

        $(#[$doc])*
        #[derive(Clone)]
        pub struct $name {
            inner: Arc<$inner>,
        }

        impl std::ops::Deref for $name {
            type Target = $live;
            #[inline(always)]
            fn deref(&self) -> &$live {
                &self.inner.live
            }
        }

        impl $name {
            /// Create one from its parameters (JSON text).
            pub fn create(class: $module, params: &str, args: &CreateArgs) -> Result<Self, CallError> {
                let name = class.meta().class_name.as_str();
                let this = created(args, "create", name, |env, sink| {
                    // SAFETY: the text, environment and sink are valid for the call.
                    unsafe { (class.create())(Span::of(params.as_bytes()), env, sink) }
                })?;
                // SAFETY: `this` is the object `class` just made, owned by the
                // handle (destroyed when its last count goes).
                let live = unsafe { $live::new(this, class) };
                Self::own($inner { live, lobes: 0 })
            }
        }
    };
}

handle!(
    /// A created shader, with the lobe kinds it reported once.
    Shader,
    ShaderInner,
    LiveShader,
    ShaderModuleRef
);
handle!(
    /// A created light.
    Light,
    LightInner,
    LiveLight,
    LightModuleRef
);
handle!(
    /// A created camera.
    Camera,
    CameraInner,
    LiveCamera,
    CameraModuleRef
);
handle!(
    /// A created integrator.
    Integrator,
    IntegratorInner,
    LiveIntegrator,
    IntegratorModuleRef
);

impl Shader {
    fn own(mut inner: ShaderInner) -> Result<Self, CallError> {
        inner.lobes = inner.live.lobes()?;
        Ok(Shader {
            inner: Arc::new(inner),
        })
    }

    /// The [`lobe`](rtk_abi::lobe) kinds it reported when created.
    pub fn lobes(&self) -> u32 {
        self.inner.lobes
    }

    /// Radiance emitted towards `wo` (black unless the shader emits).
    #[inline]
    pub fn emitted_if_any(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: Float3) -> Color {
        if self.inner.lobes & lobe::EMISSION == 0 {
            return Color::BLACK;
        }
        self.inner.live.emitted(ctx, geom, wo)
    }

    /// The record an integrator receives for material queries (what the
    /// host's `Services::material` answers).
    pub fn shader_ref(&self) -> ShaderRef {
        ShaderRef {
            this: self.inner.live.raw_this(),
            class: self.inner.live.raw_class(),
            lobes: self.inner.lobes,
        }
    }

    /// The shader with one count on it, for a plugin to own (an area
    /// light's emitter).
    pub fn counted_ref(&self) -> (ShaderRef, KeepAlive) {
        (self.shader_ref(), counted(&self.inner))
    }
}

impl Light {
    fn own(inner: LightInner) -> Result<Self, CallError> {
        Ok(Light {
            inner: Arc::new(inner),
        })
    }

    /// Whether the light surrounds the scene (offers `le`).
    pub fn is_environment(&self) -> bool {
        self.inner.live.raw_class().le().is_some()
    }

    /// Whether the light is an area light (can be bound to an emitting instance).
    pub fn is_area(&self) -> bool {
        self.inner.live.raw_class().bind_emitter().is_some()
    }

    /// Bind the emitting instance this area light stands for: `object` with
    /// `inst`'s bindings, placed by `to_world`, emitting through `shader`.
    /// Only before the light is shared (the handle is still the only one).
    pub fn bind(
        &mut self,
        object: &Object,
        inst: InstanceData,
        to_world: &glam::DAffine3,
        shader: &Shader,
    ) -> Result<(), CallError> {
        let (shader_ref, shader_keep) = shader.counted_ref();
        let emitter = EmitterRef {
            object: object.child_ref(inst),
            to_world: Affine3x4::from_daffine(to_world),
            shader: shader_ref,
            shader_keep,
        };
        let class = self.class_name();
        let Some(inner) = Arc::get_mut(&mut self.inner) else {
            // The counts just taken were to be the plugin's; no call is made,
            // so they are dropped here.
            // SAFETY: each count was taken above and is released once.
            unsafe {
                (emitter.object.keep.release)(emitter.object.keep.owner);
                (emitter.shader_keep.release)(emitter.shader_keep.owner);
            }
            return Err(CallError {
                entry: "bind_emitter",
                class,
                panicked: false,
                key: String::new(),
                message: "the light is already shared: bind it before rendering".into(),
            });
        };
        match inner.live.bind_emitter(emitter) {
            Some(r) => r,
            None => {
                // SAFETY: the light lacks the entry, so nobody took the two counts
                // taken above; each is released once, here.
                unsafe {
                    (emitter.object.keep.release)(emitter.object.keep.owner);
                    (emitter.shader_keep.release)(emitter.shader_keep.owner);
                }
                Err(CallError {
                    entry: "bind_emitter",
                    class,
                    panicked: false,
                    key: String::new(),
                    message: format!("light class `{class}` is not an area light"),
                })
            }
        }
    }
}

impl Camera {
    fn own(inner: CameraInner) -> Result<Self, CallError> {
        Ok(Camera {
            inner: Arc::new(inner),
        })
    }
}

impl Integrator {
    fn own(inner: IntegratorInner) -> Result<Self, CallError> {
        Ok(Integrator {
            inner: Arc::new(inner),
        })
    }

    /// Radiance along `ray`, with `scene` as the integrator's view of the host.
    #[inline]
    pub fn radiance(&self, ctx: &mut TraceCtx, scene: &SceneRecord, ray: &Ray) -> Color {
        self.inner.live.li(ctx, scene.scene(), ray)
    }

    /// Radiance along each of a batch of camera rays, `rngs[i]` being ray
    /// `i`'s random stream (ray streams): the integrator's `li_batch`, or
    /// `li` ray by ray with each stream in the context when its plugin
    /// predates the entry. The answers are the same either way.
    pub fn radiance_batch(
        &self,
        ctx: &mut TraceCtx,
        scene: &SceneRecord,
        rays: &[Ray],
        rngs: &mut [RngState],
        out: &mut [Color],
    ) {
        let live = &self.inner.live;
        if live.raw_class().li_batch().is_some() {
            live.li_batch(ctx, scene.scene(), rays, rngs, out);
            return;
        }
        let saved = ctx.rng;
        for ((ray, rng), o) in rays.iter().zip(rngs.iter_mut()).zip(out.iter_mut()) {
            ctx.rng = *rng;
            *o = live.li(ctx, scene.scene(), ray);
            *rng = ctx.rng;
        }
        ctx.rng = saved;
    }
}

/// Lend a bound record as the [`Scene`] a plugin receives.
pub(crate) fn scene_of(r: &SceneRef) -> &Scene {
    // SAFETY: a bound record's host is alive for its borrow (`SceneRecord`).
    unsafe { Scene::from_record(r) }
}
