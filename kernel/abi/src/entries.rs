//! Every entry of the boundary, declared once.
//!
//! Each `*_entries!` macro below holds one record's entries — name, raw
//! arguments, calling convention, documentation — and hands them to a
//! generator. Three generators read the same declarations:
//!
//! - [`__record!`](crate::__record) (this crate) writes the `#[repr(C)]`
//!   prefix record abi_stable checks at load;
//! - `rtk_sdk::__shims!` writes, for the side that implements the record,
//!   the `unsafe extern "C"` shim of each entry (pointers back into
//!   references, `catch_unwind`, the failure recorded in the trace context
//!   or the error sink), the record builder, and the `Install` method of
//!   each capability;
//! - `rtk_sdk::__callers!` writes, for the side that calls the record, one
//!   safe method per entry on a handle that vouches for the object being
//!   alive (`LiveObject` and friends), which both the plugin side (an
//!   aggregate's `Child`) and the host side (`rtk-handles`) use.
//!
//! So adding an entry is one declaration here, one trait method (with its
//! default) in the SDK, and a test; `docs/design.md` walks through it.
//!
//! # The declaration language
//! An entry is
//!
//! ```text
//! /// docs
//! TEMP NAME(RECV, (arg: RawType), ...) -> FORM [Type] (= fallback);
//! ```
//!
//! - `TEMP` is the calling convention. `hot`: a query on the render path —
//!   it takes the per-thread [`TraceCtx`](crate::TraceCtx) after `this`,
//!   allocates nothing, and a panic is recorded in the context with the
//!   plugin's class (the entry then returns `fallback`). `cold`: a call
//!   outside the render loop (create-time, prepare-time, bounds) — it takes
//!   an [`ErrSink`](crate::ErrSink) last and returns a status. `pure`: a
//!   host service with no context (never panics by design). `ctor`: a
//!   second constructor, like `create`.
//! - `RECV` is `const` or `mut`: `this` is `*const c_void` (queries: the
//!   object is immutable after `prepare` and shared by threads) or
//!   `*mut c_void` (building: the caller has the object to itself). A
//!   `ctor` writes `new`: it has no `this`, and returns the new object.
//! - Arguments are written with their raw types. Pointers are valid for the
//!   call; the implementing side sees `*const T` as `&T` (or `Option<&T>`
//!   when the callee's method takes one), `*mut T` as `&mut T`,
//!   [`Nullable<T>`](crate::Nullable) (a `*const T` that may be null) as
//!   `Option<&T>`, [`Span<T>`](crate::Span) as `&[T]`, [`SpanMut<T>`](crate::SpanMut) as
//!   `&mut [T]`, and plain values as themselves or their safe form
//!   (`Float3` as `glam::Vec3`, `ChildRef` as `Child`).
//! - `FORM [Type]` is what comes back. `plain [T] = fallback`: a value.
//!   `unit []`: nothing. `option [T]`: the raw entry writes `*mut T` (an
//!   appended `out` argument) and returns whether it did — `Option<T>` on
//!   both safe sides. `status []` (cold): success or an error in the sink.
//!   `unit []` (cold): the same raw entry for a method that cannot fail
//!   (but by panicking).
//!   `value [T]` (cold): an infallible answer written to `out`. `result [T]`
//!   (cold): a fallible one.
//!
//! # Sections
//! A record lists, in this order: `entries` (always offered), `caps` (one
//! group per capability trait a plugin names in its export macro; each
//! entry is `Option`al), `flags` (a `bool` a capability sets), then the
//! stable prefix ends (`abi_minor`, abi_stable's `last_prefix_field`) and
//! `appended` entries follow, each `Option`al and read as absent from a
//! plugin built before it. Nothing above `abi_minor` ever changes within an
//! ABI version; a new entry goes at the end of `appended` (or a new group
//! of `appended_caps`) with a minor version bump of this crate.

