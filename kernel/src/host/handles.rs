//! Owned handles to plugin objects: creation, the cold calls, and the hot
//! queries as safe methods. Each destroys its object on `Drop`.

use super::services::{prepare_env, PrepareServices, SceneRecord};
use super::{CallError, Collected};
use crate::abi::*;
use std::ffi::c_void;
use std::sync::Arc;

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
}

impl CreateArgs<'_> {
    /// The record; its pointers are valid while `self` is borrowed.
    fn raw(&self) -> CreateEnv {
        CreateEnv {
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
    call: impl FnOnce(&CreateEnv, ErrSink) -> *mut c_void,
) -> Result<*mut c_void, CallError> {
    let env = args.raw();
    let mut c = Collected::default();
    let this = call(&env, c.sink());
    if this.is_null() {
        // A null object is a refusal even if the plugin forgot to say why.
        return Err(c.result(STATUS_ERROR, entry).unwrap_err());
    }
    Ok(this)
}

// ---------------------------------------------------------------- objects

struct ObjectInner {
    this: *mut c_void,
    class: ObjectModuleRef,
    /// Kept alive while this object points at them; dropped after it.
    children: Vec<Object>,
}

impl Drop for ObjectInner {
    fn drop(&mut self) {
        // SAFETY: `this` was made by this class's `create` and is destroyed
        // once; the children, which it may still reference, are dropped after.
        unsafe { (self.class.destroy())(self.this) }
    }
}

/// A created object before `prepare`: children may still be added. Only its
/// owner can reach it (the paper's open object).
pub struct ObjectBuilder {
    inner: ObjectInner,
}

/// A prepared object: immutable, shared, safe to query from many threads.
#[derive(Clone)]
pub struct Object {
    inner: Arc<ObjectInner>,
}

// SAFETY: a prepared object is immutable and its class is `Send + Sync` by the
// SDK's contract (`Plugin: Send + Sync`); its record is `'static`.
unsafe impl Send for ObjectInner {}
// SAFETY: see above.
unsafe impl Sync for ObjectInner {}

impl ObjectBuilder {
    /// Create an object of `class` from its parameters (JSON text).
    pub fn create(
        class: ObjectModuleRef,
        params: &str,
        args: &CreateArgs,
    ) -> Result<Self, CallError> {
        let this = created(args, "create", |env, sink| {
            // SAFETY: the text, environment and sink are valid for the call.
            unsafe { (class.create())(params.as_ptr(), params.len(), env, sink) }
        })?;
        Ok(Self::own(this, class))
    }

    /// Create an object of `class` from a transform (the class must offer
    /// `from_transform`; see [`crate::classes::INSTANCE_TRANSFORM`]).
    pub fn from_transform(
        class: ObjectModuleRef,
        m: &glam::DAffine3,
        args: &CreateArgs,
    ) -> Result<Self, CallError> {
        let Some(f) = class.from_transform() else {
            return Err(CallError {
                entry: "from_transform",
                panicked: false,
                key: String::new(),
                message: format!(
                    "class `{}` cannot be made from a transform",
                    class.meta().class_name
                ),
            });
        };
        let m = Affine3x4::from_daffine(m);
        // SAFETY: the matrix, environment and sink are valid for the call.
        let this = created(args, "from_transform", |env, sink| unsafe {
            f(&m, env, sink)
        })?;
        Ok(Self::own(this, class))
    }

    fn own(this: *mut c_void, class: ObjectModuleRef) -> Self {
        ObjectBuilder {
            inner: ObjectInner {
                this,
                class,
                children: Vec::new(),
            },
        }
    }

    /// The object's class name.
    pub fn class_name(&self) -> &'static str {
        self.inner.class.meta().class_name.as_str()
    }

    /// The paper's "instance": add a prepared child with its bindings.
    pub fn add_child(&mut self, child: &Object, inst: InstanceData) -> Result<(), CallError> {
        let mut c = Collected::default();
        let r = child.raw();
        // SAFETY: `this` is live and exclusively ours; the child is prepared
        // and kept alive by `children` for as long as this object exists.
        let st = unsafe { (self.inner.class.add_child())(self.inner.this, r, &inst, c.sink()) };
        c.result(st, "add_child")?;
        self.inner.children.push(child.clone());
        Ok(())
    }

    /// The paper's "close": build, and become immutable and shareable.
    pub fn prepare(self, services: &dyn PrepareServices) -> Result<Object, CallError> {
        let mut c = Collected::default();
        let st = prepare_env(services, |env| {
            // SAFETY: `this` is live and exclusively ours; the environment is
            // valid for the call.
            unsafe { (self.inner.class.prepare())(self.inner.this, env, c.sink()) }
        });
        c.result(st, "prepare")?;
        Ok(Object {
            inner: Arc::new(self.inner),
        })
    }
}

