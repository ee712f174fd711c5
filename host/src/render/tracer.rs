//! The host's [`Services`]: the kernel's `Trace` and what integrators and
//! shaders ask of the scene. Pure dispatch to the world's handles, counting
//! what it does in the per-thread statistics; no shading policy lives here
//! (that is the integrator's), nothing allocates or locks.

use rtk_kernel::abi::*;
use rtk_kernel::glam::{Mat3, Vec3};
use rtk_kernel::host::{SceneRecord, Services, ServicesTable, Shader};
use rtk_kernel::sdk::shading::{pick_from_cdf, uniform_triangle};
use rtk_shell::World;

/// The world as the render loop and the plugins see it.
pub struct Tracer<'w> {
    world: &'w World,
    table: ServicesTable<Tracer<'w>>,
    background: Color,
    area: Vec<AreaLight>,
}

/// An emitting instance as light sampling uses it, in f32.
struct AreaLight {
    m: Mat3,
    t: Vec3,
    /// Inverse transpose of `m` (normals).
    n: Mat3,
    /// `m`'s transpose: |Mᵀ n_world| gives the area Jacobian of a hit.
    mt: Mat3,
    abs_det: f32,
    shader: u32,
}

impl AreaLight {
    /// Density by area in the renderer's space of a point whose own-space
    /// density is `1 / area`, given its unit world normal: dA_world =
    /// |det M| |M⁻ᵀ n_own| dA_own = |det M| / |Mᵀ n_world| dA_own.
    #[inline]
    fn area_pdf(&self, area: f32, n_world: Vec3) -> f32 {
        (self.mt * n_world).length() / (self.abs_det * area)
    }
}

impl<'w> Tracer<'w> {
    /// Wire the world's handles into the scene services.
    pub fn new(world: &'w World) -> Self {
        let bg = world.desc.render.background;
        let area = world
            .emitters
            .iter()
            .map(|e| {
                let m = e.to_world.matrix3.as_mat3();
                AreaLight {
                    m,
                    t: e.to_world.translation.as_vec3(),
                    n: e.normal_matrix.as_mat3(),
                    mt: m.transpose(),
                    abs_det: e.abs_det as f32,
                    shader: e.shader,
                }
            })
            .collect();
        Tracer {
            world,
            table: ServicesTable::new(),
            background: Color::new(bg[0], bg[1], bg[2]),
            area,
        }
    }

    /// Sample area light `i` (an emitting instance) from `p`.
    fn sample_area(
        &self,
        ctx: &mut TraceCtx,
        i: usize,
        p: Vec3,
        u: [f32; 2],
    ) -> Option<LightSample> {
        let (e, a) = (&self.world.emitters[i], &self.area[i]);
        let (q, n, pdf_area) = match &e.mesh {
            // A mesh: placed triangles, uniform by world area.
            Some(m) => {
                let (k, u0) = pick_from_cdf(&m.cdf, u[0])?;
                let [v0, e1, e2, n] = m.tris[k].map(Vec3::from);
                let b = uniform_triangle([u0, u[1]]);
                (v0 + b[1] * e1 + b[2] * e2, n, (1.0 / m.area) as f32)
            }
            // Anything else: its own sampling, carried through the transform.
            None => {
                let s = e.object.sample_surface(ctx, &u)?;
                let n = (a.n * s.n.v()).normalize_or_zero();
                (a.m * s.p.v() + a.t, n, a.area_pdf(s.area, n))
            }
        };
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
        let shader = self.world.shaders.get(a.shader as usize)?;
        let mut g = LocalGeom::EMPTY;
        g.p = q.into();
        g.ng = n.into();
        g.ns = n.into();
        g.shader = a.shader;
        g.filled = geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
        let li = shader.emitted(ctx, &g, (-wi).into());
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

    /// The world.
    pub fn world(&self) -> &World {
        self.world
    }

    fn scene(&self) -> SceneRecord<'_> {
        self.table.bind(self)
    }

