//! A child as an aggregate sees it: queries through the child's record with
//! safe methods only. A plugin cannot make one (the SDK's `add_child` shim
//! does), so it can never hold a raw record or a pointer it could misuse.

use super::{PluginError, TriangleSlices};
use crate::abi::*;
use crate::host::Collected;

/// A child added to an aggregate: the object and its instance bindings.
/// Queries go straight through the child's record; `local_geom` applies the
/// instance's shader when no deeper level bound one (the innermost binding wins).
#[derive(Clone, Copy)]
pub struct Child {
    obj: ObjectRef,
    inst: InstanceData,
}

// SAFETY: a child is an object that is immutable after `prepare` and whose
// class is `Send + Sync` (the SDK's `Plugin` trait requires it); its record is
// a `'static` table in a library that is never unloaded.
unsafe impl Send for Child {}
// SAFETY: see above.
unsafe impl Sync for Child {}

/// A slice from a pointer and a count (empty for a null pointer).
///
/// # Safety
/// A non-null `p` must point at `n` initialised values valid for `'a`.
unsafe fn slice_or_empty<'a, T>(p: *const T, n: u32) -> &'a [T] {
    if p.is_null() || n == 0 {
        &[]
    } else {
        // SAFETY: guaranteed by the caller.
        unsafe { std::slice::from_raw_parts(p, n as usize) }
    }
}

impl std::fmt::Debug for Child {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Child")
            .field("class", &self.class_name())
            .field("instance", &self.inst)
            .finish()
    }
}

impl Child {
    /// Wrap what the host passed to `add_child`.
    ///
    /// # Safety
    /// `obj.this` must be a live object of `obj.class`, prepared, and outlive
    /// every use of the returned child.
    pub(crate) unsafe fn new(obj: ObjectRef, inst: InstanceData) -> Self {
        Self { obj, inst }
    }

    /// The instance's bindings.
    pub fn instance(&self) -> InstanceData {
        self.inst
    }

    /// The child's class name (for messages).
    pub fn class_name(&self) -> &'static str {
        self.obj.class.meta().class_name.as_str()
    }

    /// Nearest hit in `(ray.t_min, ray.t_max)`, recorded from `level` on.
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        // SAFETY: `this` is live for the child's lifetime (constructor
        // contract); the other pointers come from references.
        unsafe { (self.obj.class.intersect())(self.obj.this, ctx, ray, hit, level) }
    }

    /// Any hit in `(ray.t_min, ray.t_max)`.
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        // SAFETY: as in `intersect`.
        unsafe { (self.obj.class.occluded())(self.obj.this, ctx, ray, level) }
    }

    /// Local geometry of the hit in `hit.stack[level..]`, with this instance's
    /// shader applied if no deeper level bound one.
    #[inline]
    pub fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        // SAFETY: as in `intersect`.
        unsafe { (self.obj.class.local_geom())(self.obj.this, ctx, ray, hit, level, mask, out) };
        if out.shader == NONE_ID {
            out.shader = self.inst.shader;
        }
    }

    /// Box over `[time0, time1]`; an error names the child's class.
    pub fn bounds(&self, time0: f32, time1: f32) -> Result<Bounds3, PluginError> {
        let mut b = Bounds3::EMPTY;
        self.cold("bounds", |this, sink| {
            // SAFETY: `this` is live (see `Child::new`); `b` outlives the call.
            unsafe { (self.obj.class.bounds())(this, time0, time1, &mut b, sink) }
        })?;
        Ok(b)
    }

    /// A sphere containing the child over `[time0, time1]`: its own
    /// (`inq_bounds`), else around its hull points, else around its box.
    pub fn bound_sphere(&self, time0: f32, time1: f32) -> Result<BoundSphere, PluginError> {
        crate::host::volumes::sphere(self.obj, (time0, time1)).map_err(|e| self.error(e))
    }

    /// Points whose convex hull contains the child: its own, else its
    /// box's corners.
    pub fn hull_points(&self, time0: f32, time1: f32) -> Result<Vec<[f32; 3]>, PluginError> {
        crate::host::volumes::hull_points(self.obj, (time0, time1)).map_err(|e| self.error(e))
    }

    /// Kay–Kajiya slabs containing the child: its own, else from its hull
    /// points (exact: diagonal sums in f64, rounded outward).
    pub fn slabs(&self, time0: f32, time1: f32) -> Result<SlabBounds, PluginError> {
        crate::host::volumes::slabs(self.obj, (time0, time1)).map_err(|e| self.error(e))
    }

    /// Run a cold entry with an error sink; a failure names the child's class.
    fn cold(
        &self,
        entry: &'static str,
        call: impl FnOnce(*const std::ffi::c_void, ErrSink) -> i32,
    ) -> Result<(), PluginError> {
        let mut c = Collected::default();
        let st = call(self.obj.this, c.sink());
        c.result(st, entry).map_err(|e| self.error(e))
    }

    /// The child's primitive set, when its class offers the protocol.
    pub fn prim_set(&self) -> Option<PrimSet> {
        let m = self.obj.class;
        let offered = m.prim_count().is_some()
            && m.prim_bounds().is_some()
            && m.intersect_prims().is_some()
            && m.occluded_prims().is_some();
        offered.then_some(PrimSet { child: *self })
    }

    fn error(&self, e: crate::host::CallError) -> PluginError {
        PluginError::msg(format!("child of class `{}`: {e}", self.class_name()))
    }
}

