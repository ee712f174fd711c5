//! Plain values passed across the boundary by pointer. None holds a pointer,
//! so safe code on either side may build, copy and read them.

use abi_stable::StableAbi;

/// "No shader bound" marker of a `u32` shader id.
pub const NONE_ID: u32 = u32::MAX;

/// Capacity of the hit-info stack: the deepest object DAG rtk traces (every
/// aggregate, transform and primitive on a path takes one level). The shell
/// refuses deeper scenes before loading any plugin.
pub const HIT_STACK_DEPTH: usize = 32;

/// A 3-vector of `f32`: positions, directions, normals, error bounds.
/// (glam's `Vec3` is not `StableAbi`; [`Float3::v`] converts.)
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

/// Linear RGB radiance or reflectance, with a fourth lane.
///
/// Why four: spectral rendering (ROADMAP) carries four wavelength samples
/// per path, as pbrt-v4's `SampledSpectrum` does, and a colour of four lanes
/// is one SIMD register. In RGB rendering `w` is 0 and stays 0 (every
/// constructor from RGB sets it so, and the arithmetic is per lane); in
/// spectral rendering `r, g, b, w` are the values at the four wavelengths
/// in [`TraceCtx::wavelengths`](crate::TraceCtx). The layout is fixed now
/// so that spectral rendering is a capability, not a new ABI.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct Color {
    /// Red, linear (not sRGB-encoded); the first wavelength's value in spectral rendering.
    pub r: f32,
    /// Green, linear; the second wavelength's value.
    pub g: f32,
    /// Blue, linear; the third wavelength's value.
    pub b: f32,
    /// 0 in RGB rendering; the fourth wavelength's value in spectral rendering.
    pub w: f32,
}

/// An axis-aligned box. An empty box has `min > max` ([`Bounds3::EMPTY`]),
/// so that it is the identity of `union`.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Bounds3 {
    /// Lower corner.
    pub min: Float3,
    /// Upper corner.
    pub max: Float3,
}

/// The paper's bounding-volume types beyond the box, asked for through the
/// object entry `inq_bounds` (the box, mandatory, is `bounds`). An object
/// answers the kinds it can bound tighter than its box; for the others the
/// caller derives one (`sdk::Child` does: a sphere around the box, the box's
/// corners as hull points, slabs from the hull points).
pub mod bound_kind {
    /// A sphere ([`BoundSphere`](super::BoundSphere)).
    pub const SPHERE: u32 = 1;
    /// Hull points: the object lies inside their convex hull.
    pub const HULL: u32 = 2;
    /// Kay–Kajiya slabs along [`SLAB_NORMALS`](super::SLAB_NORMALS).
    pub const SLABS: u32 = 3;
}

/// A bounding sphere: every point of the object is within `radius` of
/// `center` (exactly, after the rounding of both).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct BoundSphere {
    /// Centre.
    pub center: Float3,
    /// Radius (negative: nothing to bound).
    pub radius: f32,
}

/// Number of slab normals: Kay and Kajiya's seven.
pub const SLAB_COUNT: usize = 7;

/// The slab normals of [`SlabBounds`]: the three axes and the four
/// diagonals, **not normalised** (components ±1, so a point's distance along
/// one is a signed sum of its coordinates, exact in f64). Fixed by the ABI
/// so that volumes from different plugins combine.
pub const SLAB_NORMALS: [[f32; 3]; SLAB_COUNT] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, -1.0],
];

/// A plane-set bounding volume (Kay and Kajiya 1986): every point `p` of the
/// object has `lo[k] <= n_k · p <= hi[k]` for each of [`SLAB_NORMALS`].
/// The first three slabs are the object's box.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct SlabBounds {
    /// Near plane along each normal.
    pub lo: [f32; SLAB_COUNT],
    /// Far plane along each normal.
    pub hi: [f32; SLAB_COUNT],
}

/// The answer record of `inq_bounds`: the object fills the part for the kind
/// asked and sets `written`; `written == false` means "not offered for this
/// kind", and the caller derives one. Hull points go into the caller's
/// buffer, passed beside the record (as much as fits); `hull_len` says how
/// many the object has, and the caller asks again with room for all.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct BoundingVolume {
    /// Set by the object when it wrote the kind asked for.
    pub written: bool,
    /// [`bound_kind::SPHERE`].
    pub sphere: BoundSphere,
    /// [`bound_kind::SLABS`].
    pub slabs: SlabBounds,
    /// [`bound_kind::HULL`]: the number of hull points the object has.
    pub hull_len: u32,
}

/// A ray. The direction is unit length only at the root: a transform maps the
/// ray without renormalising, so `t` keeps the caller's parameterisation and
/// compares across levels. A hit counts only if `t_min < t < t_max` and `t`
/// is finite ([`Ray::accepts`]).
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
    /// Time of the ray within the shutter interval [0, 1).
    pub time: f32,
    /// Recursion depth: 0 for camera rays, +1 for each spawned ray. It bounds
    /// recursion through integrators and shaders.
    pub generation: u32,
}

