//! # rtk-sdk
//!
//! The plugin side of the boundary: one safe trait per plugin kind, optional
//! capabilities as traits of their own, and one export macro per kind.
//!
//! # What a plugin author writes
//! A `cdylib` crate depending on `rtk-kernel` alone implements [`Plugin`]
//! (its parameters and `create`) and the trait of its kind — [`Object`],
//! [`Shader`], [`Integrator`], [`Camera`] or [`Light`] — then calls the kind's
//! export macro once:
//!
//! ```ignore
//! rtk_kernel::export_object!(Mesh, class = "mesh", doc = include_str!("../README.md"),
//!                            capabilities = [PrimitiveSet]);
//! ```
//!
//! Each kind's trait has few required methods and defaults for the rest, so
//! the smallest correct plugin is short (the `list` aggregate is about 60
//! lines). A single analytic primitive implements [`AnalyticShape`] instead
//! of [`Object`] — its root finder, its surface and its box — and the SDK's
//! blanket impl makes it an object ([`analytic`]). Optional capabilities —
//! [`PrimitiveSet`], [`FromTransform`], [`Shade`] — are traits the plugin
//! implements *and names in its export macro*: the record's optional entries
//! are filled from that list, so an entry is offered exactly when its
//! methods exist.
//!
//! # Why the shape
//! - **No `unsafe` in plugin crates, and no way to reach a raw record.** The
//!   records' entries are `unsafe extern "C" fn`s; the generic shims in this
//!   module are the only code that calls into a plugin's trait, and the
//!   wrappers a plugin receives ([`Child`], [`PrimSet`], [`Scene`],
//!   [`Material`]) can only be made by the SDK and expose safe methods only.
//! - **Every entry runs under `catch_unwind`.** A panic in a cold call
//!   (create, add_child, prepare, bounds) becomes an error naming the plugin;
//!   on the hot path it is recorded in the [`TraceCtx`] with the plugin's name
//!   and the host stops the render. A panic never unwinds across
//!   `extern "C"` (that aborts: two cdylibs do not even share a std).
//! - **Two queries and a record**, as pbrt-v4 pairs `Intersect`/`IntersectP`:
//!   `intersect` finds the nearest hit and writes a small hit record,
//!   `occluded` answers any-hit shadow queries, and `local_geom` computes the
//!   expensive surface record only for the hit that is shaded.

#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![deny(clippy::missing_safety_doc)]

pub mod analytic;
pub mod batch;
pub mod bulk;
pub mod camera;
mod child;
mod conv;
mod emitter;
mod gen;
mod live;
pub mod microfacet;
pub mod params;
mod scene;
pub mod shading;
#[doc(hidden)]
pub mod shims;
pub mod sink;
pub mod texture;
#[doc(hidden)]
pub mod volumes;
pub mod xform;

pub use glam;
/// The records, for the export macros' `$crate` paths.
pub use rtk_abi as abi;
pub use serde;

/// Re-exports the export macros need (plugins do not depend on abi_stable).
#[doc(hidden)]
pub mod reexports {
    pub use abi_stable;
    pub use abi_stable::library::LibHeader;
}

use glam::Vec3;
use rtk_abi::*;
use serde::de::DeserializeOwned;
use std::path::PathBuf;

pub use analytic::{AnalyticShape, Root};
pub use child::{union_interior, Child, PrimSet};
pub use conv::{FromRaw, ToRawAnswer};
pub use emitter::{Emitter, ShaderHandle};
pub use live::{LiveCamera, LiveIntegrator, LiveLight, LiveObject, LiveServices, LiveShader};
pub use params::parse_params;
pub use scene::{Material, Scene};
#[doc(hidden)]
pub use shims::{leak, lib_header, Decl, Install, ModuleSource};

/// An error from a plugin's cold call: the parameter key path it concerns (if
/// any; the shell maps it back to the TOML file, line and column) and a message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}{}{message}", key, if key.is_empty() { "" } else { ": " })]
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

