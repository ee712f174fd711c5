#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod bpt;
mod patch;
#[cfg(test)]
mod tests;

use patch::{Patch, V3};
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::path::PathBuf;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    file: Option<String>,
    #[serde(default)]
    patches: Option<Vec<Vec<[f64; 3]>>>,
    #[serde(default = "four")]
    grid: u32,
}

fn four() -> u32 {
    4
}

/// Most sub-patches a side.
const MAX_GRID: u32 = 16;

struct Bicubic {
    file: Option<PathBuf>,
    origin: [f64; 3],
    grid: usize,
    patches: Vec<Patch>,
    /// Each patch's box, rounded outwards to f32.
    boxes: Vec<Bounds3>,
    bounds: Bounds3,
    /// Sphere and slabs of every control point (`inq_bounds`): a Bézier
    /// patch lies in the convex hull of its control points.
    sphere: BoundSphere,
    slabs: SlabBounds,
    /// The patches close a volume (every boundary curve shared by two
    /// patches): only then is there an interior to be inside of.
    closed: bool,
}

/// The f32 box around an f64 box, rounded outwards.
fn f32_box(lo: V3, hi: V3) -> Bounds3 {
    let down = |x: f64| {
        let f = x as f32;
        if f as f64 > x {
            f.next_down()
        } else {
            f
        }
    };
    let up = |x: f64| {
        let f = x as f32;
        if (f as f64) < x {
            f.next_up()
        } else {
            f
        }
    };
    Bounds3::new(
        Vec3::new(down(lo[0]), down(lo[1]), down(lo[2])),
        Vec3::new(up(hi[0]), up(hi[1]), up(hi[2])),
    )
}

/// Patches from control points already placed (f32, relative to the
/// renderer's origin): converted exactly to f64.
fn build(points: &[[[f32; 3]; 16]], g: usize) -> (Vec<Patch>, Vec<Bounds3>, Bounds3) {
    let patches: Vec<Patch> = points
        .iter()
        .map(|cp| Patch::new(cp.map(|p| p.map(f64::from)), g))
        .collect();
    let boxes: Vec<Bounds3> = patches
        .iter()
        .map(|p| f32_box(p.bounds.lo, p.bounds.hi))
        .collect();
    let bounds = boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(*b));
    (patches, boxes, bounds)
}

impl Plugin for Bicubic {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        if p.grid == 0 || p.grid > MAX_GRID {
            return Err(PluginError::key(
                "grid",
                format!("must be from 1 to {MAX_GRID}, got {}", p.grid),
            ));
        }
        let g = p.grid as usize;
        match (p.file, p.patches) {
            (Some(_), Some(_)) => Err(PluginError::key(
                "patches",
                "give either `file` or `patches`, not both",
            )),
            (None, None) => Err(PluginError::msg(
                "needs `file` (a Newell-format patch file) or `patches` (arrays of 16 control points)",
            )),
            (Some(f), None) => {
                if f.is_empty() {
                    return Err(PluginError::key("file", "must name a patch file"));
                }
                Ok(Bicubic {
                    file: Some(env.resolve(&f)),
                    origin: env.origin,
                    grid: g,
                    patches: vec![],
                    boxes: vec![],
                    bounds: Bounds3::EMPTY,
                    sphere: BoundSphere::EMPTY,
                    slabs: SlabBounds::EMPTY,
                    closed: false,
                })
            }
            (None, Some(list)) => {
                if list.is_empty() {
                    return Err(PluginError::key("patches", "must hold at least one patch"));
                }
                let mut pts = Vec::with_capacity(list.len());
                for (i, patch) in list.iter().enumerate() {
                    if patch.len() != 16 {
                        return Err(PluginError::key(
                            format!("patches[{i}]"),
                            format!("must hold 16 control points, got {}", patch.len()),
                        ));
                    }
                    let mut cp = [[0.0f32; 3]; 16];
                    for (j, q) in patch.iter().enumerate() {
                        cp[j] = env.position(&format!("patches[{i}][{j}]"), *q)?.to_array();
                    }
                    pts.push(cp);
                }
                let (patches, boxes, bounds) = build(&pts, g);
                let (sphere, slabs) = volumes(&patches);
                Ok(Bicubic {
                    file: None,
                    origin: env.origin,
                    grid: g,
                    closed: closed(&patches),
                    patches,
                    boxes,
                    bounds,
                    sphere,
                    slabs,
                })
            }
        }
    }
}

