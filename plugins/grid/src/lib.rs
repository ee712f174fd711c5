#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::accel::{CellAggregate, CellsAlongRay, Primitives};
use rtk_kernel::geom::RayBoxPrecomp;
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "three")]
    density: f32,
    #[serde(default = "cells_cap")]
    max_cells: u64,
}

fn three() -> f32 {
    3.0
}
fn cells_cap() -> u64 {
    1 << 24
}

/// The cells: resolution, box, and each cell's primitive list (CSR layout:
/// cell `c` lists `ids[start[c]..start[c + 1]]`).
struct Cells {
    res: [i32; 3],
    lo: Vec3,
    width: Vec3,
    bounds: Bounds3,
    start: Vec<u32>,
    ids: Vec<u32>,
}

struct Grid {
    children: Vec<Child>,
    density: f32,
    max_cells: u64,
    built: Option<CellAggregate<Cells>>,
}

impl Plugin for Grid {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(p.density.is_finite() && p.density > 0.0) {
            return Err(PluginError::key("density", "must be a positive number"));
        }
        if p.max_cells == 0 {
            return Err(PluginError::key("max_cells", "must be at least 1"));
        }
        Ok(Grid {
            children: Vec::new(),
            density: p.density,
            max_cells: p.max_cells,
            built: None,
        })
    }
}

impl Cells {
    /// Cells over `boxes`, about `density · n^(1/3)` along the longest axis.
    fn build(boxes: &[Bounds3], density: f32, max_cells: u64) -> Cells {
        let bounds = boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(*b));
        let ext = if bounds.is_empty() {
            Vec3::ONE
        } else {
            (bounds.max.v() - bounds.min.v()).max(Vec3::splat(f32::MIN_POSITIVE))
        };
        let per_unit = density * (boxes.len().max(1) as f32).cbrt() / ext.max_element();
        let mut res = (ext * per_unit).ceil().as_ivec3().clamp(
            rtk_kernel::glam::IVec3::ONE,
            rtk_kernel::glam::IVec3::splat(512),
        );
        while res.x as u64 * res.y as u64 * res.z as u64 > max_cells {
            res = (res / 2).max(rtk_kernel::glam::IVec3::ONE);
        }
        let lo = if bounds.is_empty() {
            Vec3::ZERO
        } else {
            bounds.min.v()
        };
        let mut c = Cells {
            res: res.to_array(),
            lo,
            width: ext / res.as_vec3(),
            bounds,
            start: Vec::new(),
            ids: Vec::new(),
        };
        c.fill(boxes);
        c
    }

    /// The cell range (inclusive) a box overlaps, grown by a thousandth of a cell.
    fn range(&self, b: &Bounds3) -> Option<([i32; 3], [i32; 3])> {
        if b.is_empty() {
            return None;
        }
        let margin = self.width * 1e-3;
        let a = ((b.min.v() - margin - self.lo) / self.width)
            .floor()
            .as_ivec3();
        let z = ((b.max.v() + margin - self.lo) / self.width)
            .floor()
            .as_ivec3();
        let top = rtk_kernel::glam::IVec3::from(self.res) - 1;
        let zero = rtk_kernel::glam::IVec3::ZERO;
        Some((a.clamp(zero, top).to_array(), z.clamp(zero, top).to_array()))
    }

    fn index(&self, x: i32, y: i32, z: i32) -> usize {
        (x + self.res[0] * (y + self.res[1] * z)) as usize
    }

    /// List each primitive in the cells its box overlaps: count, then place.
    fn fill(&mut self, boxes: &[Bounds3]) {
        let n = (self.res[0] * self.res[1] * self.res[2]) as usize;
        let mut count = vec![0u32; n + 1];
        let ranges: Vec<_> = boxes.iter().map(|b| self.range(b)).collect();
        for (a, z) in ranges.iter().flatten() {
            self.each(*a, *z, |c| count[c] += 1);
        }
        let mut start = vec![0u32; n + 1];
        for c in 0..n {
            start[c + 1] = start[c] + count[c];
        }
        let mut next = start.clone();
        let mut ids = vec![0u32; start[n] as usize];
        for (i, r) in ranges.iter().enumerate() {
            if let Some((a, z)) = r {
                self.each(*a, *z, |c| {
                    ids[next[c] as usize] = i as u32;
                    next[c] += 1;
                });
            }
        }
        self.start = start;
        self.ids = ids;
    }

    fn each(&self, a: [i32; 3], z: [i32; 3], mut f: impl FnMut(usize)) {
        for k in a[2]..=z[2] {
            for j in a[1]..=z[1] {
                for i in a[0]..=z[0] {
                    f(self.index(i, j, k));
                }
            }
        }
    }
}