/// A copy of an object's triangles: vertex positions and index triples.
pub type OwnedTriangles = (Vec<[f32; 3]>, Vec<[u32; 3]>);

impl Object {
    fn raw(&self) -> ObjectRef {
        ObjectRef {
            this: self.inner.this,
            class: self.inner.class,
        }
    }

    /// The object's class name.
    pub fn class_name(&self) -> &'static str {
        self.inner.class.meta().class_name.as_str()
    }

    /// Box over `[time0, time1]`.
    pub fn bounds(&self, time0: f32, time1: f32) -> Result<Bounds3, CallError> {
        let mut b = Bounds3::EMPTY;
        let mut c = Collected::default();
        // SAFETY: the object is live and prepared; the outputs outlive the call.
        let st =
            unsafe { (self.inner.class.bounds())(self.inner.this, time0, time1, &mut b, c.sink()) };
        c.result(st, "bounds")?;
        Ok(b)
    }

    /// Nearest hit, recorded from level 0.
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit) -> bool {
        // SAFETY: the object is live and prepared; the rest are references.
        unsafe { (self.inner.class.intersect())(self.inner.this, ctx, ray, hit, 0) }
    }

    /// Any hit.
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool {
        // SAFETY: as in `intersect`.
        unsafe { (self.inner.class.occluded())(self.inner.this, ctx, ray, 0) }
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
        // SAFETY: as in `intersect`.
        unsafe { (self.inner.class.local_geom())(self.inner.this, ctx, ray, hit, 0, mask, out) }
    }

    /// A copy of the triangles the object lends as data (positions, index
    /// triples; `None` when its class lends none), checked: every index is
    /// within the positions.
    pub fn triangles(&self) -> Result<Option<OwnedTriangles>, CallError> {
        let Some(f) = self.inner.class.triangles() else {
            return Ok(None);
        };
        let mut d = std::mem::MaybeUninit::<TriangleData>::uninit();
        let mut c = Collected::default();
        // SAFETY: the object is live and prepared; `d` outlives the call.
        let st = unsafe { f(self.inner.this, d.as_mut_ptr(), c.sink()) };
        c.result(st, "triangles")?;
        // SAFETY: the entry succeeded, so it wrote `d`: pointers into the
        // object's immutable data with their counts (the SDK checked the
        // indices), valid while the object lives; copied before returning.
        let (p, t) = unsafe {
            let d = d.assume_init();
            let slice = |ptr: *const [f32; 3], n: u32| {
                if n == 0 || ptr.is_null() {
                    Vec::new()
                } else {
                    std::slice::from_raw_parts(ptr, n as usize).to_vec()
                }
            };
            let tris = if d.triangle_count == 0 || d.indices.is_null() {
                Vec::new()
            } else {
                std::slice::from_raw_parts(d.indices, d.triangle_count as usize).to_vec()
            };
            (slice(d.positions, d.vertex_count), tris)
        };
        if t.iter().flatten().any(|&i| i as usize >= p.len()) {
            return Err(CallError {
                entry: "triangles",
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
        super::volumes::sphere(self.raw(), (time0, time1))
    }

    /// Points whose convex hull contains the object (its box's corners when
    /// it offers none).
    pub fn hull_points(&self, time0: f32, time1: f32) -> Result<Vec<[f32; 3]>, CallError> {
        super::volumes::hull_points(self.raw(), (time0, time1))
    }

    /// Kay–Kajiya slabs containing the object (from its hull points when it
    /// offers none).
    pub fn slabs(&self, time0: f32, time1: f32) -> Result<SlabBounds, CallError> {
        super::volumes::slabs(self.raw(), (time0, time1))
    }

    /// Whether the class answers `inq_bounds` itself.
    pub fn offers_volumes(&self) -> bool {
        self.inner.class.inq_bounds().is_some()
    }

    /// Whether the class can sample its surface (be an area light).
    pub fn samples_surface(&self) -> bool {
        self.inner.class.sample_surface().is_some()
    }

    /// A point uniform by area on the surface, own space (`None` when the
    /// class cannot sample its surface or it has no area).
    #[inline]
    pub fn sample_surface(&self, ctx: &mut TraceCtx, u: &[f32; 2]) -> Option<SurfaceSample> {
        let f = self.inner.class.sample_surface()?;
        let mut s = SurfaceSample::default();
        // SAFETY: as in `intersect`.
        unsafe { f(self.inner.this, ctx, u, &mut s) }.then_some(s)
    }
}

// ---------------------------------------------------------------- other kinds

macro_rules! handle {
    ($(#[$doc:meta])* $name:ident, $module:ident $(, $extra:ident: $ty:ty = $init:expr)?) => {
        $(#[$doc])*
        pub struct $name {
            this: *mut c_void,
            class: $module,
            $($extra: $ty,)?
        }

        // SAFETY: the plugin object is immutable after creation and its class
        // is `Send + Sync` by the SDK's contract; its record is `'static`.
        unsafe impl Send for $name {}
        // SAFETY: see above.
        unsafe impl Sync for $name {}

        impl Drop for $name {
            fn drop(&mut self) {
                // SAFETY: made by this class's `create`, destroyed once.
                unsafe { (self.class.destroy())(self.this) }
            }
        }

        impl $name {
            /// Create one from its parameters (JSON text).
            pub fn create(class: $module, params: &str, args: &CreateArgs) -> Result<Self, CallError> {
                let this = created(args, "create", |env, sink| {
                    // SAFETY: the text, environment and sink are valid for the call.
                    unsafe { (class.create())(params.as_ptr(), params.len(), env, sink) }
                })?;
                #[allow(unused_mut)]
                let mut made = $name { this, class, $($extra: Default::default(),)? };
                $( made.$extra = $init(&made)?; )?
                Ok(made)
            }

            /// The class name.
            pub fn class_name(&self) -> &'static str {
                self.class.meta().class_name.as_str()
            }
        }
    };
}

handle!(
    /// A created shader, with the lobe kinds it reported once.
    Shader,
    ShaderModuleRef,
    lobes: u32 = Shader::ask_lobes
);
handle!(
    /// A created light.
    Light,
    LightModuleRef
);
handle!(
    /// A created camera.
    Camera,
    CameraModuleRef
);
handle!(
    /// A created integrator.
    Integrator,
    IntegratorModuleRef
);

impl Shader {
    /// The [`lobe`](crate::lobe) kinds it reported when created.
    pub fn lobes(&self) -> u32 {
        self.lobes
    }

    /// BSDF value f(wo, wi) (tools such as `rtk conform`; integrators ask
    /// through the scene's `Material`).
    pub fn eval(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: Float3, wi: Float3) -> Color {
        // SAFETY: the shader is live; the rest are references.
        unsafe { (self.class.eval())(self.this, ctx, geom, &wo, &wi) }
    }

    /// Sample `wi` among `lobes`; `None` when there is no such lobe.
    pub fn sample(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: Float3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        let mut s = BsdfSample::default();
        // SAFETY: as in `eval`.
        unsafe { (self.class.sample())(self.this, ctx, geom, &wo, &u, lobes, &mut s) }.then_some(s)
    }

    /// The density `sample` draws `wi` with; `None` when the shader cannot
    /// tell (or predates the entry).
    pub fn pdf(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: Float3,
        wi: Float3,
        lobes: u32,
    ) -> Option<f32> {
        let f = self.class.pdf()?;
        // SAFETY: as in `eval`.
        let p = unsafe { f(self.this, ctx, geom, &wo, &wi, lobes) };
        (p >= 0.0).then_some(p)
    }

    /// Radiance emitted towards `wo` (black unless the shader emits).
    #[inline]
    pub fn emitted(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: Float3) -> Color {
        if self.lobes & lobe::EMISSION == 0 {
            return Color::BLACK;
        }
        match self.class.emitted() {
            // SAFETY: the shader is live; the rest are references.
            Some(f) => unsafe { f(self.this, ctx, geom, &wo) },
            None => Color::BLACK,
        }
    }

    /// The record an integrator receives for material queries.
    pub(crate) fn raw(&self) -> ShaderRef {
        ShaderRef {
            this: self.this,
            class: self.class,
            lobes: self.lobes,
        }
    }

    fn ask_lobes(&self) -> Result<u32, CallError> {
        let (mut lobes, mut c) = (0, Collected::default());
        // SAFETY: the shader is live; the outputs outlive the call.
        let st = unsafe { (self.class.lobes())(self.this, &mut lobes, c.sink()) };
        c.result(st, "lobes")?;
        Ok(lobes)
    }
}

impl Light {
    /// Sample the light from `p`.
    #[inline]
    pub fn sample_li(
        &self,
        ctx: &mut TraceCtx,
        p: &Float3,
        u: &[f32; 2],
        time: f32,
    ) -> Option<LightSample> {
        let mut s = LightSample::default();
        // SAFETY: the light is live; the rest are references.
        unsafe { (self.class.sample_li())(self.this, ctx, p, u, time, &mut s) }.then_some(s)
    }
}

impl Light {
    /// Whether the light surrounds the scene (offers `le`).
    pub fn is_environment(&self) -> bool {
        self.class.le().is_some()
    }

    /// Radiance from direction `dir` on a ray that left the scene (black
    /// for a light that is not an environment).
    #[inline]
    pub fn le(&self, ctx: &mut TraceCtx, dir: &Float3) -> Color {
        match self.class.le() {
            // SAFETY: the light is live; the rest are references.
            Some(f) => unsafe { f(self.this, ctx, dir) },
            None => Color::BLACK,
        }
    }

    /// Density with which `sample_li` from `p` returns `wi` (0 for lights
    /// that do not say: delta lights).
    #[inline]
    pub fn pdf_li(&self, ctx: &mut TraceCtx, p: &Float3, wi: &Float3) -> f32 {
        match self.class.pdf_li() {
            // SAFETY: the light is live; the rest are references.
            Some(f) => unsafe { f(self.this, ctx, p, wi) },
            None => 0.0,
        }
    }
}

impl Camera {
    /// A world-space ray for the sample and its weight (0 if the camera failed:
    /// the failure is in `ctx`).
    #[inline]
    pub fn generate_ray(&self, ctx: &mut TraceCtx, sample: &CameraSample) -> (Ray, f32) {
        let mut ray = Ray::new(glam::Vec3::ZERO, glam::Vec3::Z);
        // SAFETY: the camera is live; the rest are references.
        let w = unsafe { (self.class.generate_ray())(self.this, ctx, sample, &mut ray) };
        (ray, w)
    }
}

impl Integrator {
    /// Radiance along `ray`, with `scene` as the integrator's view of the host.
    #[inline]
    pub fn li(&self, ctx: &mut TraceCtx, scene: &SceneRecord, ray: &Ray) -> Color {
        // SAFETY: the integrator is live; the scene record is live for the call.
        unsafe { (self.class.li())(self.this, ctx, scene.raw(), ray) }
    }
}
