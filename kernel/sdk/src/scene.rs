//! The host's services as integrators and shaders see them: the generated
//! callers of [`LiveServices`], which [`Scene`] dereferences to, and the
//! few conveniences over them. A plugin is lent a `&Scene` for one call and
//! cannot make one: it can never keep the host's context past the call.

use crate::{LiveServices, LiveShader};
use rtk_abi::*;
use std::marker::PhantomData;

/// The scene as integrators and shaders see it: the kernel's `Trace`, the
/// root's queries, the lights and the material bound at a hit (the methods
/// of [`LiveServices`], one per entry of the services record).
#[repr(transparent)]
pub struct Scene {
    live: LiveServices,
}

// The cast in `from_record` relies on these: the record and the live
// handle are the same two words.
const _: () = assert!(std::mem::size_of::<SceneRef>() == std::mem::size_of::<Scene>());
const _: () = assert!(std::mem::align_of::<SceneRef>() == std::mem::align_of::<Scene>());

impl Scene {
    /// The record as a scene.
    ///
    /// # Safety
    /// `r.host` must be the live host context `r.services` was built for,
    /// valid for `'a`.
    #[doc(hidden)]
    pub unsafe fn from_record(r: &SceneRef) -> &Scene {
        // SAFETY: `Scene` is a `repr(transparent)` `LiveServices`, which is
        // laid out as `SceneRef` (a context pointer and the record, checked
        // above); the caller vouches for the host.
        unsafe { &*(r as *const SceneRef as *const Scene) }
    }

    /// The record, to pass on to a shader's `shade` or an integrator.
    pub(crate) fn raw(&self) -> &SceneRef {
        // SAFETY: the same layout, as in `from_record`.
        unsafe { &*(self as *const Scene as *const SceneRef) }
    }

    /// Local geometry of a root hit, fields per `mask` ([`geom_mask`]).
    #[inline]
    pub fn local_geom(&self, ctx: &mut TraceCtx, ray: &Ray, hit: &Hit, mask: u32) -> LocalGeom {
        let mut g = LocalGeom::EMPTY;
        self.live.local_geom(ctx, ray, hit, mask, &mut g);
        g
    }

    /// Nearest hits of the root for a batch of rays (ray streams): ray `i`
    /// when bit `i` of `active` is set, into `hits[i]`; the mask of those
    /// that hit. Ray by ray on a host that predates the entry.
    #[inline]
    pub fn intersect_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        kind: u32,
        hits: &mut [Hit],
        active: u64,
    ) -> u64 {
        if self.live.raw_class().intersect_batch().is_some() {
            return self
                .live
                .intersect_batch(ctx, rays, kind, hits, active)
                .unwrap_or(0);
        }
        let mut found = 0;
        for i in crate::batch::lanes(active, rays.len().min(hits.len())) {
            if self.live.intersect(ctx, &rays[i], kind, &mut hits[i]) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Any hit of the root for each active shadow ray of a batch; the mask
    /// of those occluded.
    #[inline]
    pub fn occluded_stream(&self, ctx: &mut TraceCtx, rays: &[Ray], active: u64) -> u64 {
        if let Some(m) = self.live.occluded_batch(ctx, rays, active) {
            return m;
        }
        let mut found = 0;
        for i in crate::batch::lanes(active, rays.len()) {
            if self.live.occluded(ctx, &rays[i]) {
                found |= 1 << i;
            }
        }
        found
    }

    /// Local geometry of each active root hit of a batch, into `out[i]`
    /// (each starting as [`LocalGeom::EMPTY`]).
    #[inline]
    pub fn local_geom_stream(
        &self,
        ctx: &mut TraceCtx,
        rays: &[Ray],
        hits: &[Hit],
        active: u64,
        mask: u32,
        out: &mut [LocalGeom],
    ) {
        let n = rays.len().min(hits.len()).min(out.len());
        for i in crate::batch::lanes(active, n) {
            out[i] = LocalGeom::EMPTY;
        }
        if self
            .live
            .local_geom_batch(ctx, rays, hits, active, mask, out)
            .is_none()
        {
            for i in crate::batch::lanes(active, n) {
                self.live
                    .local_geom(ctx, &rays[i], &hits[i], mask, &mut out[i]);
            }
        }
    }

    /// Light `index[i]` sampled from `p[i]` for each active point of a
    /// batch, into `out[i]`; the mask of the points that got a sample.
    #[inline]
    #[allow(clippy::too_many_arguments)] // the entry's spans, one for one
    pub fn sample_light_stream(
        &self,
        ctx: &mut TraceCtx,
        index: &[u32],
        p: &[Float3],
        u: &[[f32; 2]],
        time: &[f32],
        active: u64,
        out: &mut [LightSample],
    ) -> u64 {
        if let Some(m) = self
            .live
            .sample_light_batch(ctx, index, p, u, time, active, out)
        {
            return m;
        }
        let n = index
            .len()
            .min(p.len())
            .min(u.len())
            .min(time.len())
            .min(out.len());
        let mut got = 0;
        for i in crate::batch::lanes(active, n) {
            if let Some(s) = self.live.sample_light(ctx, index[i], p[i], u[i], time[i]) {
                out[i] = s;
                got |= 1 << i;
            }
        }
        got
    }

    /// The material bound at `geom` (`None` when no shader is bound).
    #[inline]
    pub fn material(&self, geom: &LocalGeom) -> Option<Material<'_>> {
        if geom.shader == NONE_ID {
            return None;
        }
        let r = self.live.material(geom.shader)?;
        Some(Material {
            // SAFETY: the host hands out shaders that live as long as the
            // scene, and the material borrows the scene.
            live: unsafe { LiveShader::new(r.this as *mut _, r.class) },
            lobes: r.lobes,
            _scene: PhantomData,
        })
    }
}

