//! The function-pointer records: the root module of each plugin kind, the
//! environments of the cold calls, and the scene services the host offers.
//!
//! Conventions shared by every record:
//! - every entry is an `unsafe extern "C" fn` taking the object's opaque
//!   `this` first; the caller promises that every pointer is valid for the
//!   call (and `this` for the object's life). Only the kernel's safe layers
//!   ([`crate::sdk`], [`crate::host`]) call them;
//! - an optional entry is an `Option` of a function pointer (null: not offered);
//! - **cold** entries (create, add_child, prepare, bounds, primitive counts)
//!   return a status ([`STATUS_OK`] or negative) and write their message into
//!   an [`ErrSink`] the caller owns;
//! - **hot** entries (queries, shading, sampling) never allocate and return no
//!   status: a failure is recorded in the [`TraceCtx`] with the plugin's name.
//!
//! `create` and `destroy` have the same signature in every module, yet are
//! spelled out in each: abi_stable's derive reads a function pointer's
//! layout from the field's own type (an alias does not implement `StableAbi`).

use super::*;
use abi_stable::std_types::RStr;
use abi_stable::StableAbi;
use std::ffi::c_void;

/// Status of a successful cold call.
pub const STATUS_OK: i32 = 0;
/// Status of a cold call that failed with a message in the error sink.
pub const STATUS_ERROR: i32 = -1;
/// Status of a cold call whose plugin code panicked (message in the sink).
pub const STATUS_PANIC: i32 = -2;

/// Where a cold call writes its error: the status it fails with, a key path
/// (the parameter concerned, or empty) and a message, as UTF-8 byte ranges
/// the host copies. (`create` returns a pointer, so the status travels here.)
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ErrSink {
    /// The host's collector.
    pub ctx: *mut c_void,
    /// Record the error.
    pub report: unsafe extern "C" fn(
        ctx: *mut c_void,
        status: i32,
        key: *const u8,
        key_len: usize,
        msg: *const u8,
        msg_len: usize,
    ),
}

/// What `create` knows besides its parameters.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct CreateEnv {
    /// Folder of the scene file (relative file parameters resolve against it), UTF-8.
    pub scene_dir: *const u8,
    /// Length of `scene_dir`.
    pub scene_dir_len: usize,
    /// Path of the definition being created (`objects.ball`), UTF-8.
    pub name: *const u8,
    /// Length of `name`.
    pub name_len: usize,
    /// Image width in pixels (cameras need the aspect ratio).
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
    /// The world point the renderer computes about (camera-relative
    /// rendering, docs/numerics.md X3): a plugin subtracts it, in f64, from
    /// every world position it reads (parameters, files) before rounding to
    /// f32. Zero for definitions placed by an instance transform, which
    /// absorbs it instead.
    pub origin: [f64; 3],
}

/// A task body for the host's `parallel_for`.
#[repr(transparent)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ParallelBody {
    /// Run task `i` with the caller's context `user`.
    pub func: unsafe extern "C" fn(user: *const c_void, i: u64),
}

/// What `prepare` receives: the thread budget and the host's pool. Plugins
/// must not start thread pools of their own (each cdylib would get its own
/// rayon pool and ignore `--threads`).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct PrepareEnv {
    /// Upper bound of [`TraceCtx::thread_index`] during queries.
    pub max_threads: u32,
    /// The host's context for the entries below.
    pub host: *const c_void,
    /// Run `body(user, i)` for every `i < n` on the host's pool; returns when all are done.
    pub parallel_for:
        unsafe extern "C" fn(host: *const c_void, n: u64, body: ParallelBody, user: *const c_void),
    /// Tell the host a file was read (UTF-8 path), for `--stats`.
    pub note_file: unsafe extern "C" fn(host: *const c_void, path: *const u8, len: usize),
}

