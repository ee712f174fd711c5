#![doc = include_str!("../README.md")]

use rtk_kernel::accel::{cull_bound, BuildParams, Bvh4, Nearest, Primitives};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "four")]
    max_leaf: u32,
}

fn four() -> u32 {
    4
}

struct Bvh {
    children: Vec<Child>,
    params: BuildParams,
    built: Option<(Primitives, Bvh4)>,
}

impl Plugin for Bvh {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(1..=64).contains(&p.max_leaf) {
            return Err(PluginError::key("max_leaf", "must be between 1 and 64"));
        }
        Ok(Bvh {
            children: Vec::new(),
            params: BuildParams {
                max_leaf: p.max_leaf as usize,
                ..BuildParams::default()
            },
            built: None,
        })
    }
}

impl Object for Bvh {
    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        let g = Primitives::gather(&self.children)?;
        let mut bvh = Bvh4::build(&g.boxes, self.params);
        // Leaves start at multiples of four: each names its block of four
        // triangles, screened at once.
        bvh.pad_leaves(4);
        let mut prims = g.prims;
        prims.reorder(&bvh.order);
        prims.pack();
        self.built = Some((prims, bvh));
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.built
            .as_ref()
            .map_or(Bounds3::EMPTY, |(_, b)| b.bounds())
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some((prims, bvh)) = &self.built else {
            return false;
        };
        let mut q = Nearest::new(ray);
        let mut nodes = 0;
        // Boxes within the tie margin of the best hit are still entered
        // (rule 11, `cull_bound`).
        bvh.traverse(ray, cull_bound(ray.t_max), &mut nodes, |leaf| {
            prims.intersect_range(ctx, &mut q, leaf, hit, level);
            Some(cull_bound(q.ray.t_max))
        });
        ctx.stats.node_tests += nodes;
        q.found()
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let Some((prims, bvh)) = &self.built else {
            return false;
        };
        let mut found = false;
        let mut nodes = 0;
        // Any hit will do: no tie to keep, no margin.
        bvh.traverse(ray, ray.t_max, &mut nodes, |leaf| {
            found = prims.occluded_range(ctx, ray, leaf, level);
            (!found).then_some(ray.t_max)
        });
        ctx.stats.node_tests += nodes;
        found
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
        if let Some((prims, _)) = &self.built {
            prims.local_geom(ctx, ray, hit, level, mask, out);
        }
    }
}

impl FlattensPrimitives for Bvh {}

rtk_kernel::export_object!(
    Bvh,
    class = "bvh",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
