//! The safe plugin SDK: a trait per plugin kind and one export macro per kind.
//!
//! A plugin crate implements [`Object`], [`Shader`], [`Integrator`],
//! [`Camera`] or [`Light`] and calls the matching `export_*!` macro. The
//! macro emits the plain [`PluginHeader`](crate::abi::PluginHeader) the host
//! reads before running any plugin code, and the abi_stable root module whose
//! layout the host checks. Every entry point runs under `catch_unwind`: a
//! panic in a cold-path call becomes an error naming the plugin, and a panic
//! on the hot path marks the render as failed in the [`TraceCtx`] (it never
//! unwinds across `extern "C"`, which would abort the process).
//!
//! Plugin crates contain no `unsafe`: the raw-pointer glue lives here.

pub mod shading;
mod shims;

use crate::abi::*;
use serde::de::DeserializeOwned;
use std::ffi::c_void;
use std::path::PathBuf;

pub use shims::{
    camera_module, integrator_module, lib_header, light_module, object_module, shader_module,
    CameraSource, Decl, IntegratorSource, LightSource, ModuleSource, ObjectSource, ShaderSource,
};

/// An error from a plugin's cold-path call: the parameter key path it concerns
/// (if any; the shell maps it back to the TOML file, line and column) and a message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PluginError {
    /// Parameter key path such as `radius` or `center[1]`, or empty.
    pub key: String,
    /// What went wrong.
    pub message: String,
}

impl PluginError {
    /// An error about the object as a whole.
    pub fn msg(message: impl Into<String>) -> Self {
        Self {
            key: String::new(),
            message: message.into(),
        }
    }
    /// An error about one parameter.
    pub fn key(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for PluginError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.key, self.message)
        }
    }
}

impl std::error::Error for PluginError {}

/// Parse a plugin's parameters from the JSON text the shell passes, with the
/// key path of the first error (unknown keys included).
pub fn parse_params<P: DeserializeOwned>(json: &str) -> Result<P, PluginError> {
    let de = &mut serde_json::Deserializer::from_str(json);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner().to_string();
        // serde_json appends " at line L column C" of the JSON text: useless to
        // the user, whose file is TOML; the shell adds the TOML location.
        let message = match inner.rfind(" at line ") {
            Some(i) => inner[..i].to_string(),
            None => inner,
        };
        let mut key = if path == "." { String::new() } else { path };
        // An unknown key fails before it becomes part of the path: name it.
        if let Some(rest) = message.strip_prefix("unknown field `") {
            if let Some(end) = rest.find('`') {
                let field = &rest[..end];
                let last = key.rsplit(['.', ']']).next().unwrap_or("");
                if last != field {
                    if !key.is_empty() {
                        key.push('.');
                    }
                    key.push_str(field);
                }
            }
        }
        PluginError { key, message }
    })
}

/// Reject a non-finite or out-of-range number with the key it came from.
/// Coordinates beyond 1e12 break f32 intersection (numerics.md T4).
pub fn check_finite(key: &str, values: &[f32]) -> Result<(), PluginError> {
    for v in values {
        if !v.is_finite() {
            return Err(PluginError::key(key, "must be a finite number"));
        }
        if v.abs() > 1e12 {
            return Err(PluginError::key(
                key,
                format!("{v} is beyond what f32 intersection handles (|x| <= 1e12)"),
            ));
        }
    }
    Ok(())
}

/// What `create` knows besides its parameters.
#[derive(Debug, Clone, Copy)]
pub struct Env<'a> {
    /// Folder of the scene file.
    pub scene_dir: &'a str,
    /// Name of the definition being created.
    pub name: &'a str,
    /// Image width in pixels.
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
}

impl Env<'_> {
    /// Resolve a file parameter against the scene's folder.
    pub fn resolve(&self, file: &str) -> PathBuf {
        let p = PathBuf::from(file);
        if p.is_absolute() {
            p
        } else {
            PathBuf::from(self.scene_dir).join(p)
        }
    }
}

/// What `prepare` receives: the thread budget and the host's pool.
pub struct Prepare<'a> {
    env: &'a PrepareEnv,
}

