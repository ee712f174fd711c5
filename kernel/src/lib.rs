//! # rtk-kernel
//!
//! The kernel of rtk, after Kirk and Arvo's "The Ray Tracing Kernel" (1988):
//! one small crate of interface definitions, against which every object class,
//! shader, integrator, camera and light is built as a plugin.
//!
//! - [`abi`]: the `#[repr(C)]` records that cross the plugin boundary. Every
//!   entry is an `unsafe extern "C" fn`; the records derive `StableAbi`, so the
//!   host's load check names the first field whose layout differs.
//! - [`sdk`]: the plugin side: a safe trait per kind, capabilities as traits,
//!   one export macro. Plugin crates contain no `unsafe` and cannot reach a
//!   raw record.
//! - [`host`]: the host side: owned handles with safe methods, and the
//!   services trait the scene record is built from.
//! - [`geom`]: the robust geometric routines (watertight triangle, RTG ch. 7
//!   sphere, conservative slab test, error-bound ray offsets), generic over
//!   f32 and f64 so the f64 reference and the stress tests share one
//!   implementation.
//! - [`accel`]: what aggregates share: children flattened into primitives
//!   with the list's exact answer, the codebase's one BVH, mailboxes.
//! - [`xform`]: affine transforms composed in f64 and checked.
//! - [`classes`]: the class names the shell itself must name.
//!
//! Aggregates are objects like any other: an aggregate reaches its children
//! only through their records, so any acceleration structure nests inside any
//! other (the paper's meta-hierarchy).
#![deny(missing_docs)]
#![deny(clippy::missing_safety_doc)]

pub mod abi;
pub mod accel;
pub mod classes;
pub mod geom;
pub mod host;
pub mod sdk;
mod values;
pub mod xform;

pub use abi::values::{
    bound_kind, geom_mask, light_flag, lobe, ray_kind, BoundSphere, Bounds3, BsdfSample,
    CameraSample, Color, Float3, Hit, HitEntry, InstanceData, LightSample, LocalGeom, Ray,
    SlabBounds, SurfaceSample, HIT_STACK_DEPTH, NONE_ID, SLAB_COUNT, SLAB_NORMALS,
};
pub use abi::{RngState, Stats, TraceCtx};
pub use glam;
pub use sdk::params::{self, parse_params};
pub use sdk::{
    BoundingVolumes, Camera, Child, Env, Environment, FlattensPrimitives, FromTransform,
    Integrator, Light, Material, Object, Plugin, PluginError, Prepare, PrimSet, PrimitiveSet,
    SampleSurface, Scene, Shade, Shader, TriangleSlices, Triangles,
};
pub use serde;

/// Re-exports the export macros need (plugins do not depend on abi_stable).
#[doc(hidden)]
pub mod reexports {
    pub use abi_stable;
    pub use abi_stable::library::LibHeader;
}

/// Version of this kernel crate; plugins record the one they were built against.
pub const KERNEL_VERSION: &str = env!("CARGO_PKG_VERSION");

#[cfg(test)]
mod tests {
    #[test]
    fn export_macro_uses_abi_stables_loader_symbol() {
        assert_eq!(
            abi_stable::library::ROOT_MODULE_LOADER_NAME,
            "_1as_0lib_1header_0root_bmodule_bloader"
        );
    }
}
