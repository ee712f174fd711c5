//! `inq_bounds` from the caller's side, shared by the host's objects
//! (`rtk-handles`) and [`Child`](crate::Child) (aggregates): ask the object for a
//! volume and derive the kinds it does not offer, so a caller always gets
//! one. Derivations, each containing the object whenever what it starts
//! from does: a sphere around the hull points (else around the box); the
//! box's corners as hull points; slabs from the hull points.

use crate::sink::CallError;
use crate::LiveObject;
use rtk_abi::{bound_kind, BoundSphere, BoundingVolume, Bounds3, SlabBounds};
use rtk_geom::{box_corners, SlabVolume, SphereVolume};

fn blank() -> BoundingVolume {
    BoundingVolume {
        written: false,
        sphere: BoundSphere::EMPTY,
        slabs: SlabBounds::EMPTY,
        hull_len: 0,
    }
}

/// Call `inq_bounds` once; false when the class or the object offers no
/// volume of `kind`.
fn ask(
    obj: &LiveObject,
    kind: u32,
    t: (f32, f32),
    hull: &mut [[f32; 3]],
    out: &mut BoundingVolume,
) -> Result<bool, CallError> {
    match obj.inq_bounds(kind, t.0, t.1, hull, out) {
        None => Ok(false),
        Some(r) => r.map(|()| out.written),
    }
}

fn boxed(obj: &LiveObject, t: (f32, f32)) -> Result<Bounds3, CallError> {
    obj.bounds(t.0, t.1)
}

/// The hull points the object offers, if it does.
fn offered_hull(obj: &LiveObject, t: (f32, f32)) -> Result<Option<Vec<[f32; 3]>>, CallError> {
    let mut pts: Vec<[f32; 3]> = vec![[0.0; 3]; 64];
    for _ in 0..2 {
        let mut v = blank();
        if !ask(obj, bound_kind::HULL, t, &mut pts, &mut v)? {
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
        class: obj.class_name(),
        panicked: false,
        key: String::new(),
        message: "the number of hull points changed between two calls".into(),
    })
}

/// Points whose hull contains the object over `t`.
pub fn hull_points(obj: &LiveObject, t: (f32, f32)) -> Result<Vec<[f32; 3]>, CallError> {
    match offered_hull(obj, t)? {
        Some(p) => Ok(p),
        None => Ok(box_corners(&boxed(obj, t)?)),
    }
}

/// A sphere containing the object over `t`.
pub fn sphere(obj: &LiveObject, t: (f32, f32)) -> Result<BoundSphere, CallError> {
    let mut v = blank();
    if ask(obj, bound_kind::SPHERE, t, &mut [], &mut v)? {
        return Ok(v.sphere);
    }
    Ok(match offered_hull(obj, t)? {
        Some(p) => BoundSphere::around_points(&p),
        None => BoundSphere::around_box(&boxed(obj, t)?),
    })
}

/// Kay–Kajiya slabs containing the object over `t`.
pub fn slabs(obj: &LiveObject, t: (f32, f32)) -> Result<SlabBounds, CallError> {
    let mut v = blank();
    if ask(obj, bound_kind::SLABS, t, &mut [], &mut v)? {
        return Ok(v.slabs);
    }
    Ok(SlabBounds::from_points(&hull_points(obj, t)?))
}