/// What `create` knows besides its parameters.
#[derive(Debug, Clone, Copy)]
pub struct Env<'a> {
    /// Folder of the scene file: relative file parameters resolve against it.
    pub scene_dir: &'a str,
    /// Path of the definition being created (`objects.ball`), for messages.
    pub name: &'a str,
    /// Image width in pixels (cameras need the aspect ratio).
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
    /// The world point the renderer computes about: read world positions
    /// with [`Env::position`] and [`Env::place`], which subtract it.
    ///
    /// Why: f32 spacing grows with magnitude, so a scene far from the
    /// world's origin is computed coarsely (at 5e5 the spacing is 1/32). The
    /// shell sets this to the camera's position by default; subtracting it in
    /// f64 before the one rounding to f32 gives what the camera sees the
    /// precision of a scene at the origin (docs/numerics.md X3).
    pub origin: [f64; 3],
    /// Arrays the host passed by pointer instead of as parameters (meshes
    /// from NumPy): empty for definitions read from a scene file.
    pub arrays: bulk::Arrays<'a>,
}

impl Env<'_> {
    /// A world position parameter (`center`, `eye`, ...), finite and within
    /// the kernel's range once moved to the renderer's origin. Directions
    /// and object-space vectors use [`params::direction`] and
    /// [`params::point`] instead: they do not move.
    pub fn position(&self, key: &str, v: [f64; 3]) -> Result<Vec3, PluginError> {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(PluginError::key(key, format!("must be finite, got {x}")));
        }
        let p = self.place(v);
        params::point(key, p.to_array())
    }

    /// A world position read from a file, moved to the renderer's origin:
    /// `v − origin` in f64, rounded once to f32.
    #[inline]
    pub fn place(&self, v: [f64; 3]) -> Vec3 {
        Vec3::new(
            (v[0] - self.origin[0]) as f32,
            (v[1] - self.origin[1]) as f32,
            (v[2] - self.origin[2]) as f32,
        )
    }

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

/// What `prepare` receives: the thread budget, the host's pool, and a way to
/// read files that the host counts. (A view of the record itself, so a
/// shim can lend it without copying.)
#[repr(transparent)]
pub struct Prepare {
    env: PrepareEnv,
}

impl Prepare {
    /// Upper bound of [`TraceCtx::thread_index`] during queries: size
    /// per-thread state (mailboxes) with it.
    pub fn max_threads(&self) -> u32 {
        self.env.max_threads
    }

    /// Read a whole file, telling the host (its `--stats` list the files
    /// read). Only a regular file of at most [`MAX_FILE_BYTES`] is read: a
    /// FIFO would block the build forever and `/dev/zero` would fill memory,
    /// so both are refused, with a message saying what the path is.
    pub fn read_file(&self, path: &std::path::Path) -> std::io::Result<Vec<u8>> {
        use std::io::{Error, ErrorKind, Read};
        shims::note_file(&self.env, &path.to_string_lossy());
        let meta = std::fs::metadata(path)?;
        if !meta.is_file() {
            let what = if meta.is_dir() {
                "a folder"
            } else {
                "a device, FIFO or socket"
            };
            return Err(Error::new(
                ErrorKind::InvalidInput,
                format!("it is {what}, not a regular file"),
            ));
        }
        if meta.len() > MAX_FILE_BYTES {
            return Err(Error::new(
                ErrorKind::InvalidInput,
                format!(
                    "it is {} bytes, more than the {MAX_FILE_BYTES} a plugin reads",
                    meta.len()
                ),
            ));
        }
        let mut out = Vec::new();
        std::fs::File::open(path)?
            .take(MAX_FILE_BYTES + 1)
            .read_to_end(&mut out)?;
        if out.len() as u64 > MAX_FILE_BYTES {
            return Err(Error::new(
                ErrorKind::InvalidInput,
                "it grew while being read",
            ));
        }
        Ok(out)
    }