/// The hit-info stack: the path from the root to the primitive hit, one
/// word per level, and the leaf's two words of its own.
///
/// The object called at `level` writes `stack[level]` — an aggregate the
/// slot of the child that accepted the hit, a primitive the primitive's id
/// — and only when it (or its child) accepted a closer hit, so a later child
/// that misses never overwrites the winning path. `depth` is one past the
/// deepest level written by the accepted hit; `uv` belongs to the primitive
/// at `depth - 1` (barycentrics for triangles, patch parameters for
/// patches). Ties at equal `t` go to the lowest (child, primitive), so that
/// every aggregate returns exactly the `list`'s answer.
///
/// Why one word a level (ABI 2 had sixteen bytes a level): a ray stream
/// carries a hit per ray, and 144 bytes a hit keep a batch of 64 in L1 where
/// 520 would not; no level but the leaf ever had words of its own.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct Hit {
    /// Ray parameter of the accepted hit (infinite while none).
    pub t: f32,
    /// One past the deepest level written.
    pub depth: u32,
    /// The leaf primitive's own two words (barycentrics b1, b2 for triangles).
    pub uv: [f32; 2],
    /// Per level: the child slot (aggregates, transforms) or the primitive id (leaves).
    pub stack: [u32; HIT_STACK_DEPTH],
}

/// Bits of [`LocalGeom::filled`] and of the request mask passed to
/// `local_geom`: an object computes only the fields asked for (a normals view
/// needs no uv, a Whitted shader no tangents).
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
    /// Normal derivatives `dndu`, `dndv` (bump mapping; objects that do not
    /// compute them leave them zero and the bit clear).
    pub const NORMAL_DERIVATIVES: u32 = 1 << 5;
    /// Everything.
    pub const ALL: u32 =
        POSITION | GEOMETRIC_NORMAL | SHADING_NORMAL | TANGENTS | UV | NORMAL_DERIVATIVES;
}

/// Local geometry at a hit, computed only for the hit that is shaded.
/// All fields are in the caller's space: each transform level maps them on
/// the way out (normals by M⁻ᵀ, tangents by M, the error bound grown by the
/// transform's own rounding).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct LocalGeom {
    /// Hit position.
    pub p: Float3,
    /// Absolute error bound of `p`, per component: spawned rays start past it.
    pub p_err: Float3,
    /// Geometric normal (unit, facing as the surface's orientation says).
    pub ng: Float3,
    /// Shading normal (unit, same hemisphere as `ng`).
    pub ns: Float3,
    /// Tangent along u.
    pub dpdu: Float3,
    /// Tangent along v.
    pub dpdv: Float3,
    /// Derivative of the shading normal along u.
    pub dndu: Float3,
    /// Derivative of the shading normal along v.
    pub dndv: Float3,
    /// Surface parameterisation.
    pub uv: [f32; 2],
    /// Bound shader id (the innermost binding wins), or [`NONE_ID`].
    pub shader: u32,
    /// The light bound to the emitting instance hit (multiple importance
    /// sampling weighs a hit on it by that light's density), or [`NONE_ID`].
    pub light: u32,
    /// The instance id the shell gave the innermost instance with one (what
    /// a hit reports as its object), or [`NONE_ID`].
    pub instance: u32,
    /// The primitive hit within its object (per-face attributes), set by
    /// the primitive's `local_geom`; 0 for single-primitive objects.
    pub prim: u32,
    /// Which [`geom_mask`] fields are valid.
    pub filled: u32,
}

/// What a parent's `add_child` receives besides the child: the instance's
/// bindings. Transforms are objects of their own (the shell wraps a
/// transformed instance in one).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct InstanceData {
    /// Shader bound to this instance, or [`NONE_ID`].
    pub shader: u32,
    /// Light bound to this instance (an emitting instance's area light), or [`NONE_ID`].
    pub light: u32,
    /// The instance's id (the shell numbers instances a user can name), or [`NONE_ID`].
    pub id: u32,
}

/// A light sample seen from a reference point.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct LightSample {
    /// Unit direction from the reference point towards the light.
    pub wi: Float3,
    /// Distance to the light along `wi` (infinite for directional lights).
    pub dist: f32,
    /// Incident radiance (irradiance for delta lights) along `-wi`.
    pub li: Color,
    /// Density of the sample, solid-angle measure (1 for delta lights).
    pub pdf: f32,
}

/// Lobe kinds of a material, for [`BsdfSample::lobe`] and for the filter a
/// caller passes to `sample` (Whitted asks for specular lobes only; a path
/// tracer for all).
pub mod lobe {
    /// Reflection (same side as the incoming direction).
    pub const REFLECTION: u32 = 1;
    /// Transmission (the other side).
    pub const TRANSMISSION: u32 = 1 << 1;
    /// A diffuse lobe.
    pub const DIFFUSE: u32 = 1 << 2;
    /// A glossy lobe.
    pub const GLOSSY: u32 = 1 << 3;
    /// A delta (perfectly specular) lobe.
    pub const SPECULAR: u32 = 1 << 4;
    /// Every scattering lobe.
    pub const ALL: u32 = REFLECTION | TRANSMISSION | DIFFUSE | GLOSSY | SPECULAR;
    /// Not a lobe: the material emits (answers `emitted`). The shell makes
    /// every instance bound to such a shader an area light, so the bit must
    /// be set by a shader that emits and only by one. Outside [`ALL`], which
    /// filters scattering.
    pub const EMISSION: u32 = 1 << 5;
}

