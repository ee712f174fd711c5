#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod load;
mod obj;
mod ply;

use rtk_kernel::geom::{intersect_triangle, triangle_point_inset};
use rtk_kernel::glam::{self, Vec3};
use rtk_kernel::sdk::shading::{pick_from_cdf, uniform_triangle};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use std::path::PathBuf;

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(crate = "rtk_kernel::serde", rename_all = "lowercase")]
enum Normals {
    Auto,
    Face,
    Vertex,
}

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    /// Empty when the host passes the mesh as arrays ([`Env::arrays`]).
    #[serde(default)]
    file: String,
    #[serde(default = "auto")]
    normals: Normals,
}

fn auto() -> Normals {
    Normals::Auto
}

/// Where the triangles come from: a file read at `prepare`, or the host's
/// arrays, copied (and placed at the origin) in `create`, since they are
/// lent only for that call.
enum Source {
    File(PathBuf),
    Arrays(Option<load::MeshData>),
}

struct Mesh {
    source: Source,
    /// The renderer's origin (`Env::origin`), subtracted from the file's
    /// vertices when they are read.
    origin: [f64; 3],
    normals_mode: Normals,
    p: Vec<[f32; 3]>,
    tris: Vec<[u32; 3]>,
    vn: Option<Vec<Vec3>>,
    uv: Option<Vec<[f32; 2]>>,
    bounds: Bounds3,
    /// Each triangle's three vertices, contiguous: the hot loop reads one
    /// 36-byte record per triangle instead of following three indices.
    tv: Vec<[[f32; 3]; 3]>,
    /// 0..n: every triangle, for the brute-force queries.
    all_ids: Vec<u32>,
    /// Running sum of the triangles' areas (f64, so a million small
    /// triangles add up exactly enough): area lights pick a triangle by it.
    area_cdf: Vec<f64>,
    /// The solid the mesh bounds, when it is closed (`None` inside: open),
    /// built at the first `in_interior` (nothing else needs it).
    solid: std::sync::OnceLock<Option<rtk_kernel::accel::TriangleSolid>>,
}

impl Mesh {
    #[inline]
    fn verts(&self, i: u32) -> [[f32; 3]; 3] {
        let t = self.tris[i as usize];
        [
            self.p[t[0] as usize],
            self.p[t[1] as usize],
            self.p[t[2] as usize],
        ]
    }

    fn tri_bounds(&self, i: u32) -> Bounds3 {
        let v = self.verts(i);
        Bounds3::EMPTY
            .include(v[0].into())
            .include(v[1].into())
            .include(v[2].into())
    }

    /// Nearest hit among `ids`, lowest id on ties; updates `best`.
    #[inline]
    fn test_ids(
        &self,
        ray: &Ray,
        ids: &[u32],
        best: &mut Option<(f32, u32, [f32; 2])>,
        prim_tests: &mut u64,
    ) {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        *prim_tests += ids.len() as u64;
        // Let an equal t through (one ulp more) so the tie rule can apply.
        let mut limit = match best {
            Some((t, _, _)) => t.next_up(),
            None => ray.t_max,
        };
        for &i in ids {
            if let Some(h) = intersect_triangle(o, d, self.tv[i as usize], ray.t_min, limit) {
                let better = match best {
                    Some((t, id, _)) => h.t < *t || i < *id,
                    None => true,
                };
                if better && h.t < ray.t_max {
                    *best = Some((h.t, i, [h.b[1], h.b[2]]));
                    limit = h.t.next_up();
                }
            }
        }
    }

    #[inline]
    fn any_ids(&self, ray: &Ray, ids: &[u32], prim_tests: &mut u64) -> bool {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        ids.iter().any(|&i| {
            *prim_tests += 1;
            intersect_triangle(o, d, self.verts(i), ray.t_min, ray.t_max).is_some()
        })
    }

    /// Nearest hit by testing every triangle: a mesh is intersected fast
    /// only inside an aggregate (the shell wraps it in one: `accel`).
    fn nearest(&self, ctx: &mut TraceCtx, ray: &Ray) -> Option<(f32, u32, [f32; 2])> {
        let mut best = None;
        let mut prim_tests = 0;
        for chunk in self.all_ids.chunks(256) {
            self.test_ids(ray, chunk, &mut best, &mut prim_tests);
        }
        ctx.stats.prim_tests += prim_tests;
        best
    }
}

