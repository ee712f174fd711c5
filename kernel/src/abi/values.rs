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

/// Linear RGB radiance or reflectance.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, Default, PartialEq)]
pub struct Color {
    /// Red, linear (not sRGB-encoded).
    pub r: f32,
    /// Green, linear.
    pub g: f32,
    /// Blue, linear.
    pub b: f32,
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
/// kind", and the caller derives one.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug)]
pub struct BoundingVolume {
    /// Set by the object when it wrote the kind asked for.
    pub written: bool,
    /// [`bound_kind::SPHERE`].
    pub sphere: BoundSphere,
    /// [`bound_kind::SLABS`].
    pub slabs: SlabBounds,
    /// [`bound_kind::HULL`]: the caller's buffer of `hull_cap` points. The
    /// object writes up to `hull_cap` of its points and sets `hull_len` to
    /// how many it has; when that exceeds `hull_cap` the caller asks again
    /// with room for all.
    pub hull: *mut [f32; 3],
    /// Capacity of `hull`.
    pub hull_cap: u32,
    /// Number of hull points the object has.
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

/// The hit-info stack: the path from the root to the primitive hit.
///
/// The object called at `level` writes `stack[level]`, and only when it (or
/// its child) accepted a closer hit, so a later child that misses never
/// overwrites the winning path. `depth` is one past the deepest level written
/// by the accepted hit. Ties at equal `t` go to the lowest (child, primitive),
/// so that every aggregate returns exactly the `list`'s answer.
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
    /// Everything.
    pub const ALL: u32 = POSITION | GEOMETRIC_NORMAL | SHADING_NORMAL | TANGENTS | UV;
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
    /// Surface parameterisation.
    pub uv: [f32; 2],
    /// Bound shader id (the innermost binding wins), or [`NONE_ID`].
    pub shader: u32,
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

/// An instance transform as the shell composed it (f64, row-major 3x4:
/// `[m00 m01 m02 tx, m10 m11 m12 ty, m20 m21 m22 tz]`), checked finite and
/// well conditioned before any plugin sees it.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Affine3x4 {
    /// Rows of the matrix with the translation in the last column.
    pub rows: [[f64; 4]; 3],
}
