//! Area lights: every instance bound to an emitting shader (its `lobes`
//! has [`lobe::EMISSION`]) becomes a light, sampled through its object's
//! `sample_surface` and placed by the transforms on its path from the root
//! (DESIGN.md §2, "the shell builds the light list").
//!
//! Why each emitting instance must be reached through exactly one path: a
//! hit tells the host which binding it found (the emitting binding's shader
//! id is its own), not which of several world copies, and multiple
//! importance sampling needs the density of the copy that was hit. Bind the
//! emitting shader on the outer instances instead.

use super::objects::Builder;
use crate::desc::Instance;
use crate::error::{ErrorKind, SceneError};
use glam::{DAffine3, DMat3};
use rtk_kernel::host::Object;
use rtk_kernel::lobe;
use std::collections::BTreeMap;

/// An emitting instance, placed in the renderer's space.
pub struct Emitter {
    /// The object whose surface emits (the definition's own, not its
    /// acceleration wrapper), sampled in its own space.
    pub object: Object,
    /// Own space to the renderer's space.
    pub to_world: DAffine3,
    /// `to_world`'s linear part, inverse transposed (normals).
    pub normal_matrix: DMat3,
    /// |det| of `to_world`'s linear part.
    pub abs_det: f64,
    /// The object's surface area, own space.
    pub area: f32,
    /// The binding's shader id: what a hit on it reports.
    pub shader: u32,
    /// Instance path, for messages.
    pub path: String,
    /// For an object that lends its triangles (a mesh): the triangles in
    /// the renderer's space, so light samples are drawn uniformly by world
    /// area with no call into the plugin and no transform per sample.
    pub mesh: Option<EmitterMesh>,
}

/// An emitting mesh's triangles, placed: sampled by world area.
pub struct EmitterMesh {
    /// Per triangle: first vertex, the two edges from it, the unit normal
    /// (the side `local_geom`'s `ng` faces, through the transform).
    pub tris: Vec<[[f32; 3]; 4]>,
    /// Running sum of the triangles' world areas.
    pub cdf: Vec<f64>,
    /// Total world area.
    pub area: f64,
}

impl EmitterMesh {
    /// Place `positions`/`indices` by `m`, in f64, rounding once.
    fn new(m: DAffine3, positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Option<EmitterMesh> {
        let flip = m.matrix3.determinant() < 0.0;
        let mut tris = Vec::with_capacity(indices.len());
        let mut cdf = Vec::with_capacity(indices.len());
        let mut sum = 0.0f64;
        for t in indices {
            let v = t.map(|i| {
                m.transform_point3(glam::DVec3::from(positions[i as usize].map(f64::from)))
            });
            let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
            let c = e1.cross(e2);
            let a = 0.5 * c.length();
            // The normal as the mesh computes it, carried through M: the
            // cross product of the placed edges, flipped by a mirroring M.
            let n = if flip { -c } else { c }.normalize_or_zero();
            sum += a;
            cdf.push(sum);
            tris.push([v[0], e1, e2, n].map(|x| x.as_vec3().to_array()));
        }
        (sum > 0.0 && sum.is_finite()).then_some(EmitterMesh {
            tris,
            cdf,
            area: sum,
        })
    }
}

impl Builder<'_> {
    /// Every emitting instance reachable from `root`, in the order found.
    pub(crate) fn emitters(&mut self, root: &Instance) -> Result<Vec<Emitter>, SceneError> {
        let mut seen = BTreeMap::new();
        let mut out = Vec::new();
        self.walk(root, None, true, &mut seen, &mut out)?;
        Ok(out)
    }

