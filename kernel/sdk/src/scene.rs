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