/// Whether the patches close a volume: every boundary curve that is not
/// collapsed to a point (a pole, as at the top of a lid) is shared, control
/// point for control point and in either direction, by exactly two patches.
fn closed(patches: &[patch::Patch]) -> bool {
    use std::collections::HashMap;
    let mut curves: HashMap<[[u64; 3]; 4], u32> = HashMap::new();
    for p in patches {
        for idx in [
            [0, 1, 2, 3],
            [12, 13, 14, 15],
            [0, 4, 8, 12],
            [3, 7, 11, 15],
        ] {
            let c = idx.map(|k| p.cp[k].map(f64::to_bits));
            if c.iter().all(|q| *q == c[0]) {
                continue;
            }
            let mut r = c;
            r.reverse();
            *curves.entry(c.min(r)).or_insert(0) += 1;
        }
    }
    !curves.is_empty() && curves.values().all(|&n| n == 2)
}

/// Three directions unrelated to any patch layout (unit).
const VOTERS: [[f32; 3]; 3] = [
    [0.546_307, 0.718_221, 0.430_850],
    [-0.691_283, 0.182_137, 0.699_155],
    [0.214_089, -0.887_307, 0.408_428],
];

impl Bicubic {
    /// How many times the ray from `p` along `d` crosses the surface: the
    /// hits one after the other, each past the last (two patches meeting
    /// at one `t` count once).
    fn crossings(&self, p: Vec3, d: [f32; 3]) -> u32 {
        let mut ray = Ray::new(p, d.into());
        let mut count = 0;
        // Bounded: a ray crosses a closed patch surface a few times.
        for _ in 0..4 * self.patches.len() + 8 {
            match self.nearest(&ray, 0..self.patches.len() as u32) {
                Some((t, _, _)) => {
                    count += 1;
                    ray.t_min = t;
                }
                None => break,
            }
        }
        count
    }

    /// Nearest hit among `ids` (lowest id on equal t).
    fn nearest(&self, ray: &Ray, ids: impl Iterator<Item = u32>) -> Option<(f32, u32, [f32; 2])> {
        let o = ray.origin.to_array().map(f64::from);
        let d = ray.dir.to_array().map(f64::from);
        let mut best: Option<(f32, u32, [f32; 2])> = None;
        let mut t_max = ray.t_max as f64;
        for i in ids {
            if let Some(h) = self.patches[i as usize].intersect(o, d, ray.t_min as f64, t_max) {
                let t = h.t as f32;
                // The f32 t must itself be accepted by the ray.
                if !ray.accepts(t) {
                    continue;
                }
                let better = match best {
                    Some((bt, bi, _)) => t < bt || (t == bt && i < bi),
                    None => true,
                };
                if better {
                    best = Some((t, i, [h.u as f32, h.v as f32]));
                    t_max = h.t.max(t as f64);
                }
            }
        }
        best
    }
}

/// Largest patch file read: 1 GiB (the most patches and vertices a file
/// may declare, 2^24 each, take well under that as text).
const MAX_FILE_BYTES: u64 = 1 << 30;

/// Read a patch file through the host, bounded: only a regular file of at
/// most [`MAX_FILE_BYTES`] (a FIFO would block, `/dev/zero` never end).
fn read_patch_file(env: &Prepare, path: &std::path::Path) -> Result<Vec<u8>, PluginError> {
    let cannot = |e: &dyn std::fmt::Display| {
        PluginError::key("file", format!("cannot read {}: {e}", path.display()))
    };
    let meta = std::fs::metadata(path).map_err(|e| cannot(&e))?;
    if !meta.is_file() {
        #[cfg(unix)]
        let special = {
            use std::os::unix::fs::FileTypeExt;
            let t = meta.file_type();
            if t.is_fifo() {
                Some("a FIFO")
            } else if t.is_char_device() || t.is_block_device() {
                Some("a device")
            } else {
                None
            }
        };
        #[cfg(not(unix))]
        let special: Option<&str> = None;
        let kind = match special {
            Some(k) => k,
            None if meta.is_dir() => "a folder",
            None => "a special file",
        };
        return Err(cannot(&format!("it is {kind}, not a regular file")));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(cannot(&format!(
            "it is {} bytes, more than rtk's limit of {} GiB for a patch file",
            meta.len(),
            MAX_FILE_BYTES >> 30
        )));
    }
    let bytes = env.read_file(path).map_err(|e| cannot(&e))?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(cannot(&"it grew beyond 1 GiB while it was read"));
    }
    Ok(bytes)
}