impl Prepare<'_> {
    /// Upper bound of `TraceCtx::thread_index` during queries: size
    /// per-thread state (mailboxes) with it.
    pub fn max_threads(&self) -> u32 {
        self.env.max_threads
    }

    /// Read a whole file, telling the host (its `--stats` count the files read).
    pub fn read_file(&self, path: &std::path::Path) -> std::io::Result<Vec<u8>> {
        let s = path.to_string_lossy();
        (self.env.note_file)(self.env.host, s.as_ptr(), s.len());
        std::fs::read(path)
    }

    /// Run `f(i)` for `i < n` on the host's thread pool (plugins must not start
    /// pools of their own). A panic in `f` is re-raised here after all tasks end.
    pub fn parallel_for<F: Fn(u64) + Sync>(&self, n: u64, f: F) {
        shims::parallel_for(self.env, n, f)
    }
}

/// A child added to an aggregate: the object and its instance bindings.
/// Queries go straight through the child's function table; `local_geom`
/// applies the instance's shader and emitter when no deeper level bound one
/// (the innermost binding wins).
#[derive(Clone, Copy, Debug)]
pub struct Child {
    obj: ObjectRef,
    inst: InstanceData,
}

impl Child {
    /// Wrap a reference (the SDK's shims do this; the host makes the references).
    pub fn new(obj: ObjectRef, inst: InstanceData) -> Self {
        Self { obj, inst }
    }
    /// The instance's bindings.
    pub fn instance(&self) -> &InstanceData {
        &self.inst
    }
    /// The raw reference.
    pub fn object_ref(&self) -> ObjectRef {
        self.obj
    }
    /// Nearest hit in `(ray.t_min, ray.t_max)`.
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        (self.obj.fns.intersect)(self.obj.this, ctx, ray, hit, level)
    }
    /// Any hit in `(ray.t_min, ray.t_max)`.
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        (self.obj.fns.occluded)(self.obj.this, ctx, ray, level)
    }
    /// Local geometry, with this instance's bindings applied if none deeper.
    #[inline]
    pub fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        (self.obj.fns.local_geom)(self.obj.this, ctx, ray, hit, level, mask, out);
        if out.shader == NONE_ID {
            out.shader = self.inst.shader;
        }
        if out.emitter == NONE_ID {
            out.emitter = self.inst.emitter;
        }
    }
    /// Box over `[time0, time1]`.
    pub fn bounds(&self, time0: f32, time1: f32) -> Bounds3 {
        let mut b = Bounds3::EMPTY;
        (self.obj.fns.bounds)(self.obj.this, time0, time1, &mut b);
        b
    }
    /// Inside test (CSG), when the child offers one.
    pub fn in_interior(&self, ctx: &mut TraceCtx, p: Float3, time: f32) -> Option<bool> {
        self.obj
            .fns
            .in_interior
            .map(|f| f(self.obj.this, ctx, &p, time))
    }
    /// The child's primitive set, when it exposes the whole protocol.
    pub fn prim_set(&self) -> Option<PrimSet> {
        let f = self.obj.fns;
        Some(PrimSet {
            this: self.obj.this,
            count: f.prim_count?,
            bounds: f.prim_bounds?,
            intersect: f.intersect_prims?,
            occluded: f.occluded_prims?,
        })
    }
}

/// A child's primitive-set protocol: batched queries over its primitives,
/// in the child's own space. One call per leaf, never one per primitive.
#[derive(Clone, Copy, Debug)]
pub struct PrimSet {
    this: *const c_void,
    count: extern "C" fn(*const c_void) -> u32,
    bounds: extern "C" fn(*const c_void, u32, u32, *mut Bounds3),
    intersect: extern "C" fn(
        *const c_void,
        *mut TraceCtx,
        *const Ray,
        *const u32,
        u32,
        *mut Hit,
        u32,
    ) -> bool,
    occluded: extern "C" fn(*const c_void, *mut TraceCtx, *const Ray, *const u32, u32, u32) -> bool,
}

// SAFETY: a PrimSet points at an object that is immutable after `prepare` and
// whose class is `Sync` (the SDK's traits require it).
unsafe impl Send for PrimSet {}
// SAFETY: see above.
unsafe impl Sync for PrimSet {}

