//! The stable records that cross the plugin boundary.
//!
//! Everything here is `#[repr(C)]` and derives [`StableAbi`], so that the host's
//! load check walks every field a plugin can reach and names the first one whose
//! layout differs. The records are decided for the whole roadmap (materials,
//! integrators, area lights, cameras with lens and time samples, bounds over a
//! time interval, the primitive-set protocol): later work appends to the module
//! records, which are prefix types, and never changes a field.
//!
//! Conventions shared by every record:
//! - `extern "C"` function pointers take an opaque `this` pointer first.
//! - An optional entry is an `Option` of a function pointer (null when absent).
//! - Cold-path calls (create, add_child, prepare) return a status ([`STATUS_OK`]
//!   or negative) and write their message into an [`ErrSink`] the caller owns.
//! - Hot-path calls never allocate and never return errors; a plugin failure is
//!   reported through the [`TraceCtx`] failure flag.

use abi_stable::StableAbi;
use std::ffi::c_void;

/// Version of the records in this module. A plugin built against another value
/// is refused before any of its code runs.
pub const ABI_VERSION: u32 = 1;

/// Status code of a successful cold-path call.
pub const STATUS_OK: i32 = 0;
/// Status code of a call that failed with a message in the error sink.
pub const STATUS_ERROR: i32 = -1;
/// Status code of a call whose plugin code panicked (message in the sink).
pub const STATUS_PANIC: i32 = -2;

/// "No shader bound" / "not an emitter" / "no instance" marker for `u32` ids.
pub const NONE_ID: u32 = u32::MAX;

/// Capacity of the hit-info stack: the deepest object DAG the kernel traces
/// (every aggregate, transform and primitive on a path takes one level). The
/// shell refuses scenes whose DAG is deeper.
pub const HIT_STACK_DEPTH: usize = 32;

// --------------------------------------------------------------------------
// Plain values
// --------------------------------------------------------------------------

/// A 3-vector of `f32` (positions, directions, normals, error bounds).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct Float3 {
    /// x component.
    pub x: f32,
    /// y component.
    pub y: f32,
    /// z component.
    pub z: f32,
}

/// Linear RGB radiance or reflectance.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct Color {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
}

/// An axis-aligned box. An empty box has `min > max` (see [`Bounds3::EMPTY`]).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    /// Lower corner.
    pub min: Float3,
    /// Upper corner.
    pub max: Float3,
}

/// A bounding sphere (the paper's second bounding-volume type).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct BoundingSphere {
    /// Centre.
    pub center: Float3,
    /// Radius.
    pub radius: f32,
}

/// A ray. The direction is unit length only at the root: a transform maps the
/// ray without renormalising, so `t` keeps the caller's parameterisation and
/// compares across levels. A hit counts only if `t_min < t < t_max` and `t`
/// is finite.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Float3,
    /// Direction (not necessarily unit length below the root).
    pub dir: Float3,
    /// Open lower end of the accepted interval.
    pub t_min: f32,
    /// Open upper end of the accepted interval; aggregates narrow it as they find hits.
    pub t_max: f32,
    /// Time of the ray within the shutter interval (motion blur).
    pub time: f32,
    /// Recursion depth: 0 for camera rays, +1 for each spawned ray.
    pub generation: u32,
}

/// One entry of the hit-info stack: what the object at this level chose.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct HitEntry {
    /// Child slot (aggregates) or 0.
    pub index: u32,
    /// Primitive within the object (meshes, primitive sets) or 0.
    pub prim: u32,
    /// Two words of the object's own (barycentrics for triangles).
    pub uv: [f32; 2],
}

/// The hit-info stack. The object called at `level` writes `stack[level]`, and
/// only when it (or its child) accepted a closer hit; `depth` is one past the
/// deepest level written by the accepted hit. Ties at equal `t` go to the lowest
/// (child, primitive) so that every aggregate returns exactly the list's answer.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the accepted hit (infinite while none).
    pub t: f32,
    /// One past the deepest level written.
    pub depth: u32,
    /// Per-level choices.
    pub stack: [HitEntry; HIT_STACK_DEPTH],
}