    /// Radiance along a camera ray (counted as a camera ray).
    #[inline]
    pub fn camera_li(&self, ctx: &mut TraceCtx, ray: &Ray) -> Color {
        count(ctx, ray_kind::CAMERA);
        self.world.integrator.li(ctx, &self.scene(), ray)
    }
}

#[inline]
fn count(ctx: &mut TraceCtx, kind: u32) {
    if kind != ray_kind::TRACED {
        if let Some(c) = ctx.stats.rays.get_mut(kind as usize) {
            *c += 1;
        }
    }
}

impl Services for Tracer<'_> {
    fn trace(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32) -> Color {
        count(ctx, kind);
        self.world.integrator.li(ctx, &self.scene(), ray)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32, hit: &mut Hit) -> bool {
        count(ctx, kind);
        self.world.root.intersect(ctx, ray, hit)
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool {
        count(ctx, ray_kind::SHADOW);
        self.world.root.occluded(ctx, ray)
    }

    fn local_geom(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &Hit, mask: u32, out: &mut LocalGeom) {
        ctx.stats.local_geom_calls += 1;
        for (bit, n) in ctx.stats.local_geom_fields.iter_mut().enumerate() {
            *n += ((mask >> bit) & 1) as u64;
        }
        self.world.root.local_geom(ctx, ray, hit, mask, out);
        if out.shader == NONE_ID {
            out.shader = self.world.root_inst.shader;
        }
    }

    fn background(&self, ctx: &mut TraceCtx, ray: &Ray) -> Color {
        match self.world.environment {
            Some(i) => {
                let d: Float3 = ray.dir.v().normalize_or_zero().into();
                self.world.lights[i].le(ctx, &d)
            }
            None => self.background,
        }
    }

    fn light_count(&self) -> u32 {
        (self.world.lights.len() + self.world.emitters.len()) as u32
    }

    fn light_flags(&self, index: u32) -> u32 {
        let i = index as usize;
        let n = self.world.lights.len();
        if i >= n {
            light_flag::AREA
        } else if Some(i) == self.world.environment {
            light_flag::ENVIRONMENT
        } else {
            light_flag::DELTA
        }
    }

    fn light_pdf(&self, ctx: &mut TraceCtx, p: Vec3, ray: &Ray, geom: Option<&LocalGeom>) -> f32 {
        let Some(g) = geom else {
            return match self.world.environment {
                Some(i) => {
                    let d: Float3 = ray.dir.v().normalize_or_zero().into();
                    self.world.lights[i].pdf_li(ctx, &p.into(), &d)
                }
                None => 0.0,
            };
        };
        let Some(&e) = self.world.emitter_of_shader.get(g.shader as usize) else {
            return 0.0;
        };
        let Some(a) = self.area.get(e as usize) else {
            return 0.0;
        };
        let _ = ctx;
        let em = &self.world.emitters[e as usize];
        let n = g.ng.v();
        let d = g.p.v() - p;
        let dist2 = d.length_squared();
        let cos = n.dot(d).abs() / dist2.sqrt();
        if !(cos > 0.0) {
            return 0.0;
        }
        let pdf_area = match &em.mesh {
            Some(m) => (1.0 / m.area) as f32,
            None => a.area_pdf(em.area, n),
        };
        pdf_area * dist2 / cos
    }

    fn sample_light(
        &self,
        ctx: &mut TraceCtx,
        index: u32,
        p: Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample> {
        ctx.stats.light_samples += 1;
        let n = self.world.lights.len();
        match self.world.lights.get(index as usize) {
            Some(l) => l.sample_li(ctx, &p.into(), &u, time),
            None if (index as usize) < n + self.area.len() => {
                self.sample_area(ctx, index as usize - n, p, u)
            }
            None => None,
        }
    }

    fn material(&self, shader: u32) -> Option<&Shader> {
        self.world.shaders.get(shader as usize)
    }
}
