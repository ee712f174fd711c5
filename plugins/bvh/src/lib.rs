#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::accel::{
    cull_bound, AnyHit, BuildParams, Bvh, Line, Nearest, Primitives, Simd, Slot, Visit,
};
use rtk_kernel::geom::{overlaps, SlabRay, SphereRay};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    max_leaf: Option<u32>,
    #[serde(default)]
    width: Option<u32>,
    #[serde(default)]
    bound: Bound,
    #[serde(default)]
    simd: SimdChoice,
}

/// The walk of an 8-wide tree (`simd`): the best the CPU has, or one
/// named, to compare them (each gives the same hits).
#[derive(Deserialize, Default, Clone, Copy, PartialEq)]
#[serde(crate = "rtk_kernel::serde", rename_all = "lowercase")]
enum SimdChoice {
    #[default]
    Auto,
    Avx512,
    Avx2,
    Portable,
}

impl SimdChoice {
    fn simd(self) -> Simd {
        match self {
            SimdChoice::Auto => Bvh::<8>::best_simd(),
            SimdChoice::Avx512 => Simd::Avx512,
            SimdChoice::Avx2 => Simd::Avx2,
            SimdChoice::Portable => Simd::Portable,
        }
    }
}

/// The volume each child of a node is bounded by (issue 12: what the
/// paper's volume types cost and save). Boxes are always tested, W at a
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

/// The tree, 4 or 8 wide (chosen in `create`).
enum Tree {
    Four(Bvh<4>),
    Eight(Bvh<8>),
}

struct Built {
    prims: Primitives,
    tree: Tree,
    volumes: Volumes,
}

struct BvhObject {
    children: Vec<Child>,
    /// `max_leaf` as given; the default depends on what is gathered
    /// ([`build_params`]).
    max_leaf: Option<u32>,
    width: u32,
    bound: Bound,
    /// The 8-wide tree's walk (checked against the CPU in `create`).
    simd: Simd,
    built: Option<Built>,
}

impl Plugin for BvhObject {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if p.max_leaf.is_some_and(|m| !(1..=64).contains(&m)) {
            return Err(PluginError::key("max_leaf", "must be between 1 and 64"));
        }
        let width = match p.width {
            None if Bvh::<8>::simd_available() => 8,
            None => 4,
            Some(w @ (4 | 8)) => w,
            Some(w) => {
                return Err(PluginError::key(
                    "width",
                    format!("must be 4 or 8, got {w}"),
                ))
            }
        };
        if width == 4 && p.simd != SimdChoice::Auto {
            let why = if p.width.is_none() {
                "the tree is 4-wide, as this CPU has no AVX2, and a 4-wide tree always runs SSE: drop `simd`"
            } else {
                "chooses the walk of an 8-wide tree; a 4-wide one always runs SSE: drop `simd` or set `width = 8`"
            };
            return Err(PluginError::key("simd", why));
        }
        let simd = p.simd.simd();
        if !Bvh::<8>::supports(simd) {
            let here: Vec<String> = [Simd::Avx512, Simd::Avx2, Simd::Portable]
                .into_iter()
                .filter(|&s| Bvh::<8>::supports(s))
                .map(|s| format!("\"{}\"", s.name()))
                .collect();
            return Err(PluginError::key(
                "simd",
                format!(
                    "\"{}\" needs {}, which this CPU lacks; it runs {} (\"auto\" picks the best)",
                    simd.name(),
                    match simd {
                        Simd::Avx512 => "AVX-512 F, VL, BW and DQ (and AVX2)",
                        _ => "AVX2, FMA, BMI1, BMI2, POPCNT and LZCNT",
                    },
                    here.join(" and ")
                ),
            ));
        }
        Ok(BvhObject {
            children: Vec::new(),
            max_leaf: p.max_leaf,
            width,
            bound: p.bound,
            simd,
            built: None,
        })
    }
}