/// Bits of [`LocalGeom::filled`] and of the request mask passed to `local_geom`:
/// an object computes only the fields asked for.
pub mod geom_mask {
    /// Position `p` and its error bound `p_err`.
    pub const POSITION: u32 = 1;
    /// Geometric normal `ng`.
    pub const GEOMETRIC_NORMAL: u32 = 1 << 1;
    /// Shading normal `ns`.
    pub const SHADING_NORMAL: u32 = 1 << 2;
    /// Tangents `dpdu`, `dpdv`.
    pub const TANGENTS: u32 = 1 << 3;
    /// Surface parameterisation `uv`.
    pub const UV: u32 = 1 << 4;
    /// Everything.
    pub const ALL: u32 = POSITION | GEOMETRIC_NORMAL | SHADING_NORMAL | TANGENTS | UV;
}

/// Local geometry at a hit, computed only for the hit that is shaded.
/// All fields are in the caller's space (each transform level maps them).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct LocalGeom {
    /// Hit position.
    pub p: Float3,
    /// Absolute error bound of `p`, per component.
    pub p_err: Float3,
    /// Geometric normal (unit, facing as the surface's orientation says).
    pub ng: Float3,
    /// Shading normal (unit, same hemisphere as `ng`).
    pub ns: Float3,
    /// Tangent along u.
    pub dpdu: Float3,
    /// Tangent along v.
    pub dpdv: Float3,
    /// Surface parameterisation.
    pub uv: [f32; 2],
    /// Bound shader id (the innermost binding wins), or [`NONE_ID`].
    pub shader: u32,
    /// Emitter id when the surface emits, or [`NONE_ID`].
    pub emitter: u32,
    /// Which [`geom_mask`] fields are valid.
    pub filled: u32,
}

/// What the parent's `add_child` receives besides the child: the instance's
/// bindings. Transforms are objects of their own (the `transform` class).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct InstanceData {
    /// Shader bound to this instance, or [`NONE_ID`].
    pub shader: u32,
    /// Emitter id of this instance (area lights), or [`NONE_ID`].
    pub emitter: u32,
    /// Reserved flags (0).
    pub flags: u32,
    /// Reserved (0).
    pub reserved: u32,
}

/// A point sampled on a surface (area lights).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceSample {
    /// Position.
    pub p: Float3,
    /// Error bound of `p`.
    pub p_err: Float3,
    /// Unit normal.
    pub n: Float3,
    /// Density with respect to area.
    pub pdf_area: f32,
}

/// A light sample seen from a reference point.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct LightSample {
    /// Unit direction from the reference point towards the light.
    pub wi: Float3,
    /// Distance to the light along `wi` (infinite for directional lights).
    pub dist: f32,
    /// Incident radiance (or irradiance for delta lights) along `-wi`.
    pub li: Color,
    /// Density of the sample (1 for delta lights), solid-angle measure.
    pub pdf: f32,
    /// Light flags ([`light_flags`]).
    pub flags: u32,
}

/// Light kinds.
pub mod light_flags {
    /// A point light: a single position.
    pub const DELTA_POSITION: u32 = 1;
    /// A directional light: a single direction.
    pub const DELTA_DIRECTION: u32 = 1 << 1;
    /// An area light on an emitting object.
    pub const AREA: u32 = 1 << 2;
    /// An environment light at infinity.
    pub const INFINITE: u32 = 1 << 3;
}

/// A scattering sample from a material.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct BsdfSample {
    /// Sampled incident direction (unit, world space).
    pub wi: Float3,
    /// BSDF value for (wo, wi).
    pub f: Color,
    /// Density of `wi` (solid angle); for specular samples, 1 with `f` pre-divided.
    pub pdf: f32,
    /// [`bsdf_flags`].
    pub flags: u32,
}

/// Kinds of scattering.
pub mod bsdf_flags {
    /// Reflection.
    pub const REFLECTION: u32 = 1;
    /// Transmission.
    pub const TRANSMISSION: u32 = 1 << 1;
    /// A delta (perfectly specular) lobe.
    pub const SPECULAR: u32 = 1 << 2;
}

/// Kinds of rays, for statistics and for shaders that want to know.
pub mod ray_kind {
    /// Primary rays from the camera.
    pub const CAMERA: u32 = 0;
    /// Mirror and glossy reflection.
    pub const REFLECTION: u32 = 1;
    /// Refraction and transmission.
    pub const REFRACTION: u32 = 2;
    /// Shadow (visibility) rays; these go through `occluded`.
    pub const SHADOW: u32 = 3;
    /// Diffuse and other scattered rays.
    pub const SCATTER: u32 = 4;
    /// A ray already counted where it was made (by the camera loop or by
    /// `trace`): integrators pass this to `intersect` for the ray `li` received.
    pub const TRACED: u32 = 7;
    /// Number of kinds.
    pub const COUNT: usize = 5;
}

