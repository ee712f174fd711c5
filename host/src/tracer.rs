//! The host's [`Services`]: the kernel's `Trace` and what integrators and
//! shaders ask of the scene. Pure dispatch to the world's handles, counting
//! what it does in the per-thread statistics; no shading policy lives here
//! (that is the integrator's), nothing allocates or locks.

use rtk_kernel::abi::*;
use rtk_kernel::glam::Vec3;
use rtk_kernel::host::{SceneRecord, Services, ServicesTable, Shader};
use rtk_shell::World;

/// The world as the render loop and the plugins see it.
pub struct Tracer<'w> {
    world: &'w World,
    table: ServicesTable<Tracer<'w>>,
    background: Color,
}

impl<'w> Tracer<'w> {
    /// Wire the world's handles into the scene services.
    pub fn new(world: &'w World) -> Self {
        let bg = world.desc.render.background;
        Tracer {
            world,
            table: ServicesTable::new(),
            background: Color::new(bg[0], bg[1], bg[2]),
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

    fn background(&self, _ctx: &mut TraceCtx, _ray: &Ray) -> Color {
        self.background
    }

    fn light_count(&self) -> u32 {
        self.world.lights.len() as u32
    }

    fn sample_light(
        &self,
        ctx: &mut TraceCtx,
        index: u32,
        p: Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample> {
        let l = self.world.lights.get(index as usize)?;
        ctx.stats.light_samples += 1;
        l.sample_li(ctx, &p.into(), &u, time)
    }

    fn material(&self, shader: u32) -> Option<&Shader> {
        self.world.shaders.get(shader as usize)
    }
}