    /// Run `f(i)` for `i < n` on the host's thread pool (plugins must not start
    /// pools of their own). A panic in `f` is re-raised here after all tasks end.
    pub fn parallel_for<F: Fn(u64) + Sync>(&self, n: u64, f: F) {
        shims::parallel_for(&self.env, n, f)
    }
}

/// Largest file [`Prepare::read_file`] reads: 4 GiB (a mesh of ~100 M
/// triangles in binary PLY); larger inputs are refused rather than risk the
/// machine's memory.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// What every plugin has: parameters parsed from the scene (unknown keys
/// refused with `#[serde(deny_unknown_fields)]`) and a constructor. One
/// generic `create` entry serves every kind through this trait.
pub trait Plugin: Send + Sync + Sized + 'static {
    /// Parameters, parsed from the scene's table for this definition.
    type Params: DeserializeOwned;
    /// Create from parameters. Bulk data (meshes) is read in `prepare`, only
    /// if the object is reachable.
    fn create(params: Self::Params, env: &Env) -> Result<Self, PluginError>;
}

/// An object class: primitive, aggregate or transform.
///
/// Required: `bounds`, `intersect`, `local_geom`. Defaulted: `occluded` (an
/// `intersect` into a scratch record: override it to stop at the first hit),
/// `add_child` (refuses children: primitives), `prepare` (nothing to build).
/// After [`prepare`](Object::prepare) the object is immutable and every query
/// may be called from many threads at once (hence `Send + Sync`).
pub trait Object: Plugin {
    /// The paper's "instance": add a child (aggregates and operators).
    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        let _ = child;
        Err(PluginError::key("children", "this class takes no children"))
    }

    /// The paper's "close": build after every child was added. Children are
    /// prepared before their parents, so their bounds are known here.
    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        let _ = env;
        Ok(())
    }

    /// Box over `[time0, time1]` in the object's own space. An aggregate
    /// computes it in `prepare` (where a child's failure can be reported) and
    /// returns it here.
    fn bounds(&self, time0: f32, time1: f32) -> Bounds3;

    /// Nearest hit in `(ray.t_min, ray.t_max)`: on success write `hit.t` and
    /// `hit.stack[level..]`, set `hit.depth`, and return true. Ties at equal
    /// `t` go to the lowest (child, primitive).
    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool;

    /// Any hit in `(ray.t_min, ray.t_max)`.
    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        self.intersect(ctx, ray, &mut Hit::new(), level)
    }

    /// Local geometry of the hit in `hit.stack[level..]`: fill the fields
    /// `mask` asks for (more is allowed) and say which in `out.filled`.
    fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    );

    /// The paper's fifth operation: is `p` (own space) inside the object
    /// at `time`? A closed object answers [`Interior::INSIDE`] or
    /// [`Interior::OUTSIDE`]; the default, [`Interior::NONE`], says it has no
    /// interior (open surfaces, flat shapes). Points closer to the surface
    /// than its position error bound may be answered either way; farther
    /// ones must agree with the parity of `intersect` along any ray from
    /// them (`rtk conform` checks it).
    fn in_interior(&self, ctx: &mut TraceCtx, p: Vec3, time: f32) -> Interior {
        let _ = (ctx, p, time);
        Interior::NONE
    }

    /// Nearest hits of a batch of rays (ray streams): ray `i` when bit `i`
    /// of `active` is set, into `hits[i]`; the mask of those that hit. The
    /// default asks [`intersect`](Object::intersect) ray by ray; an
    /// aggregate that finds them together (packets) must give the same
    /// answers, bit for bit (`rtk conform` checks it).
    fn intersect_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &mut [Hit],
        active: u64,
        level: u32,
    ) -> u64 {
        let mut found = 0;
        for i in batch::lanes(active, rays.len().min(hits.len())) {
            if self.intersect(ctx, &rays[i], &mut hits[i], level) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Any hit for each active ray of a batch; the mask of those occluded.
    /// The default asks [`occluded`](Object::occluded) ray by ray.
    fn occluded_batch(&self, ctx: &mut TraceCtx, rays: &[Ray], active: u64, level: u32) -> u64 {
        let mut found = 0;
        for i in batch::lanes(active, rays.len()) {
            if self.occluded(ctx, &rays[i], level) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Local geometry of each active hit of a batch, into `out[i]`. The
    /// default asks [`local_geom`](Object::local_geom) hit by hit.
    #[allow(clippy::too_many_arguments)]
    fn local_geom_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &[Hit],
        active: u64,
        level: u32,
        mask: u32,
        out: &mut [LocalGeom],
    ) {
        for i in batch::lanes(active, rays.len().min(hits.len()).min(out.len())) {
            self.local_geom(ctx, &rays[i], &hits[i], level, mask, &mut out[i]);
        }
    }
}

/// Capability: the primitive-set protocol. An aggregate over this object may
/// build its own structure over the primitives (in the object's space) and
/// query them in batches, one call per leaf.
pub trait PrimitiveSet: Object {
    /// Number of primitives.
    fn prim_count(&self) -> u32;
    /// Boxes of primitives `first..first + out.len()` (a range beyond the
    /// count is a caller's error: panic with a message).
    fn prim_bounds(&self, first: u32, out: &mut [Bounds3]);
    /// Nearest hit among `ids`; writes `hit.stack[level]` as `intersect` would.
    fn intersect_prims(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        ids: &[u32],
        hit: &mut Hit,
        level: u32,
    ) -> bool;
    /// Any hit among `ids`.
    fn occluded_prims(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], level: u32) -> bool {
        self.intersect_prims(ctx, ray, ids, &mut Hit::new(), level)
    }
}

/// Capability: triangles as data. The object lends its vertex positions and
/// index triples (triangle `i` is primitive `i`), so an aggregate can store
/// and intersect them itself, inline, with the kernel's watertight routine,
/// instead of calling `intersect_prims` once per leaf. Its `local_geom` must
/// read the hit record an aggregate writes for it (see
/// [`TriangleData`]): `hit.entry(level).prim` and
/// `.uv = [b1, b2]`, which is what [`Hit::record_leaf`] writes too.
pub trait Triangles: PrimitiveSet {
    /// Positions and index triples, unchanged after `prepare`.
    fn triangles(&self) -> TriangleSlices<'_>;
}

/// What [`Triangles::triangles`] lends.
#[derive(Clone, Copy, Debug)]
pub struct TriangleSlices<'a> {
    /// Vertex positions.
    pub positions: &'a [[f32; 3]],
    /// Vertex indices of each triangle, below `positions.len()`.
    pub indices: &'a [[u32; 3]],
}