/// A reference to a created object: its data and its class's record. Valid
/// until the scene is dropped; after `prepare` the object is immutable.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct ObjectRef {
    /// The object's data.
    pub this: *const c_void,
    /// Its class's record.
    pub class: ObjectModuleRef,
}

/// Metadata common to every plugin module.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ModuleMeta {
    /// The class name the scene uses.
    pub class_name: RStr<'static>,
    /// The plugin's documentation (parameter table and a TOML example).
    pub doc: RStr<'static>,
    /// Version of the plugin crate.
    pub plugin_version: RStr<'static>,
}

// --------------------------------------------------------------------------
// Object classes
// --------------------------------------------------------------------------

/// The root module of an object-class plugin: primitives, aggregates,
/// transforms (and, as they land, CSG operators). Aggregates and primitives
/// have the same record, so any aggregate nests inside any other.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = ObjectModuleRef)))]
pub struct ObjectModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// The paper's "create": from parameters (JSON text); null on error.
    pub create: unsafe extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy an object made by `create` (or `from_transform`).
    pub destroy: unsafe extern "C" fn(this: *mut c_void),
    /// The paper's "instance": add a child with its instance data. The child
    /// outlives the parent (the host drops parents first).
    pub add_child: unsafe extern "C" fn(
        this: *mut c_void,
        child: ObjectRef,
        inst: *const InstanceData,
        sink: ErrSink,
    ) -> i32,
    /// The paper's "close": build after all children were added. After this the
    /// object is immutable and every query must be safe to call concurrently.
    pub prepare:
        unsafe extern "C" fn(this: *mut c_void, env: *const PrepareEnv, sink: ErrSink) -> i32,
    /// Axis-aligned box over the time interval `[time0, time1]`, in the
    /// object's own space; valid after `prepare`.
    pub bounds: unsafe extern "C" fn(
        this: *const c_void,
        time0: f32,
        time1: f32,
        out: *mut Bounds3,
        sink: ErrSink,
    ) -> i32,
    /// Nearest hit in `(ray.t_min, ray.t_max)`; on success writes `hit.t`,
    /// `hit.stack[level..]` and `hit.depth` and returns true.
    pub intersect: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        hit: *mut Hit,
        level: u32,
    ) -> bool,
    /// Any hit in `(ray.t_min, ray.t_max)` (shadow rays): no nearest search, no hit record.
    pub occluded: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        level: u32,
    ) -> bool,
    /// Local geometry of the hit recorded in `hit.stack[level..]`, fields per
    /// `mask` (computed only for the hit that is shaded).
    pub local_geom: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        hit: *const Hit,
        level: u32,
        mask: u32,
        out: *mut LocalGeom,
    ),
    /// Create from a transform the shell composed (the class the shell wraps
    /// transformed instances in offers it): typed data, not parameter text.
    pub from_transform: Option<
        unsafe extern "C" fn(
            m: *const Affine3x4,
            env: *const CreateEnv,
            sink: ErrSink,
        ) -> *mut c_void,
    >,
    /// Primitive-set protocol: number of primitives.
    pub prim_count:
        Option<unsafe extern "C" fn(this: *const c_void, out: *mut u32, sink: ErrSink) -> i32>,
    /// Primitive-set protocol: boxes of primitives `first..first+n`, own space.
    pub prim_bounds: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            first: u32,
            n: u32,
            out: *mut Bounds3,
            sink: ErrSink,
        ) -> i32,
    >,
    /// Primitive-set protocol: nearest hit among the listed primitives; writes
    /// `hit.stack[level]` as `intersect` would (one batched call per leaf).
    pub intersect_prims: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            ray: *const Ray,
            ids: *const u32,
            n: u32,
            hit: *mut Hit,
            level: u32,
        ) -> bool,
    >,
    /// Primitive-set protocol: any hit among the listed primitives.
    #[sabi(last_prefix_field)]
    pub occluded_prims: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            ray: *const Ray,
            ids: *const u32,
            n: u32,
            level: u32,
        ) -> bool,
    >,
    // ---- Appended after the ABI 2 prefix: absent (read as None / false)
    // ---- in plugins built before they existed.
    /// Triangles as data: lend the object's vertex positions and index
    /// triples ([`TriangleData`]), so an aggregate intersects them inline with
    /// the kernel's watertight routine in its own layout (issue 7).
    #[sabi(missing_field(default))]
    pub triangles: Option<
        unsafe extern "C" fn(this: *const c_void, out: *mut TriangleData, sink: ErrSink) -> i32,
    >,
    /// The class builds its own structure over its children's primitives
    /// (`bvh`, `grid`...): the shell then adds a primitive set to it as is,
    /// rather than wrapped in the set's own acceleration structure.
    #[sabi(missing_field(default))]
    pub flattens_primitives: bool,
    /// Area lights: a point uniformly distributed by area over the object's
    /// surface, own space ([`SurfaceSample`]); false when it has no area.
    /// Any object that offers it can be bound to an emitting shader, under
    /// any transform (issue 9).
    #[sabi(missing_field(default))]
    pub sample_surface: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            u: *const [f32; 2],
            out: *mut SurfaceSample,
        ) -> bool,
    >,
    /// The paper's `inq_bounds` for the volume types beyond the box
    /// ([`bound_kind`]: sphere, hull points, slabs) over `[time0, time1]`, own
    /// space; the object sets `out.written` for a kind it offers (issue 12).
    /// Absent, or not written: the caller derives the volume from the box.
    #[sabi(missing_field(default))]
    pub inq_bounds: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            kind: u32,
            time0: f32,
            time1: f32,
            out: *mut BoundingVolume,
            sink: ErrSink,
        ) -> i32,
    >,
}

