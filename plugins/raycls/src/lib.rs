#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod cells;

use cells::{Limits, Tree, MAX_DEPTH};
use rtk_kernel::accel::{cull_bound, Nearest, Primitives};
use rtk_kernel::geom::RayBoxPrecomp;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    // Signed, so a negative value meets the range check below and its
    // message, not the integer type's "0 to 4294967295".
    #[serde(default = "default_candidates")]
    max_candidates: i64,
    #[serde(default = "default_depth")]
    max_depth: i64,
    #[serde(default = "default_visits")]
    min_visits: i64,
    #[serde(default = "default_memory")]
    max_memory_mb: f64,
    #[serde(default)]
    stats: bool,
}

fn default_candidates() -> i64 {
    8
}
fn default_depth() -> i64 {
    48
}
fn default_visits() -> i64 {
    2
}
fn default_memory() -> f64 {
    512.0
}

/// Most megabytes (2²⁰ bytes) a budget may name: 1 PiB.
const MAX_MEMORY_MB: f64 = 1_073_741_824.0;
/// Candidates handed to the primitive table at once between checks of the
/// stopping distance.
const BATCH: usize = 4;

/// How a ray is answered.
enum Class {
    /// It misses the scene's box: only the always-tested primitives.
    Miss,
    /// Every primitive (non-finite rays, a subnormal direction, an origin
    /// too far away to classify within the cells' padding): exactly the
    /// list.
    Brute,
    /// Through the cell of this root (0–5 inner, 6–11 outer) and point
    /// (origin, u, v).
    Cell(usize, [f64; 5]),
}

struct Built {
    prims: Primitives,
    tree: Tree,
    /// Primitives with infinite boxes: tested by every query, classified
    /// nowhere.
    always: Vec<u32>,
    /// The union of the finite boxes: the roots' origin box, padded.
    finite: Bounds3,
    /// What `bounds` reports: every box.
    bounds: Bounds3,
}

/// The aggregate: its children until `prepare`, then the primitive table
/// and the lazily built cells.
struct RayCls {
    children: Vec<Child>,
    limits: Limits,
    stats: bool,
    built: Option<Built>,
}

impl Plugin for RayCls {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(1..=1 << 20).contains(&p.max_candidates) {
            return Err(PluginError::key(
                "max_candidates",
                "must be between 1 and 1048576",
            ));
        }
        if !(0..=MAX_DEPTH as i64).contains(&p.max_depth) {
            return Err(PluginError::key(
                "max_depth",
                format!("must be between 0 and {MAX_DEPTH}"),
            ));
        }
        if !(1..=1 << 20).contains(&p.min_visits) {
            return Err(PluginError::key(
                "min_visits",
                "must be between 1 and 1048576",
            ));
        }
        if !(p.max_memory_mb > 0.0 && p.max_memory_mb <= MAX_MEMORY_MB) {
            return Err(PluginError::key(
                "max_memory_mb",
                "must be a positive number of megabytes, at most 2^30",
            ));
        }
        Ok(RayCls {
            children: Vec::new(),
            limits: Limits {
                max_cands: p.max_candidates as usize,
                max_depth: p.max_depth as u32,
                min_visits: p.min_visits as u32,
                budget_bytes: (p.max_memory_mb * 1_048_576.0) as u64,
            },
            stats: p.stats,
            built: None,
        })
    }
}

impl Built {
    /// How `ray` is answered; see [`Class`].
    #[inline]
    fn classify(&self, ray: &Ray) -> Class {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        if !(o.iter().chain(&d).all(|x| x.is_finite())) || ray.t_min.is_nan() || ray.t_max.is_nan()
        {
            return Class::Brute;
        }
        if self.finite.is_empty()
            || RayBoxPrecomp::new(ray)
                .intersect(&self.finite, ray.t_min, ray.t_max)
                .is_none()
        {
            return Class::Miss;
        }
        match self.tree.classify(o, d, ray.t_min) {
            Some((root, x)) => Class::Cell(root, x),
            None => Class::Brute,
        }
    }
}

impl Object for RayCls {
    /// Inside any child: the union of their interiors.
    fn in_interior(&self, ctx: &mut TraceCtx, p: rtk_kernel::glam::Vec3, time: f32) -> Interior {
        union_interior(&self.children, ctx, p, time)
    }

    fn add_child(&mut self, child: Child) -> Result<(), PluginError> {
        self.children.push(child);
        Ok(())
    }

