//! Area lights: every instance bound to an emitting shader (its `lobes`
//! has [`lobe::EMISSION`]) becomes a light of the class
//! [`AREA_LIGHT`](rtk_kernel::classes::AREA_LIGHT), bound to the instance's
//! object placed by the transforms on its path from the root (DESIGN.md §2,
//! "the shell builds the light list"). The light plugin samples the surface
//! and knows its densities; the shell only finds and places the instances.
//!
//! Why each emitting instance must be reached through exactly one path: a
//! hit tells the host which binding it found (the emitting binding's shader
//! id is its own), not which of several world copies, and multiple
//! importance sampling needs the density of the copy that was hit. Bind the
//! emitting shader on the outer instances instead.

use super::objects::Builder;
use crate::desc::Desc;
use crate::desc::Instance;
use crate::error::{ErrorKind, SceneError};
use crate::plugins::{Module, Plugin, Registry};
use crate::tree::Origin;
use glam::DAffine3;
use rtk_handles::{CallError, CreateArgs, Light, Object, Shader};
use rtk_kernel::{lobe, InstanceData};
use std::collections::BTreeMap;
use std::sync::Arc;

/// An emitting instance, placed in the renderer's space: what its area
/// light is bound to.
pub struct Emitter {
    /// The object whose surface emits (the definition's own, not its
    /// acceleration wrapper), sampled in its own space.
    pub object: Object,
    /// The instance's bindings: its own shader id and its light.
    pub inst: InstanceData,
    /// Own space to the renderer's space.
    pub to_world: DAffine3,
    /// Instance path, for messages.
    pub path: String,
    /// Where the instance is written, for messages.
    pub origin: Origin,
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
        let desc = self.desc;
        let od = &desc.objects[&inst.object];
        if self.emits(&data) {
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
            let object = self.emitting_object(inst, child_shifted)?;
            out.push(Emitter {
                object,
                inst: data,
                to_world: self.placement(m),
                path: inst.path.clone(),
                origin: inst.origin.clone(),
            });
        }
        if rtk_kernel::classes::PLACE_THEIR_CHILD.contains(&od.def.class.as_str()) {
            return self.refuse_emitters_below(inst);
        }
        for c in &super::objects::expand_groups(desc, &od.children) {
            self.walk(c, m, child_shifted, seen, out)?;
        }
        Ok(())
    }

    /// Whether the shader of bindings `data` emits.
    fn emits(&self, data: &InstanceData) -> bool {
        self.shaders
            .get(data.shader as usize)
            .is_some_and(|s| s.lobes() & lobe::EMISSION != 0)
    }

    /// The object of the emitting instance `inst`, made `shifted` or not:
    /// it must sample its surface and have an area to emit from.
    fn emitting_object(&self, inst: &Instance, shifted: bool) -> Result<Object, SceneError> {
        let object = self.made_object(&inst.object, shifted);
        let Some(object) = object.filter(|o| o.samples_surface()) else {
            let od = &self.desc.objects[&inst.object];
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
            .sample_surface(&mut ctx, [0.5, 0.5])
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
        Ok(object)
    }

    /// An emitting object's own space to the renderer's, given `m`, the
    /// transforms of the instances above it: below the first transform,
    /// objects are made unshifted and the transform absorbed the shift
    /// (objects.rs), so the shift is applied here.
    fn placement(&self, m: Option<DAffine3>) -> DAffine3 {
        match m {
            Some(m) => DAffine3::from_translation(-glam::DVec3::from(self.desc.render.origin)) * m,
            None => DAffine3::IDENTITY,
        }
    }

    /// Below an object that places its child itself (`transform`,
    /// `motion`), the matrix is the plugin's to read: lights there cannot
    /// be placed. Refuse only if one is there.
    fn refuse_emitters_below(&mut self, inst: &Instance) -> Result<(), SceneError> {
        if self.any_emitter_below(&inst.object)? {
            return Err(SceneError::invalid(
                &inst.origin,
                &inst.path,
                "object",
                "an emitting instance below an object of class `transform` or `motion` \
                 cannot be placed as a light; use the instance's `transform` list instead",
            ));
        }
        Ok(())
    }

    fn any_emitter_below(&mut self, name: &str) -> Result<bool, SceneError> {
        let desc = self.desc;
        for c in &super::objects::expand_groups(desc, &desc.objects[name].children) {
            let data = self.bindings(c)?;
            if self.emits(&data) || self.any_emitter_below(&c.object)? {
                return Ok(true);
            }
        }
        Ok(false)
    }
}

/// The area lights of `emitters`, in light-id order (the ids the bindings
/// gave them, after the scene's `first` lights): one light of class
/// [`AREA_LIGHT`](rtk_kernel::classes::AREA_LIGHT) per emitting instance,
/// created and bound to its object, placement and shader. The class is
/// loaded only when the scene has an emitter.
pub(crate) fn area_lights(
    registry: &mut Registry,
    desc: &Desc,
    scene_dir: &str,
    first: usize,
    emitters: &[Emitter],
    shaders: &[Shader],
) -> Result<(Vec<Light>, Option<Arc<Plugin>>), SceneError> {
    let Some(e0) = emitters.first() else {
        return Ok((Vec::new(), None));
    };
    let class = rtk_kernel::classes::AREA_LIGHT;
    let plugin = registry
        .get(class)
        .map_err(|e| super::needs::class_refused(e, class, &e0.origin, &e0.path, "shader"))?;
    let Module::Light(module) = plugin.module else {
        return Err(SceneError::new(
            ErrorKind::Plugin,
            &e0.origin,
            &e0.path,
            "shader",
            format!("the plugin `{class}` is not a light"),
        ));
    };
    let mut by_id: Vec<Option<&Emitter>> = vec![None; emitters.len()];
    for e in emitters {
        match (e.inst.light as usize).checked_sub(first) {
            Some(k) if k < by_id.len() && by_id[k].is_none() => by_id[k] = Some(e),
            _ => {
                return Err(SceneError::invalid(
                    &e.origin,
                    &e.path,
                    "shader",
                    "this emitting instance's light was not numbered once (a bug in rtk)",
                ))
            }
        }
    }
    let mut lights = Vec::with_capacity(emitters.len());
    for e in by_id.into_iter().flatten() {
        let failed = |err: CallError| {
            SceneError::new(
                ErrorKind::PluginCall,
                &e.origin,
                &e.path,
                "shader",
                format!("plugin `{class}` refused the emitting instance: {err}"),
            )
        };
        let args = CreateArgs {
            scene_dir,
            name: &e.path,
            image_width: desc.render.width,
            image_height: desc.render.height,
            origin: desc.render.origin,
            arrays: &[],
        };
        let mut light = Light::create(module, "{}", &args).map_err(failed)?;
        let shader = &shaders[e.inst.shader as usize];
        light
            .bind(&e.object, e.inst, &e.to_world, shader)
            .map_err(failed)?;
        lights.push(light);
    }
    Ok((lights, Some(plugin)))
}