impl Object for Bicubic {
    /// Inside closed patches by the majority of three rays' parities;
    /// open ones (Newell's teapot: its spout and handle end on the body)
    /// have no interior.
    fn in_interior(&self, _ctx: &mut TraceCtx, p: Vec3, _time: f32) -> Interior {
        if !self.closed {
            return Interior::NONE;
        }
        let odd = VOTERS
            .iter()
            .filter(|d| self.crossings(p, **d) % 2 == 1)
            .count();
        Interior::from_bool(odd >= 2)
    }

    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        let Some(path) = &self.file else {
            return Ok(());
        };
        let bytes = read_patch_file(env, path)?;
        let text = String::from_utf8_lossy(&bytes);
        let (idx, verts) = bpt::parse(&text)
            .map_err(|e| PluginError::key("file", format!("{}: {e}", path.display())))?;
        let o = self.origin;
        let place = |v: [f64; 3]| -> [f32; 3] { std::array::from_fn(|k| (v[k] - o[k]) as f32) };
        let pts: Vec<[[f32; 3]; 16]> = idx
            .iter()
            .map(|p| p.map(|k| place(verts[k as usize])))
            .collect();
        let (patches, boxes, bounds) = build(&pts, self.grid);
        self.patches = patches;
        self.boxes = boxes;
        self.bounds = bounds;
        (self.sphere, self.slabs) = volumes(&self.patches);
        self.closed = closed(&self.patches);
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        ctx.stats.prim_tests += self.patches.len() as u64;
        match self.nearest(ray, 0..self.patches.len() as u32) {
            Some((t, prim, uv)) => {
                hit.record_leaf(level, t, prim, uv);
                true
            }
            None => false,
        }
    }

    fn local_geom(
        &self,
        _ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let patch = &self.patches[hit.at(level) as usize];
        let o = ray.origin.to_array().map(f64::from);
        let d = ray.dir.to_array().map(f64::from);
        // The hit record keeps (u, v) in f32: polish them on this ray.
        let (u, v) = patch.refine(o, d, hit.uv[0] as f64, hit.uv[1] as f64);
        let ev = patch.eval(u, v);
        let err = patch.point_error(&ev);
        // Never NaN: a patch degenerate around (u, v) faces the ray.
        let n = patch.normal(u, v).unwrap_or_else(|| {
            let l = patch::dot(d, d).sqrt();
            d.map(|x| -x / l)
        });
        let n = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).normalize_or(Vec3::Y);
        out.p = Vec3::new(ev.p[0] as f32, ev.p[1] as f32, ev.p[2] as f32).into();
        out.p_err = Vec3::new(err[0] as f32, err[1] as f32, err[2] as f32).into();
        out.ng = n.into();
        out.ns = n.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            out.uv = [u.clamp(0.0, 1.0) as f32, v.clamp(0.0, 1.0) as f32];
            let du = Vec3::new(ev.du[0] as f32, ev.du[1] as f32, ev.du[2] as f32);
            let dv = Vec3::new(ev.dv[0] as f32, ev.dv[1] as f32, ev.dv[2] as f32);
            let (du, dv) =
                if du.cross(dv).length_squared() > 0.0 && du.is_finite() && dv.is_finite() {
                    (du, dv)
                } else {
                    n.any_orthonormal_pair()
                };
            out.dpdu = du.into();
            out.dpdv = dv.into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

impl PrimitiveSet for Bicubic {
    fn prim_count(&self) -> u32 {
        self.patches.len() as u32
    }
    fn prim_bounds(&self, first: u32, out: &mut [Bounds3]) {
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.boxes[first as usize + k];
        }
    }
    fn intersect_prims(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        ids: &[u32],
        hit: &mut Hit,
        level: u32,
    ) -> bool {
        ctx.stats.prim_tests += ids.len() as u64;
        match self.nearest(ray, ids.iter().copied()) {
            Some((t, prim, uv)) => {
                hit.record_leaf(level, t, prim, uv);
                true
            }
            None => false,
        }
    }
}

/// Sphere and slabs of every control point, formed in f64 and rounded
/// outward (the f64 control points are not f32 hull points).
fn volumes(patches: &[Patch]) -> (BoundSphere, SlabBounds) {
    let cps: Vec<V3> = patches.iter().flat_map(|p| p.cp).collect();
    (
        BoundSphere::around_points_f64(&cps, 0.0),
        SlabBounds::from_points_f64(&cps, 0.0),
    )
}

/// A Bézier patch lies in the convex hull of its control points.
impl BoundingVolumes for Bicubic {
    fn bound_sphere(&self, _t0: f32, _t1: f32) -> Option<BoundSphere> {
        Some(self.sphere)
    }
    fn slabs(&self, _t0: f32, _t1: f32) -> Option<SlabBounds> {
        Some(self.slabs)
    }
}

rtk_kernel::export_object!(
    Bicubic,
    class = "bicubic",
    doc = include_str!("../README.md"),
    capabilities = [PrimitiveSet, BoundingVolumes]
);