    /// `m`: the composed transform of the instances above (None: none yet);
    /// `shifted`: the instance's parent space is the renderer's.
    fn walk(
        &mut self,
        inst: &Instance,
        m: Option<DAffine3>,
        shifted: bool,
        seen: &mut BTreeMap<String, ()>,
        out: &mut Vec<Emitter>,
    ) -> Result<(), SceneError> {
        let m = match (m, inst.transform) {
            (Some(a), Some(b)) => Some(a * b),
            (a, b) => a.or(b),
        };
        let child_shifted = shifted && inst.transform.is_none();
        let data = self.bindings(inst)?;
        let emits = self
            .shaders
            .get(data.shader as usize)
            .is_some_and(|s| s.lobes() & lobe::EMISSION != 0);
        let desc = self.desc;
        let od = &desc.objects[&inst.object];
        if emits {
            if seen.insert(inst.path.clone(), ()).is_some() {
                return Err(SceneError::invalid(
                    &inst.origin,
                    &inst.path,
                    "shader",
                    format!(
                        "the emitting shader `{}` is bound on an instance the scene reaches \
                         through more than one path; bind it on the outer instances instead",
                        inst.shader.as_deref().unwrap_or("")
                    ),
                ));
            }
            let object = self.made_object(&inst.object, child_shifted);
            let Some(object) = object.filter(|o| o.samples_surface()) else {
                return Err(SceneError::new(
                    ErrorKind::Invalid,
                    &inst.origin,
                    &inst.path,
                    "shader",
                    format!(
                        "the shader `{}` emits, but object `{}` (class `{}`) cannot sample its \
                         surface, so it cannot be an area light; bind the shader to its \
                         primitives (mesh, sphere, disk, polygon...) instead",
                        inst.shader.as_deref().unwrap_or(""),
                        inst.object,
                        od.def.class
                    ),
                ));
            };
            let mut ctx = rtk_kernel::TraceCtx::new(0, 1, 0);
            let area = object
                .sample_surface(&mut ctx, &[0.5, 0.5])
                .map_or(0.0, |s| s.area);
            if !(area > 0.0 && area.is_finite()) {
                return Err(SceneError::invalid(
                    &inst.origin,
                    &inst.path,
                    "shader",
                    format!(
                        "object `{}` is bound to the emitting shader `{}` but has no surface \
                         area to emit from",
                        inst.object,
                        inst.shader.as_deref().unwrap_or("")
                    ),
                ));
            }
            // Below the first transform, objects are made unshifted and the
            // transform absorbed the shift (objects.rs).
            let to_world = match m {
                Some(m) => DAffine3::from_translation(-glam::DVec3::from(desc.render.origin)) * m,
                None => DAffine3::IDENTITY,
            };
            let l = to_world.matrix3;
            let mesh = match object.triangles() {
                Ok(Some((p, t))) => EmitterMesh::new(to_world, &p, &t),
                _ => None,
            };
            out.push(Emitter {
                object,
                to_world,
                normal_matrix: l.inverse().transpose(),
                abs_det: l.determinant().abs(),
                area,
                shader: data.shader,
                path: inst.path.clone(),
                mesh,
            });
        }
        if rtk_kernel::classes::PLACE_THEIR_CHILD.contains(&od.def.class.as_str()) {
            // Its matrix is the plugin's to read: lights below it cannot be
            // placed. Refuse only if one is there.
            return if self.any_emitter_below(&inst.object)? {
                Err(SceneError::invalid(
                    &inst.origin,
                    &inst.path,
                    "object",
                    "an emitting instance below an object of class `transform` or `motion` \
                     cannot be placed as a light; use the instance's `transform` list instead",
                ))
            } else {
                Ok(())
            };
        }
        let children_shifted = child_shifted;
        for c in &super::objects::expand_groups(desc, &od.children) {
            self.walk(c, m, children_shifted, seen, out)?;
        }
        Ok(())
    }

    fn any_emitter_below(&mut self, name: &str) -> Result<bool, SceneError> {
        let desc = self.desc;
        for c in &super::objects::expand_groups(desc, &desc.objects[name].children) {
            let data = self.bindings(c)?;
            let emits = self
                .shaders
                .get(data.shader as usize)
                .is_some_and(|s| s.lobes() & lobe::EMISSION != 0);
            if emits || self.any_emitter_below(&c.object)? {
                return Ok(true);
            }
        }
        Ok(false)
    }
}
