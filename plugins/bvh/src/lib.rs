#![doc = include_str!("../README.md")]

use rtk_kernel::accel::{cull_bound, BuildParams, Bvh4, Nearest, Primitives, Slot};
use rtk_kernel::geom::{overlaps, SlabRay, SphereRay};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "four")]
    max_leaf: u32,
    #[serde(default)]
    bound: Bound,
}

/// The volume each child of a node is bounded by (issue 12: what the
/// paper's volume types cost and save). Boxes are always tested, four at a
/// time; a sphere or slabs is tested after, on the box's survivors, so the
/// child is bounded by the intersection of both.
#[derive(Deserialize, Default, Clone, Copy, PartialEq)]
#[serde(crate = "rtk_kernel::serde", rename_all = "lowercase")]
enum Bound {
    #[default]
    Box,
    Sphere,
    Slabs,
}

/// The second volume of every slot, when `bound` asks for one.
enum Volumes {
    None,
    Spheres(Vec<BoundSphere>),
    Slabs(Vec<SlabBounds>),
}

fn four() -> u32 {
    4
}

struct Bvh {
    children: Vec<Child>,
    params: BuildParams,
    bound: Bound,
    built: Option<(Primitives, Bvh4)>,
    volumes: Volumes,
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
            bound: p.bound,
            built: None,
            volumes: Volumes::None,
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
        self.volumes = match self.bound {
            Bound::Box => Volumes::None,
            Bound::Sphere => Volumes::Spheres(slot_volumes(
                &bvh,
                &prims,
                |i| prims.bound_sphere(i),
                |a, b| a.union(b),
                BoundSphere::EMPTY,
            )?),
            Bound::Slabs => Volumes::Slabs(slot_volumes(
                &bvh,
                &prims,
                |i| prims.slabs(i),
                |a, b| a.union(b),
                SlabBounds::EMPTY,
            )?),
        };
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
        let leaf = |leaf| {
            prims.intersect_range(ctx, &mut q, leaf, hit, level);
            Some(cull_bound(q.ray.t_max))
        };
        let t_max = cull_bound(ray.t_max);
        match &self.volumes {
            Volumes::None => bvh.traverse(ray, t_max, &mut nodes, leaf),
            Volumes::Spheres(v) => bvh.traverse_screened(
                ray,
                t_max,
                &mut nodes,
                screen(ray, v, SphereRay::new(ray), BoundSphere::interval),
                leaf,
            ),
            Volumes::Slabs(v) => bvh.traverse_screened(
                ray,
                t_max,
                &mut nodes,
                screen(ray, v, SlabRay::new(ray), SlabBounds::interval),
                leaf,
            ),
        }
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
        let leaf = |leaf| {
            found = prims.occluded_range(ctx, ray, leaf, level);
            (!found).then_some(ray.t_max)
        };
        match &self.volumes {
            Volumes::None => bvh.traverse(ray, ray.t_max, &mut nodes, leaf),
            Volumes::Spheres(v) => bvh.traverse_screened(
                ray,
                ray.t_max,
                &mut nodes,
                screen(ray, v, SphereRay::new(ray), BoundSphere::interval),
                leaf,
            ),
            Volumes::Slabs(v) => bvh.traverse_screened(
                ray,
                ray.t_max,
                &mut nodes,
                screen(ray, v, SlabRay::new(ray), SlabBounds::interval),
                leaf,
            ),
        }
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

/// The test of a slot's second volume: it may only reject the child or move
/// its entry later (the volume's entry, when past the box's).
fn screen<'a, V, P: 'a>(
    ray: &'a Ray,
    v: &'a [V],
    pre: P,
    interval: fn(&V, &P) -> Option<(f32, f32)>,
) -> impl FnMut(usize, f32, f32) -> Option<f32> + 'a {
    move |slot, t_box, t_max| {
        overlaps(interval(&v[slot], &pre), ray.t_min, t_max).map(|t| t.max(t_box))
    }
}

/// A volume for every slot of the tree, children first: a leaf's from its
/// entries' volumes, an inner slot's from its node's four.
fn slot_volumes<V: Copy>(
    bvh: &Bvh4,
    prims: &Primitives,
    of: impl Fn(usize) -> Result<V, PluginError>,
    union: impl Fn(&V, &V) -> V,
    empty: V,
) -> Result<Vec<V>, PluginError> {
    let _ = prims;
    let mut v = vec![empty; bvh.slot_count()];
    for (id, slot) in bvh.slots() {
        v[id] = match slot {
            Slot::Empty => empty,
            Slot::Leaf(r) => {
                let mut acc = empty;
                for i in r {
                    acc = union(&acc, &of(i)?);
                }
                acc
            }
            Slot::Node(n) => (0..4).fold(empty, |acc, k| union(&acc, &v[n * 4 + k])),
        };
    }
    Ok(v)
}

impl FlattensPrimitives for Bvh {}

rtk_kernel::export_object!(
    Bvh,
    class = "bvh",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