/// A camera sample: where on the film, where on the lens, when.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraSample {
    /// Film position in [0,1]²: x to the right, y downwards.
    pub film: [f32; 2],
    /// Lens sample in [0,1)².
    pub lens: [f32; 2],
    /// Time sample in [0,1).
    pub time: f32,
}

// --------------------------------------------------------------------------
// Per-thread trace state
// --------------------------------------------------------------------------

/// Per-thread counters. Plain `u64`s in the per-thread context: no atomics on
/// the hot path; the host sums them after the render.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Rays traced, by [`ray_kind`].
    pub rays: [u64; 8],
    /// Calls of `local_geom` at the root.
    pub local_geom_calls: u64,
    /// Per [`geom_mask`] bit, how many `local_geom` requests asked for it.
    pub local_geom_fields: [u64; 8],
    /// Bounding-volume (node, voxel, box) tests made by aggregates.
    pub node_tests: u64,
    /// Primitive intersection tests.
    pub prim_tests: u64,
    /// Shader `shade` / material calls.
    pub shader_calls: u64,
    /// Light samples taken.
    pub light_samples: u64,
    /// Non-finite radiance samples replaced by black.
    pub nonfinite_samples: u64,
    /// Room for counters added later without breaking the layout.
    pub reserved: [u64; 8],
}

/// A small PCG32 stream state, seeded per (seed, pixel, sample) by the host so
/// that images do not depend on the thread count.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct RngState {
    /// Generator state.
    pub state: u64,
    /// Stream increment (odd).
    pub inc: u64,
}

/// Where a plugin reports a failure on the hot path.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct FailureSink {
    /// Host context.
    pub ctx: *mut c_void,
    /// Record a failure: plugin class name and message, as UTF-8 byte ranges.
    pub report: extern "C" fn(
        ctx: *mut c_void,
        class: *const u8,
        class_len: usize,
        msg: *const u8,
        msg_len: usize,
    ),
}

/// Per-thread trace context, passed to every query.
#[repr(C)]
#[derive(StableAbi, Debug)]
pub struct TraceCtx {
    /// Index of the calling thread, below `max_threads`.
    pub thread_index: u32,
    /// The `max_threads` given to `prepare`.
    pub max_threads: u32,
    /// Per-thread query counter: a query that needs a unique id (mailboxes)
    /// takes `next_query` and increments it. Ids are unique per thread.
    pub next_query: u64,
    /// Random stream for this camera sample.
    pub rng: RngState,
    /// Per-thread scratch memory owned by the host.
    pub scratch: *mut u8,
    /// Size of `scratch` in bytes.
    pub scratch_len: usize,
    /// Counters.
    pub stats: Stats,
    /// Non-zero once a plugin failed during this render.
    pub failed: u32,
    /// Where failures are reported.
    pub failure: FailureSink,
}

// --------------------------------------------------------------------------
// Errors and environments for cold-path calls
// --------------------------------------------------------------------------

/// A host-provided sink for an error: the parameter key path (empty if none)
/// and a message, both UTF-8. The host copies the text.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ErrSink {
    /// Host context.
    pub ctx: *mut c_void,
    /// Record the error.
    pub report: extern "C" fn(
        ctx: *mut c_void,
        key: *const u8,
        key_len: usize,
        msg: *const u8,
        msg_len: usize,
    ),
}

/// What `create` receives besides its parameters.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct CreateEnv {
    /// Folder of the scene file (relative file parameters resolve against it), UTF-8.
    pub scene_dir: *const u8,
    /// Length of `scene_dir`.
    pub scene_dir_len: usize,
    /// Name of the definition being created, UTF-8 (for messages).
    pub name: *const u8,
    /// Length of `name`.
    pub name_len: usize,
    /// Image width in pixels.
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
}

