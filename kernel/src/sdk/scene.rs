//! The host's services as integrators and shaders see them: safe methods over
//! the [`SceneRef`] record, which only the SDK's shims can wrap.

use crate::abi::*;
use glam::Vec3;
use std::marker::PhantomData;

/// The scene as integrators and shaders see it: the kernel's `Trace`, the
/// root's queries, the lights and the material bound at a hit.
#[derive(Clone, Copy)]
pub struct Scene<'a> {
    r: &'a SceneRef,
}

impl<'a> Scene<'a> {
    /// Wrap the record the host passed.
    ///
    /// # Safety
    /// `r.host` must be the live host context `r.services` was built for, valid
    /// for `'a`.
    pub(crate) unsafe fn new(r: &'a SceneRef) -> Self {
        Self { r }
    }

    /// The record, to pass on to a shader's `shade`.
    pub(crate) fn raw(&self) -> &'a SceneRef {
        self.r
    }

    /// `Trace(ray) -> color` through the scene's integrator; `kind` is a
    /// [`ray_kind`] for the statistics.
    #[inline]
    pub fn trace(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32) -> Color {
        // SAFETY: the constructor's contract; the rest are references.
        unsafe { (self.r.services.trace())(self.r.host, ctx, ray, kind) }
    }

    /// Nearest hit of the root.
    #[inline]
    pub fn intersect(&self, ctx: &mut TraceCtx, ray: &Ray, kind: u32, hit: &mut Hit) -> bool {
        // SAFETY: as in `trace`.
        unsafe { (self.r.services.intersect())(self.r.host, ctx, ray, kind, hit) }
    }

    /// Any hit of the root (shadow rays).
    #[inline]
    pub fn occluded(&self, ctx: &mut TraceCtx, ray: &Ray) -> bool {
        // SAFETY: as in `trace`.
        unsafe { (self.r.services.occluded())(self.r.host, ctx, ray) }
    }

    /// Local geometry of a root hit, fields per `mask` ([`geom_mask`]).
    #[inline]
    pub fn local_geom(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &Hit, mask: u32) -> LocalGeom {
        let mut g = LocalGeom::EMPTY;
        // SAFETY: as in `trace`.
        unsafe { (self.r.services.local_geom())(self.r.host, ctx, ray, hit, mask, &mut g) };
        g
    }

    /// Radiance of a ray leaving the scene.
    #[inline]
    pub fn background(&self, ctx: &mut TraceCtx, ray: &Ray) -> Color {
        // SAFETY: as in `trace`.
        unsafe { (self.r.services.background())(self.r.host, ctx, ray) }
    }

    /// Number of lights.
    #[inline]
    pub fn light_count(&self) -> u32 {
        // SAFETY: as in `trace`.
        unsafe { (self.r.services.light_count())(self.r.host) }
    }

    /// Sample light `index` from `p`.
    #[inline]
    pub fn sample_light(
        &self,
        ctx: &mut TraceCtx,
        index: u32,
        p: Vec3,
        u: [f32; 2],
        time: f32,
    ) -> Option<LightSample> {
        let mut s = LightSample::default();
        let p: Float3 = p.into();
        // SAFETY: as in `trace`.
        unsafe { (self.r.services.sample_light())(self.r.host, ctx, index, &p, &u, time, &mut s) }
            .then_some(s)
    }

    /// Density (solid angle, per light) with which sampling the light that
    /// `ray` found, from `p`, would have produced its direction: `geom` is
    /// its hit on an emitting surface, `None` when it left the scene (the
    /// environment light). 0 when there is no such light, or the host
    /// predates the entry.
    #[inline]
    pub fn light_pdf(
        &self,
        ctx: &mut TraceCtx,
        p: Vec3,
        ray: &Ray,
        geom: Option<&LocalGeom>,
    ) -> f32 {
        let Some(f) = self.r.services.light_pdf() else {
            return 0.0;
        };
        let g = geom.map_or(std::ptr::null(), |g| g as *const LocalGeom);
        // SAFETY: as in `trace`; `g` is null or a reference.
        unsafe { f(self.r.host, ctx, &p.into(), ray, g) }
    }

    /// The [`light_flag`] bits of light `index`; a host that predates the
    /// entry has only delta lights.
    #[inline]
    pub fn light_flags(&self, index: u32) -> u32 {
        match self.r.services.light_flags() {
            // SAFETY: as in `trace`.
            Some(f) => unsafe { f(self.r.host, index) },
            None => light_flag::DELTA,
        }
    }

    /// The material bound at `geom` (`None` when no shader is bound).
    #[inline]
    pub fn material(&self, geom: &LocalGeom) -> Option<Material<'a>> {
        if geom.shader == NONE_ID {
            return None;
        }
        let mut out = std::mem::MaybeUninit::<ShaderRef>::uninit();
        // SAFETY: as in `trace`; `out` is written when the entry returns true.
        let found =
            unsafe { (self.r.services.material())(self.r.host, geom.shader, out.as_mut_ptr()) };
        // SAFETY: the entry wrote `out` because it returned true; the shader
        // lives as long as the scene (`'a`).
        found.then(|| Material {
            r: unsafe { out.assume_init() },
            _scene: PhantomData,
        })
    }
}

