//! A child as an aggregate sees it: a counted handle on the child object,
//! with the entries as safe methods (through [`LiveObject`], which it
//! dereferences to) and the instance's bindings applied.
//!
//! Why counted: an aggregate keeps its children for its whole life, and
//! safe code may keep one longer still (in a `static`, past the world it
//! came from). The child holds one count on the host's object, taken when
//! the host hands it over (`add_child`) or when it is cloned — never on the
//! hot path — so whatever a plugin does with it, the object it calls is
//! alive. A plugin cannot make one (the SDK's `add_child` shim does), so it
//! can never hold a raw record or a pointer it could misuse.

use super::{PluginError, TriangleSlices};
use crate::LiveObject;
use rtk_abi::*;

/// A child added to an aggregate: the object, counted, and its instance
/// bindings. Queries go straight through the child's record
/// ([`LiveObject`]'s methods); [`Child::local_geom`] applies the instance's
/// shader, light and id where no deeper level bound one (the innermost
/// binding wins).
pub struct Child {
    live: LiveObject,
    inst: InstanceData,
    keep: KeepAlive,
}

// SAFETY: the object is `Sync` (see `LiveObject`), and the count's
// `retain`/`release` are thread-safe (the record's contract for `KeepAlive`),
// so a child may be used, cloned and dropped on any thread.
unsafe impl Send for Child {}
// SAFETY: as for `Send`; shared use only reaches `&self` entries.
unsafe impl Sync for Child {}

impl Child {
    /// Take over what the host passed to `add_child`.
    ///
    /// # Safety
    /// `r.obj` must be a live, prepared object of `r.obj.class`, and
    /// `r.keep` must hold one count on it that the new child now owns.
    pub(crate) unsafe fn from_counted(r: ChildRef) -> Self {
        Child {
            // SAFETY: the count keeps the object alive while the child lives.
            live: unsafe { LiveObject::new(r.obj.this as *mut _, r.obj.class) },
            inst: r.inst,
            keep: r.keep,
        }
    }

    /// The instance's bindings.
    pub fn instance(&self) -> InstanceData {
        self.inst
    }