/// The object class record: primitives, aggregates, transforms, CSG.
/// Aggregates and primitives share it, so any aggregate nests in any other.
#[macro_export]
macro_rules! object_entries {
    ($gen:path $(, $cfg:tt)*) => {
        $gen! {
            config [$($cfg)*]
            kind Object, module ObjectModule, prefix ObjectModuleRef, trait Object;
            entries {
                /// The paper's "instance": add a child with its instance
                /// data. The child arrives counted ([`ChildRef`]): the object
                /// holds it, and it outlives every use the object makes of it.
                cold add_child(mut, (child: ChildRef)) -> status [];
                /// The paper's "close": build after every child was added.
                /// After this the object is immutable and every query must be
                /// safe to call concurrently.
                cold prepare(mut, (env: *const PrepareEnv)) -> status [];
                /// The paper's "inquire bounds" for the box: an axis-aligned
                /// box over the time interval `[time0, time1]`, in the
                /// object's own space; valid after `prepare`.
                cold bounds(const, (time0: f32), (time1: f32)) -> value [Bounds3];
                /// Nearest hit in `(ray.t_min, ray.t_max)`; on success writes
                /// `hit.t`, `hit.stack[level..]`, `hit.uv` and `hit.depth`.
                hot intersect(const, (ray: *const Ray), (hit: *mut Hit), (level: u32)) -> plain [bool] = false;
                /// Any hit in `(ray.t_min, ray.t_max)` (shadow rays): no
                /// nearest search, no hit record.
                hot occluded(const, (ray: *const Ray), (level: u32)) -> plain [bool] = false;
                /// Local geometry of the hit recorded in `hit.stack[level..]`,
                /// fields per `mask` (computed only for the hit that is shaded).
                hot local_geom(const, (ray: *const Ray), (hit: *const Hit), (level: u32), (mask: u32), (out: *mut LocalGeom)) -> unit [];
                /// The paper's fifth operation, "in interior": is the point
                /// `p` (own space) inside the object at `time`. Closed
                /// objects answer inside or outside; open ones, and classes
                /// that do not say, [`Interior::NONE`].
                hot in_interior(const, (p: Float3), (time: f32)) -> plain [Interior] = Interior::NONE;
            }
            caps {
                /// Creation from a transform the shell composed (the class
                /// the shell wraps transformed instances in offers it): typed
                /// data, not parameter text.
                FromTransform {
                    /// Create from an object-to-parent transform.
                    ctor from_transform(new, (m: *const Affine3x4)) -> status [];
                }
                /// The primitive-set protocol: an aggregate over the object
                /// builds its own structure over its primitives, in the
                /// object's space, and queries them one batched call per leaf.
                PrimitiveSet {
                    /// Number of primitives.
                    cold prim_count(const) -> value [u32];
                    /// Boxes of primitives `first..first + out.len()`, own space.
                    cold prim_bounds(const, (first: u32), (out: SpanMut<Bounds3>)) -> unit [];
                    /// Nearest hit among the listed primitives; writes
                    /// `hit.stack[level]` as `intersect` would.
                    hot intersect_prims(const, (ray: *const Ray), (ids: Span<u32>), (hit: *mut Hit), (level: u32)) -> plain [bool] = false;
                    /// Any hit among the listed primitives.
                    hot occluded_prims(const, (ray: *const Ray), (ids: Span<u32>), (level: u32)) -> plain [bool] = false;
                }
                /// Triangles as data: the object lends its vertex positions
                /// and index triples ([`TriangleData`]), so an aggregate
                /// intersects them inline in its own layout.
                Triangles {
                    /// The triangles, valid and unchanged for the object's life.
                    cold triangles(const) -> value [TriangleData];
                }
                /// Points on the surface, uniform by area in the object's own
                /// space: the object can be an area light under any transform.
                SampleSurface {
                    /// A point for `u` ∈ [0, 1)² with its normal and the
                    /// object's total area; none when it has no area.
                    hot sample_surface(const, (u: [f32; 2])) -> option [SurfaceSample];
                }
                /// The paper's bounding volumes beyond the box.
                BoundingVolumes {
                    /// Write the volume of `kind` ([`bound_kind`]: sphere,
                    /// hull points, slabs) over `[time0, time1]`, own space,
                    /// and set `out.written`; leave it unset for a kind not
                    /// offered (the caller derives one from the box). Hull
                    /// points go into `hull`, as many as fit.
                    cold inq_bounds(const, (kind: u32), (time0: f32), (time1: f32), (hull: SpanMut<[f32; 3]>), (out: *mut BoundingVolume)) -> status [];
                }
            }
            flags {
                /// The class builds its own structure over its children's
                /// primitives (`bvh`, `grid`...): the shell adds a primitive
                /// set to it as is, not wrapped in its own structure.
                FlattensPrimitives flattens_primitives;
            }
            appended {
                /// Ray streams (ABI 3.1). Nearest hits of a batch of at most
                /// 64 rays: ray `i` is asked, as `intersect` would ask it,
                /// when bit `i` of `active` is set, its hit written to
                /// `hits[i]`; returns the mask of the rays that hit. The
                /// answers are `intersect`'s, bit for bit; an aggregate may
                /// find them together (packets).
                hot intersect_batch(const, (rays: Span<Ray>), (hits: SpanMut<Hit>), (active: u64), (level: u32)) -> plain [u64] = 0;
                /// Any hit for each active ray of a batch (shadow rays);
                /// returns the mask of the rays occluded.
                hot occluded_batch(const, (rays: Span<Ray>), (active: u64), (level: u32)) -> plain [u64] = 0;
                /// Local geometry of each active hit of a batch, as
                /// `local_geom` would give it, into `out[i]`.
                hot local_geom_batch(const, (rays: Span<Ray>), (hits: Span<Hit>), (active: u64), (level: u32), (mask: u32), (out: SpanMut<LocalGeom>)) -> unit [];
            }
            appended_caps {}
        }
    };
}

