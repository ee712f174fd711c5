//! # rtk-kernel
//!
//! What an rtk plugin depends on, behind one dependency: after Kirk and
//! Arvo's "The Ray Tracing Kernel" (1988), a small set of interface
//! definitions against which every object class, shader, integrator, camera
//! and light is built as a plugin. The kernel is split by reason to change:
//!
//! - [`abi`] (`rtk-abi`): the `#[repr(C)]` records that cross the plugin
//!   boundary, the plain values, the plugin header and `ABI_VERSION`. Its
//!   version is the ABI's, and the only one the loader checks.
//! - [`sdk`] (`rtk-sdk`): the plugin side: a safe trait per kind,
//!   capabilities as traits, one export macro per kind, parameter parsing,
//!   shading helpers, image textures. Plugin crates contain no `unsafe` and
//!   cannot reach a raw record.
//! - [`geom`] (`rtk-geom`): the robust geometric routines, generic over f32
//!   and f64 so the f64 reference and the stress tests share one
//!   implementation.
//! - [`accel`] (`rtk-accel`): what aggregates share: children flattened into
//!   primitives with the list's exact answer, the BVH, mailboxes, the cell
//!   walk of grids, octrees and kd-trees. It belongs
//!   to the aggregates that use it, not to the interface: changing it is not
//!   an ABI event.
//!
//! The host side of the boundary (owned handles, the scene services) is
//! `rtk-handles`, which plugins never need.
//!
//! Aggregates are objects like any other: an aggregate reaches its children
//! only through their records, so any acceleration structure nests inside any
//! other (the paper's meta-hierarchy).
#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]

pub use rtk_abi as abi;
pub use rtk_abi::classes;
pub use rtk_accel as accel;
pub use rtk_geom as geom;
pub use rtk_sdk as sdk;
pub use rtk_sdk::xform;

pub use glam;
pub use rtk_abi::values::{
    bound_kind, geom_mask, light_flag, lobe, ray_kind, BoundSphere, BoundingVolume, Bounds3,
    BsdfSample, CameraRay, CameraSample, Color, Float3, Hit, InstanceData, Interior, LightSample,
    LocalGeom, Ray, SlabBounds, SurfaceSample, HIT_STACK_DEPTH, NONE_ID, SLAB_COUNT, SLAB_NORMALS,
};
pub use rtk_abi::{RngState, Stats, TraceCtx};
pub use rtk_geom::{SlabVolume, SphereVolume};
pub use rtk_sdk::params::{self, parse_params};
pub use rtk_sdk::{
    export_camera, export_integrator, export_light, export_object, export_shader, union_interior,
    AnalyticShape, Area, BoundingVolumes, Camera, Child, Emitter, Env, Environment,
    FlattensPrimitives, FromTransform, Integrator, Light, LiveObject, Material, Object, Plugin,
    PluginError, Prepare, PrimSet, PrimitiveSet, Root, SampleSurface, Scene, Shade, Shader,
    ShaderHandle, TriangleSlices, Triangles,
};
pub use serde;

/// Version of this crate, the one a plugin's `Cargo.toml` names. The loader
/// does not check it: it checks the ABI crate's (`abi::ABI_CRATE_VERSION`).
pub const KERNEL_VERSION: &str = env!("CARGO_PKG_VERSION");