/// The SAH's settings for what was gathered. Leaves are tested four
/// triangles at a time, so the SAH counts a leaf in blocks of four, each
/// costing a node visit (Embree's builders' costs). Over triangles only, a
/// leaf may hold up to 12 (three blocks): with the kernel's build filling
/// each node before it makes leaves, the dragon's tree then has the shape
/// of Embree's (node and leaf counts, SAH cost), and its primary rays run
/// faster than with leaves of at most 4, the others no slower (BENCHMARKS.md,
/// issue 7, "Fourth session: Embree's own tree"). A leaf of other entries
/// costs a call per entry, whatever the blocks say: there leaves stay at 4.
fn build_params(g: &rtk_kernel::accel::Gathered, max_leaf: Option<u32>) -> BuildParams {
    let tris = g.prims.all_triangles();
    BuildParams {
        max_leaf: max_leaf.map_or(if tris { 12 } else { 4 }, |m| m as usize),
        prim_cost: 1.0,
        block: 4,
    }
}

/// Build a `W`-wide tree over the gathered primitives, with its slots'
/// second volumes.
fn build<const W: usize>(
    g: rtk_kernel::accel::Gathered,
    params: BuildParams,
    bound: Bound,
    simd: Simd,
    env: &Prepare,
) -> Result<(Primitives, Bvh<W>, Volumes), PluginError> {
    // Subtrees are built on the host's pool.
    let mut bvh = Bvh::<W>::build_on(&g.boxes, params, &|n, f| env.parallel_for(n, f));
    if W == 8 {
        // Checked against the CPU in `create`.
        bvh.set_simd(simd);
    }
    // Leaves start at multiples of four: each names its block of four
    // triangles, screened at once.
    bvh.pad_leaves(4);
    let mut prims = g.prims;
    prims.reorder(&bvh.order);
    let volumes = match bound {
        Bound::Box => Volumes::None,
        Bound::Sphere => Volumes::Spheres(slot_volumes(
            &bvh,
            |i| prims.bound_sphere(i),
            |a, b| a.union(b),
            BoundSphere::EMPTY,
        )?),
        Bound::Slabs => Volumes::Slabs(slot_volumes(
            &bvh,
            |i| prims.slabs(i),
            |a, b| a.union(b),
            SlabBounds::EMPTY,
        )?),
    };
    prims.pack();
    prims.mark_leaves(bvh.leaves());
    if W == 8 && bvh.simd() != Simd::Portable && bound == Bound::Box {
        // The 8-wide AVX walks read each node with its leaves beside it,
        // and nothing reads the table's own blocks after.
        if bvh.interleave(|first| prims.leaf_lines(first)) {
            prims.drop_blocks();
        }
    }
    Ok((prims, bvh, volumes))
}

/// Nearest hit through a `W`-wide tree.
#[inline(always)]
fn intersect_in<const W: usize>(
    b: &Built,
    bvh: &Bvh<W>,
    ctx: &mut TraceCtx,
    ray: &Ray,
    hit: &mut Hit,
    level: u32,
) -> bool {
    let mut q = None;
    let mut nodes = 0;
    let leaf = NearestLeaf {
        prims: &b.prims,
        ctx,
        ray,
        q: &mut q,
        hit,
        level,
    };
    // Boxes within the tie margin of the best hit are still entered
    // (rule 11, `cull_bound`).
    let t_max = cull_bound(ray.t_max);
    match &b.volumes {
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
    q.is_some_and(|q| q.found())
}

/// The leaf test of a nearest-hit query, compiled into the walk
/// ([`Visit`]). The query (the ray's shear for the triangle test) is made
/// at the first leaf: a ray that reaches none never pays for it.
struct NearestLeaf<'a> {
    prims: &'a Primitives,
    ctx: &'a mut TraceCtx,
    ray: &'a Ray,
    q: &'a mut Option<Nearest>,
    hit: &'a mut Hit,
    level: u32,
}

impl Visit for NearestLeaf<'_> {
    #[inline(always)]
    fn leaf(&mut self, first: usize) -> Option<f32> {
        let q = self.q.get_or_insert_with(|| Nearest::new(self.ray));
        (self.prims).intersect_leaf(self.ctx, q, first, self.hit, self.level);
        Some(cull_bound(q.ray.t_max))
    }

    #[inline(always)]
    fn prefetch(&self, first: usize) {
        self.prims.prefetch_leaf(first);
    }

    #[inline(always)]
    fn leaf_lines(&mut self, lines: &[Line]) -> Option<f32> {
        let q = self.q.get_or_insert_with(|| Nearest::new(self.ray));
        (self.prims).intersect_lines(self.ctx, q, lines, self.hit, self.level);
        Some(cull_bound(q.ray.t_max))
    }
}