/// What `prepare` receives: the thread budget and the host's thread pool.
/// Plugins must not start thread pools of their own.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct PrepareEnv {
    /// Upper bound (exclusive) of `TraceCtx::thread_index` during queries.
    pub max_threads: u32,
    /// Host context for `parallel_for`.
    pub host: *const c_void,
    /// Run `body(user, i)` for every `i < n` on the host's pool; returns when all are done.
    pub parallel_for:
        extern "C" fn(host: *const c_void, n: u64, body: ParallelBody, user: *const c_void),
    /// Tell the host a file was read (for `--stats` and dependency tracking).
    pub note_file: extern "C" fn(host: *const c_void, path: *const u8, len: usize),
}

/// The task body `parallel_for` runs for each index (a wrapper, because the
/// layout checker does not follow function pointers nested in parameters).
#[repr(transparent)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ParallelBody {
    /// Run task `i` with the caller's context `user`.
    pub func: extern "C" fn(user: *const c_void, i: u64),
}

// --------------------------------------------------------------------------
// Object classes
// --------------------------------------------------------------------------

/// The hot entries of an object class: a plain table the host copies out of the
/// plugin's module at load, so that calls never go through a prefix-field check.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ObjectFns {
    /// Nearest hit in `(ray.t_min, ray.t_max)`; on success writes `hit.t`,
    /// `hit.stack[level..]` and `hit.depth` and returns true.
    pub intersect: extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        hit: *mut Hit,
        level: u32,
    ) -> bool,
    /// Any hit in `(ray.t_min, ray.t_max)` (shadow rays): no nearest search, no hit record.
    pub occluded:
        extern "C" fn(this: *const c_void, ctx: *mut TraceCtx, ray: *const Ray, level: u32) -> bool,
    /// Local geometry of the hit recorded in `hit.stack[level..]`, fields per `mask`.
    pub local_geom: extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        hit: *const Hit,
        level: u32,
        mask: u32,
        out: *mut LocalGeom,
    ),
    /// Axis-aligned box over the time interval `[time0, time1]` (mandatory).
    pub bounds: extern "C" fn(this: *const c_void, time0: f32, time1: f32, out: *mut Bounds3),
    /// Bounding sphere over the time interval (optional).
    pub bounding_sphere: Option<
        extern "C" fn(
            this: *const c_void,
            time0: f32,
            time1: f32,
            out: *mut BoundingSphere,
        ) -> bool,
    >,
    /// Points whose convex hull bounds the object; writes at most `cap`, returns
    /// how many there are (call again with a larger buffer if more) (optional).
    pub hull_points: Option<
        extern "C" fn(
            this: *const c_void,
            time0: f32,
            time1: f32,
            out: *mut Float3,
            cap: u32,
        ) -> u32,
    >,
    /// Kay–Kajiya slabs: for each of `n` unit normals, the min and max of `n·p`
    /// over the object (optional).
    pub slab_bounds: Option<
        extern "C" fn(
            this: *const c_void,
            time0: f32,
            time1: f32,
            normals: *const Float3,
            n: u32,
            out_min: *mut f32,
            out_max: *mut f32,
        ) -> bool,
    >,
    /// Is the point inside the object's solid at `time` (CSG; optional).
    pub in_interior: Option<
        extern "C" fn(this: *const c_void, ctx: *mut TraceCtx, p: *const Float3, time: f32) -> bool,
    >,
    /// Sample a point on the surface uniformly by area (area lights; optional).
    pub sample_surface: Option<
        extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            u: *const [f32; 3],
            time: f32,
            out: *mut SurfaceSample,
        ) -> bool,
    >,
    /// Surface area at `time` (optional, with `sample_surface`).
    pub area: Option<extern "C" fn(this: *const c_void, time: f32) -> f32>,
    /// Primitive-set protocol: number of primitives (optional).
    pub prim_count: Option<extern "C" fn(this: *const c_void) -> u32>,
    /// Primitive-set protocol: boxes of primitives `first..first+n`, own space.
    pub prim_bounds:
        Option<extern "C" fn(this: *const c_void, first: u32, n: u32, out: *mut Bounds3)>,
    /// Primitive-set protocol: nearest hit among the listed primitives; writes
    /// `hit.stack[level]` as `intersect` would (one batched call per leaf).
    pub intersect_prims: Option<
        extern "C" fn(
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
    pub occluded_prims: Option<
        extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            ray: *const Ray,
            ids: *const u32,
            n: u32,
            level: u32,
        ) -> bool,
    >,
    /// Primitive-set protocol: the aggregate's leaf order, handed once after
    /// `prepare` so the child may lay its data out in that order (optional).
    pub reorder_prims: Option<extern "C" fn(this: *mut c_void, order: *const u32, n: u32) -> i32>,
}

