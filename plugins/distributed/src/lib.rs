#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::{spawn_ray, SHADOW_EPSILON};
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "depth")]
    max_depth: u32,
    #[serde(default = "depth")]
    branch_depth: u32,
    #[serde(default = "one")]
    light_samples: u32,
    #[serde(default = "one")]
    glossy_samples: u32,
}

fn depth() -> u32 {
    8
}
fn one() -> u32 {
    1
}

/// Deepest `max_depth` accepted: each bounce is a few plugin frames deep on
/// the render thread's stack (as for `whitted`).
const MAX_DEPTH_LIMIT: u32 = 1024;

/// Most samples per light or per glossy lobe at one hit.
const MAX_SAMPLES: u32 = 4096;

/// The largest f32 below 1: stratified numbers stay in [0, 1).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

struct Distributed {
    max_depth: u32,
    /// From this generation on, only the stronger of a mirror and a
    /// refraction ray is followed (whitted's work bound).
    branch_depth: u32,
    light_samples: u32,
    glossy_samples: u32,
}

/// What the integrator reads: position (spawning rays), both normals, and
/// uv for shaders that texture.
const MASK: u32 =
    geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL | geom_mask::UV;

/// The delta lobes followed, in the order their rays are traced (whitted's).
const SPECULAR_LOBES: [(u32, u32); 2] = [
    (lobe::SPECULAR | lobe::TRANSMISSION, ray_kind::REFRACTION),
    (lobe::SPECULAR | lobe::REFLECTION, ray_kind::REFLECTION),
];

/// The lobes a glossy ray is sampled from.
const GLOSSY_LOBES: u32 = lobe::GLOSSY | lobe::REFLECTION | lobe::TRANSMISSION;

impl Plugin for Distributed {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if p.max_depth > MAX_DEPTH_LIMIT {
            return Err(PluginError::key("max_depth", "must be at most 1024"));
        }
        if !(1..=MAX_SAMPLES).contains(&p.light_samples) {
            return Err(PluginError::key(
                "light_samples",
                format!(
                    "must be between 1 and {MAX_SAMPLES}, got {}",
                    p.light_samples
                ),
            ));
        }
        if p.glossy_samples > MAX_SAMPLES {
            return Err(PluginError::key(
                "glossy_samples",
                format!("must be at most {MAX_SAMPLES}, got {}", p.glossy_samples),
            ));
        }
        Ok(Distributed {
            max_depth: p.max_depth,
            branch_depth: p.branch_depth,
            light_samples: p.light_samples,
            glossy_samples: p.glossy_samples,
        })
    }
}

/// Sample `k` of `n` in [0, 1)²: jittered on an m×m grid (m = ⌊√n⌋) for
/// the first m² samples, uniform for the rest — Cook's jittered sampling.
/// With n = 1 it is two plain random numbers.
#[inline]
fn stratified(ctx: &mut TraceCtx, k: u32, n: u32) -> [f32; 2] {
    let u = [ctx.rng.next_f32(), ctx.rng.next_f32()];
    let m = n.isqrt();
    if k >= m * m {
        return u;
    }
    let (i, j) = ((k % m) as f32, (k / m) as f32);
    let m = m as f32;
    [
        ((i + u[0]) / m).min(ONE_MINUS_EPSILON),
        ((j + u[1]) / m).min(ONE_MINUS_EPSILON),
    ]
}

impl Distributed {
    /// Direct light through the material's BSDF: each delta light with one
    /// sample, every other light with `light_samples` (jittered over the
    /// light's sample domain: an area light's penumbra), each sample tested
    /// with one shadow ray; the estimate per light is their mean.
    fn direct(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        g: &LocalGeom,
        m: &Material,
        wo: Vec3,
    ) -> Color {
        let n = g.ns.v();
        let mut sum = Color::BLACK;
        for i in 0..scene.light_count() {
            let count = if scene.light_flags(i) & light_flag::DELTA != 0 {
                1
            } else {
                self.light_samples
            };
            let mut light = Color::BLACK;
            for k in 0..count {
                let u = stratified(ctx, k, count);
                let Some(ls) = scene.sample_light(ctx, i, g.p.v(), u, ray.time) else {
                    continue;
                };
                if !(ls.pdf > 0.0) || ls.li.is_black() {
                    continue;
                }
                let wi = ls.wi.v();
                let cos = n.dot(wi).abs();
                if cos == 0.0 {
                    continue;
                }
                let f = m.eval(ctx, g, wo, wi);
                if f.is_black() {
                    continue;
                }
                let mut shadow = spawn_ray(g, wi, ray);
                if ls.dist.is_finite() {
                    // Stop short of the light: its sampled point sits at `dist`.
                    shadow.t_max = ls.dist * (1.0 - SHADOW_EPSILON);
                }
                if scene.occluded(ctx, &shadow) {
                    continue;
                }
                light = light.plus(f.times(ls.li).scale(cos / ls.pdf));
            }
            sum = sum.plus(if count == 1 {
                light
            } else {
                light.scale(1.0 / count as f32)
            });
        }
        sum
    }