    /// Local geometry of the hit in `hit.stack[level..]`, with this
    /// instance's bindings applied where no deeper level bound one.
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
        self.live.local_geom(ctx, ray, hit, level, mask, out);
        self.inst.bind(out);
    }

    /// Nearest hits of a batch of rays through the child (ray streams,
    /// [`Object::intersect_batch`](crate::Object::intersect_batch)), ray by
    /// ray when its class predates the entry; the mask of those that hit.
    #[inline]
    pub fn intersect_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &mut [Hit],
        active: u64,
        level: u32,
    ) -> u64 {
        if self.live.raw_class().intersect_batch().is_some() {
            return self
                .live
                .intersect_batch(ctx, rays, hits, active, level)
                .unwrap_or(0);
        }
        let mut found = 0;
        for i in crate::batch::lanes(active, rays.len().min(hits.len())) {
            if self.live.intersect(ctx, &rays[i], &mut hits[i], level) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Any hit for each active ray of a batch (ray by ray when the class
    /// predates the entry); the mask of those occluded.
    #[inline]
    pub fn occluded_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        active: u64,
        level: u32,
    ) -> u64 {
        if let Some(m) = self.live.occluded_batch(ctx, rays, active, level) {
            return m;
        }
        let mut found = 0;
        for i in crate::batch::lanes(active, rays.len()) {
            if self.live.occluded(ctx, &rays[i], level) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Local geometry of each active hit of a batch, with this instance's
    /// bindings applied as [`Child::local_geom`] applies them.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn local_geom_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &[Hit],
        active: u64,
        level: u32,
        mask: u32,
        out: &mut [LocalGeom],
    ) {
        let n = rays.len().min(hits.len()).min(out.len());
        if self
            .live
            .local_geom_batch(ctx, rays, hits, active, level, mask, out)
            .is_none()
        {
            for i in crate::batch::lanes(active, n) {
                self.live
                    .local_geom(ctx, &rays[i], &hits[i], level, mask, &mut out[i]);
            }
        }
        for i in crate::batch::lanes(active, n) {
            self.inst.bind(&mut out[i]);
        }
    }

    /// Box over `[time0, time1]`; an error names the child's class.
    pub fn bounds(&self, time0: f32, time1: f32) -> Result<Bounds3, PluginError> {
        Ok(self.live.bounds(time0, time1)?)
    }

    /// A sphere containing the child over `[time0, time1]`: its own
    /// (`inq_bounds`), else around its hull points, else around its box.
    pub fn bound_sphere(&self, time0: f32, time1: f32) -> Result<BoundSphere, PluginError> {
        Ok(crate::volumes::sphere(&self.live, (time0, time1))?)
    }

    /// Points whose convex hull contains the child: its own, else its
    /// box's corners.
    pub fn hull_points(&self, time0: f32, time1: f32) -> Result<Vec<[f32; 3]>, PluginError> {
        Ok(crate::volumes::hull_points(&self.live, (time0, time1))?)
    }

    /// Kay–Kajiya slabs containing the child: its own, else from its hull
    /// points (exact: diagonal sums in f64, rounded outward).
    pub fn slabs(&self, time0: f32, time1: f32) -> Result<SlabBounds, PluginError> {
        Ok(crate::volumes::slabs(&self.live, (time0, time1))?)
    }

    /// The child's primitive set, when its class offers the protocol.
    pub fn prim_set(&self) -> Option<PrimSet> {
        let m = self.live.raw_class();
        let offered = m.prim_count().is_some()
            && m.prim_bounds().is_some()
            && m.intersect_prims().is_some()
            && m.occluded_prims().is_some();
        offered.then(|| PrimSet {
            child: self.clone(),
        })
    }
}

impl std::ops::Deref for Child {
    type Target = LiveObject;
    #[inline(always)]
    fn deref(&self) -> &LiveObject {
        &self.live
    }
}

impl Clone for Child {
    fn clone(&self) -> Self {
        // SAFETY: `keep` holds a count, so the owner is alive to take another.
        unsafe { (self.keep.retain)(self.keep.owner) };
        // SAFETY: the new count keeps the object alive for the clone.
        let live = unsafe { LiveObject::new(self.live.raw_this(), self.live.raw_class()) };
        Child {
            live,
            inst: self.inst,
            keep: self.keep,
        }
    }
}

impl Drop for Child {
    fn drop(&mut self) {
        // SAFETY: this child owns one count, released once.
        unsafe { (self.keep.release)(self.keep.owner) };
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

/// The paper's "in interior" of a union of children (what an aggregate
/// answers): inside when any child says so, else outside when any has an
/// interior, else none ([`Interior::union`]). Every child is asked: what a
/// point is inside of is asked by CSG and tools, never per ray.
pub fn union_interior(
    children: &[Child],
    ctx: &mut TraceCtx,
    p: glam::Vec3,
    time: f32,
) -> Interior {
    let mut answer = Interior::NONE;
    for c in children {
        answer = answer.union(c.in_interior(ctx, p, time));
        if answer.is_inside() {
            break;
        }
    }
    answer
}

/// A child's primitive-set protocol: batched queries over its primitives, in
/// the child's own space. One call per leaf, never one per primitive. Made
/// only for a child whose class offers all four entries.
#[derive(Clone)]
pub struct PrimSet {
    child: Child,
}

impl PrimSet {
    /// The child whose primitives these are.
    pub fn child(&self) -> &Child {
        &self.child
    }

    /// The child's triangles as data, when its class lends them (checked:
    /// every index is within the positions). They live as long as the set.
    pub fn triangles(&self) -> Result<Option<TriangleSlices<'_>>, PluginError> {
        let Some(d) = self.child.live.triangles() else {
            return Ok(None);
        };
        let d = d?;
        // SAFETY: the entry succeeded, so `d` points into the child's
        // immutable data, which the count in `self` keeps alive while the
        // borrow of `self` lasts.
        let (positions, indices) = unsafe {
            (
                spanned(d.positions, d.vertex_count),
                spanned(d.indices, d.triangle_count),
            )
        };
        if let Some(bad) = indices
            .iter()
            .flatten()
            .find(|&&i| i as usize >= positions.len())
        {
            return Err(PluginError::msg(format!(
                "child of class `{}`: triangle index {bad} is beyond the {} vertices",
                self.child.class_name(),
                positions.len()
            )));
        }
        Ok(Some(TriangleSlices { positions, indices }))
    }

    /// Number of primitives.
    pub fn count(&self) -> Result<u32, PluginError> {
        Ok(self.child.live.prim_count().unwrap_or(Ok(0))?)
    }

    /// Boxes of primitives `first..first + out.len()`.
    pub fn bounds(&self, first: u32, out: &mut [Bounds3]) -> Result<(), PluginError> {
        let total = self.count()? as u64;
        if first as u64 + out.len() as u64 > total {
            return Err(PluginError::msg(format!(
                "asked for the boxes of primitives {first}..{} of {total}",
                first as u64 + out.len() as u64
            )));
        }
        Ok(self.child.live.prim_bounds(first, out).unwrap_or(Ok(()))?)
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
        self.child
            .live
            .intersect_prims(ctx, ray, ids, hit, level)
            .unwrap_or(false)
    }

    /// Any hit among `ids`.
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], level: u32) -> bool {
        self.child
            .live
            .occluded_prims(ctx, ray, ids, level)
            .unwrap_or(false)
    }
}

/// A slice from a pointer and a count (empty for a null pointer).
///
/// # Safety
/// A non-null `p` must point at `n` initialised values valid for `'a`.
unsafe fn spanned<'a, T>(p: *const T, n: u32) -> &'a [T] {
    if p.is_null() || n == 0 {
        &[]
    } else {
        // SAFETY: guaranteed by the caller.
        unsafe { std::slice::from_raw_parts(p, n as usize) }
    }
}
