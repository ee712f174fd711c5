//! The scalar abstraction that lets one routine run in f32 (production) and
//! f64 (reference).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A floating-point scalar: f32 or f64.
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + std::fmt::Debug
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Half the spacing of floats at 1 (unit roundoff).
    const UNIT_ROUNDOFF: Self;
    /// Positive infinity.
    const INFINITY: Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Absolute value.
    fn abs(self) -> Self;
    /// Finite (not NaN, not infinite).
    fn is_finite(self) -> bool;
    /// Convert from f64 (rounding).
    fn from_f64(v: f64) -> Self;
    /// Convert to f64 (exact).
    fn to_f64(self) -> f64;
    /// Sign: -1 for negative, +1 otherwise.
    fn signum1(self) -> Self;
}

macro_rules! impl_real {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const UNIT_ROUNDOFF: Self = <$t>::EPSILON * 0.5;
            const INFINITY: Self = <$t>::INFINITY;
            #[inline]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn signum1(self) -> Self {
                if self < 0.0 {
                    -1.0
                } else {
                    1.0
                }
            }
        }
    };
}
impl_real!(f32);
impl_real!(f64);

/// pbrt's γ(n) = nε/(1-nε): a bound on the relative error of n roundings.
#[inline]
pub fn gamma<R: Real>(n: u32) -> R {
    let ne = R::from_f64(n as f64) * R::UNIT_ROUNDOFF;
    ne / (R::ONE - ne)
}

/// The larger of `a` and `b`, by comparison: a NaN `b` never replaces `a`
/// (and an empty box's infinities behave), unlike a `max` that returns the
/// other operand for NaN. The one max helper of the kernel.
#[inline]
pub fn max_of<R: PartialOrd>(a: R, b: R) -> R {
    if b > a {
        b
    } else {
        a
    }
}

/// The smaller of `a` and `b`, by comparison (see [`max_of`]).
#[inline]
pub fn min_of<R: PartialOrd>(a: R, b: R) -> R {
    if b < a {
        b
    } else {
        a
    }
}