impl std::ops::Deref for Scene {
    type Target = LiveServices;
    #[inline(always)]
    fn deref(&self) -> &LiveServices {
        &self.live
    }
}

/// A shader bound at a hit, asked material queries directly (no host hop).
pub struct Material<'a> {
    live: LiveShader,
    lobes: u32,
    _scene: PhantomData<&'a Scene>,
}

impl Material<'_> {
    /// The [`lobe`] kinds the material has.
    #[inline]
    pub fn lobes(&self) -> u32 {
        self.lobes
    }

    /// BSDF value f(wo, wi), cosine not included.
    #[inline]
    pub fn eval(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        wi: glam::Vec3,
    ) -> Color {
        ctx.stats.shader_calls += 1;
        self.live.eval(ctx, geom, wo, wi)
    }

    /// Sample `wi` from the lobes `lobes` allows ([`lobe`] bits).
    #[inline]
    pub fn sample(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        ctx.stats.shader_calls += 1;
        self.live.sample(ctx, geom, wo, u, lobes)
    }

    /// Density (solid angle) with which `sample` restricted to `lobes`
    /// returns `wi`; `None` when the shader cannot tell (then do not weight
    /// its samples by MIS).
    #[inline]
    pub fn pdf(
        &self,
        ctx: &mut TraceCtx,
        geom: &LocalGeom,
        wo: glam::Vec3,
        wi: glam::Vec3,
        lobes: u32,
    ) -> Option<f32> {
        ctx.stats.shader_calls += 1;
        self.live.pdf(ctx, geom, wo, wi, lobes)
    }

    /// Radiance the surface emits towards `wo` (black for a material that
    /// does not emit).
    #[inline]
    pub fn emitted(&self, ctx: &mut TraceCtx, geom: &LocalGeom, wo: glam::Vec3) -> Color {
        if self.lobes & lobe::EMISSION == 0 {
            return Color::BLACK;
        }
        ctx.stats.shader_calls += 1;
        self.live.emitted(ctx, geom, wo)
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
        self.live.raw_class().shade()?;
        ctx.stats.shader_calls += 1;
        self.live.shade(ctx, scene, ray, geom)
    }
}
