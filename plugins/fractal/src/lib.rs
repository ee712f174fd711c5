#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod terrain;

use rtk_kernel::geom::{intersect_triangle, triangle_point_inset};
use rtk_kernel::glam::{self, Vec3};
use rtk_kernel::sdk::shading::{pick_from_cdf, uniform_triangle};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use terrain::{Terrain, TerrainSpec, MAX_LEVELS};

#[derive(Deserialize, Clone, Copy, PartialEq, Debug)]
#[serde(crate = "rtk_kernel::serde", rename_all = "lowercase")]
enum Normals {
    Face,
    Vertex,
}

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "one_u64")]
    seed: u64,
    #[serde(default = "default_size")]
    size: [f64; 2],
    #[serde(default = "default_levels")]
    levels: u32,
    #[serde(default = "one")]
    height: f64,
    #[serde(default = "default_roughness")]
    roughness: f64,
    #[serde(default)]
    center: [f64; 3],
    #[serde(default = "face")]
    normals: Normals,
}

fn one_u64() -> u64 {
    1
}
fn one() -> f64 {
    1.0
}
fn default_size() -> [f64; 2] {
    [10.0, 10.0]
}
fn default_levels() -> u32 {
    7
}
fn default_roughness() -> f64 {
    0.7
}
fn face() -> Normals {
    Normals::Face
}

struct Fractal {
    spec: TerrainSpec,
    normals_mode: Normals,
    t: Terrain,
    vn: Option<Vec<Vec3>>,
    bounds: Bounds3,
    /// Each triangle's three vertices, contiguous (as `mesh` keeps them).
    tv: Vec<[[f32; 3]; 3]>,
    all_ids: Vec<u32>,
    area_cdf: Vec<f64>,
}

impl Plugin for Fractal {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        // Validates the centre (finite, in range once moved to the origin).
        env.position("center", p.center)?;
        if p.levels > MAX_LEVELS {
            return Err(PluginError::key(
                "levels",
                format!(
                    "must be at most {MAX_LEVELS} (2^{MAX_LEVELS} + 1 vertices a side, \
                     {} triangles), got {}",
                    2u64 << (2 * MAX_LEVELS),
                    p.levels
                ),
            ));
        }
        if p.levels == 0 {
            return Err(PluginError::key("levels", "must be at least 1, got 0"));
        }
        for (k, s) in p.size.iter().enumerate() {
            if !s.is_finite() || *s <= 0.0 || *s > params::MAX_COORDINATE as f64 {
                return Err(PluginError::key(
                    format!("size[{k}]"),
                    format!("must be a positive number up to 1e12, got {s}"),
                ));
            }
        }
        if !p.height.is_finite() || p.height < 0.0 || p.height > params::MAX_COORDINATE as f64 {
            return Err(PluginError::key(
                "height",
                format!("must be a number from 0 to 1e12, got {}", p.height),
            ));
        }
        if !(0.0..=2.0).contains(&p.roughness) {
            return Err(PluginError::key(
                "roughness",
                format!(
                    "must be from 0 to 2 (the Hurst exponent H), got {}",
                    p.roughness
                ),
            ));
        }
        Ok(Fractal {
            spec: TerrainSpec {
                seed: p.seed,
                size: p.size,
                levels: p.levels,
                height: p.height,
                roughness: p.roughness,
                center: p.center,
                origin: env.origin,
            },
            normals_mode: p.normals,
            t: Terrain::default(),
            vn: None,
            bounds: Bounds3::EMPTY,
            tv: vec![],
            all_ids: vec![],
            area_cdf: vec![],
        })
    }
}

impl Fractal {
    fn tri_bounds(&self, i: u32) -> Bounds3 {
        let v = self.tv[i as usize];
        Bounds3::EMPTY
            .include(v[0].into())
            .include(v[1].into())
            .include(v[2].into())
    }