    fn prepare(&mut self, _env: &Prepare) -> Result<(), PluginError> {
        let g = Primitives::gather(&self.children)?;
        let mut live = Vec::new();
        let mut always = Vec::new();
        let mut finite = Bounds3::EMPTY;
        let mut bounds = Bounds3::EMPTY;
        for (i, b) in g.boxes.iter().enumerate() {
            // Empty (or NaN) boxes bound nothing that can be hit.
            if b.is_empty() {
                continue;
            }
            bounds = bounds.union(*b);
            if b.min.is_finite() && b.max.is_finite() {
                finite = finite.union(*b);
                live.push(i as u32);
            } else {
                always.push(i as u32);
            }
        }
        let fixed = g.prims.bytes()
            + always.capacity() * 4
            + std::mem::size_of::<Built>()
            + self.children.capacity() * std::mem::size_of::<Child>();
        let tree = Tree::new(g.boxes, live, finite, self.limits, fixed as u64);
        self.built = Some(Built {
            prims: g.prims,
            tree,
            always,
            finite,
            bounds,
        });
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.built.as_ref().map_or(Bounds3::EMPTY, |b| b.bounds)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        let Some(b) = &self.built else {
            return false;
        };
        let mut q = Nearest::new(ray);
        if !b.always.is_empty() {
            let ids = b.always.iter().map(|&i| i as usize);
            b.prims.intersect_ids(ctx, &mut q, ids, hit, level);
        }
        match b.classify(ray) {
            Class::Miss => {}
            Class::Brute => b
                .prims
                .intersect_ids(ctx, &mut q, 0..b.prims.len(), hit, level),
            Class::Cell(face, x) => {
                let mut nodes = 0;
                let cell = b.tree.descend(face, &x, &mut nodes);
                ctx.stats.node_tests += nodes;
                let Some(cell) = cell else {
                    b.prims
                        .intersect_ids(ctx, &mut q, 0..b.prims.len(), hit, level);
                    return q.found();
                };
                let a0 = (face % 6) / 2;
                let o0 = ray.origin.to_array()[a0];
                let inv0 = 1.0 / ray.dir.to_array()[a0];
                let c = &cell.cands;
                let mut i = 0;
                // Nearest side first; stop at the first candidate whose near
                // side lies beyond the best hit by more than the tie margin
                // (rule 11, `cull_bound`): its primitive, and every later
                // one, can only be hit farther. `!(t > bound)` keeps going on
                // a NaN.
                while i < c.len() {
                    let bound = cull_bound(q.ray.t_max);
                    let mut j = i;
                    while j < c.len() && j - i < BATCH && !((c[j].near - o0) * inv0 > bound) {
                        j += 1;
                    }
                    if j == i {
                        break;
                    }
                    let ids = c[i..j].iter().map(|c| c.id as usize);
                    b.prims.intersect_ids(ctx, &mut q, ids, hit, level);
                    i = j;
                }
            }
        }
        q.found()
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, level: u32) -> bool {
        let Some(b) = &self.built else {
            return false;
        };
        if !b.always.is_empty() {
            let ids = b.always.iter().map(|&i| i as usize);
            if b.prims.occluded_ids(ctx, ray, ids, level) {
                return true;
            }
        }
        match b.classify(ray) {
            Class::Miss => false,
            Class::Brute => b.prims.occluded_ids(ctx, ray, 0..b.prims.len(), level),
            Class::Cell(face, x) => {
                let mut nodes = 0;
                let cell = b.tree.descend(face, &x, &mut nodes);
                ctx.stats.node_tests += nodes;
                let Some(cell) = cell else {
                    return b.prims.occluded_ids(ctx, ray, 0..b.prims.len(), level);
                };
                let a0 = (face % 6) / 2;
                let o0 = ray.origin.to_array()[a0];
                let inv0 = 1.0 / ray.dir.to_array()[a0];
                // Any hit will do; the candidates that start within reach
                // form a prefix (their near sides are sorted). The margin
                // covers the rounding of the near distance.
                let bound = cull_bound(ray.t_max);
                let c = &cell.cands;
                let end = c.partition_point(|c| !((c.near - o0) * inv0 > bound));
                let ids = c[..end].iter().map(|c| c.id as usize);
                b.prims.occluded_ids(ctx, ray, ids, level)
            }
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

impl Drop for RayCls {
    fn drop(&mut self) {
        if !self.stats {
            return;
        }
        let Some(b) = &self.built else {
            return;
        };
        let t = &b.tree.budget;
        let r = std::sync::atomic::Ordering::Relaxed;
        eprintln!(
            "raycls stats: primitives={} cells={} memory_bytes={} peak_bytes={} budget_bytes={} refused={} raced={}",
            b.prims.len(),
            t.cells.load(r),
            t.used(),
            t.peak(),
            t.limit,
            t.refused.load(r),
            t.raced.load(r),
        );
    }
}

impl FlattensPrimitives for RayCls {}

rtk_kernel::export_object!(
    RayCls,
    class = "raycls",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