impl PrimSet {
    /// Number of primitives.
    pub fn count(&self) -> u32 {
        (self.count)(self.this)
    }
    /// Boxes of primitives `first..first + out.len()`.
    pub fn bounds(&self, first: u32, out: &mut [Bounds3]) {
        (self.bounds)(self.this, first, out.len() as u32, out.as_mut_ptr())
    }
    /// Nearest hit among `ids`; writes `hit.stack[level]` as the child's `intersect` would.
    #[inline]
    pub fn intersect(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        ids: &[u32],
        hit: &mut Hit,
        level: u32,
    ) -> bool {
        (self.intersect)(
            self.this,
            ctx,
            ray,
            ids.as_ptr(),
            ids.len() as u32,
            hit,
            level,
        )
    }
    /// Any hit among `ids`.
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], level: u32) -> bool {
        (self.occluded)(self.this, ctx, ray, ids.as_ptr(), ids.len() as u32, level)
    }
}

/// The host's services, as integrators and shaders see them.
#[derive(Clone, Copy)]
pub struct Scene<'a> {
    api: &'a SceneApi,
}

impl<'a> Scene<'a> {
    /// Wrap the host's record.
    pub fn new(api: &'a SceneApi) -> Self {
        Self { api }
    }
    /// The raw record (to pass on to a shader).
    pub fn api(&self) -> &'a SceneApi {
        self.api
    }
    /// The integrator's recursion limit.
    pub fn max_depth(&self) -> u32 {
        self.api.max_depth
    }
    /// `Trace(ray) -> color` through the scene's integrator.
    #[inline]
    pub fn trace(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32) -> Color {
        (self.api.trace)(self.api.host, ctx, ray, kind)
    }
    /// Nearest hit of the root.
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32, hit: &mut Hit) -> bool {
        (self.api.intersect)(self.api.host, ctx, ray, kind, hit)
    }
    /// Any hit (shadow rays).
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool {
        (self.api.occluded)(self.api.host, ctx, ray)
    }
    /// Local geometry of a root hit, fields per `mask` ([`geom_mask`]).
    #[inline]
    pub fn local_geom(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &Hit, mask: u32) -> LocalGeom {
        let mut g = LocalGeom::EMPTY;
        (self.api.local_geom)(self.api.host, ctx, ray, hit, mask, &mut g);
        g
    }
    /// Whitted-style shading by the bound shader.
    #[inline]
    pub fn shade(&self, ctx: &mut TraceCtx, ray: &Ray, geom: &LocalGeom) -> Color {
        (self.api.shade)(self.api.host, ctx, ray, geom)
    }
    /// Radiance of a ray leaving the scene.
    #[inline]
    pub fn background(&self, ray: &Ray) -> Color {
        (self.api.background)(self.api.host, ray)
    }
    /// Number of lights.
    #[inline]
    pub fn light_count(&self) -> u32 {
        (self.api.light_count)(self.api.host)
    }
    /// Sample light `index` from `p`.
    #[inline]
    pub fn sample_light(
        &self,
        ctx: &mut TraceCtx,
        index: u32,
        p: glam::Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample> {
        let mut s = LightSample::default();
        let p: Float3 = p.into();
        (self.api.sample_light)(self.api.host, ctx, index, &p, &u, time, &mut s).then_some(s)
    }
    /// BSDF value of the bound material.
    #[inline]
    pub fn bsdf_eval(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        wi: glam::Vec3,
    ) -> Color {
        (self.api.bsdf_eval)(self.api.host, ctx, geom, &wo.into(), &wi.into())
    }
    /// Sample the bound material.
    #[inline]
    pub fn bsdf_sample(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        u: [f32; 2],
    ) -> Option<BsdfSample> {
        let mut s = BsdfSample::default();
        (self.api.bsdf_sample)(self.api.host, ctx, geom, &wo.into(), &u, &mut s).then_some(s)
    }
    /// Density of the bound material's sampling.
    #[inline]
    pub fn bsdf_pdf(&self, geom: &LocalGeom, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        (self.api.bsdf_pdf)(self.api.host, geom, &wo.into(), &wi.into())
    }
    /// Emitted radiance of the bound material.
    #[inline]
    pub fn emitted(&self, geom: &LocalGeom, wo: glam::Vec3) -> Color {
        (self.api.emitted)(self.api.host, geom, &wo.into())
    }
}