/// The shader record: material queries for integrators, and optionally
/// shading as a whole (the paper's shaders cast their own rays).
#[macro_export]
macro_rules! shader_entries {
    ($gen:path $(, $cfg:tt)*) => {
        $gen! {
            config [$($cfg)*]
            kind Shader, module ShaderModule, prefix ShaderModuleRef, trait Shader;
            entries {
                /// The [`lobe`] kinds this shader has (asked once, after `create`).
                cold lobes(const) -> value [u32];
                /// BSDF value f(wo, wi), cosine not included; both directions
                /// unit, pointing away from the surface.
                hot eval(const, (geom: *const LocalGeom), (wo: Float3), (wi: Float3)) -> plain [Color] = Color::BLACK;
                /// Sample `wi` from the lobes `lobes` (a [`lobe`] mask) allows;
                /// none when no such lobe exists or the sample carries nothing.
                hot sample(const, (geom: *const LocalGeom), (wo: Float3), (u: [f32; 2]), (lobes: u32)) -> option [BsdfSample];
                /// Density (solid angle) with which `sample`, restricted to
                /// `lobes`, returns `wi`; 0 for delta lobes; none when the
                /// shader cannot tell (then an integrator must not weight its
                /// samples by MIS).
                hot pdf(const, (geom: *const LocalGeom), (wo: Float3), (wi: Float3), (lobes: u32)) -> option [f32];
                /// Radiance emitted towards `wo`; asked only of a shader whose
                /// `lobes` has [`lobe::EMISSION`].
                hot emitted(const, (geom: *const LocalGeom), (wo: Float3)) -> plain [Color] = Color::BLACK;
            }
            caps {
                /// Shading as a whole, in place of the integrator's use of
                /// the material queries.
                Shade {
                    /// Radiance leaving the hit towards `-ray.dir`.
                    hot shade(const, (scene: *const SceneRef), (ray: *const Ray), (geom: *const LocalGeom)) -> plain [Color] = Color::BLACK;
                }
            }
            flags {}
            appended {}
            appended_caps {}
        }
    };
}

