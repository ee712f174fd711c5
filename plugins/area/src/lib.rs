#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::{DAffine3, DVec3, Mat3, Vec3};
use rtk_kernel::sdk::shading::{pick_from_cdf, uniform_triangle};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {}

/// An area light: unbound until the shell binds its emitting instance.
struct AreaLight {
    bound: Option<Bound>,
}

/// The emitting instance, placed in the renderer's space, in f32.
struct Bound {
    emitter: Emitter,
    m: Mat3,
    t: Vec3,
    /// Inverse transpose of `m` (normals).
    n: Mat3,
    /// `m`'s transpose: |Mᵀ n_world| gives the area Jacobian of a hit.
    mt: Mat3,
    abs_det: f32,
    /// The object's surface area in its own space.
    area: f32,
    /// For an object that lends its triangles: them, placed.
    mesh: Option<PlacedMesh>,
}

/// An emitting mesh's triangles in the renderer's space, sampled by world
/// area with no call into the mesh and no transform per sample.
struct PlacedMesh {
    /// Per triangle: first vertex, the two edges from it, the unit normal
    /// (the side the mesh's `ng` faces, through the placement).
    tris: Vec<[[f32; 3]; 4]>,
    /// Running sum of the triangles' world areas.
    cdf: Vec<f64>,
    /// Total world area.
    area: f64,
}

impl PlacedMesh {
    /// Place `positions`/`indices` by `m`, in f64, rounding once.
    fn new(m: DAffine3, positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Option<PlacedMesh> {
        let flip = m.matrix3.determinant() < 0.0;
        let mut tris = Vec::with_capacity(indices.len());
        let mut cdf = Vec::with_capacity(indices.len());
        let mut sum = 0.0f64;
        for t in indices {
            let v =
                t.map(|i| m.transform_point3(DVec3::from(positions[i as usize].map(f64::from))));
            let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
            let c = e1.cross(e2);
            let a = 0.5 * c.length();
            // The normal as the mesh computes it, carried through M: the
            // cross product of the placed edges, flipped by a mirroring M.
            let n = if flip { -c } else { c }.normalize_or_zero();
            sum += a;
            cdf.push(sum);
            tris.push([v[0], e1, e2, n].map(|x| x.as_vec3().to_array()));
        }
        (sum > 0.0 && sum.is_finite()).then_some(PlacedMesh {
            tris,
            cdf,
            area: sum,
        })
    }
}

impl Bound {
    fn new(emitter: Emitter) -> Result<Bound, PluginError> {
        let to_world = emitter.to_world;
        let l = to_world.matrix3;
        let m = l.as_mat3();
        let mut ctx = TraceCtx::new(0, 1, 0);
        let area = emitter
            .object
            .sample_surface(&mut ctx, [0.5, 0.5])
            .map_or(0.0, |s| s.area);
        if !(area > 0.0 && area.is_finite()) {
            return Err(PluginError::msg(format!(
                "the emitting object (class `{}`) has no surface area to emit from",
                emitter.object.class_name()
            )));
        }
        let mesh = match emitter.object.prim_set().map(|s| {
            s.triangles()
                .map(|t| t.and_then(|t| PlacedMesh::new(to_world, t.positions, t.indices)))
        }) {
            Some(r) => r?,
            None => None,
        };
        Ok(Bound {
            m,
            t: to_world.translation.as_vec3(),
            n: l.inverse().transpose().as_mat3(),
            mt: m.transpose(),
            abs_det: l.determinant().abs() as f32,
            area,
            mesh,
            emitter,
        })
    }

    /// Density by area in the renderer's space of a point whose own-space
    /// density is `1 / area`, given its unit world normal: dA_world =
    /// |det M| |M⁻ᵀ n_own| dA_own = |det M| / |Mᵀ n_world| dA_own.
    #[inline]
    fn area_pdf(&self, area: f32, n_world: Vec3) -> f32 {
        (self.mt * n_world).length() / (self.abs_det * area)
    }

    /// A point on the surface for `u`, its unit normal and its density by
    /// world area.
    fn sample_point(&self, ctx: &mut TraceCtx, u: [f32; 2]) -> Option<(Vec3, Vec3, f32)> {
        match &self.mesh {
            // A mesh: placed triangles, uniform by world area.
            Some(m) => {
                let (k, u0) = pick_from_cdf(&m.cdf, u[0])?;
                let [v0, e1, e2, n] = m.tris[k].map(Vec3::from);
                let b = uniform_triangle([u0, u[1]]);
                Some((v0 + b[1] * e1 + b[2] * e2, n, (1.0 / m.area) as f32))
            }
            // Anything else: its own sampling, carried through the placement.
            None => {
                let s = self.emitter.object.sample_surface(ctx, u)?;
                let n = (self.n * s.n.v()).normalize_or_zero();
                Some((self.m * s.p.v() + self.t, n, self.area_pdf(s.area, n)))
            }
        }
    }
}

impl Plugin for AreaLight {
    type Params = Params;

    fn create(_p: Params, _env: &Env) -> Result<Self, PluginError> {
        Ok(AreaLight { bound: None })
    }
}

impl Light for AreaLight {
    fn sample_li(
        &self,
        ctx: &mut TraceCtx,
        p: Vec3,
        u: [f32; 2],
        _time: f32,
    ) -> Option<LightSample> {
        let b = self.bound.as_ref()?;
        let (q, n, pdf_area) = b.sample_point(ctx, u)?;
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        if !(dist > 0.0) || n == Vec3::ZERO {
            return None;
        }
        let wi = d / dist;
        let cos = n.dot(wi).abs();
        if !(cos > 0.0) {
            return None;
        }
        let mut g = LocalGeom::EMPTY;
        g.p = q.into();
        g.ng = n.into();
        g.ns = n.into();
        g.shader = b.emitter.object.instance().shader;
        g.filled = geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        let li = if b.emitter.shader.lobes() & lobe::EMISSION != 0 {
            b.emitter.shader.emitted(ctx, &g, -wi)
        } else {
            Color::BLACK
        };
        if li.is_black() {
            return None;
        }
        let pdf = pdf_area * dist2 / cos;
        (pdf.is_finite() && pdf > 0.0).then_some(LightSample {
            wi: wi.into(),
            dist,
            li,
            pdf,
        })
    }
}

impl Area for AreaLight {
    fn bind_emitter(&mut self, emitter: Emitter) -> Result<(), PluginError> {
        if self.bound.is_some() {
            return Err(PluginError::msg(
                "this area light is bound already: one light stands for one instance",
            ));
        }
        self.bound = Some(Bound::new(emitter)?);
        Ok(())
    }

    fn pdf_hit(&self, _ctx: &mut TraceCtx, p: Vec3, _ray: &Ray, geom: &LocalGeom) -> f32 {
        let Some(b) = &self.bound else {
            return 0.0;
        };
        let n = geom.ng.v();
        let d = geom.p.v() - p;
        let dist2 = d.length_squared();
        let cos = n.dot(d).abs() / dist2.sqrt();
        if !(cos > 0.0) {
            return 0.0;
        }
        let pdf_area = match &b.mesh {
            Some(m) => (1.0 / m.area) as f32,
            None => b.area_pdf(b.area, n),
        };
        pdf_area * dist2 / cos
    }
}

rtk_kernel::export_light!(
    AreaLight,
    class = "area",
    doc = include_str!("../README.md"),
    capabilities = [Area]
);