/// A child's primitive-set protocol: batched queries over its primitives, in
/// the child's own space. One call per leaf, never one per primitive. Made
/// only for a child whose class offers all four entries.
#[derive(Clone, Copy)]
pub struct PrimSet {
    child: Child,
}

impl PrimSet {
    /// The child whose primitives these are.
    pub fn child(&self) -> &Child {
        &self.child
    }

    /// The child's triangles as data, when its class lends them (checked:
    /// every index is within the positions).
    pub fn triangles(&self) -> Result<Option<TriangleSlices<'_>>, PluginError> {
        let Some(f) = self.child.obj.class.triangles() else {
            return Ok(None);
        };
        let mut d = std::mem::MaybeUninit::<TriangleData>::uninit();
        // SAFETY: the child's object is live; `d` is written on success.
        self.child.cold("triangles", |this, sink| unsafe {
            f(this, d.as_mut_ptr(), sink)
        })?;
        // SAFETY: the entry succeeded, so it wrote `d`: pointers into the
        // child's immutable data, which outlives every use of this set, with
        // the counts the SDK checked (indices within the positions).
        let slices = unsafe {
            let d = d.assume_init();
            TriangleSlices {
                positions: slice_or_empty(d.positions, d.vertex_count),
                indices: slice_or_empty(d.indices, d.triangle_count),
            }
        };
        Ok(Some(slices))
    }

    /// Number of primitives.
    pub fn count(&self) -> Result<u32, PluginError> {
        let Some(f) = self.child.obj.class.prim_count() else {
            return Ok(0);
        };
        let mut n = 0;
        // SAFETY: the child's object is live (see `Child::new`); `n` outlives the call.
        self.child
            .cold("prim_count", |this, sink| unsafe { f(this, &mut n, sink) })?;
        Ok(n)
    }

    /// Boxes of primitives `first..first + out.len()`.
    pub fn bounds(&self, first: u32, out: &mut [Bounds3]) -> Result<(), PluginError> {
        let Some(f) = self.child.obj.class.prim_bounds() else {
            return Ok(());
        };
        let n = u32::try_from(out.len()).map_err(|_| PluginError::msg("too many boxes"))?;
        // SAFETY: as in `count`; `out` has room for `n` boxes.
        self.child.cold("prim_bounds", |this, sink| unsafe {
            f(this, first, n, out.as_mut_ptr(), sink)
        })
    }

    /// Nearest hit among `ids`; writes `hit.stack[level]` as the child's
    /// `intersect` would.
    #[inline]
    pub fn intersect(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        ids: &[u32],
        hit: &mut Hit,
        level: u32,
    ) -> bool {
        let Some(f) = self.child.obj.class.intersect_prims() else {
            return false;
        };
        // SAFETY: as in `count`; `ids` holds `ids.len()` ids (a leaf is far
        // below u32::MAX primitives: the count itself is a u32).
        unsafe {
            f(
                self.child.obj.this,
                ctx,
                ray,
                ids.as_ptr(),
                ids.len() as u32,
                hit,
                level,
            )
        }
    }

    /// Any hit among `ids`.
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], level: u32) -> bool {
        let Some(f) = self.child.obj.class.occluded_prims() else {
            return false;
        };
        // SAFETY: as in `intersect`.
        unsafe {
            f(
                self.child.obj.this,
                ctx,
                ray,
                ids.as_ptr(),
                ids.len() as u32,
                level,
            )
        }
    }
}
