//! The kernel's `Trace` and the host services integrators and shaders call
//! ([`SceneApi`]): root queries, shading dispatch, lights, materials.
//! Every entry is a thin dispatch that counts what it does in the per-thread
//! statistics; nothing here allocates or locks.

use rtk_kernel::abi::*;
use rtk_shell::World;
use std::ffi::c_void;

type ShadeFn = extern "C" fn(
    *const c_void,
    *mut TraceCtx,
    *const SceneApi,
    *const Ray,
    *const LocalGeom,
) -> Color;
type EvalFn = extern "C" fn(
    *const c_void,
    *mut TraceCtx,
    *const LocalGeom,
    *const Float3,
    *const Float3,
) -> Color;
type SampleFn = extern "C" fn(
    *const c_void,
    *mut TraceCtx,
    *const LocalGeom,
    *const Float3,
    *const [f32; 2],
    *mut BsdfSample,
) -> bool;
type PdfFn = extern "C" fn(*const c_void, *const LocalGeom, *const Float3, *const Float3) -> f32;
type EmittedFn = extern "C" fn(*const c_void, *const LocalGeom, *const Float3) -> Color;
type SampleLiFn = extern "C" fn(
    *const c_void,
    *mut TraceCtx,
    *const Float3,
    *const [f32; 2],
    f32,
    *mut LightSample,
) -> bool;

/// A shader's entries, copied out of its module once.
struct ShaderFns {
    this: *const c_void,
    shade: Option<ShadeFn>,
    eval: EvalFn,
    sample: SampleFn,
    pdf: PdfFn,
    emitted: Option<EmittedFn>,
}

struct LightFns {
    this: *const c_void,
    sample_li: SampleLiFn,
    le: Option<extern "C" fn(*const c_void, *const Ray) -> Color>,
}

/// The host side of [`SceneApi`]. Boxed, because the record points at it.
pub struct Tracer<'w> {
    world: &'w World,
    root: ObjectRef,
    root_inst: InstanceData,
    li: extern "C" fn(*const c_void, *mut TraceCtx, *const SceneApi, *const Ray) -> Color,
    integrator: *const c_void,
    shaders: Vec<ShaderFns>,
    lights: Vec<LightFns>,
    background: Color,
    api: SceneApi,
}

// SAFETY: every pointer refers to plugin state that is immutable during
// rendering and `Sync` by the SDK's contract.
unsafe impl Sync for Tracer<'_> {}
// SAFETY: see above.
unsafe impl Send for Tracer<'_> {}

impl<'w> Tracer<'w> {
    /// Wire the world's plugins into a [`SceneApi`].
    pub fn new(world: &'w World) -> Box<Self> {
        let im = world.integrator.module;
        let max_depth = (im.max_depth())(world.integrator.this);
        let shaders = world
            .shaders
            .iter()
            .map(|s| ShaderFns {
                this: s.this,
                shade: s.module.shade(),
                eval: s.module.eval(),
                sample: s.module.sample(),
                pdf: s.module.pdf(),
                emitted: s.module.emitted(),
            })
            .collect();
        let lights = world
            .lights
            .iter()
            .map(|l| LightFns {
                this: l.this,
                sample_li: l.module.sample_li(),
                le: l.module.le(),
            })
            .collect();
        let bg = world.desc.render.background;
        let mut t = Box::new(Tracer {
            world,
            root: world.root,
            root_inst: world.root_inst,
            li: im.li(),
            integrator: world.integrator.this,
            shaders,
            lights,
            background: Color::new(bg[0], bg[1], bg[2]),
            api: SceneApi {
                host: std::ptr::null(),
                max_depth,
                trace: api_trace,
                intersect: api_intersect,
                occluded: api_occluded,
                local_geom: api_local_geom,
                shade: api_shade,
                background: api_background,
                light_count: api_light_count,
                sample_light: api_sample_light,
                bsdf_eval: api_bsdf_eval,
                bsdf_sample: api_bsdf_sample,
                bsdf_pdf: api_bsdf_pdf,
                emitted: api_emitted,
            },
        });
        t.api.host = &*t as *const Tracer as *const c_void;
        t
    }

    /// The world.
    pub fn world(&self) -> &World {
        self.world
    }

    /// Radiance along a camera ray (counted as a camera ray).
    #[inline]
    pub fn camera_li(&self, ctx: &mut TraceCtx, ray: &Ray) -> Color {
        ctx.stats.rays[ray_kind::CAMERA as usize] += 1;
        (self.li)(self.integrator, ctx, &self.api, ray)
    }
}

/// # Safety
/// `host` must be the `api.host` of a live [`Tracer`].
#[inline]
unsafe fn tracer<'a>(host: *const c_void) -> &'a Tracer<'a> {
    // SAFETY: guaranteed by the caller: every SceneApi entry receives the
    // pointer set in `Tracer::new`, valid for the whole render.
    unsafe { &*(host as *const Tracer) }
}

#[inline]
fn count(ctx: &mut TraceCtx, kind: u32) {
    if kind != ray_kind::TRACED {
        if let Some(c) = ctx.stats.rays.get_mut(kind as usize) {
            *c += 1;
        }
    }
}

extern "C" fn api_trace(
    host: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    kind: u32,
) -> Color {
    // SAFETY: the SceneApi contract: live tracer, valid exclusive context and ray.
    let (t, c) = unsafe { (tracer(host), &mut *ctx) };
    count(c, kind);
    (t.li)(t.integrator, ctx, &t.api, ray)
}

extern "C" fn api_intersect(
    host: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    kind: u32,
    hit: *mut Hit,
) -> bool {
    // SAFETY: as above.
    let (t, c) = unsafe { (tracer(host), &mut *ctx) };
    count(c, kind);
    (t.root.fns.intersect)(t.root.this, ctx, ray, hit, 0)
}

