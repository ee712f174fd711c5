//! # rtk-kernel
//!
//! The kernel of rtk, after Kirk and Arvo's "The Ray Tracing Kernel" (1988):
//! one small crate of interface definitions, against which every object class,
//! shader, integrator, camera and light is built as a plugin.
//!
//! - [`abi`]: the `#[repr(C)]` records that cross the plugin boundary: the
//!   object-class record (the paper's create / add child / prepare /
//!   intersect / local geometry / bounds / interior operations, plus `occluded`
//!   and the primitive-set protocol), the ray, the hit-info stack, the local
//!   geometry with its request mask, the trace context, and the root modules
//!   of each plugin kind. They derive `StableAbi`, so the host's load check
//!   names the first field whose layout differs.
//! - [`sdk`]: the safe side for plugin authors: a trait per kind, one export
//!   macro, no `unsafe` in plugin crates, every entry under `catch_unwind`.
//! - [`geom`]: the robust geometric routines (RTG ch. 7 sphere, conservative
//!   slab test, error-bound ray offsets), generic over f32 and f64 so the f64
//!   reference and the stress tests share one implementation.
//!
//! Aggregates are objects like any other: an aggregate reaches its children
//! only through their records, so any acceleration structure nests inside any
//! other (the paper's meta-hierarchy).
#![deny(missing_docs)]
#![deny(clippy::missing_safety_doc)]

pub mod abi;
pub mod geom;
pub mod sdk;
mod values;
pub mod xform;

pub use abi::*;
pub use glam;
pub use sdk::{
    check_finite, parse_params, Camera, Child, Env, Integrator, Light, Object, PluginError,
    Prepare, PrimSet, Scene, Shader,
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