/// A reference to a created object: its data and its class's hot table.
/// Valid until the scene is dropped; after `prepare` the object is immutable.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ObjectRef {
    /// The object's data.
    pub this: *const c_void,
    /// Its class's hot entries.
    pub fns: &'static ObjectFns,
}

/// The root module of an object-class plugin (primitives, aggregates,
/// transforms, CSG operators). A prefix type: fields are only ever appended.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = ObjectModuleRef)))]
#[sabi(missing_field(panic))]
pub struct ObjectModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error (message in `sink`).
    pub create: extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy an object made by `create`.
    pub destroy: extern "C" fn(this: *mut c_void),
    /// The paper's "instance": add a child with its instance data (aggregates).
    pub add_child: extern "C" fn(
        this: *mut c_void,
        child: ObjectRef,
        inst: *const InstanceData,
        sink: ErrSink,
    ) -> i32,
    /// The paper's "close": build after all children were added. After this the
    /// object is immutable and every query must be safe to call concurrently.
    pub prepare: extern "C" fn(this: *mut c_void, env: *const PrepareEnv, sink: ErrSink) -> i32,
    /// The hot entries.
    #[sabi(last_prefix_field)]
    pub fns: ObjectFns,
}

// --------------------------------------------------------------------------
// Host services for integrators and shaders
// --------------------------------------------------------------------------

/// What the host offers integrators and shaders: the kernel's `Trace`, the
/// root's queries, lights and the bound materials.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct SceneApi {
    /// Host context.
    pub host: *const c_void,
    /// Recursion limit the integrator was configured with (informational).
    pub max_depth: u32,
    /// `Trace(ray) -> color`: the integrator's radiance along the ray;
    /// `kind` is a [`ray_kind`] for statistics.
    pub trace:
        extern "C" fn(host: *const c_void, ctx: *mut TraceCtx, ray: *const Ray, kind: u32) -> Color,
    /// Nearest hit of the root; `kind` is a [`ray_kind`] for statistics.
    pub intersect: extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        kind: u32,
        hit: *mut Hit,
    ) -> bool,
    /// Any hit of the root (shadow rays).
    pub occluded: extern "C" fn(host: *const c_void, ctx: *mut TraceCtx, ray: *const Ray) -> bool,
    /// Local geometry of a root hit, per mask; the root instance's binding applies.
    pub local_geom: extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        hit: *const Hit,
        mask: u32,
        out: *mut LocalGeom,
    ),
    /// Whitted-style shading by the shader bound at the hit (black when none or
    /// when the shader has no `shade`).
    pub shade: extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        ray: *const Ray,
        geom: *const LocalGeom,
    ) -> Color,
    /// Radiance of rays that leave the scene.
    pub background: extern "C" fn(host: *const c_void, ray: *const Ray) -> Color,
    /// Number of lights.
    pub light_count: extern "C" fn(host: *const c_void) -> u32,
    /// Sample light `index` from reference point `p` at `time`.
    pub sample_light: extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        index: u32,
        p: *const Float3,
        u: *const [f32; 2],
        time: f32,
        out: *mut LightSample,
    ) -> bool,
    /// Material query of the shader bound at `geom`: BSDF value.
    pub bsdf_eval: extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        geom: *const LocalGeom,
        wo: *const Float3,
        wi: *const Float3,
    ) -> Color,
    /// Material query: sample an incident direction.
    pub bsdf_sample: extern "C" fn(
        host: *const c_void,
        ctx: *mut TraceCtx,
        geom: *const LocalGeom,
        wo: *const Float3,
        u: *const [f32; 2],
        out: *mut BsdfSample,
    ) -> bool,
    /// Material query: density of `wi`.
    pub bsdf_pdf: extern "C" fn(
        host: *const c_void,
        geom: *const LocalGeom,
        wo: *const Float3,
        wi: *const Float3,
    ) -> f32,
    /// Material query: emitted radiance towards `wo`.
    pub emitted:
        extern "C" fn(host: *const c_void, geom: *const LocalGeom, wo: *const Float3) -> Color,
}

// --------------------------------------------------------------------------
// Shaders, integrators, cameras, lights
// --------------------------------------------------------------------------