impl Plugin for Mesh {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let source = if env.arrays.get("vertices").is_some() {
            if !p.file.is_empty() {
                return Err(PluginError::key(
                    "file",
                    "give the mesh as a file or as arrays (vertices, indices), not both",
                ));
            }
            Source::Arrays(Some(from_arrays(env)?))
        } else {
            Source::File(file_param(&p.file, env)?)
        };
        Ok(Mesh {
            source,
            origin: env.origin,
            normals_mode: p.normals,
            p: vec![],
            tris: vec![],
            vn: None,
            uv: None,
            bounds: Bounds3::EMPTY,
            tv: vec![],
            all_ids: vec![],
            area_cdf: vec![],
            solid: std::sync::OnceLock::new(),
        })
    }
}

/// The `file` parameter resolved, once its format is known.
fn file_param(file: &str, env: &Env) -> Result<PathBuf, PluginError> {
    if file.is_empty() {
        // Worded and located as the parameter parser words a missing key.
        return Err(PluginError::msg(
            "missing key `file` (a .ply or .obj file; or the host passes vertices and indices arrays)",
        ));
    }
    let ext = std::path::Path::new(file)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("ply") | Some("obj")) {
        return Err(PluginError::key(
            "file",
            format!("{file}: unknown mesh format: use .ply or .obj"),
        ));
    }
    Ok(env.resolve(file))
}

/// Rows rounded to f32 (normals and texture coordinates do not move).
fn narrow<const N: usize>(v: Vec<[f64; N]>) -> Vec<[f32; N]> {
    v.into_iter().map(|r| r.map(|c| c as f32)).collect()
}

/// The mesh the host passed as arrays: `vertices` (V x 3, f32 or f64, placed
/// at the renderer's origin in f64 and rounded once), `indices` (F x 3, any
/// integer type), optional `normals` (V x 3) and `uvs` (V x 2).
fn from_arrays(env: &Env) -> Result<load::MeshData, PluginError> {
    let known = ["vertices", "indices", "normals", "uvs"];
    if let Some(n) = env.arrays.names().find(|n| !known.contains(n)) {
        return Err(PluginError::key(
            n,
            "unknown array: a mesh takes vertices, indices, normals and uvs",
        ));
    }
    let array = |name: &str| env.arrays.get(name);
    let vertices = array("vertices").expect("checked by the caller");
    let world = vertices.rows_f64::<3>()?;
    if let Some((i, v)) = world
        .iter()
        .enumerate()
        .find(|(_, v)| v.iter().any(|c| !c.is_finite()))
    {
        return Err(PluginError::key(
            "vertices",
            format!("row {i} is not finite: {v:?}"),
        ));
    }
    let indices = array("indices")
        .ok_or_else(|| PluginError::key("indices", "missing: F x 3 vertex indices"))?;
    let bound = u32::try_from(world.len())
        .map_err(|_| PluginError::key("vertices", "more than 2^32 - 1 vertices"))?;
    let m = load::MeshData {
        positions: world.iter().map(|&v| env.place(v).to_array()).collect(),
        tris: indices.rows_index::<3>(bound)?,
        normals: array("normals")
            .map(|a| a.rows_f64::<3>().map(narrow))
            .transpose()?,
        uvs: array("uvs")
            .map(|a| a.rows_f64::<2>().map(narrow))
            .transpose()?,
    };
    load::validate(&m).map_err(|e| PluginError::key("vertices", e))?;
    Ok(m)
}

