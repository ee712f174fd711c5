#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod traverse;
mod tree;

use rtk_kernel::accel::{Mailbox, Nearest, Primitives};
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

/// What `prepare` builds: the primitive table, the tree over it, and the
/// marks that keep a primitive referenced by several leaves from being
/// tested twice in one query.
struct Built {
    prims: Primitives,
    tree: KdTree,
    mailbox: Mailbox,
}

struct KdTreeAggregate {
    children: Vec<Child>,
    settings: Settings,
    built: Option<Built>,
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
        let mailbox = Mailbox::new(g.prims.len(), env.max_threads());
        self.built = Some(Built {
            prims: g.prims,
            tree,
            mailbox,
        });
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.built
            .as_ref()
            .map_or(Bounds3::EMPTY, |b| b.tree.bounds)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some(b) = &self.built else {
            return false;
        };
        let qid = Mailbox::query(ctx);
        let mut q = Nearest::new(ray);
        let mut nodes = 0;
        b.tree.traverse(ray, &mut nodes, |leaf| {
            b.mailbox.fresh(ctx, qid, leaf, |ctx, ids| {
                let ids = ids.iter().map(|&i| i as usize);
                b.prims.intersect_ids(ctx, &mut q, ids, hit, level);
                true
            });
            Some(q.ray.t_max)
        });
        ctx.stats.node_tests += nodes;
        q.found()
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let Some(b) = &self.built else {
            return false;
        };
        let qid = Mailbox::query(ctx);
        let mut found = false;
        let mut nodes = 0;
        b.tree.traverse(ray, &mut nodes, |leaf| {
            found = !b.mailbox.fresh(ctx, qid, leaf, |ctx, ids| {
                let ids = ids.iter().map(|&i| i as usize);
                !b.prims.occluded_ids(ctx, ray, ids, level)
            });
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
        if let Some(b) = &self.built {
            b.prims.local_geom(ctx, ray, hit, level, mask, out);
        }
    }
}

impl FlattensPrimitives for KdTreeAggregate {}

rtk_kernel::export_object!(
    KdTreeAggregate,
    class = "kdtree",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
