//! # rtk-handles
//!
//! The host side of the boundary: owned, safe handles to what plugins create,
//! and the host-services trait from which the scene record is built.
//!
//! The shell and the host never call a record entry themselves: they hold
//! [`ObjectBuilder`]s and [`Object`]s, [`Shader`]s, [`Light`]s, [`Camera`]s and
//! [`Integrator`]s, each of which destroys its plugin object on `Drop` and
//! offers the entries as safe methods. The host implements [`Services`] (the
//! kernel's `Trace`, the root's queries, lights, materials); a generic shim
//! turns it into the [`SceneRef`](rtk_abi::SceneRef) record integrators and
//! shaders receive. Each entry's signature is thus written twice in all: in
//! its record and in the SDK shim that implements it; the calls here go
//! through the records' accessors.
//!
//! Objects form a DAG: a parent holds its children's handles, so a child can
//! never be destroyed before the parents that point at it.

#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![deny(clippy::missing_safety_doc)]

mod handles;
mod services;

pub use handles::{Bulk, Camera, CreateArgs, Integrator, Light, Object, ObjectBuilder, Shader};
pub use services::{PrepareServices, SceneRecord, Services, ServicesTable};

pub use rtk_sdk::sink::CallError;
use rtk_sdk::sink::Collected;
