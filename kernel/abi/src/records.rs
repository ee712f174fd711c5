//! The function-pointer records: the root module of each plugin kind, the
//! environments of the cold calls, and the scene services the host offers.
//!
//! Conventions shared by every record:
//! - every entry is an `unsafe extern "C" fn` taking the object's opaque
//!   `this` first; the caller promises that every pointer is valid for the
//!   call (and `this` for the object's life). Only the kernel's safe layers
//!   (`rtk-sdk`, `rtk-handles`) call them;
//! - an optional entry is an `Option` of a function pointer (null: not offered);
//! - **cold** entries (create, add_child, prepare, bounds, primitive counts)
//!   return a status ([`STATUS_OK`] or negative) and write their message into
//!   an [`ErrSink`] the caller owns;
//! - **hot** entries (queries, shading, sampling) never allocate and return no
//!   status: a failure is recorded in the [`TraceCtx`] with the plugin's name.
//!
//! The module records themselves ([`ObjectModule`], [`ShaderModule`],
//! [`IntegratorModule`], [`CameraModule`], [`LightModule`] and the
//! [`SceneServices`]) are generated from their declarations in
//! [`crate::entries`] by [`__record!`](crate::__record); this file holds what
//! they pass: the environments of the cold calls, the references to other
//! objects, the error sink.

use crate::*;
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
    /// Named arrays passed by pointer rather than as parameter text (meshes
    /// from arrays), valid during the call; empty when none.
    pub arrays: Span<BulkArray>,
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

/// A reference to a created object: its data and its class's record.
/// Plain data: whoever holds one must know by other means that the object
/// is alive (a [`ChildRef`] carries that proof with it).
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct ObjectRef {
    /// The object's data.
    pub this: *const c_void,
    /// Its class's record.
    pub class: ObjectModuleRef,
}

/// A counted reference to something the host owns: `retain` adds a count,
/// `release` drops one, and the owner lives while any count is held. Both
/// are thread-safe and never called on the hot path (only when a handle is
/// made, cloned or dropped).
///
/// Why counts and not lifetimes: a plugin may keep what it is handed (an
/// aggregate keeps its children, an area light its emitter) for as long as
/// it likes, even past the world it came from (`rtk stress` builds many
/// worlds in one process); a count makes that safe without `unsafe` in the
/// plugin and without a lifetime on every plugin type.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct KeepAlive {
    /// The owner (opaque).
    pub owner: *const c_void,
    /// Add a count.
    pub retain: unsafe extern "C" fn(owner: *const c_void),
    /// Drop a count; the last one frees the owner.
    pub release: unsafe extern "C" fn(owner: *const c_void),
}

/// A child as `add_child` receives it: the object, the instance's bindings,
/// and one count on the object, which the receiver now owns.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct ChildRef {
    /// The prepared child.
    pub obj: ObjectRef,
    /// The instance's bindings (shader, light, id).
    pub inst: InstanceData,
    /// The count that keeps `obj` alive.
    pub keep: KeepAlive,
}

/// An emitting instance as an area light receives it (`bind_emitter`): the
/// object with one count on it, its object-to-world placement (f64, the
/// renderer's origin already subtracted), and the emitting shader with one
/// count on it. The light samples the placed surface and asks the shader
/// for the radiance it emits.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct EmitterRef {
    /// The emitting object, counted; its instance data names the light.
    pub object: ChildRef,
    /// Object to world (renderer's space).
    pub to_world: Affine3x4,
    /// The shader that emits.
    pub shader: ShaderRef,
    /// The count that keeps `shader` alive.
    pub shader_keep: KeepAlive,
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

/// The scene services with the host context they are called with.
#[repr(C)]
#[derive(StableAbi, Clone, Copy)]
pub struct SceneRef {
    /// The host's context, passed first to every entry.
    pub host: *const c_void,
    /// The entries.
    pub services: SceneServicesRef,
}

/// The version of this crate's minor number, written into every record a
/// plugin builds (`abi_minor`, the last field of the stable prefix): a
/// record built against minor 0 lacks what later minors appended.
pub const ABI_MINOR: u32 = parse_minor(env!("CARGO_PKG_VERSION_MINOR"));

const fn parse_minor(s: &str) -> u32 {
    let b = s.as_bytes();
    let (mut i, mut v) = (0, 0u32);
    while i < b.len() {
        v = v * 10 + (b[i] - b'0') as u32;
        i += 1;
    }
    v
}

crate::object_entries!(crate::__record);
crate::shader_entries!(crate::__record);
crate::integrator_entries!(crate::__record);
crate::camera_entries!(crate::__record);
crate::light_entries!(crate::__record);
crate::scene_entries!(crate::__record);

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
