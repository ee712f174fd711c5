#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod traverse;
mod tree;

use rtk_kernel::accel::{CellAggregate, CellsAlongRay, Primitives};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use tree::{KdTree, Settings};

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "four")]
    max_leaf: u32,
    #[serde(default = "half")]
    empty_bonus: f32,
}

fn four() -> u32 {
    4
}

fn half() -> f32 {
    0.5
}

struct KdTreeAggregate {
    children: Vec<Child>,
    settings: Settings,
    built: Option<CellAggregate<KdTree>>,
}

impl Plugin for KdTreeAggregate {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(1..=64).contains(&p.max_leaf) {
            return Err(PluginError::key("max_leaf", "must be between 1 and 64"));
        }
        // Written so that NaN fails too.
        if !(p.empty_bonus >= 0.0 && p.empty_bonus < 1.0) {
            return Err(PluginError::key(
                "empty_bonus",
                "must be at least 0 and below 1",
            ));
        }
        Ok(KdTreeAggregate {
            children: Vec::new(),
            settings: Settings {
                max_leaf: p.max_leaf as usize,
                empty_bonus: p.empty_bonus,
            },
            built: None,
        })
    }
}

impl Object for KdTreeAggregate {
    /// Inside any child: the union of their interiors.
    fn in_interior(&self, ctx: &mut TraceCtx, p: rtk_kernel::glam::Vec3, time: f32) -> Interior {
        union_interior(&self.children, ctx, p, time)
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        let g = Primitives::gather(&self.children)?;
        let tree = KdTree::build(&g.boxes, self.settings);
        debug_assert!(
            tree.depth <= tree.max_depth,
            "the depth bound sizes the stack"
        );
        self.built = Some(CellAggregate::new(g.prims, tree, env.max_threads()));
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.built
            .as_ref()
            .map_or(Bounds3::EMPTY, CellAggregate::bounds)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        self.built
            .as_ref()
            .is_some_and(|b| b.intersect(ctx, ray, hit, level))
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        self.built
            .as_ref()
            .is_some_and(|b| b.occluded(ctx, ray, level))
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
        if let Some(b) = &self.built {
            b.local_geom(ctx, ray, hit, level, mask, out);
        }
    }
}

/// The leaves along a ray are the kd-tree's cells.
impl CellsAlongRay for KdTree {
    fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    #[inline]
    fn walk(&self, ray: &Ray, node_tests: &mut u64, leaf: impl FnMut(&[u32]) -> Option<f32>) {
        self.traverse(ray, node_tests, leaf);
    }
}

impl FlattensPrimitives for KdTreeAggregate {}

rtk_kernel::export_object!(
    KdTreeAggregate,
    class = "kdtree",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