/// A triangle mesh's data, lent by the object that owns it through the
/// `triangles` entry: valid and unchanged for the object's lifetime.
///
/// Triangle `i` (the primitive id) has the vertices
/// `positions[indices[i][k]]`. An aggregate that intersects them itself
/// writes, for a hit on triangle `i` of the child at its slot `c`:
/// `stack[level] = { index: c }` and `stack[level + 1] = { prim: i, uv: [b1, b2] }`
/// (the barycentric weights of vertices 1 and 2), with `depth = level + 2`,
/// exactly what the child's own `intersect` would record, so the child's
/// `local_geom` at `level + 1` serves the hit.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct TriangleData {
    /// Vertex positions.
    pub positions: *const [f32; 3],
    /// Number of positions.
    pub vertex_count: u32,
    /// Vertex indices of each triangle.
    pub indices: *const [u32; 3],
    /// Number of triangles (the primitive count).
    pub triangle_count: u32,
}

// --------------------------------------------------------------------------
// Shaders, integrators, cameras, lights
// --------------------------------------------------------------------------

/// A shader bound at a hit, as the host hands it to an integrator: the
/// integrator then asks it material queries directly, with no host hop.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct ShaderRef {
    /// The shader's data.
    pub this: *const c_void,
    /// Its class's record.
    pub class: ShaderModuleRef,
    /// The [`lobe`] kinds it has (asked once, when it was created), so an
    /// integrator skips queries for lobes a material lacks.
    pub lobes: u32,
}

