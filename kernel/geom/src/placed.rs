//! A hit point carried out of an instance's space: its error bound grows by
//! the transform's own rounding and by what the way back costs
//! (docs/numerics.md rule 8). Shared by every class that places a child by a
//! matrix (`transform`, `motion`), so the rule has one implementation.

use glam::{Mat3, Vec3};

use super::gamma;

/// The absolute values of a matrix's entries.
#[inline]
pub fn abs_mat3(m: Mat3) -> Mat3 {
    Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs())
}

/// The error bound of `q = M p + t`, computed in f32 from a child's point
/// `p` with bound `e`: pbrt-v4's (γ₃ + 1)|M|e + γ₃(|M||p| + |t|), plus the
/// way back: a ray spawned near q returns to the child's space through M⁻¹
/// in f32, which moves its origin there by up to γ₄(|M⁻¹|(|q| + e) +
/// |M⁻¹'s translation|); mapped out by |M|, the offset must clear that too,
/// or the origin lands back inside the surface it left (X1: 1 in 1e6
/// spawned rays at |p| ~ 4e4 under four levels without it).
#[inline]
pub fn placed_point_error(
    p: Vec3,
    e: Vec3,
    q: Vec3,
    t: Vec3,
    abs_m: Mat3,
    abs_inv: Mat3,
    abs_inv_t: Vec3,
) -> Vec3 {
    let g3 = gamma::<f32>(3);
    let e = (1.0 + g3) * (abs_m * e) + g3 * (abs_m * p.abs() + t.abs());
    let back = gamma::<f32>(4) * (abs_inv * (q.abs() + e) + abs_inv_t);
    e + abs_m * back
}