/// A point sampled on an object's surface, uniformly by area in the
/// object's own space (the `sample_surface` entry): its density is
/// `1 / area` there. The host converts it to world space and to solid angle.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceSample {
    /// The point.
    pub p: Float3,
    /// Geometric normal there (unit, the side `local_geom`'s `ng` faces).
    pub n: Float3,
    /// The object's total surface area, own space.
    pub area: f32,
}

/// A scattering sample from a material.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct BsdfSample {
    /// Sampled incident direction (unit, world space).
    pub wi: Float3,
    /// Throughput of the sample: f(wo, wi)·|cos θi| / pdf. For a delta lobe
    /// this is the lobe's reflectance or transmittance (pdf 1).
    pub weight: Color,
    /// Density of `wi` (solid angle); 1 for delta lobes.
    pub pdf: f32,
    /// The [`lobe`] bits of the lobe sampled.
    pub lobe: u32,
    /// Relative index of refraction across a sampled transmission (η_t/η_i),
    /// 1 for reflection: what Russian roulette divides out of the throughput
    /// (pbrt-v4's `etaScale`). 0 from a shader that does not say (read as 1).
    pub eta: f32,
}

/// What kind of light a light index is (the `light_flags` service), so an
/// integrator knows which samples multiple importance sampling can weigh.
pub mod light_flag {
    /// A point or a single direction: no ray can find it, its sample's
    /// `pdf` is 1 and its `li` is irradiance.
    pub const DELTA: u32 = 1;
    /// Surrounds the scene: rays that leave the scene find it.
    pub const ENVIRONMENT: u32 = 1 << 1;
    /// An emitting instance's surface: rays can hit it.
    pub const AREA: u32 = 1 << 2;
}

/// Kinds of rays, counted separately in the statistics.
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
}

/// A camera sample: where on the film, where on the lens, when. Depth of field
/// and motion blur need no change to the camera record.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraSample {
    /// Film position in \[0,1\]²: x to the right, y downwards.
    pub film: [f32; 2],
    /// Lens sample in [0,1)².
    pub lens: [f32; 2],
    /// Time sample in [0,1).
    pub time: f32,
}

/// A camera's answer for one sample: a world-space ray (unit direction)
/// and the sample's weight (the camera's importance; 1 for a pinhole).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct CameraRay {
    /// The ray.
    pub ray: Ray,
    /// Its weight.
    pub weight: f32,
}

/// The paper's fifth operation's answer (`in_interior`): is a point inside
/// the object. A plain word rather than an enum, so no value a plugin
/// returns can be an invalid one.
#[repr(transparent)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Interior(pub u32);

/// A pointer argument that may be null (`Option<&T>` on both safe sides).
pub type Nullable<T> = *const T;

/// A borrowed array across the boundary: `len` values at `ptr` (null when
/// empty), valid for the call that passes it. `&[T]` on either side.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct Span<T> {
    /// First element (null or dangling when `len` is 0).
    pub ptr: *const T,
    /// Number of elements.
    pub len: usize,
}

/// A borrowed mutable array across the boundary: `&mut [T]` on either side.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct SpanMut<T> {
    /// First element.
    pub ptr: *mut T,
    /// Number of elements.
    pub len: usize,
}

/// Element types of a [`BulkArray`].
pub mod bulk_dtype {
    /// 32-bit float.
    pub const F32: u32 = 1;
    /// 64-bit float.
    pub const F64: u32 = 2;
    /// 32-bit unsigned integer.
    pub const U32: u32 = 3;
    /// 32-bit signed integer.
    pub const I32: u32 = 4;
    /// 64-bit signed integer.
    pub const I64: u32 = 5;
    /// Byte.
    pub const U8: u32 = 6;
}

/// A named array handed to `create` by pointer, not as text (meshes built
/// from NumPy arrays, imported attributes): a C-order `rows × cols` block of
/// [`bulk_dtype`] elements, valid during `create` (a plugin copies what it keeps).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct BulkArray {
    /// The parameter name it stands for (`vertices`, `indices`), UTF-8.
    pub name: Span<u8>,
    /// A [`bulk_dtype`].
    pub dtype: u32,
    /// Number of rows.
    pub rows: u64,
    /// Number of columns (3 for positions).
    pub cols: u64,
    /// The first byte of `rows * cols` elements.
    pub data: *const u8,
}

/// An instance transform as the shell composed it (f64, row-major 3x4:
/// `[m00 m01 m02 tx, m10 m11 m12 ty, m20 m21 m22 tz]`), checked finite and
/// well conditioned before any plugin sees it.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Affine3x4 {
    /// Rows of the matrix with the translation in the last column.
    pub rows: [[f64; 4]; 3],
}