/// A shader bound at a hit, asked material queries directly (no host hop).
#[derive(Clone, Copy)]
pub struct Material<'a> {
    r: ShaderRef,
    _scene: PhantomData<&'a SceneRef>,
}

impl Material<'_> {
    /// The [`lobe`] kinds the material has.
    #[inline]
    pub fn lobes(&self) -> u32 {
        self.r.lobes
    }

    /// BSDF value f(wo, wi), cosine not included.
    #[inline]
    pub fn eval(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        ctx.stats.shader_calls += 1;
        // SAFETY: the shader is live for the scene's lifetime (see
        // `Scene::material`); the rest are references.
        unsafe { (self.r.class.eval())(self.r.this, ctx, geom, &wo.into(), &wi.into()) }
    }

    /// Sample `wi` from the lobes `lobes` allows ([`lobe`] bits).
    #[inline]
    pub fn sample(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        ctx.stats.shader_calls += 1;
        let mut s = BsdfSample::default();
        // SAFETY: as in `eval`.
        unsafe { (self.r.class.sample())(self.r.this, ctx, geom, &wo.into(), &u, lobes, &mut s) }
            .then_some(s)
    }

    /// Density (solid angle) with which `sample` restricted to `lobes`
    /// returns `wi`; `None` when the shader cannot tell (then do not weight
    /// its samples by MIS).
    #[inline]
    pub fn pdf(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: Vec3,
        wi: Vec3,
        lobes: u32,
    ) -> Option<f32> {
        let f = self.r.class.pdf()?;
        ctx.stats.shader_calls += 1;
        // SAFETY: as in `eval`.
        let p = unsafe { f(self.r.this, ctx, geom, &wo.into(), &wi.into(), lobes) };
        (p >= 0.0).then_some(p)
    }

    /// Radiance the surface emits towards `wo` (black for a material that
    /// does not emit).
    #[inline]
    pub fn emitted(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: Vec3) -> Color {
        if self.r.lobes & lobe::EMISSION == 0 {
            return Color::BLACK;
        }
        let Some(f) = self.r.class.emitted() else {
            return Color::BLACK;
        };
        ctx.stats.shader_calls += 1;
        // SAFETY: as in `eval`.
        unsafe { f(self.r.this, ctx, geom, &wo.into()) }
    }

    /// The shader's own shading, if it overrides the integrator's
    /// (`None` when it answers material queries only).
    #[inline]
    pub fn shade(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        geom: &LocalGeom,
    ) -> Option<Color> {
        let f = self.r.class.shade()?;
        ctx.stats.shader_calls += 1;
        // SAFETY: as in `eval`; `scene` wraps a live record.
        Some(unsafe { f(self.r.this, ctx, scene.raw(), ray, geom) })
    }
}
