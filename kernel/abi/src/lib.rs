//! # rtk-abi
//!
//! The records that cross the plugin boundary, and nothing else: the crate
//! every plugin and the host are checked against. Its version is the ABI's
//! (major = [`ABI_VERSION`]); tuning an aggregate, the geometry or the SDK
//! never moves it, so it never turns such a change into a version event.
//!
//! Everything here is `#[repr(C)]` and derives [`StableAbi`](abi_stable::StableAbi),
//! so the host's load check walks every field a plugin can reach and names the
//! first one whose layout differs.
//!
//! - [`values`]: plain data passed by pointer: rays, the hit-info stack, local
//!   geometry, light and scattering samples. No pointers inside, so safe code
//!   may build and read them freely.
//! - [`trace`]: the per-thread [`TraceCtx`]: counters, the random stream and
//!   the failure record. Plain data too.
//! - [`records`]: the function-pointer records: one root module per plugin kind
//!   and the scene services the host offers integrators and shaders. Every
//!   entry is an `unsafe extern "C" fn`: calling one is a promise about the
//!   pointers passed, which only the kernel's two safe layers make
//!   (`rtk-sdk` for plugins, `rtk-handles` for the host).
//! - [`header`]: the plain header read before any plugin code runs.
//!
//! # How the records grow
//! Each module record is an abi_stable *prefix type*. The fields up to and
//! including the one marked `#[sabi(last_prefix_field)]` are the **stable
//! prefix of ABI 2**: present in every plugin built against ABI 2, read
//! without a check. A later issue appends an entry *after* that field; a
//! plugin built before it simply lacks it, and the caller reads it as an
//! `Option` (absent means "not offered"). Nothing in the prefix ever changes
//! or moves; a change there is a new ABI version (see [`ABI_VERSION`]).
//!
//! An entry exists because something calls it. The semantics planned for the
//! roadmap (bounds of other types, CSG interiors, surface sampling, material
//! densities, ray streams) are written down in `docs/design.md`; each is
//! appended by the issue that first calls it.

#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![deny(clippy::missing_safety_doc)]

pub mod classes;
pub mod entries;
pub mod header;
mod ops;
mod record;
pub mod records;
pub mod trace;
pub mod values;

pub use header::*;
pub use records::*;
pub use trace::*;
pub use values::*;

/// Version of the records in this crate: the major version of `rtk-abi`
/// itself, so that one number moves with the boundary. A plugin built
/// against another value is refused, naming both versions, before any of its
/// code runs; a later minor version (entries appended) loads.
///
/// 3 (Kernel v3): every entry declared once; plain values laid out for ray
/// streams, attributes, light bindings and spectral colour.
/// 2: every entry `unsafe extern "C" fn`; failures on the hot path recorded in
/// the trace context; cold entries (bounds, primitive counts) return a status.
pub const ABI_VERSION: u32 = parse_u32(env!("CARGO_PKG_VERSION_MAJOR"));

/// A decimal number at compile time (the crate's major version).
const fn parse_u32(s: &str) -> u32 {
    let b = s.as_bytes();
    let (mut i, mut v) = (0, 0u32);
    while i < b.len() {
        assert!(b[i].is_ascii_digit(), "the major version is a number");
        v = v * 10 + (b[i] - b'0') as u32;
        i += 1;
    }
    v
}

/// This crate's version: the ABI's, recorded in every plugin's header and
/// compared by the loader (the major must equal the host's).
pub const ABI_CRATE_VERSION: &str = env!("CARGO_PKG_VERSION");
