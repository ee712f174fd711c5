//! # rtk-geom
//!
//! Robust geometric routines shared by plugins, the tests and the f64
//! reference: one implementation, generic over [`Real`] (f32 and f64).
//!
//! The rules they follow are `docs/numerics.md`'s: hit points carry an
//! error bound, spawned rays are offset past it along the geometric normal
//! (no scene epsilon), slab tests are conservative and NaN-ordered, and a hit
//! is accepted only when `t_min < t < t_max` and finite.

#![deny(missing_docs)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![deny(clippy::missing_safety_doc)]

mod disk;
mod offset;
mod placed;
mod real;
mod slab;
mod sphere;
mod triangle;
pub mod vec;
mod volume;

pub use disk::{Disk, DiskSurface};
pub use offset::{offset_ray_origin, spawn_ray, spawn_ray_between, spawn_ray_to, SHADOW_EPSILON};
pub use placed::{abs_mat3, placed_point_error};
pub use real::{gamma, max_of, min_of, Real};
pub use slab::{slab, RayBoxPrecomp, SlabHit};
pub use sphere::{
    intersect_sphere, intersect_sphere_in_f64, nearest_root, sphere_point_and_error,
    sphere_point_in_f64, SphereHit,
};
pub use triangle::{
    intersect_triangle, intersect_triangle_f64, intersect_triangle_sheared, is_degenerate,
    triangle_point_and_error, triangle_point_inset, RayShear, TriHit,
};
pub use volume::{
    box_corners, f32_down, f32_up, overlaps, SlabRay, SlabVolume, SphereRay, SphereVolume,
};