/// Metadata common to every plugin module.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct ModuleMeta {
    /// The class name the scene uses.
    pub class_name: abi_stable::std_types::RStr<'static>,
    /// The plugin's documentation (parameter table and a TOML example).
    pub doc: abi_stable::std_types::RStr<'static>,
    /// Version of the plugin crate.
    pub plugin_version: abi_stable::std_types::RStr<'static>,
}

/// Root module of a shader plugin. Shaders answer the material queries and
/// may offer `shade` for recursive Whitted-style shading.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = ShaderModuleRef)))]
#[sabi(missing_field(panic))]
pub struct ShaderModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy.
    pub destroy: extern "C" fn(this: *mut c_void),
    /// BSDF value f(wo, wi) (cosine not included).
    pub eval: extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        geom: *const LocalGeom,
        wo: *const Float3,
        wi: *const Float3,
    ) -> Color,
    /// Sample wi given wo.
    pub sample: extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        geom: *const LocalGeom,
        wo: *const Float3,
        u: *const [f32; 2],
        out: *mut BsdfSample,
    ) -> bool,
    /// Density of `sample` choosing wi.
    pub pdf: extern "C" fn(
        this: *const c_void,
        geom: *const LocalGeom,
        wo: *const Float3,
        wi: *const Float3,
    ) -> f32,
    /// Emitted radiance towards wo (optional: absent means black).
    pub emitted: Option<
        extern "C" fn(this: *const c_void, geom: *const LocalGeom, wo: *const Float3) -> Color,
    >,
    /// Whitted-style recursive shading (optional).
    #[sabi(last_prefix_field)]
    pub shade: Option<
        extern "C" fn(
            this: *const c_void,
            ctx: *mut TraceCtx,
            scene: *const SceneApi,
            ray: *const Ray,
            geom: *const LocalGeom,
        ) -> Color,
    >,
}

/// Root module of an integrator plugin: drives each camera sample.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = IntegratorModuleRef)))]
#[sabi(missing_field(panic))]
pub struct IntegratorModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy.
    pub destroy: extern "C" fn(this: *mut c_void),
    /// Recursion limit the integrator applies (reported in [`SceneApi::max_depth`]).
    pub max_depth: extern "C" fn(this: *const c_void) -> u32,
    /// Radiance arriving along `-ray.dir` at `ray.origin`.
    #[sabi(last_prefix_field)]
    pub li: extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        scene: *const SceneApi,
        ray: *const Ray,
    ) -> Color,
}

/// Root module of a camera plugin. Ray generation takes a film position, a
/// lens sample and a time sample, so depth of field and motion blur need no
/// change to the record.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = CameraModuleRef)))]
#[sabi(missing_field(panic))]
pub struct CameraModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy.
    pub destroy: extern "C" fn(this: *mut c_void),
    /// Generate a world-space ray (unit direction); returns the sample weight.
    #[sabi(last_prefix_field)]
    pub generate_ray:
        extern "C" fn(this: *const c_void, sample: *const CameraSample, out: *mut Ray) -> f32,
}

/// Root module of a light plugin (point, directional, environment).
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = LightModuleRef)))]
#[sabi(missing_field(panic))]
pub struct LightModule {
    /// Common metadata.
    pub meta: ModuleMeta,
    /// Create from parameters (JSON text); null on error.
    pub create: extern "C" fn(
        params: *const u8,
        params_len: usize,
        env: *const CreateEnv,
        sink: ErrSink,
    ) -> *mut c_void,
    /// Destroy.
    pub destroy: extern "C" fn(this: *mut c_void),
    /// [`light_flags`] of this light.
    pub flags: extern "C" fn(this: *const c_void) -> u32,
    /// Called once with the world bounds before rendering (optional).
    pub preprocess: Option<extern "C" fn(this: *mut c_void, world: *const Bounds3)>,
    /// Sample incident light at `p`.
    pub sample_li: extern "C" fn(
        this: *const c_void,
        ctx: *mut TraceCtx,
        p: *const Float3,
        u: *const [f32; 2],
        time: f32,
        out: *mut LightSample,
    ) -> bool,
    /// Density of sampling `wi` from `p` (optional; 0 for delta lights).
    pub pdf_li:
        Option<extern "C" fn(this: *const c_void, p: *const Float3, wi: *const Float3) -> f32>,
    /// Radiance of an escaping ray (environment lights; optional).
    #[sabi(last_prefix_field)]
    pub le: Option<extern "C" fn(this: *const c_void, ray: *const Ray) -> Color>,
}

