//! How a raw argument becomes what the implementing side's method takes,
//! and how a cold entry's answer becomes its raw record.
//!
//! The generated shims call `FromRaw::from_raw` on every argument and let
//! the trait method's signature pick the safe type: `*const T` becomes `&T`
//! (or `Option<&T>`), `*mut T` becomes `&mut T`, a [`Span`] a slice, a
//! `Float3` a `glam::Vec3`, a [`ChildRef`] a [`Child`](crate::Child). So a
//! declaration names raw types only, and a trait may take the richer ones.

use crate::{Child, Emitter, Prepare, Scene};
use rtk_abi::*;

/// A raw argument of an entry, as the method implementing it takes it.
pub trait FromRaw<R>: Sized {
    /// Convert.
    ///
    /// # Safety
    /// The record's contract for the argument: pointers valid (and, for
    /// `*mut`, exclusive) for the call the value is used in.
    unsafe fn from_raw(r: R) -> Self;
}

impl<T> FromRaw<T> for T {
    #[inline(always)]
    unsafe fn from_raw(r: T) -> T {
        r
    }
}

impl<T> FromRaw<*const T> for &T {
    #[inline(always)]
    unsafe fn from_raw(r: *const T) -> Self {
        // SAFETY: guaranteed by the caller (valid for the call).
        unsafe { &*r }
    }
}

impl<T> FromRaw<*const T> for Option<&T> {
    #[inline(always)]
    unsafe fn from_raw(r: *const T) -> Self {
        // SAFETY: guaranteed by the caller: null, or valid for the call.
        unsafe { r.as_ref() }
    }
}

impl<T> FromRaw<*mut T> for &mut T {
    #[inline(always)]
    unsafe fn from_raw(r: *mut T) -> Self {
        // SAFETY: guaranteed by the caller (valid and exclusive for the call).
        unsafe { &mut *r }
    }
}

impl<T> FromRaw<Span<T>> for &[T] {
    #[inline(always)]
    unsafe fn from_raw(r: Span<T>) -> Self {
        // SAFETY: guaranteed by the caller.
        unsafe { r.as_slice() }
    }
}

impl<T> FromRaw<SpanMut<T>> for &mut [T] {
    #[inline(always)]
    unsafe fn from_raw(r: SpanMut<T>) -> Self {
        // SAFETY: guaranteed by the caller.
        unsafe { r.as_mut_slice() }
    }
}

impl FromRaw<Float3> for glam::Vec3 {
    #[inline(always)]
    unsafe fn from_raw(r: Float3) -> Self {
        r.v()
    }
}

impl FromRaw<*const Affine3x4> for glam::DAffine3 {
    #[inline]
    unsafe fn from_raw(r: *const Affine3x4) -> Self {
        // SAFETY: guaranteed by the caller.
        unsafe { (*r).to_daffine() }
    }
}

impl FromRaw<*const PrepareEnv> for &Prepare {
    #[inline]
    unsafe fn from_raw(r: *const PrepareEnv) -> Self {
        // SAFETY: `Prepare` is a `repr(transparent)` wrapper of the
        // environment, valid for the call (guaranteed by the caller).
        unsafe { &*(r as *const Prepare) }
    }
}

impl FromRaw<*const SceneRef> for &Scene {
    #[inline(always)]
    unsafe fn from_raw(r: *const SceneRef) -> Self {
        // SAFETY: `Scene` is a `repr(transparent)` wrapper of the record,
        // whose host is live for the call (guaranteed by the caller).
        unsafe { &*(r as *const Scene) }
    }
}

impl FromRaw<ChildRef> for Child {
    #[inline]
    unsafe fn from_raw(r: ChildRef) -> Self {
        // SAFETY: the host passes a prepared child with one count that the
        // receiver now owns (`add_child`'s contract).
        unsafe { Child::from_counted(r) }
    }
}

impl FromRaw<EmitterRef> for Emitter {
    #[inline]
    unsafe fn from_raw(r: EmitterRef) -> Self {
        // SAFETY: the host passes a counted object and shader (`bind_emitter`'s contract).
        unsafe { Emitter::from_counted(r) }
    }
}

/// A cold entry's answer as its raw record: identity for plain values, and
/// a checked conversion where the raw form carries pointers (triangles).
pub trait ToRawAnswer<R> {
    /// Convert, or say why the answer cannot cross.
    fn to_raw_answer(self) -> Result<R, crate::PluginError>;
}

impl<T> ToRawAnswer<T> for T {
    #[inline(always)]
    fn to_raw_answer(self) -> Result<T, crate::PluginError> {
        Ok(self)
    }
}

impl ToRawAnswer<TriangleData> for crate::TriangleSlices<'_> {
    fn to_raw_answer(self) -> Result<TriangleData, crate::PluginError> {
        use crate::PluginError;
        let nv = self.positions.len();
        if let Some(bad) = self.indices.iter().flatten().find(|&&i| i as usize >= nv) {
            return Err(PluginError::msg(format!(
                "triangle index {bad} is beyond the {nv} vertices"
            )));
        }
        Ok(TriangleData {
            positions: self.positions.as_ptr(),
            vertex_count: u32::try_from(nv).map_err(|_| PluginError::msg("too many vertices"))?,
            indices: self.indices.as_ptr(),
            triangle_count: u32::try_from(self.indices.len())
                .map_err(|_| PluginError::msg("too many triangles"))?,
        })
    }
}