extern "C" fn api_occluded(host: *const c_void, ctx: *mut TraceCtx, ray: *const Ray) -> bool {
    // SAFETY: as above.
    let (t, c) = unsafe { (tracer(host), &mut *ctx) };
    c.stats.rays[ray_kind::SHADOW as usize] += 1;
    (t.root.fns.occluded)(t.root.this, ctx, ray, 0)
}

extern "C" fn api_local_geom(
    host: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    hit: *const Hit,
    mask: u32,
    out: *mut LocalGeom,
) {
    // SAFETY: as above; `out` is a valid output record.
    let (t, c, o) = unsafe { (tracer(host), &mut *ctx, &mut *out) };
    c.stats.local_geom_calls += 1;
    for (bit, n) in c.stats.local_geom_fields.iter_mut().enumerate() {
        *n += ((mask >> bit) & 1) as u64;
    }
    *o = LocalGeom::EMPTY;
    (t.root.fns.local_geom)(t.root.this, ctx, ray, hit, 0, mask, out);
    if o.shader == NONE_ID {
        o.shader = t.root_inst.shader;
    }
    if o.emitter == NONE_ID {
        o.emitter = t.root_inst.emitter;
    }
}

extern "C" fn api_shade(
    host: *const c_void,
    ctx: *mut TraceCtx,
    ray: *const Ray,
    geom: *const LocalGeom,
) -> Color {
    // SAFETY: as above.
    let (t, c, g, r) = unsafe { (tracer(host), &mut *ctx, &*geom, &*ray) };
    match t.shaders.get(g.shader as usize) {
        Some(s) => {
            c.stats.shader_calls += 1;
            match s.shade {
                Some(shade) => shade(s.this, ctx, &t.api, ray, geom),
                None => direct_light(t, c, s, r, g),
            }
        }
        // No shader bound: a grey "headlight" so that an unshaded scene is
        // still visible (documented in docs/scene-format.md).
        None => Color::splat(0.8 * g.ns.v().dot(-r.dir.v().normalize_or_zero()).abs()),
    }
}

/// Whitted shading for a material-only shader (no `shade`): its emission plus
/// direct light through its `eval`, with the SDK's shadow-ray helper.
fn direct_light(t: &Tracer, ctx: &mut TraceCtx, s: &ShaderFns, ray: &Ray, g: &LocalGeom) -> Color {
    let wo: Float3 = (-ray.dir.v().normalize_or_zero()).into();
    let emitted = match s.emitted {
        Some(e) => e(s.this, g, &wo),
        None => Color::BLACK,
    };
    let scene = rtk_kernel::Scene::new(&t.api);
    emitted.plus(rtk_kernel::sdk::shading::direct_light(
        ctx,
        &scene,
        ray,
        g,
        |ctx, wi| (s.eval)(s.this, ctx, g, &wo, &wi.into()),
    ))
}

extern "C" fn api_background(host: *const c_void, ray: *const Ray) -> Color {
    // SAFETY: as above.
    let t = unsafe { tracer(host) };
    let mut c = t.background;
    for l in &t.lights {
        if let Some(le) = l.le {
            c = c.plus(le(l.this, ray));
        }
    }
    c
}

extern "C" fn api_light_count(host: *const c_void) -> u32 {
    // SAFETY: as above.
    unsafe { tracer(host) }.lights.len() as u32
}

extern "C" fn api_sample_light(
    host: *const c_void,
    ctx: *mut TraceCtx,
    index: u32,
    p: *const Float3,
    u: *const [f32; 2],
    time: f32,
    out: *mut LightSample,
) -> bool {
    // SAFETY: as above.
    let (t, c) = unsafe { (tracer(host), &mut *ctx) };
    let Some(l) = t.lights.get(index as usize) else {
        return false;
    };
    c.stats.light_samples += 1;
    (l.sample_li)(l.this, ctx, p, u, time, out)
}

extern "C" fn api_bsdf_eval(
    host: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    wi: *const Float3,
) -> Color {
    // SAFETY: as above.
    let (t, g) = unsafe { (tracer(host), &*geom) };
    match t.shaders.get(g.shader as usize) {
        Some(s) => (s.eval)(s.this, ctx, geom, wo, wi),
        None => Color::BLACK,
    }
}

extern "C" fn api_bsdf_sample(
    host: *const c_void,
    ctx: *mut TraceCtx,
    geom: *const LocalGeom,
    wo: *const Float3,
    u: *const [f32; 2],
    out: *mut BsdfSample,
) -> bool {
    // SAFETY: as above.
    let (t, g) = unsafe { (tracer(host), &*geom) };
    match t.shaders.get(g.shader as usize) {
        Some(s) => (s.sample)(s.this, ctx, geom, wo, u, out),
        None => false,
    }
}

extern "C" fn api_bsdf_pdf(
    host: *const c_void,
    geom: *const LocalGeom,
    wo: *const Float3,
    wi: *const Float3,
) -> f32 {
    // SAFETY: as above.
    let (t, g) = unsafe { (tracer(host), &*geom) };
    match t.shaders.get(g.shader as usize) {
        Some(s) => (s.pdf)(s.this, geom, wo, wi),
        None => 0.0,
    }
}

extern "C" fn api_emitted(host: *const c_void, geom: *const LocalGeom, wo: *const Float3) -> Color {
    // SAFETY: as above.
    let (t, g) = unsafe { (tracer(host), &*geom) };
    match t
        .shaders
        .get(g.shader as usize)
        .and_then(|s| s.emitted.map(|e| (s.this, e)))
    {
        Some((this, e)) => e(this, geom, wo),
        None => Color::BLACK,
    }
}
