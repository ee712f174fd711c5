#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

mod shape;
use rtk_kernel::geom::vec;

use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;
use shape::{plane64, Polygon};

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    points: Vec<[f64; 3]>,
    #[serde(default)]
    holes: Vec<Vec<[f64; 3]>>,
}

/// Points farther than this fraction of the polygon's size (the diagonal of
/// its box) from the plane are refused.
const PLANARITY_TOLERANCE: f64 = 1e-4;

struct PolygonObject {
    poly: Polygon<f32>,
    bounds: Bounds3,
    /// In-plane tangent directions (u along the first edge, v = n × u).
    tu: Vec3,
    tv: Vec3,
    /// The points' extent along `tu` and `tv`, relative to the plane's point.
    u_min: f32,
    u_len: f32,
    v_min: f32,
    v_len: f32,
}

/// Check one loop's points: at least 3, each finite; moved to the
/// renderer's origin in f64 (they are rounded to f32 later, once).
fn loop_points(env: &Env, key: &str, pts: &[[f64; 3]]) -> Result<Vec<[f64; 3]>, PluginError> {
    if pts.len() < 3 {
        return Err(PluginError::key(
            key,
            format!("a polygon needs at least 3 points, got {}", pts.len()),
        ));
    }
    pts.iter()
        .enumerate()
        .map(|(i, p)| {
            env.position(&format!("{key}[{i}]"), *p)?;
            Ok(std::array::from_fn(|k| p[k] - env.origin[k]))
        })
        .collect()
}

impl Plugin for PolygonObject {
    type Params = Params;

    fn create(p: Params, env: &Env) -> Result<Self, PluginError> {
        let mut loops = vec![loop_points(env, "points", &p.points)?];
        let mut keys = vec!["points".to_string()];
        for (i, h) in p.holes.iter().enumerate() {
            let key = format!("holes[{i}]");
            loops.push(loop_points(env, &key, h)?);
            keys.push(key);
        }
        let (n, c) = plane64(&loops[0]).ok_or_else(|| {
            PluginError::key(
                "points",
                "the points enclose no area (they are collinear or repeated)",
            )
        })?;
        // Coplanarity, relative to the size of the whole polygon.
        let all = || loops.iter().flatten();
        let lo: [f64; 3] =
            std::array::from_fn(|k| all().map(|p| p[k]).fold(f64::INFINITY, f64::min));
        let hi: [f64; 3] =
            std::array::from_fn(|k| all().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max));
        let max_dev = check_coplanar(&loops, &keys, n, c, lo, hi)?;
        // The box of the points, widened by their distance from the plane
        // (hits lie on the plane).
        let (blo, bhi) = vec::f32_box(lo.map(|x| x - max_dev), hi.map(|x| x + max_dev));
        // uv: u along the first edge (in the plane), v = n × u.
        let e0 = vec::sub(loops[0][1], loops[0][0]);
        let e0 = vec::sub(e0, vec::scale(n, vec::dot(n, e0)));
        let u = if vec::norm64(e0) > 0.0 {
            e0.map(|x| x / vec::norm64(e0))
        } else {
            vec::frame64(n)[0]
        };
        let v = vec::cross64(n, u);
        let (mut u0, mut u1, mut v0, mut v1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for q in all() {
            let r = vec::sub(*q, c);
            let (a, b) = (vec::dot(r, u), vec::dot(r, v));
            u0 = u0.min(a);
            u1 = u1.max(a);
            v0 = v0.min(b);
            v1 = v1.max(b);
        }
        let tiny = f32::MIN_POSITIVE as f64;
        Ok(PolygonObject {
            poly: Polygon::new(&loops, n, c),
            bounds: Bounds3::new(Vec3::from(blo), Vec3::from(bhi)),
            tu: Vec3::from(u.map(|x| x as f32)),
            tv: Vec3::from(v.map(|x| x as f32)),
            u_min: u0 as f32,
            u_len: (u1 - u0).max(tiny) as f32,
            v_min: v0 as f32,
            v_len: (v1 - v0).max(tiny) as f32,
        })
    }
}

/// The largest distance of any point from the plane (n, c), or an error
/// naming the point farthest from it (with a single stray point, the one
/// that strays) when that exceeds the tolerance, relative to the size of
/// the polygon's box `lo..hi`.
fn check_coplanar(
    loops: &[Vec<[f64; 3]>],
    keys: &[String],
    n: [f64; 3],
    c: [f64; 3],
    lo: [f64; 3],
    hi: [f64; 3],
) -> Result<f64, PluginError> {
    let size = vec::norm64(std::array::from_fn(|k| hi[k] - lo[k]));
    let tol = PLANARITY_TOLERANCE * size;
    let mut max_dev = 0.0f64;
    let mut worst = String::new();
    for (l, key) in loops.iter().zip(keys) {
        for (j, q) in l.iter().enumerate() {
            let dev = vec::dot(n, vec::sub(*q, c)).abs();
            if dev > max_dev {
                max_dev = dev;
                worst = format!("{key}[{j}]");
            }
        }
    }
    if max_dev > tol {
        return Err(PluginError::key(
            worst,
            format!(
                "lies {max_dev:.3e} off the plane of the polygon's points, more than \
                 {PLANARITY_TOLERANCE:e} of the polygon's size ({tol:.3e}): the points \
                 must be coplanar"
            ),
        ));
    }
    Ok(max_dev)
}

impl AnalyticShape for PolygonObject {
    fn bounds(&self, _t0: f32, _t1: f32) -> Bounds3 {
        self.bounds
    }

    fn nearest_root(&self, ray: &Ray) -> Option<Root> {
        self.poly
            .intersect(
                ray.origin.to_array(),
                ray.dir.to_array(),
                ray.t_min,
                ray.t_max,
            )
            .map(Root::at)
    }

    fn surface(&self, ray: &Ray, root: Root, mask: u32, out: &mut LocalGeom) {
        let s = self
            .poly
            .surface(ray.origin.to_array(), ray.dir.to_array(), root.t);
        let n = Vec3::from(self.poly.n).normalize_or(Vec3::Z);
        out.p = Vec3::from(s.p).into();
        out.p_err = Vec3::from(s.p_err).into();
        out.ng = n.into();
        out.ns = n.into();
        out.filled |= geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        if mask & (geom_mask::UV | geom_mask::TANGENTS) != 0 {
            // uv: the plane coordinates along tu, tv, scaled so that the
            // polygon's box in the plane is [0, 1]².
            let q = Vec3::from(s.q);
            out.uv = [
                (q.dot(self.tu) - self.u_min) / self.u_len,
                (q.dot(self.tv) - self.v_min) / self.v_len,
            ];
            out.dpdu = (self.tu * self.u_len).into();
            out.dpdv = (self.tv * self.v_len).into();
            out.filled |= geom_mask::UV | geom_mask::TANGENTS;
        }
    }
}

rtk_kernel::export_object!(
    PolygonObject,
    class = "polygon",
    doc = include_str!("../README.md")
);
