//! `__NAME__`: an aggregate (acceleration structure). This one is the smallest
//! correct one, an exhaustive list: replace the loops by your structure and
//! check it with `rtk conform` and `rtk bench-aggregate __NAME__`.
#![forbid(unsafe_code)]

use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

/// The parameters (none yet): unknown keys are refused, naming the key.
#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {}

struct Agg {
    children: Vec<Child>,
    /// Over the whole shutter interval [0, 1].
    bounds: Bounds3,
}

impl Plugin for Agg {
    type Params = Params;

    fn create(_p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(Agg {
            children: Vec::new(),
            bounds: Bounds3::EMPTY,
        })
    }
}

impl Object for Agg {
    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    /// Runs once, after every child was added: build here.
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
        // closer, so ties go to the lowest index (as `list` does).
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

    /// Shadow rays: any hit will do.
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

// `doc` is shown by `rtk plugins`: the crate needs its README.md.
rtk_kernel::export_object!(Agg, class = "__NAME__", doc = include_str!("../README.md"));