impl Object for Mesh {
    /// Inside a closed mesh by the parity of rays from the point
    /// (`TriangleSolid`); an open mesh has no interior.
    fn in_interior(&self, _ctx: &mut TraceCtx, p: Vec3, _time: f32) -> Interior {
        let solid = self
            .solid
            .get_or_init(|| rtk_kernel::accel::TriangleSolid::new(&self.p, &self.tris));
        match solid {
            Some(s) => Interior::from_bool(s.contains(p.to_array())),
            None => Interior::NONE,
        }
    }

    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        let m = match &mut self.source {
            Source::File(path) => load::load(path, &load::read_file(env, path)?)?,
            // Placed at the origin already (in f64, from the host's values).
            Source::Arrays(m) => m.take().ok_or_else(|| PluginError::msg("prepared twice"))?,
        };
        let placed = matches!(self.source, Source::Arrays(_));
        self.p = m.positions;
        if self.origin != [0.0; 3] && !placed {
            // In f64, then rounded once: camera-relative rendering (X3).
            let o = self.origin;
            for v in &mut self.p {
                *v = std::array::from_fn(|i| (v[i] as f64 - o[i]) as f32);
            }
        }
        self.tris = m.tris;
        self.tv = self
            .tris
            .iter()
            .map(|t| {
                [
                    self.p[t[0] as usize],
                    self.p[t[1] as usize],
                    self.p[t[2] as usize],
                ]
            })
            .collect();
        self.all_ids = (0..self.tris.len() as u32).collect();
        let mut sum = 0.0f64;
        self.area_cdf = self
            .tv
            .iter()
            .map(|v| {
                let w = |i: usize| glam::DVec3::from(v[i].map(f64::from));
                sum += 0.5 * (w(1) - w(0)).cross(w(2) - w(0)).length();
                sum
            })
            .collect();
        self.uv = m.uvs;
        self.vn = match (self.normals_mode, m.normals) {
            (Normals::Face, _) => None,
            (_, Some(n)) => Some(
                n.into_iter()
                    .map(|v| Vec3::from(v).normalize_or(Vec3::Z))
                    .collect(),
            ),
            (Normals::Vertex, None) => Some(self.vertex_normals()),
            (Normals::Auto, None) => None,
        };
        let boxes: Vec<Bounds3> = (0..self.tris.len() as u32)
            .map(|i| self.tri_bounds(i))
            .collect();
        self.bounds = boxes.iter().fold(Bounds3::EMPTY, |a, b| a.union(*b));
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        match self.nearest(ctx, ray) {
            Some((t, prim, uv)) => {
                hit.record_leaf(level, t, prim, uv);
                true
            }
            None => false,
        }
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, _level: u32) -> bool {
        let mut tests = 0;
        let found = self.any_ids(ray, &self.all_ids, &mut tests);
        ctx.stats.prim_tests += tests;
        found
    }

    fn local_geom(
        &self,
        _ctx: &mut TraceCtx,
        _ray: &Ray,
        hit: &Hit,
        level: u32,
        mask: u32,
        out: &mut LocalGeom,
    ) {
        let i = hit.at(level);
        let v = self.verts(i);
        let b = [1.0 - hit.uv[0] - hit.uv[1], hit.uv[0], hit.uv[1]];
        let (p, err) = triangle_point_inset(v, b);
        let (p0, p1, p2) = (Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]));
        let ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Z);
        out.p = Vec3::from(p).into();
        out.p_err = Vec3::from(err).into();
        out.ng = ng.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL;
        if mask & geom_mask::SHADING_NORMAL != 0 {
            let ns = match &self.vn {
                Some(vn) => {
                    let t = self.tris[i as usize];
                    (vn[t[0] as usize] * b[0] + vn[t[1] as usize] * b[1] + vn[t[2] as usize] * b[2])
                        .normalize_or(ng)
                }
                None => ng,
            };
            out.ns = ns.into();
            out.filled |= geom_mask::SHADING_NORMAL;
        }
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            let t = self.tris[i as usize];
            let uv = match &self.uv {
                Some(u) => [u[t[0] as usize], u[t[1] as usize], u[t[2] as usize]],
                None => [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
            };
            if mask & geom_mask::UV != 0 {
                out.uv = [
                    b[0] * uv[0][0] + b[1] * uv[1][0] + b[2] * uv[2][0],
                    b[0] * uv[0][1] + b[1] * uv[1][1] + b[2] * uv[2][1],
                ];
                out.filled |= geom_mask::UV;
            }
            // The tangents only when asked: the path and most shaders read
            // uv (textures) and never dp/du.
            if mask & geom_mask::TANGENTS != 0 {
                (out.dpdu, out.dpdv) = tangents(uv, [p0, p1, p2], ng);
                out.filled |= geom_mask::TANGENTS;
            }
        }
    }
}