impl CellsAlongRay for Cells {
    fn bounds(&self) -> Bounds3 {
        self.bounds
    }

    /// Step from cell to cell along the ray (Amanatides and Woo's 3D-DDA):
    /// from the cell where the ray enters the box, across whichever cell
    /// boundary comes first, until the next cell starts beyond the best hit
    /// or the ray leaves the box.
    #[inline]
    fn walk(&self, ray: &Ray, node_tests: &mut u64, mut cell: impl FnMut(&[u32]) -> Option<f32>) {
        let Some(h) = RayBoxPrecomp::new(ray).intersect(&self.bounds, ray.t_min, ray.t_max) else {
            return;
        };
        let (o, d) = (ray.origin.v(), ray.dir.v());
        let p = o + d * h.t0.max(ray.t_min);
        let mut pos = [0i32; 3];
        let (mut next, mut delta, mut step, mut out) = ([0f32; 3], [0f32; 3], [0i32; 3], [0i32; 3]);
        for a in 0..3 {
            let v = ((p[a] - self.lo[a]) / self.width[a]).floor() as i32;
            pos[a] = v.clamp(0, self.res[a] - 1);
            if d[a] > 0.0 {
                let edge = self.lo[a] + (pos[a] + 1) as f32 * self.width[a];
                next[a] = h.t0 + (edge - p[a]) / d[a];
                delta[a] = self.width[a] / d[a];
                (step[a], out[a]) = (1, self.res[a]);
            } else if d[a] < 0.0 {
                let edge = self.lo[a] + pos[a] as f32 * self.width[a];
                next[a] = h.t0 + (edge - p[a]) / d[a];
                delta[a] = -self.width[a] / d[a];
                (step[a], out[a]) = (-1, -1);
            } else {
                (next[a], delta[a], step[a], out[a]) = (f32::INFINITY, 0.0, 0, -2);
            }
        }
        let mut best = ray.t_max;
        loop {
            *node_tests += 1;
            let c = self.index(pos[0], pos[1], pos[2]);
            let ids = &self.ids[self.start[c] as usize..self.start[c + 1] as usize];
            if !ids.is_empty() {
                match cell(ids) {
                    Some(t) => best = t,
                    None => return,
                }
            }
            // The axis whose boundary comes first.
            let a = if next[0] < next[1] {
                if next[0] < next[2] {
                    0
                } else {
                    2
                }
            } else if next[1] < next[2] {
                1
            } else {
                2
            };
            // The next cell starts beyond the best hit (a tie at its entry
            // must still be able to win there), or beyond the box: done.
            if next[a] > best || next[a] > h.t1 || !next[a].is_finite() {
                return;
            }
            pos[a] += step[a];
            if pos[a] == out[a] {
                return;
            }
            next[a] += delta[a];
        }
    }
}

impl Object for Grid {
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
        let cells = Cells::build(&g.boxes, self.density, self.max_cells);
        self.built = Some(CellAggregate::new(g.prims, cells, env.max_threads()));
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

impl FlattensPrimitives for Grid {}

rtk_kernel::export_object!(
    Grid,
    class = "grid",
    doc = include_str!("../README.md"),
    capabilities = [FlattensPrimitives]
);