/// The integrator record: the radiance of each camera ray.
#[macro_export]
macro_rules! integrator_entries {
    ($gen:path $(, $cfg:tt)*) => {
        $gen! {
            config [$($cfg)*]
            kind Integrator, module IntegratorModule, prefix IntegratorModuleRef, trait Integrator;
            entries {
                /// Radiance arriving along `-ray.dir` at `ray.origin`.
                hot li(const, (scene: *const SceneRef), (ray: *const Ray)) -> plain [Color] = Color::BLACK;
            }
            caps {}
            flags {}
            appended {
                /// Ray streams (ABI 3.1). The radiance along each of a batch
                /// of camera rays, `rngs[i]` being ray `i`'s random stream
                /// (what `li` would draw from the context's), into `out[i]`:
                /// the answers are `li`'s, bit for bit, however the paths are
                /// advanced (together, regrouped at every bounce).
                hot li_batch(const, (scene: *const SceneRef), (rays: Span<Ray>), (rngs: SpanMut<RngState>), (out: SpanMut<Color>)) -> unit [];
            }
            appended_caps {}
        }
    };
}

/// The camera record. Ray generation takes a film position, a lens sample
/// and a time sample, so depth of field and motion blur need no change to it.
#[macro_export]
macro_rules! camera_entries {
    ($gen:path $(, $cfg:tt)*) => {
        $gen! {
            config [$($cfg)*]
            kind Camera, module CameraModule, prefix CameraModuleRef, trait Camera;
            entries {
                /// A world-space ray (unit direction) and its weight; none
                /// when the sample sees nothing (outside a lens's aperture).
                hot generate_ray(const, (sample: *const CameraSample)) -> option [CameraRay];
            }
            caps {}
            flags {}
            appended {}
            appended_caps {}
        }
    };
}

/// The light record: delta lights, environments, and area lights bound to
/// an emitting instance.
#[macro_export]
macro_rules! light_entries {
    ($gen:path $(, $cfg:tt)*) => {
        $gen! {
            config [$($cfg)*]
            kind Light, module LightModule, prefix LightModuleRef, trait Light;
            entries {
                /// Sample the light seen from `p` at `time`; none when it
                /// contributes nothing there.
                hot sample_li(const, (p: Float3), (u: [f32; 2]), (time: f32)) -> option [LightSample];
            }
            caps {
                /// The light surrounds the scene: rays that leave it find
                /// its radiance (a scene has at most one).
                Environment {
                    /// Radiance arriving from direction `dir` (unit, towards the light).
                    hot le(const, (dir: Float3)) -> plain [Color] = Color::BLACK;
                    /// Density (solid angle) with which `sample_li` from `p` returns `wi`.
                    hot pdf_li(const, (p: Float3), (wi: Float3)) -> plain [f32] = 0.0;
                }
                /// The light is an emitting instance's surface: the shell
                /// binds the instance (its object, placement and shader)
                /// once, before rendering, and rays can hit it.
                Area {
                    /// Take the emitting instance this light stands for.
                    cold bind_emitter(mut, (emitter: EmitterRef)) -> status [];
                    /// Density (solid angle) with which `sample_li` from `p`
                    /// would have produced `ray`, which hit this light's
                    /// surface at `geom` (what MIS weighs a BSDF sample by).
                    hot pdf_hit(const, (p: Float3), (ray: *const Ray), (geom: *const LocalGeom)) -> plain [f32] = 0.0;
                }
            }
            flags {}
            appended {
                /// Ray streams (ABI 3.1). `sample_li` for each active point
                /// of a batch (at most 64), into `out[i]`; returns the mask
                /// of the points that got a sample.
                hot sample_li_batch(const, (p: Span<Float3>), (u: Span<[f32; 2]>), (time: Span<f32>), (active: u64), (out: SpanMut<LightSample>)) -> plain [u64] = 0;
            }
            appended_caps {}
        }
    };
}