/// dp/du and dp/dv of the triangle `p` with texture coordinates `uv`
/// (pbrt-v4's, from the edges to the third vertex), or any orthonormal
/// pair around `ng` where the uv map is degenerate.
fn tangents(uv: [[f32; 2]; 3], p: [Vec3; 3], ng: Vec3) -> (Float3, Float3) {
    let (du02, du12) = (uv[0][0] - uv[2][0], uv[1][0] - uv[2][0]);
    let (dv02, dv12) = (uv[0][1] - uv[2][1], uv[1][1] - uv[2][1]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let det = du02 * dv12 - dv02 * du12;
    let (dpdu, dpdv) = if det.abs() > 1e-12 {
        let inv = 1.0 / det;
        (
            (dv12 * dp02 - dv02 * dp12) * inv,
            (du02 * dp12 - du12 * dp02) * inv,
        )
    } else {
        ng.any_orthonormal_pair()
    };
    (dpdu.into(), dpdv.into())
}

impl PrimitiveSet for Mesh {
    fn prim_count(&self) -> u32 {
        self.tris.len() as u32
    }
    fn prim_bounds(&self, first: u32, out: &mut [Bounds3]) {
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.tri_bounds(first + k as u32);
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
        let mut best = None;
        let mut tests = 0;
        self.test_ids(ray, ids, &mut best, &mut tests);
        ctx.stats.prim_tests += tests;
        match best {
            Some((t, prim, uv)) => {
                hit.record_leaf(level, t, prim, uv);
                true
            }
            None => false,
        }
    }
    fn occluded_prims(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], _level: u32) -> bool {
        let mut tests = 0;
        let r = self.any_ids(ray, ids, &mut tests);
        ctx.stats.prim_tests += tests;
        r
    }
}

impl Mesh {
    /// Area-weighted vertex normals.
    fn vertex_normals(&self) -> Vec<Vec3> {
        let mut n = vec![Vec3::ZERO; self.p.len()];
        for t in &self.tris {
            let (a, b, c) = (
                Vec3::from(self.p[t[0] as usize]),
                Vec3::from(self.p[t[1] as usize]),
                Vec3::from(self.p[t[2] as usize]),
            );
            let f = (b - a).cross(c - a); // length = 2 * area
            for &v in t {
                n[v as usize] += f;
            }
        }
        n.into_iter().map(|v| v.normalize_or(Vec3::Z)).collect()
    }
}

impl Triangles for Mesh {
    fn triangles(&self) -> TriangleSlices<'_> {
        TriangleSlices {
            positions: &self.p,
            indices: &self.tris,
        }
    }
}

impl SampleSurface for Mesh {
    fn area(&self) -> f32 {
        self.area_cdf.last().copied().unwrap_or(0.0) as f32
    }

    fn sample_point(&self, u: [f32; 2]) -> Option<(Vec3, Vec3)> {
        let (i, u0) = pick_from_cdf(&self.area_cdf, u[0])?;
        let v = self.tv[i].map(Vec3::from);
        let b = uniform_triangle([u0, u[1]]);
        let p = v[0] + b[1] * (v[1] - v[0]) + b[2] * (v[2] - v[0]);
        // The normal `local_geom` reports as `ng`.
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        (n != Vec3::ZERO).then_some((p, n))
    }
}

/// The vertices are exact hull points: the triangles are intersected on
/// them, unrounded. Spheres and slabs are derived from them by the caller.
impl BoundingVolumes for Mesh {
    fn hull_points(&self, _t0: f32, _t1: f32) -> Option<std::borrow::Cow<'_, [[f32; 3]]>> {
        Some(std::borrow::Cow::Borrowed(&self.p))
    }
}

rtk_kernel::export_object!(
    Mesh,
    class = "mesh",
    doc = include_str!("../README.md"),
    capabilities = [PrimitiveSet, Triangles, SampleSurface, BoundingVolumes]
);