    /// Nearest hit among `ids`, lowest id on ties; updates `best`.
    #[inline]
    fn test_ids(&self, ray: &Ray, ids: &[u32], best: &mut Option<(f32, u32, [f32; 2])>) {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
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

    fn any_ids(&self, ray: &Ray, ids: &[u32]) -> bool {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        ids.iter()
            .any(|&i| intersect_triangle(o, d, self.tv[i as usize], ray.t_min, ray.t_max).is_some())
    }
}

impl Object for Fractal {
    fn prepare(&mut self, env: &Prepare) -> Result<(), PluginError> {
        self.t = Terrain::generate(&self.spec, Some(env));
        let (p, tris) = (&self.t.positions, &self.t.tris);
        self.tv = tris
            .iter()
            .map(|t| [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]])
            .collect();
        self.all_ids = (0..tris.len() as u32).collect();
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
        self.vn = (self.normals_mode == Normals::Vertex).then(|| self.t.vertex_normals());
        self.bounds = self.t.bounds();
        Ok(())
    }

    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &mut Hit, level: u32) -> bool {
        // Every triangle: fast only inside an aggregate (the shell wraps the
        // object in its `accel`, bvh by default).
        let mut best = None;
        for chunk in self.all_ids.chunks(256) {
            self.test_ids(ray, chunk, &mut best);
        }
        ctx.stats.prim_tests += self.all_ids.len() as u64;
        match best {
            Some((t, prim, uv)) => {
                hit.record_leaf(level, t, prim, uv);
                true
            }
            None => false,
        }
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray, _level: u32) -> bool {
        ctx.stats.prim_tests += self.all_ids.len() as u64;
        self.any_ids(ray, &self.all_ids)
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
        let i = hit.at(level) as usize;
        let v = self.tv[i];
        let b = [1.0 - hit.uv[0] - hit.uv[1], hit.uv[0], hit.uv[1]];
        let (p, err) = triangle_point_inset(v, b);
        let (p0, p1, p2) = (Vec3::from(v[0]), Vec3::from(v[1]), Vec3::from(v[2]));
        let ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Y);
        out.p = Vec3::from(p).into();
        out.p_err = Vec3::from(err).into();
        out.ng = ng.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL;
        let tri = self.t.tris[i];
        if mask & geom_mask::SHADING_NORMAL != 0 {
            let ns = match &self.vn {
                Some(vn) => (vn[tri[0] as usize] * b[0]
                    + vn[tri[1] as usize] * b[1]
                    + vn[tri[2] as usize] * b[2])
                    .normalize_or(ng),
                None => ng,
            };
            out.ns = ns.into();
            out.filled |= geom_mask::SHADING_NORMAL;
        }
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            let uv = tri.map(|k| self.t.uv(k));
            out.uv = [
                b[0] * uv[0][0] + b[1] * uv[1][0] + b[2] * uv[2][0],
                b[0] * uv[0][1] + b[1] * uv[1][1] + b[2] * uv[2][1],
            ];
            // u runs along +x over size[0], v along +z over size[1]: the
            // tangents are the grid's axes lifted onto the triangle's plane.
            let (sx, sz) = (self.spec.size[0] as f32, self.spec.size[1] as f32);
            let lift = |a: Vec3| -> Vec3 {
                // The direction in the plane whose xz projection is `a`.
                if ng.y.abs() > 1e-6 {
                    Vec3::new(a.x, -(ng.x * a.x + ng.z * a.z) / ng.y, a.z)
                } else {
                    a
                }
            };
            out.dpdu = lift(Vec3::new(sx, 0.0, 0.0)).into();
            out.dpdv = lift(Vec3::new(0.0, 0.0, sz)).into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

impl PrimitiveSet for Fractal {
    fn prim_count(&self) -> u32 {
        self.tv.len() as u32
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
        self.test_ids(ray, ids, &mut best);
        ctx.stats.prim_tests += ids.len() as u64;
        match best {
            Some((t, prim, uv)) => {
                hit.record_leaf(level, t, prim, uv);
                true
            }
            None => false,
        }
    }
    fn occluded_prims(&self, ctx: &mut TraceCtx, ray: &Ray, ids: &[u32], _level: u32) -> bool {
        ctx.stats.prim_tests += ids.len() as u64;
        self.any_ids(ray, ids)
    }
}

impl Triangles for Fractal {
    fn triangles(&self) -> TriangleSlices<'_> {
        TriangleSlices {
            positions: &self.t.positions,
            indices: &self.t.tris,
        }
    }
}

/// The vertices are exact hull points: the triangles are intersected on
/// them.
impl BoundingVolumes for Fractal {
    fn hull_points(&self, _t0: f32, _t1: f32) -> Option<std::borrow::Cow<'_, [[f32; 3]]>> {
        Some(std::borrow::Cow::Borrowed(&self.t.positions))
    }
}

impl SampleSurface for Fractal {
    fn area(&self) -> f32 {
        self.area_cdf.last().copied().unwrap_or(0.0) as f32
    }

    fn sample_point(&self, u: [f32; 2]) -> Option<(Vec3, Vec3)> {
        let (i, u0) = pick_from_cdf(&self.area_cdf, u[0])?;
        let v = self.tv[i].map(Vec3::from);
        let b = uniform_triangle([u0, u[1]]);
        let p = v[0] + b[1] * (v[1] - v[0]) + b[2] * (v[2] - v[0]);
        let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        (n != Vec3::ZERO).then_some((p, n))
    }
}

rtk_kernel::export_object!(
    Fractal,
    class = "fractal",
    doc = include_str!("../README.md"),
    capabilities = [PrimitiveSet, Triangles, SampleSurface, BoundingVolumes]
);