/// Capability (a marker): this aggregate builds its own structure over its
/// children's primitives (through [`Child::prim_set`]). The shell then adds
/// an object that offers the primitive-set protocol to it as is, not wrapped
/// in that object's own acceleration structure (the `accel` key).
pub trait FlattensPrimitives: Object {}

/// Capability: creation from a transform the shell composed and checked.
/// Capability: points on the surface, uniform by area in the object's own
/// space, so the object can be an area light under any transform (the host
/// converts the density through the transform's area Jacobian).
pub trait SampleSurface: Object {
    /// The surface's total area, own space (0: no surface to sample).
    fn area(&self) -> f32;
    /// A point for `u` ∈ [0, 1)², uniform by area, with its geometric
    /// normal facing as `local_geom`'s `ng` does.
    fn sample_point(&self, u: [f32; 2]) -> Option<(glam::Vec3, glam::Vec3)>;
    /// The entry itself: [`sample_point`](Self::sample_point) with the
    /// area, none for an object without area. Override only to do both at once.
    fn sample_surface(&self, ctx: &mut TraceCtx, u: [f32; 2]) -> Option<SurfaceSample> {
        let _ = ctx;
        let area = self.area();
        if !(area > 0.0) {
            return None;
        }
        self.sample_point(u).map(|(p, n)| SurfaceSample {
            p: p.into(),
            n: n.into(),
            area,
        })
    }
}