    /// Radiance arriving along `ray` (traced as `kind`). `after_glossy`:
    /// the ray was sampled from a glossy lobe, whose vertex already counted
    /// every light a light sample can reach — so light that such a sample
    /// could have found (an area light's surface, an environment light) is
    /// not counted again here.
    fn radiance(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        kind: u32,
        after_glossy: bool,
    ) -> Color {
        if ray.generation > self.max_depth {
            return Color::BLACK;
        }
        let mut hit = Hit::new();
        if !scene.intersect(ctx, ray, kind, &mut hit) {
            if after_glossy && scene.light_pdf(ctx, ray.origin.v(), ray, None) > 0.0 {
                return Color::BLACK;
            }
            return scene.background(ctx, ray);
        }
        let g = scene.local_geom(ctx, ray, &hit, MASK);
        let Some(m) = scene.material(&g) else {
            // No shader bound: a grey headlight, so an unshaded scene is visible.
            let facing = g.ns.v().dot(-ray.dir.v().normalize_or_zero()).abs();
            return Color::splat(0.8 * facing);
        };
        if let Some(c) = m.shade(ctx, scene, ray, &g) {
            return c;
        }
        let wo: Vec3 = -ray.dir.v().normalize();
        let mut l = self.emitted(ctx, scene, ray, &g, &m, wo, after_glossy);
        // Direct light, soft shadows from area lights.
        l = l.plus(self.direct(ctx, scene, ray, &g, &m, wo));
        for (s, kind) in self
            .specular_rays(ctx, ray, &g, &m, wo)
            .into_iter()
            .flatten()
        {
            let r = spawn_ray(&g, s.wi.v(), ray);
            l = l.plus(s.weight.times(scene.trace(ctx, &r, kind)));
        }
        if m.lobes() & lobe::GLOSSY != 0 && self.glossy_samples > 0 {
            l = l.plus(self.glossy(ctx, scene, ray, &g, &m, wo, after_glossy));
        }
        l
    }

    /// What the surface emits: seen by camera rays and specular bounces.
    /// After a glossy bounce, light that a light sample could have found
    /// was counted at the glossy vertex already.
    #[allow(clippy::too_many_arguments)]
    fn emitted(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        g: &LocalGeom,
        m: &Material,
        wo: Vec3,
        after_glossy: bool,
    ) -> Color {
        if m.lobes() & lobe::EMISSION == 0 {
            return Color::BLACK;
        }
        let le = m.emitted(ctx, g, wo);
        if le.is_black() {
            return Color::BLACK;
        }
        let sampled = after_glossy && scene.light_pdf(ctx, ray.origin.v(), ray, Some(g)) > 0.0;
        if sampled {
            Color::BLACK
        } else {
            le
        }
    }

    /// The delta lobes' rays, as whitted follows them (through `trace`),
    /// and with its work bound: from `branch_depth` on, only the stronger.
    fn specular_rays(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        g: &LocalGeom,
        m: &Material,
        wo: Vec3,
    ) -> [Option<(BsdfSample, u32)>; 2] {
        let lobes = m.lobes();
        let mut rays = [None, None];
        for (i, (want, kind)) in SPECULAR_LOBES.into_iter().enumerate() {
            if lobes & want != want {
                continue;
            }
            if let Some(s) = m.sample(ctx, g, wo, [0.5, 0.5], want) {
                rays[i] = Some((s, kind));
            }
        }
        if ray.generation >= self.branch_depth {
            if let [Some((a, _)), Some((b, _))] = &rays {
                let strength = |w: Color| w.r.max(w.g).max(w.b);
                rays[usize::from(strength(b.weight) < strength(a.weight))] = None;
            }
        }
        rays
    }

    /// Glossy lobes: the mean of `glossy_samples` rays (one after a glossy
    /// bounce) distributed by the material's own sampling.
    #[allow(clippy::too_many_arguments)]
    fn glossy(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        g: &LocalGeom,
        m: &Material,
        wo: Vec3,
        after_glossy: bool,
    ) -> Color {
        let n = if after_glossy { 1 } else { self.glossy_samples };
        let mut acc = Color::BLACK;
        for k in 0..n {
            let u = stratified(ctx, k, n);
            let Some(s) = m.sample(ctx, g, wo, u, GLOSSY_LOBES) else {
                continue;
            };
            // Only a glossy lobe's sample: a material that can only
            // sample its diffuse and glossy terms together (phong)
            // would make this diffuse interreflection, which Cook's
            // method leaves out.
            if s.lobe & lobe::GLOSSY == 0 || s.lobe & (lobe::DIFFUSE | lobe::SPECULAR) != 0 {
                continue;
            }
            if s.weight.is_black() || !s.weight.is_finite() {
                continue;
            }
            let r = spawn_ray(g, s.wi.v(), ray);
            let kind = if s.lobe & lobe::TRANSMISSION != 0 {
                ray_kind::REFRACTION
            } else {
                ray_kind::REFLECTION
            };
            let li = self.radiance(ctx, scene, &r, kind, true);
            acc = acc.plus(s.weight.times(li));
        }
        acc.scale(1.0 / n as f32)
    }
}

impl Integrator for Distributed {
    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray) -> Color {
        self.radiance(ctx, scene, ray, ray_kind::TRACED, false)
    }
}

rtk_kernel::export_integrator!(
    Distributed,
    class = "distributed",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stratified_samples_fill_their_cells() {
        let mut ctx = TraceCtx::new(0, 1, 0);
        ctx.rng = RngState::seeded(3);
        for n in [1u32, 2, 4, 5, 9, 16, 17] {
            let m = n.isqrt();
            let mut seen = vec![0u32; (m * m) as usize];
            for k in 0..n {
                let u = stratified(&mut ctx, k, n);
                assert!(u.iter().all(|&x| (0.0..1.0).contains(&x)), "{u:?}");
                if k < m * m {
                    let (i, j) = ((u[0] * m as f32) as u32, (u[1] * m as f32) as u32);
                    assert_eq!(j * m + i, k);
                    seen[k as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1));
        }
    }
}
