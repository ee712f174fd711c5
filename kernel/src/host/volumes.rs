//! `inq_bounds` from the caller's side, shared by [`Object`](super::Object)
//! (host) and [`Child`](crate::sdk::Child) (aggregates): ask the object for a
//! volume and derive the kinds it does not offer, so a caller always gets
//! one. Derivations, each containing the object whenever what it starts
//! from does: a sphere around the hull points (else around the box); the
//! box's corners as hull points; slabs from the hull points.

use super::{CallError, Collected};
use crate::abi::{bound_kind, BoundSphere, BoundingVolume, Bounds3, ObjectRef, SlabBounds};
use crate::geom::box_corners;

fn blank() -> BoundingVolume {
    BoundingVolume {
        written: false,
        sphere: BoundSphere::EMPTY,
        slabs: SlabBounds::EMPTY,
        hull: std::ptr::null_mut(),
        hull_cap: 0,
        hull_len: 0,
    }
}

/// Call `inq_bounds` once; `None` when the class or the object offers no
/// volume of `kind`.
fn ask(
    obj: ObjectRef,
    kind: u32,
    t: (f32, f32),
    out: &mut BoundingVolume,
) -> Result<bool, CallError> {
    let Some(f) = obj.class.inq_bounds() else {
        return Ok(false);
    };
    let mut c = Collected::default();
    // SAFETY: the object is live and prepared (callers hold it); `out` is
    // exclusive and its `hull` has room for `hull_cap` points.
    let st = unsafe { f(obj.this, kind, t.0, t.1, out, c.sink()) };
    c.result(st, "inq_bounds")?;
    Ok(out.written)
}

fn boxed(obj: ObjectRef, t: (f32, f32)) -> Result<Bounds3, CallError> {
    let mut b = Bounds3::EMPTY;
    let mut c = Collected::default();
    // SAFETY: as in `ask`; `b` outlives the call.
    let st = unsafe { (obj.class.bounds())(obj.this, t.0, t.1, &mut b, c.sink()) };
    c.result(st, "bounds")?;
    Ok(b)
}

/// The hull points the object offers, if it does.
fn offered_hull(obj: ObjectRef, t: (f32, f32)) -> Result<Option<Vec<[f32; 3]>>, CallError> {
    let mut pts: Vec<[f32; 3]> = vec![[0.0; 3]; 64];
    for _ in 0..2 {
        let mut v = blank();
        v.hull = pts.as_mut_ptr();
        v.hull_cap = pts.len() as u32;
        if !ask(obj, bound_kind::HULL, t, &mut v)? {
            return Ok(None);
        }
        if v.hull_len as usize <= pts.len() {
            pts.truncate(v.hull_len as usize);
            return Ok(Some(pts));
        }
        pts = vec![[0.0; 3]; v.hull_len as usize];
    }
    Err(CallError {
        entry: "inq_bounds",
        panicked: false,
        key: String::new(),
        message: "the number of hull points changed between two calls".into(),
    })
}

/// Points whose hull contains the object over `t`.
pub(crate) fn hull_points(obj: ObjectRef, t: (f32, f32)) -> Result<Vec<[f32; 3]>, CallError> {
    match offered_hull(obj, t)? {
        Some(p) => Ok(p),
        None => Ok(box_corners(&boxed(obj, t)?)),
    }
}

/// A sphere containing the object over `t`.
pub(crate) fn sphere(obj: ObjectRef, t: (f32, f32)) -> Result<BoundSphere, CallError> {
    let mut v = blank();
    if ask(obj, bound_kind::SPHERE, t, &mut v)? {
        return Ok(v.sphere);
    }
    Ok(match offered_hull(obj, t)? {
        Some(p) => BoundSphere::around_points(&p),
        None => BoundSphere::around_box(&boxed(obj, t)?),
    })
}

/// Kay–Kajiya slabs containing the object over `t`.
pub(crate) fn slabs(obj: ObjectRef, t: (f32, f32)) -> Result<SlabBounds, CallError> {
    let mut v = blank();
    if ask(obj, bound_kind::SLABS, t, &mut v)? {
        return Ok(v.slabs);
    }
    Ok(SlabBounds::from_points(&hull_points(obj, t)?))
}