/// The leaf test of an any-hit query, compiled into the walk; its query is
/// made at the first leaf too.
struct AnyLeaf<'a> {
    prims: &'a Primitives,
    ctx: &'a mut TraceCtx,
    ray: &'a Ray,
    q: Option<AnyHit>,
    found: &'a mut bool,
    level: u32,
}

impl Visit for AnyLeaf<'_> {
    #[inline(always)]
    fn leaf(&mut self, first: usize) -> Option<f32> {
        let q = self.q.get_or_insert_with(|| AnyHit::new(self.ray));
        *self.found = (self.prims).occluded_leaf(self.ctx, q, first, self.level);
        (!*self.found).then_some(self.ray.t_max)
    }

    #[inline(always)]
    fn prefetch(&self, first: usize) {
        self.prims.prefetch_leaf(first);
    }

    #[inline(always)]
    fn leaf_lines(&mut self, lines: &[Line]) -> Option<f32> {
        let q = self.q.get_or_insert_with(|| AnyHit::new(self.ray));
        *self.found = (self.prims).occluded_lines(self.ctx, q, lines, self.level);
        (!*self.found).then_some(self.ray.t_max)
    }
}

/// Any hit through a `W`-wide tree.
#[inline(always)]
fn occluded_in<const W: usize>(
    b: &Built,
    bvh: &Bvh<W>,
    ctx: &mut TraceCtx,
    ray: &Ray,
    level: u32,
) -> bool {
    let mut found = false;
    let mut nodes = 0;
    // Any hit will do: no tie to keep, no margin.
    let leaf = AnyLeaf {
        prims: &b.prims,
        ctx,
        ray,
        q: None,
        found: &mut found,
        level,
    };
    match &b.volumes {
        Volumes::None => bvh.traverse_any(ray, ray.t_max, &mut nodes, leaf),
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

impl Object for BvhObject {
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
        let params = build_params(&g, self.max_leaf);
        self.built = Some(if self.width == 8 {
            let (prims, bvh, volumes) = build::<8>(g, params, self.bound, self.simd, env)?;
            Built {
                prims,
                tree: Tree::Eight(bvh),
                volumes,
            }
        } else {
            let (prims, bvh, volumes) = build::<4>(g, params, self.bound, self.simd, env)?;
            Built {
                prims,
                tree: Tree::Four(bvh),
                volumes,
            }
        });
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        match self.built.as_ref().map(|b| &b.tree) {
            Some(Tree::Four(t)) => t.bounds(),
            Some(Tree::Eight(t)) => t.bounds(),
            None => Bounds3::EMPTY,
        }
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some(b) = &self.built else {
            return false;
        };
        match &b.tree {
            Tree::Four(t) => intersect_in(b, t, ctx, ray, hit, level),
            Tree::Eight(t) => intersect_in(b, t, ctx, ray, hit, level),
        }
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let Some(b) = &self.built else {
            return false;
        };
        match &b.tree {
            Tree::Four(t) => occluded_in(b, t, ctx, ray, level),
            Tree::Eight(t) => occluded_in(b, t, ctx, ray, level),
        }
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
/// entries' volumes, an inner slot's from its node's `W`.
fn slot_volumes<const W: usize, V: Copy>(
    bvh: &Bvh<W>,
    of: impl Fn(usize) -> Result<V, PluginError>,
    union: impl Fn(&V, &V) -> V,
    empty: V,
) -> Result<Vec<V>, PluginError> {
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
            Slot::Node(n) => (0..W).fold(empty, |acc, k| union(&acc, &v[n * W + k])),
        };
    }
    Ok(v)
}

impl FlattensPrimitives for BvhObject {}

rtk_kernel::export_object!(
    BvhObject,
    class = "bvh",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