/// An object class: primitive, aggregate, transform or CSG operator.
///
/// After [`prepare`](Object::prepare) the object is immutable and every query
/// may be called from many threads at once (hence `Send + Sync`). Optional
/// entries are switched on by the `HAS_*` constants.
pub trait Object: Send + Sync + Sized + 'static {
    /// Parameters, parsed from the scene with unknown keys refused
    /// (`#[serde(deny_unknown_fields)]`).
    type Params: DeserializeOwned;

    /// Create from parameters. Bulk data is read in `prepare`, not here.
    fn create(params: Self::Params, env: &Env) -> Result<Self, PluginError>;

    /// Add a child (aggregates and operators). The default refuses children.
    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        let _ = child;
        Err(PluginError::key("children", "this class takes no children"))
    }

    /// Build after every child was added (read files, build structures).
    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        let _ = env;
        Ok(())
    }

    /// Box over `[time0, time1]`, in the object's own space.
    fn bounds(&self, time0: f32, time1: f32) -> Bounds3;

    /// Nearest hit in `(ray.t_min, ray.t_max)`: on success write `hit.t` and
    /// `hit.stack[level..]`, set `hit.depth`, and return true.
    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool;

    /// Any hit in `(ray.t_min, ray.t_max)`.
    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool;

    /// Local geometry of the hit in `hit.stack[level..]`; fill the fields
    /// `mask` asks for (and say so in `out.filled`).
    fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    );

    /// Offer [`bounding_sphere`](Object::bounding_sphere).
    const HAS_BOUNDING_SPHERE: bool = false;
    /// A bounding sphere over `[time0, time1]`.
    fn bounding_sphere(&self, time0: f32, time1: f32) -> BoundingSphere {
        let _ = (time0, time1);
        BoundingSphere::default()
    }

    /// Offer [`in_interior`](Object::in_interior) (solids, for CSG).
    const HAS_INTERIOR: bool = false;
    /// Is `p` inside the solid at `time`.
    fn in_interior(&self, ctx: &mut TraceCtx, p: Float3, time: f32) -> bool {
        let _ = (ctx, p, time);
        false
    }

    /// Offer [`sample_surface`](Object::sample_surface) and [`area`](Object::area) (area lights).
    const HAS_SURFACE_SAMPLING: bool = false;
    /// Sample a point uniformly by area.
    fn sample_surface(&self, ctx: &mut TraceCtx, u: [f32; 3], time: f32) -> Option<SurfaceSample> {
        let _ = (ctx, u, time);
        None
    }
    /// Surface area.
    fn area(&self, time: f32) -> f32 {
        let _ = time;
        0.0
    }

    /// Offer the primitive-set protocol.
    const HAS_PRIM_SET: bool = false;
    /// Number of primitives.
    fn prim_count(&self) -> u32 {
        0
    }
    /// Boxes of primitives `first..first + out.len()`.
    fn prim_bounds(&self, first: u32, out: &mut [Bounds3]) {
        let _ = (first, out);
    }
    /// Nearest hit among `ids`.
    fn intersect_prims(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        ids: &[u32],
        hit: &mut Hit,
        level: u32,
    ) -> bool {
        let _ = (ctx, ray, ids, hit, level);
        false
    }
    /// Any hit among `ids`.
    fn occluded_prims(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], level: u32) -> bool {
        let _ = (ctx, ray, ids, level);
        false
    }
}

/// A shader: material queries, and optionally Whitted-style `shade`.
pub trait Shader: Send + Sync + Sized + 'static {
    /// Parameters.
    type Params: DeserializeOwned;
    /// Create from parameters.
    fn create(params: Self::Params, env: &Env) -> Result<Self, PluginError>;
    /// BSDF value (no cosine).
    fn eval(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: glam::Vec3, wi: glam::Vec3) -> Color {
        let _ = (ctx, geom, wo, wi);
        Color::BLACK
    }
    /// Sample an incident direction.
    fn sample(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        u: [f32; 2],
    ) -> Option<BsdfSample> {
        let _ = (ctx, geom, wo, u);
        None
    }
    /// Density of `sample`.
    fn pdf(&self, geom: &LocalGeom, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        let _ = (geom, wo, wi);
        0.0
    }
    /// Offer [`emitted`](Shader::emitted).
    const EMITS: bool = false;
    /// Emitted radiance towards `wo`.
    fn emitted(&self, geom: &LocalGeom, wo: glam::Vec3) -> Color {
        let _ = (geom, wo);
        Color::BLACK
    }
    /// Offer [`shade`](Shader::shade).
    const SHADES: bool = false;
    /// Whitted-style shading: direct light, reflection and refraction through `scene`.
    fn shade(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray, geom: &LocalGeom) -> Color {
        let _ = (ctx, scene, ray, geom);
        Color::BLACK
    }
}

