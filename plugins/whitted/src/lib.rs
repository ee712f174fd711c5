#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::spawn_ray;
use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::direct_light;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "depth")]
    max_depth: u32,
    #[serde(default = "branch")]
    branch_depth: u32,
}

fn branch() -> u32 {
    8
}

fn depth() -> u32 {
    32
}

/// Deepest `max_depth` accepted: each bounce is a few plugin frames deep on
/// the render thread's stack.
const MAX_DEPTH_LIMIT: u32 = 1024;

struct Whitted {
    max_depth: u32,
    /// From this generation on, a surface with both a mirror and a
    /// refraction ray follows only the stronger one (the work bound).
    branch_depth: u32,
}

/// What Whitted shading reads: position (spawning rays), both normals.
const MASK: u32 = geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;

/// The delta lobes Whitted follows, in the order their rays are traced.
const SPECULAR_LOBES: [(u32, u32); 2] = [
    (lobe::SPECULAR | lobe::TRANSMISSION, ray_kind::REFRACTION),
    (lobe::SPECULAR | lobe::REFLECTION, ray_kind::REFLECTION),
];

impl Plugin for Whitted {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if p.max_depth > MAX_DEPTH_LIMIT {
            return Err(PluginError::key("max_depth", "must be at most 1024"));
        }
        Ok(Whitted {
            max_depth: p.max_depth,
            branch_depth: p.branch_depth,
        })
    }
}

impl Integrator for Whitted {
    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, ray: &Ray) -> Color {
        if ray.generation > self.max_depth {
            return Color::BLACK;
        }
        let mut hit = Hit::new();
        if !scene.intersect(ctx, ray, ray_kind::TRACED, &mut hit) {
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
        // What the surface emits, plus direct light through the material's
        // BRDF, one shadow ray a light (area lights included)...
        let mut l = m.emitted(ctx, &g, wo);
        l = l.plus(direct_light(ctx, scene, ray, &g, |ctx, wi| {
            m.eval(ctx, &g, wo, wi)
        }));
        // ...plus the mirror and refraction rays of its delta lobes. Glass
        // spawns two rays a hit, so a ray tree grows as 2^depth (a glass
        // ball in a mirror room: 33 M rays for an 8×8 image at depth 24).
        // From `branch_depth` on, only the stronger ray is followed, which
        // bounds a camera ray's tree to about 2^branch_depth · max_depth
        // rays; what is dropped weighs less than what is kept.
        let mut rays = [None, None];
        for (i, (lobes, kind)) in SPECULAR_LOBES.into_iter().enumerate() {
            if m.lobes() & lobes != lobes {
                continue;
            }
            if let Some(s) = m.sample(ctx, &g, wo, [0.5, 0.5], lobes) {
                rays[i] = Some((s, kind));
            }
        }
        if ray.generation >= self.branch_depth {
            if let [Some((a, _)), Some((b, _))] = &rays {
                let strength = |w: Color| w.r.max(w.g).max(w.b);
                let weaker = usize::from(strength(b.weight) < strength(a.weight));
                rays[weaker] = None;
            }
        }
        for (s, kind) in rays.into_iter().flatten() {
            let r = spawn_ray(&g, s.wi.v(), ray);
            l = l.plus(s.weight.times(scene.trace(ctx, &r, kind)));
        }
        l
    }
}

rtk_kernel::export_integrator!(
    Whitted,
    class = "whitted",
    doc = include_str!("../README.md")
);