/// The scene services: the kernel's `Trace` and what the host offers
/// integrators and shaders. The host implements this record and plugins
/// call it (the reverse of the others), through `rtk_sdk::Scene`.
#[macro_export]
macro_rules! scene_entries {
    ($gen:path $(, $cfg:tt)*) => {
        $gen! {
            config [$($cfg)*]
            kind Services, module SceneServices, prefix SceneServicesRef, trait Services;
            entries {
                /// `Trace(ray) -> color`: the integrator's radiance along the
                /// ray; `kind` is a [`ray_kind`] for the statistics.
                hot trace(const, (ray: *const Ray), (kind: u32)) -> plain [Color] = Color::BLACK;
                /// Nearest hit of the root; `kind` is a [`ray_kind`].
                hot intersect(const, (ray: *const Ray), (kind: u32), (hit: *mut Hit)) -> plain [bool] = false;
                /// Any hit of the root (shadow rays).
                hot occluded(const, (ray: *const Ray)) -> plain [bool] = false;
                /// Local geometry of a root hit, per mask; the root
                /// instance's bindings apply.
                hot local_geom(const, (ray: *const Ray), (hit: *const Hit), (mask: u32), (out: *mut LocalGeom)) -> unit [];
                /// Radiance of a ray that leaves the scene.
                hot background(const, (ray: *const Ray)) -> plain [Color] = Color::BLACK;
                /// Number of lights.
                pure light_count(const) -> plain [u32] = 0;
                /// The [`light_flag`] bits of light `index`.
                pure light_flags(const, (index: u32)) -> plain [u32] = 0;
                /// Sample light `index` from reference point `p` at `time`.
                hot sample_light(const, (index: u32), (p: Float3), (u: [f32; 2]), (time: f32)) -> option [LightSample];
                /// Density (solid angle, per light) with which sampling the
                /// light that `ray` found, from `p`, gives its direction:
                /// `geom` is the ray's hit on an emitting surface, or null
                /// when the ray left the scene (the environment light's
                /// density; 0 without one). The caller's own choice among
                /// the lights is not included.
                hot light_pdf(const, (p: Float3), (ray: *const Ray), (geom: Nullable<LocalGeom>)) -> plain [f32] = 0.0;
                /// The shader with id `shader` (from [`LocalGeom::shader`]).
                pure material(const, (shader: u32)) -> option [ShaderRef];
            }
            caps {}
            flags {}
            appended {
                /// Ray streams (ABI 3.1). Nearest hits of the root for a
                /// batch of at most 64 rays (bit `i` of `active`: ray `i`
                /// asked); returns the mask of those that hit.
                hot intersect_batch(const, (rays: Span<Ray>), (kind: u32), (hits: SpanMut<Hit>), (active: u64)) -> plain [u64] = 0;
                /// Any hit of the root for each active shadow ray of a
                /// batch; returns the mask of those occluded.
                hot occluded_batch(const, (rays: Span<Ray>), (active: u64)) -> plain [u64] = 0;
                /// Local geometry of each active root hit of a batch.
                hot local_geom_batch(const, (rays: Span<Ray>), (hits: Span<Hit>), (active: u64), (mask: u32), (out: SpanMut<LocalGeom>)) -> unit [];
                /// `sample_light` for each active point of a batch: light
                /// `index[i]` from `p[i]`, into `out[i]`; returns the mask of
                /// the points that got a sample.
                hot sample_light_batch(const, (index: Span<u32>), (p: Span<Float3>), (u: Span<[f32; 2]>), (time: Span<f32>), (active: u64), (out: SpanMut<LightSample>)) -> plain [u64] = 0;
            }
            appended_caps {}
        }
    };
}