/// An integrator: the radiance along each camera ray.
pub trait Integrator: Send + Sync + Sized + 'static {
    /// Parameters.
    type Params: DeserializeOwned;
    /// Create from parameters.
    fn create(params: Self::Params, env: &Env) -> Result<Self, PluginError>;
    /// Recursion limit.
    fn max_depth(&self) -> u32;
    /// Radiance along `ray`.
    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray) -> Color;
}

/// A camera.
pub trait Camera: Send + Sync + Sized + 'static {
    /// Parameters.
    type Params: DeserializeOwned;
    /// Create from parameters (the image size is in `env`).
    fn create(params: Self::Params, env: &Env) -> Result<Self, PluginError>;
    /// A world-space ray (unit direction) and its weight.
    fn generate_ray(&self, sample: &CameraSample) -> (Ray, f32);
}

/// A light.
pub trait Light: Send + Sync + Sized + 'static {
    /// Parameters.
    type Params: DeserializeOwned;
    /// Create from parameters.
    fn create(params: Self::Params, env: &Env) -> Result<Self, PluginError>;
    /// [`light_flags`].
    fn flags(&self) -> u32;
    /// Learn the world bounds before rendering.
    fn preprocess(&mut self, world: &Bounds3) {
        let _ = world;
    }
    /// Sample incident light at `p`.
    fn sample_li(
        &self,
        ctx: &mut TraceCtx,
        p: glam::Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample>;
    /// Offer [`le`](Light::le) (environment lights).
    const HAS_LE: bool = false;
    /// Radiance of an escaping ray.
    fn le(&self, ray: &Ray) -> Color {
        let _ = ray;
        Color::BLACK
    }
}

/// Export an object class. `export_object!(MyType, class = "name", doc = include_str!("../README.md"));`
#[macro_export]
macro_rules! export_object {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(Object, ObjectSource, $ty, $class, $doc);
    };
}

/// Export a shader. Same form as [`export_object!`].
#[macro_export]
macro_rules! export_shader {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(Shader, ShaderSource, $ty, $class, $doc);
    };
}

/// Export an integrator. Same form as [`export_object!`].
#[macro_export]
macro_rules! export_integrator {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(Integrator, IntegratorSource, $ty, $class, $doc);
    };
}

/// Export a camera. Same form as [`export_object!`].
#[macro_export]
macro_rules! export_camera {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(Camera, CameraSource, $ty, $class, $doc);
    };
}

/// Export a light. Same form as [`export_object!`].
#[macro_export]
macro_rules! export_light {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(Light, LightSource, $ty, $class, $doc);
    };
}

/// The shared expansion of the `export_*!` macros: the plain header read
/// before any plugin code runs, and abi_stable's root-module loader under its
/// mangled name (what `#[export_root_module]` would emit, spelled with `$crate`
/// paths so plugins need no direct abi_stable dependency).
#[doc(hidden)]
#[macro_export]
macro_rules! __export_plugin {
    ($kind:ident, $source:ident, $ty:ty, $class:literal, $doc:expr) => {
        #[doc(hidden)]
        pub struct __RtkDecl;
        impl $crate::sdk::Decl for __RtkDecl {
            const CLASS: &'static str = $class;
            const DOC: &'static str = $doc;
            const VERSION: &'static str = env!("CARGO_PKG_VERSION");
        }

        /// The header the host reads before running any code of this plugin.
        #[no_mangle]
        pub static RTK_PLUGIN_HEADER: $crate::abi::PluginHeader = $crate::abi::PluginHeader::new(
            $crate::abi::PluginKind::$kind,
            $class,
            cfg!(panic = "unwind"),
        );

        /// abi_stable's root-module loader.
        #[export_name = "_1as_0lib_1header_0root_bmodule_bloader"]
        pub static __RTK_ROOT_MODULE_LOADER: $crate::reexports::LibHeader =
            $crate::sdk::lib_header::<$crate::sdk::$source<$ty, __RtkDecl>>();
    };
}
