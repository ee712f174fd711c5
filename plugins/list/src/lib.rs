#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {}

/// The paper's exhaustive list: every child tested for every ray. Slow, and
/// the oracle every other aggregate must match hit for hit.
struct List {
    children: Vec<Child>,
    /// Over the whole shutter interval [0, 1]: a superset of any sub-interval's.
    bounds: Bounds3,
}

impl Plugin for List {
    type Params = Params;

    fn create(_p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(List {
            children: Vec::new(),
            bounds: Bounds3::EMPTY,
        })
    }
}

impl Object for List {
    /// Inside any child: the union of their interiors.
    fn in_interior(&self, ctx: &mut TraceCtx, p: rtk_kernel::glam::Vec3, time: f32) -> Interior {
        union_interior(&self.children, ctx, p, time)
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        for c in &self.children {
            self.bounds = self.bounds.union(c.bounds(0.0, 1.0)?);
        }
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        // Narrow t_max as hits are found; a later child must be strictly
        // closer, so ties go to the lowest index.
        let mut r = *ray;
        let mut found = false;
        for (i, c) in self.children.iter().enumerate() {
            if c.intersect(ctx, &r, hit, level + 1) {
                r.t_max = hit.t;
                hit.record_child(level, i as u32);
                found = true;
            }
        }
        found
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        self.children
            .iter()
            .any(|c| c.occluded(ctx, ray, level + 1))
    }

    fn local_geom(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let i = hit.at(level) as usize;
        self.children[i].local_geom(ctx, ray, hit, level + 1, mask, out);
    }
}

rtk_kernel::export_object!(List, class = "list", doc = include_str!("../README.md"));