/// Capability: the paper's bounding volumes beyond the box (`inq_bounds`).
///
/// Every method is optional: answer the kinds you bound tighter than your
/// box (a sphere for a sphere or a torus, hull points for a mesh or a
/// polygon, slabs for anything whose plane-set volume you can compute
/// exactly). For a kind you leave out, callers derive one from what you
/// do answer, or from the box: a sphere around the box, the box's corners
/// as hull points, slabs from the hull points (see [`Child::slabs`]).
/// Every volume must contain the object over `[time0, time1]`, in its own
/// space, after rounding: build them with the kernel's outward-rounding
/// constructors ([`BoundSphere::around_points`](rtk_geom::SphereVolume::around_points),
/// [`SlabBounds::from_points`](rtk_geom::SlabVolume::from_points)).
pub trait BoundingVolumes: Object {
    /// A sphere containing the object.
    fn bound_sphere(&self, time0: f32, time1: f32) -> Option<rtk_abi::BoundSphere> {
        let _ = (time0, time1);
        None
    }
    /// Points whose convex hull contains the object (a mesh's vertices).
    fn hull_points(&self, time0: f32, time1: f32) -> Option<std::borrow::Cow<'_, [[f32; 3]]>> {
        let _ = (time0, time1);
        None
    }
    /// Kay–Kajiya slabs containing the object.
    fn slabs(&self, time0: f32, time1: f32) -> Option<rtk_abi::SlabBounds> {
        let _ = (time0, time1);
        None
    }

    /// The entry itself: the volume of `kind` into `out` (and
    /// `out.written`), from the three methods above. Override only to
    /// answer all kinds at once.
    fn inq_bounds(
        &self,
        kind: u32,
        time0: f32,
        time1: f32,
        hull: &mut [[f32; 3]],
        out: &mut BoundingVolume,
    ) -> Result<(), PluginError> {
        out.written = false;
        match kind {
            bound_kind::SPHERE => {
                if let Some(s) = self.bound_sphere(time0, time1) {
                    out.sphere = s;
                    out.written = true;
                }
            }
            bound_kind::SLABS => {
                if let Some(s) = self.slabs(time0, time1) {
                    out.slabs = s;
                    out.written = true;
                }
            }
            bound_kind::HULL => {
                if let Some(pts) = self.hull_points(time0, time1) {
                    out.hull_len = u32::try_from(pts.len())
                        .map_err(|_| PluginError::msg("more than 2^32 hull points"))?;
                    let n = pts.len().min(hull.len());
                    hull[..n].copy_from_slice(&pts[..n]);
                    out.written = true;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// The class named by [`crate::classes::INSTANCE_TRANSFORM`] offers it.
pub trait FromTransform: Object {
    /// Create from the object-to-parent transform (f64, finite, well conditioned).
    fn from_transform(m: glam::DAffine3, env: &Env) -> Result<Self, PluginError>;
}

/// A shader: answers material queries for the integrator.
pub trait Shader: Plugin {
    /// The [`lobe`] kinds this material has (reflection, transmission,
    /// diffuse, glossy, specular), asked once; integrators skip queries for
    /// lobes it lacks. The default, every lobe, is always correct.
    fn lobes(&self) -> u32 {
        lobe::ALL
    }
    /// BSDF value f(wo, wi), cosine not included; both directions are unit
    /// and point away from the surface.
    fn eval(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: glam::Vec3, wi: glam::Vec3) -> Color;
    /// Sample `wi` among the lobes `lobes` allows ([`lobe`] bits); `None` when
    /// there is no such lobe. The default offers none. (Set
    /// [`BsdfSample::eta`] on a transmission; 0 reads as 1.)
    fn sample(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        let _ = (ctx, geom, wo, u, lobes);
        None
    }
    /// Density (solid angle) with which [`Shader::sample`], restricted to
    /// `lobes`, returns `wi`; 0 where only delta lobes could. `None` (the
    /// default) says the shader cannot tell: a path tracer then does not
    /// weight this material's samples by MIS (it counts light found by its
    /// BSDF samples only through next-event estimation), which is unbiased
    /// but noisier for glossy materials.
    fn pdf(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        wi: glam::Vec3,
        lobes: u32,
    ) -> Option<f32> {
        let _ = (ctx, geom, wo, wi, lobes);
        None
    }
    /// Radiance emitted towards `wo`. Asked only when [`Shader::lobes`] has
    /// [`lobe::EMISSION`]: a shader that emits must say so there, which also
    /// makes every instance it is bound to an area light.
    fn emitted(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: glam::Vec3) -> Color {
        let _ = (ctx, geom, wo);
        Color::BLACK
    }
}

/// Capability: shading as a whole, in place of the integrator's use of the
/// material queries (the paper's shaders cast their own rays).
pub trait Shade: Shader {
    /// Radiance leaving the hit towards `-ray.dir`.
    fn shade(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray, geom: &LocalGeom) -> Color;
}

/// An integrator: the radiance along each camera ray.
pub trait Integrator: Plugin {
    /// Radiance arriving along `-ray.dir` at `ray.origin`.
    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray) -> Color;

    /// The radiance along each of a batch of camera rays (ray streams),
    /// `rngs[i]` being ray `i`'s random stream, into `out[i]`. The default
    /// runs [`li`](Integrator::li) ray by ray with each stream in the
    /// context; an integrator that advances the paths together must give
    /// the same answers, bit for bit, drawing each path's numbers from its
    /// own stream in the order `li` would.
    fn li_batch(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        rays: &[Ray],
        rngs: &mut [RngState],
        out: &mut [Color],
    ) {
        let saved = ctx.rng;
        for ((ray, rng), o) in rays.iter().zip(rngs.iter_mut()).zip(out.iter_mut()) {
            ctx.rng = *rng;
            *o = self.li(ctx, scene, ray);
            *rng = ctx.rng;
        }
        ctx.rng = saved;
    }
}

/// A camera.
pub trait Camera: Plugin {
    /// A world-space ray (unit direction) for the sample and its weight;
    /// `None` when the sample sees nothing.
    fn generate_ray(&self, ctx: &mut TraceCtx, sample: &CameraSample) -> Option<CameraRay>;
}

/// A light.
pub trait Light: Plugin {
    /// Sample incident light at `p`; `None` when the light contributes nothing.
    fn sample_li(
        &self,
        ctx: &mut TraceCtx,
        p: glam::Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample>;

    /// [`sample_li`](Light::sample_li) for each active point of a batch,
    /// into `out[i]`; the mask of the points that got a sample. The default
    /// asks point by point.
    fn sample_li_batch(
        &self,
        ctx: &mut TraceCtx,
        p: &[Float3],
        u: &[[f32; 2]],
        time: &[f32],
        active: u64,
        out: &mut [LightSample],
    ) -> u64 {
        let n = p.len().min(u.len()).min(time.len()).min(out.len());
        let mut got = 0;
        for i in batch::lanes(active, n) {
            if let Some(s) = self.sample_li(ctx, p[i].v(), u[i], time[i]) {
                out[i] = s;
                got |= 1 << i;
            }
        }
        got
    }
}

/// Capability: the light surrounds the scene, so rays that leave it find
/// its radiance (a scene has at most one environment light).
pub trait Environment: Light {
    /// Radiance arriving from direction `dir` (unit, towards the light).
    fn le(&self, ctx: &mut TraceCtx, dir: glam::Vec3) -> Color;
    /// Density (solid angle) with which [`Light::sample_li`] returns `wi`.
    fn pdf_li(&self, ctx: &mut TraceCtx, p: glam::Vec3, wi: glam::Vec3) -> f32;
}

/// Capability: the light is an emitting instance's surface (an area light).
/// The shell creates one such light per emitting instance and binds the
/// instance to it before rendering; hits on the instance report this light
/// ([`LocalGeom::light`]), and multiple importance sampling asks it for the
/// density of a hit ([`Area::pdf_hit`]).
pub trait Area: Light {
    /// Take the emitting instance this light stands for: its object, its
    /// placement in the renderer's space and its shader (kept as long as
    /// the light likes: the handles are counted).
    fn bind_emitter(&mut self, emitter: Emitter) -> Result<(), PluginError>;
    /// Density (solid angle) with which [`Light::sample_li`] from `p` would
    /// have produced `ray`, which hit this light's surface at `geom`.
    fn pdf_hit(&self, ctx: &mut TraceCtx, p: glam::Vec3, ray: &Ray, geom: &LocalGeom) -> f32;
}

/// Export an object class:
/// `export_object!(MyType, class = "name", doc = include_str!("../README.md"));`,
/// with `capabilities = [PrimitiveSet, FromTransform]` for what it offers.
#[macro_export]
macro_rules! export_object {
    ($ty:ty, class = $class:literal, doc = $doc:expr
     $(, capabilities = [$($cap:ident),* $(,)?])? $(,)?) => {
        $crate::__export_plugin!(Object, ObjectModuleRef, object, $ty, $class, $doc,
                                 [$($($cap),*)?]);
    };
}

/// Export a shader. Same form as [`export_object!`]; capability: `Shade`.
#[macro_export]
macro_rules! export_shader {
    ($ty:ty, class = $class:literal, doc = $doc:expr
     $(, capabilities = [$($cap:ident),* $(,)?])? $(,)?) => {
        $crate::__export_plugin!(Shader, ShaderModuleRef, shader, $ty, $class, $doc,
                                 [$($($cap),*)?]);
    };
}

/// Export an integrator. Same form as [`export_object!`].
#[macro_export]
macro_rules! export_integrator {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(
            Integrator,
            IntegratorModuleRef,
            integrator,
            $ty,
            $class,
            $doc,
            []
        );
    };
}

/// Export a camera. Same form as [`export_object!`].
#[macro_export]
macro_rules! export_camera {
    ($ty:ty, class = $class:literal, doc = $doc:expr $(,)?) => {
        $crate::__export_plugin!(Camera, CameraModuleRef, camera, $ty, $class, $doc, []);
    };
}

/// Export a light. Same form as [`export_object!`]; capabilities:
/// `Environment`, `Area`.
#[macro_export]
macro_rules! export_light {
    ($ty:ty, class = $class:literal, doc = $doc:expr
     $(, capabilities = [$($cap:ident),* $(,)?])? $(,)?) => {
        $crate::__export_plugin!(Light, LightModuleRef, light, $ty, $class, $doc,
                                 [$($($cap),*)?]);
    };
}

/// The shared expansion of the `export_*!` macros: the plain header read
/// before any plugin code runs, and abi_stable's root-module loader under its
/// mangled name (what `#[export_root_module]` would emit, spelled with
/// `$crate` paths so plugins need no direct abi_stable dependency). Each named
/// capability fills its optional entries through [`Install`].
#[doc(hidden)]
#[macro_export]
macro_rules! __export_plugin {
    ($kind:ident, $module:ident, $build:ident, $ty:ty, $class:literal, $doc:expr,
     [$($cap:ident),*]) => {
        #[doc(hidden)]
        pub struct __RtkPlugin;
        impl $crate::Decl for __RtkPlugin {
            const CLASS: &'static str = $class;
            const DOC: &'static str = $doc;
            const VERSION: &'static str = env!("CARGO_PKG_VERSION");
        }
        impl $crate::ModuleSource for __RtkPlugin {
            type Module = $crate::abi::$module;
            fn module() -> Self::Module {
                #[allow(unused_mut)]
                let mut m = $crate::shims::$build::module::<$ty, __RtkPlugin>();
                $( $crate::Install::<$ty, __RtkPlugin>::$cap(&mut m); )*
                $crate::leak(m)
            }
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
            $crate::lib_header::<__RtkPlugin>();
    };
}