/// The root module of a shader plugin. Shaders answer material queries;
/// a shader may also override shading as a whole (`shade`), as the paper's
/// shaders do.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = ShaderModuleRef)))]
pub struct ShaderModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: unsafe extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy an object made by `create`.
    pub destroy: unsafe extern "C" fn(this: *mut c_void),
    /// The [`lobe`] kinds this shader has (called once, after `create`).
    pub lobes: unsafe extern "C" fn(this: *const c_void, out: *mut u32, sink: ErrSink) -> i32,
    /// BSDF value f(wo, wi), cosine not included; both directions unit, pointing away.
    pub eval: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        geom: *const LocalGeom,
        wo: *const Float3,
        wi: *const Float3,
    ) -> Color,
    /// Sample `wi` from the lobes that `lobes` (a [`lobe`] mask) allows; false
    /// when no such lobe exists or the sample has no contribution.
    pub sample: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        geom: *const LocalGeom,
        wo: *const Float3,
        u: *const [f32; 2],
        lobes: u32,
        out: *mut BsdfSample,
    ) -> bool,
    /// Shading as a whole, overriding the integrator's use of the material
    /// queries (optional).
    #[sabi(last_prefix_field)]
    pub shade: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            scene: *const SceneRef,
            ray: *const Ray,
            geom: *const LocalGeom,
        ) -> Color,
    >,
    // ---- Appended after the ABI 2 prefix (issue 9): absent (None) in
    // ---- shaders built before them, which then neither emit nor report a
    // ---- density (an integrator must then not weight their samples by MIS).
    /// Density (solid angle) with which `sample`, restricted to `lobes`,
    /// returns `wi`; 0 for delta lobes.
    #[sabi(missing_field(default))]
    pub pdf: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            geom: *const LocalGeom,
            wo: *const Float3,
            wi: *const Float3,
            lobes: u32,
        ) -> f32,
    >,
    /// Radiance the surface emits towards `wo` (unit, pointing away); only a
    /// shader whose `lobes` has [`lobe::EMISSION`]
    /// is asked.
    #[sabi(missing_field(default))]
    pub emitted: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            geom: *const LocalGeom,
            wo: *const Float3,
        ) -> Color,
    >,
}

/// The root module of an integrator plugin: the radiance of each camera ray.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = IntegratorModuleRef)))]
pub struct IntegratorModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: unsafe extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy an object made by `create`.
    pub destroy: unsafe extern "C" fn(this: *mut c_void),
    /// Radiance arriving along `-ray.dir` at `ray.origin`.
    #[sabi(last_prefix_field)]
    pub li: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        scene: *const SceneRef,
        ray: *const Ray,
    ) -> Color,
}

/// The root module of a camera plugin. Ray generation takes a film position,
/// a lens sample and a time sample, so depth of field and motion blur need no
/// change to the record.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = CameraModuleRef)))]
pub struct CameraModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: unsafe extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy an object made by `create`.
    pub destroy: unsafe extern "C" fn(this: *mut c_void),
    /// Write a world-space ray (unit direction) and return the sample's weight.
    #[sabi(last_prefix_field)]
    pub generate_ray: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        sample: *const CameraSample,
        out: *mut Ray,
    ) -> f32,
}

/// The root module of a light plugin.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = LightModuleRef)))]
pub struct LightModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: unsafe extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy an object made by `create`.
    pub destroy: unsafe extern "C" fn(this: *mut c_void),
    /// Sample the light seen from `p` at `time`; false when it contributes nothing.
    #[sabi(last_prefix_field)]
    pub sample_li: unsafe extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        p: *const Float3,
        u: *const [f32; 2],
        time: f32,
        out: *mut LightSample,
    ) -> bool,
    // ---- Appended after the ABI 2 prefix (issue 9): absent (None) in
    // ---- lights built before them.
    /// Radiance arriving from direction `dir` (unit, towards the light) on
    /// a ray that leaves the scene: environment lights answer, lights at a
    /// point or a single direction have none to find.
    #[sabi(missing_field(default))]
    pub le: Option<
        unsafe extern "C" fn(this: *const c_void, ctx: *mut TraceCtx, dir: *const Float3) -> Color,
    >,
    /// Density (solid angle) with which `sample_li` from `p` returns `wi`;
    /// 0 for delta lights.
    #[sabi(missing_field(default))]
    pub pdf_li: Option<
        unsafe extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            p: *const Float3,
            wi: *const Float3,
        ) -> f32,
    >,
}