// --------------------------------------------------------------------------
// The header read before any plugin code runs
// --------------------------------------------------------------------------

/// Kinds of plugin.
#[repr(u32)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PluginKind {
    /// An object class (primitive, aggregate, transform, CSG).
    Object = 1,
    /// A shader (material).
    Shader = 2,
    /// An integrator.
    Integrator = 3,
    /// A camera.
    Camera = 4,
    /// A light.
    Light = 5,
}

impl PluginKind {
    /// Decode a raw kind.
    pub fn from_u32(v: u32) -> Option<Self> {
        Some(match v {
            1 => Self::Object,
            2 => Self::Shader,
            3 => Self::Integrator,
            4 => Self::Camera,
            5 => Self::Light,
            _ => return None,
        })
    }
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Object => "object",
            Self::Shader => "shader",
            Self::Integrator => "integrator",
            Self::Camera => "camera",
            Self::Light => "light",
        }
    }
}

/// Magic bytes opening [`PluginHeader`].
pub const PLUGIN_MAGIC: [u8; 8] = *b"RTKPLUG\0";
/// Name of the exported header symbol.
pub const PLUGIN_HEADER_SYMBOL: &[u8] = b"RTK_PLUGIN_HEADER\0";

/// Plain data every plugin exports under [`PLUGIN_HEADER_SYMBOL`]. The host
/// reads it without calling any plugin code, and refuses the library if the
/// magic, the ABI version, the kernel version or the panic strategy is wrong.
/// Strings are NUL-padded fixed arrays so that no pointer needs relocating.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PluginHeader {
    /// [`PLUGIN_MAGIC`].
    pub magic: [u8; 8],
    /// Size of this struct as the plugin saw it.
    pub header_size: u32,
    /// [`ABI_VERSION`] the plugin was built against.
    pub abi_version: u32,
    /// [`PluginKind`] as `u32`.
    pub kind: u32,
    /// 1 if built with `panic = "unwind"`, 0 for `panic = "abort"`.
    pub panic_unwind: u32,
    /// Kernel crate version the plugin was built against, NUL-padded.
    pub kernel_version: [u8; 32],
    /// Class name, NUL-padded.
    pub class_name: [u8; 64],
}

impl PluginHeader {
    /// Build a header at compile time (used by the export macros).
    pub const fn new(kind: PluginKind, class_name: &str, panic_unwind: bool) -> Self {
        Self {
            magic: PLUGIN_MAGIC,
            header_size: std::mem::size_of::<PluginHeader>() as u32,
            abi_version: ABI_VERSION,
            kind: kind as u32,
            panic_unwind: panic_unwind as u32,
            kernel_version: pad::<32>(env!("CARGO_PKG_VERSION")),
            class_name: pad::<64>(class_name),
        }
    }

    /// The class name as a string (up to the first NUL).
    pub fn class_name(&self) -> String {
        unpad(&self.class_name)
    }

    /// The kernel version as a string.
    pub fn kernel_version(&self) -> String {
        unpad(&self.kernel_version)
    }
}

const fn pad<const N: usize>(s: &str) -> [u8; N] {
    let b = s.as_bytes();
    assert!(b.len() < N, "name too long for the plugin header");
    let mut out = [0u8; N];
    let mut i = 0;
    while i < b.len() {
        out[i] = b[i];
        i += 1;
    }
    out
}

fn unpad(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).into_owned()
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

// The records hold raw pointers that the host guarantees valid for the
// object's lifetime; sharing them between threads is the ABI's contract
// (objects are immutable after `prepare`).
// SAFETY: `ObjectRef` points at an object that is immutable after `prepare` and
// whose class is `Sync` (enforced by the SDK traits); its table is `'static`.
unsafe impl Send for ObjectRef {}
// SAFETY: see above.
unsafe impl Sync for ObjectRef {}
// SAFETY: `SceneApi` points at host state that is immutable during rendering
// and whose entries are safe to call concurrently.
unsafe impl Send for SceneApi {}
// SAFETY: see above.
unsafe impl Sync for SceneApi {}
// SAFETY: `PrepareEnv` is only used during `prepare`; its host pointer refers
// to the host's thread pool, which is `Sync`.
unsafe impl Sync for PrepareEnv {}
