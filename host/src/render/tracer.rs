//! The host's [`Services`]: the kernel's `Trace` and what integrators and
//! shaders ask of the scene. Pure dispatch to the world's handles, counting
//! what it does in the per-thread statistics; no shading policy lives here
//! (that is the integrator's), nothing allocates or locks.

use super::profile::{ticks, Part, Profile};
use rtk_handles::{SceneRecord, Services, ServicesTable, Shader};
use rtk_kernel::abi::*;
use rtk_kernel::glam::Vec3;
use rtk_shell::World;

/// The world as the render loop and the plugins see it.
pub struct Tracer<'w> {
    world: &'w World,
    table: ServicesTable<Tracer<'w>>,
    background: Color,
    /// `--profile`'s accumulators, when asked for.
    profile: Option<&'w Profile>,
}

impl<'w> Tracer<'w> {
    /// Wire the world's handles into the scene services.
    pub fn new(world: &'w World) -> Self {
        let bg = world.desc.render.background;
        Tracer {
            world,
            table: ServicesTable::new(),
            background: Color::new(bg[0], bg[1], bg[2]),
            profile: None,
        }
    }

    /// The tracer timing its services into `profile` (`--profile`).
    pub fn with_profile(self, profile: &'w Profile) -> Self {
        Tracer {
            profile: Some(profile),
            ..self
        }
    }

    /// The services' record, for timing an empty crossing.
    pub fn record(&self) -> SceneRecord<'_> {
        self.scene()
    }

    /// `f`, its time added to `part` of the profile when there is one.
    #[inline(always)]
    fn timed<R>(&self, ctx: &mut TraceCtx, part: Part, f: impl FnOnce(&mut TraceCtx) -> R) -> R {
        match self.profile {
            None => f(ctx),
            Some(p) => {
                let (thread, t0) = (ctx.thread_index(), ticks());
                let r = f(ctx);
                p.add(thread, part, t0);
                r
            }
        }
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
        self.timed(ctx, Part::Integrator, |ctx| {
            self.world.integrator.radiance(ctx, &self.scene(), ray)
        })
    }

    /// Radiance along each of a batch of camera rays (each counted as a
    /// camera ray), `rngs[i]` being ray `i`'s random stream.
    pub fn camera_li_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        rngs: &mut [RngState],
        out: &mut [Color],
    ) {
        ctx.stats.rays[ray_kind::CAMERA as usize] += rays.len() as u64;
        self.timed(ctx, Part::Integrator, |ctx| {
            self.world
                .integrator
                .radiance_batch(ctx, &self.scene(), rays, rngs, out)
        })
    }
}

/// Count the active rays of a batch as rays of `kind`.
#[inline]
fn count_batch(ctx: &mut TraceCtx, kind: u32, active: u64, n: usize) {
    if kind != ray_kind::TRACED {
        if let Some(c) = ctx.stats.rays.get_mut(kind as usize) {
            *c += (active & rtk_kernel::sdk::batch::all(n)).count_ones() as u64;
        }
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
        self.world.integrator.radiance(ctx, &self.scene(), ray)
    }

    fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32, hit: &mut Hit) -> bool {
        count(ctx, kind);
        self.timed(ctx, Part::Traversal, |ctx| {
            self.world.root.intersect(ctx, ray, hit)
        })
    }

    fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool {
        count(ctx, ray_kind::SHADOW);
        self.timed(ctx, Part::Traversal, |ctx| {
            self.world.root.occluded(ctx, ray)
        })
    }

    fn local_geom(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &Hit, mask: u32, out: &mut LocalGeom) {
        ctx.stats.local_geom_calls += 1;
        for (bit, n) in ctx.stats.local_geom_fields.iter_mut().enumerate() {
            *n += ((mask >> bit) & 1) as u64;
        }
        self.timed(ctx, Part::Surface, |ctx| {
            self.world.root.local_geom(ctx, ray, hit, mask, out);
            self.world.root_inst.bind(out);
        })
    }

    fn background(&self, ctx: &mut TraceCtx, ray: &Ray) -> Color {
        match self.world.environment {
            Some(i) => {
                let d: Float3 = ray.dir.v().normalize_or_zero().into();
                self.world.lights[i].le(ctx, d).unwrap_or(Color::BLACK)
            }
            None => self.background,
        }
    }

    fn light_count(&self) -> u32 {
        self.world.lights.len() as u32
    }

    fn light_flags(&self, index: u32) -> u32 {
        let i = index as usize;
        match self.world.lights.get(i) {
            Some(_) if Some(i) == self.world.environment => light_flag::ENVIRONMENT,
            Some(l) if l.is_area() => light_flag::AREA,
            _ => light_flag::DELTA,
        }
    }

    fn light_pdf(&self, ctx: &mut TraceCtx, p: Vec3, ray: &Ray, geom: Option<&LocalGeom>) -> f32 {
        match geom {
            None => match self.world.environment {
                Some(i) => {
                    let d: Float3 = ray.dir.v().normalize_or_zero().into();
                    self.world.lights[i].pdf_li(ctx, p, d).unwrap_or(0.0)
                }
                None => 0.0,
            },
            Some(g) => self
                .world
                .lights
                .get(g.light as usize)
                .and_then(|l| l.pdf_hit(ctx, p, ray, g))
                .unwrap_or(0.0),
        }
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
        let l = self.world.lights.get(index as usize)?;
        self.timed(ctx, Part::Lights, |ctx| l.sample_li(ctx, p, u, time))
    }

    fn intersect_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        kind: u32,
        hits: &mut [Hit],
        active: u64,
    ) -> u64 {
        count_batch(ctx, kind, active, rays.len());
        self.timed(ctx, Part::Traversal, |ctx| {
            self.world.root.intersect_stream(ctx, rays, hits, active)
        })
    }

    fn occluded_batch(&self, ctx: &mut TraceCtx, rays: &[Ray], active: u64) -> u64 {
        count_batch(ctx, ray_kind::SHADOW, active, rays.len());
        self.timed(ctx, Part::Traversal, |ctx| {
            self.world.root.occluded_stream(ctx, rays, active)
        })
    }

    fn local_geom_batch(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &[Hit],
        active: u64,
        mask: u32,
        out: &mut [LocalGeom],
    ) {
        let n = (active & rtk_kernel::sdk::batch::all(rays.len())).count_ones() as u64;
        ctx.stats.local_geom_calls += n;
        for (bit, c) in ctx.stats.local_geom_fields.iter_mut().enumerate() {
            *c += ((mask >> bit) & 1) as u64 * n;
        }
        self.timed(ctx, Part::Surface, |ctx| {
            self.world
                .root
                .local_geom_stream(ctx, rays, hits, active, mask, out);
            let m = rays.len().min(hits.len()).min(out.len());
            for i in rtk_kernel::sdk::batch::lanes(active, m) {
                self.world.root_inst.bind(&mut out[i]);
            }
        })
    }

    fn material(&self, shader: u32) -> Option<ShaderRef> {
        self.world
            .shaders
            .get(shader as usize)
            .map(Shader::shader_ref)
    }
}