// --------------------------------------------------------------------------
// The scene services: what the host offers integrators and shaders
// --------------------------------------------------------------------------

/// The kernel's `Trace` and the root's queries, lights and bound materials.
/// Built by [`crate::host::ServicesTable`] from the host's implementation of
/// [`crate::host::Services`]; plugins reach it through [`crate::Scene`].
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = SceneServicesRef)))]
pub struct SceneServices {
    /// `Trace(ray) -> color`: the integrator's radiance along the ray;
    /// `kind` is a [`ray_kind`] for the statistics.
    pub trace: unsafe extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        kind: u32,
    ) -> Color,
    /// Nearest hit of the root; `kind` is a [`ray_kind`] for the statistics.
    pub intersect: unsafe extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        kind: u32,
        hit: *mut Hit,
    ) -> bool,
    /// Any hit of the root (shadow rays).
    pub occluded:
        unsafe extern "C" fn(host: *const c_void, ctx: *mut TraceCtx, ray: *const Ray) -> bool,
    /// Local geometry of a root hit, per mask; the root instance's binding applies.
    pub local_geom: unsafe extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        hit: *const Hit,
        mask: u32,
        out: *mut LocalGeom,
    ),
    /// Radiance of a ray that leaves the scene.
    pub background:
        unsafe extern "C" fn(host: *const c_void, ctx: *mut TraceCtx, ray: *const Ray) -> Color,
    /// Number of lights.
    pub light_count: unsafe extern "C" fn(host: *const c_void) -> u32,
    /// Sample light `index` from reference point `p` at `time`.
    pub sample_light: unsafe extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        index: u32,
        p: *const Float3,
        u: *const [f32; 2],
        time: f32,
        out: *mut LightSample,
    ) -> bool,
    /// The shader with id `shader` (from [`LocalGeom::shader`]); false when none.
    #[sabi(last_prefix_field)]
    pub material:
        unsafe extern "C" fn(host: *const c_void, shader: u32, out: *mut ShaderRef) -> bool,
    // ---- Appended after the ABI 2 prefix (issue 9): absent (None) from
    // ---- hosts built before them.
    /// Density (solid angle) with which `sample_light` of the light that
    /// `ray` found, sampled from `p`, would have produced `ray`'s direction:
    /// `geom` is the ray's hit on an emitting surface, or null when the ray
    /// left the scene (the environment light's density; 0 without one). Per
    /// light: the caller's own choice among the `light_count` lights is not
    /// included. Multiple importance sampling weighs a BSDF sample that
    /// found a light by it.
    #[sabi(missing_field(default))]
    pub light_pdf: Option<
        unsafe extern "C" fn(
            host: *const c_void,
            ctx: *mut TraceCtx,
            p: *const Float3,
            ray: *const Ray,
            geom: *const LocalGeom,
        ) -> f32,
    >,
    /// The [`light_flag`] bits of light `index`.
    #[sabi(missing_field(default))]
    pub light_flags: Option<unsafe extern "C" fn(host: *const c_void, index: u32) -> u32>,
}

/// The scene services with the host context they are called with.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct SceneRef {
    /// The host's context, passed first to every entry.
    pub host: *const c_void,
    /// The entries.
    pub services: SceneServicesRef,
}

macro_rules! impl_root_module {
    ($($ty:ident),*) => {$(
        impl abi_stable::library::RootModule for $ty {
            abi_stable::declare_root_module_statics! {$ty}
            const BASE_NAME: &'static str = "rtk_plugin";
            const NAME: &'static str = "rtk plugin";
            const VERSION_STRINGS: abi_stable::sabi_types::VersionStrings =
                abi_stable::package_version_strings!();
        }
    )*};
}
impl_root_module!(
    ObjectModuleRef,
    ShaderModuleRef,
    IntegratorModuleRef,
    CameraModuleRef,
    LightModuleRef
);
