#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::geom::{spawn_ray, SHADOW_EPSILON};
use rtk_kernel::glam::Vec3;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default)]
    max_depth: Option<u32>,
    #[serde(default = "rr")]
    rr_depth: u32,
}

fn rr() -> u32 {
    5
}

/// Longest path whatever `max_depth` says: throughput that never falls
/// (a NaN would never fail the roulette) must not hang the render.
const HARD_LIMIT: u32 = 1 << 16;

struct Path {
    max_depth: u32,
    rr_depth: u32,
}

impl Plugin for Path {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if p.max_depth == Some(0) {
            return Err(PluginError::key(
                "max_depth",
                "must be at least 1 (1: emitters seen directly); leave it out for no limit",
            ));
        }
        if p.rr_depth == 0 {
            return Err(PluginError::key("rr_depth", "must be at least 1"));
        }
        Ok(Path {
            max_depth: p.max_depth.unwrap_or(HARD_LIMIT).min(HARD_LIMIT),
            rr_depth: p.rr_depth,
        })
    }
}

/// What the surface fields the path reads: position, both normals, uv
/// (textures) and the tangents dp/du, dp/dv (bump maps tilt the normal
/// along them; an object computes them for the one hit shaded).
const MASK: u32 = geom_mask::POSITION
    | geom_mask::GEOMETRIC_NORMAL
    | geom_mask::SHADING_NORMAL
    | geom_mask::UV
    | geom_mask::TANGENTS;

/// How light found by the previous segment's direction is weighted.
#[derive(Clone, Copy)]
enum Found {
    /// A camera ray or a delta lobe's: no light sample could have made it.
    Unweighted,
    /// A BSDF sample from `p` with density `pdf`: weigh against the light's.
    Weighed { p: Vec3, pdf: f32 },
    /// From a material that cannot report its density: next-event
    /// estimation counted the lights there in full, so found light counts 0
    /// (unless no light sample could reach it: see `escape_weight`).
    NextEventOnly,
}

/// The power heuristic (β = 2) for `a` against `b`.
#[inline]
fn power(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

#[inline]
fn max_component(c: Color) -> f32 {
    c.r.max(c.g).max(c.b)
}

impl Path {
    /// One light sample at the vertex `g`: the light's contribution, MIS
    /// weighted against the BSDF's density, divided by the choice of light;
    /// and whether the material reports its density, when that was asked
    /// (the BSDF sample then needs no second call to find out).
    #[allow(clippy::too_many_arguments)]
    fn next_event(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        g: &LocalGeom,
        m: &Material,
        wo: Vec3,
        n_lights: u32,
    ) -> (Color, Option<bool>) {
        let none = (Color::BLACK, None);
        let i = ((ctx.rng.next_f32() * n_lights as f32) as u32).min(n_lights - 1);
        let u = [ctx.rng.next_f32(), ctx.rng.next_f32()];
        let Some(ls) = scene.sample_light(ctx, i, g.p.v(), u, ray.time) else {
            return none;
        };
        if !(ls.pdf > 0.0) || ls.li.is_black() {
            return none;
        }
        let wi = ls.wi.v();
        let cos = g.ns.v().dot(wi).abs();
        let f = m.eval(ctx, g, wo, wi);
        if f.is_black() || !(cos > 0.0) {
            return none;
        }
        let pl = ls.pdf / n_lights as f32;
        let (w, known) = if scene.light_flags(i) & light_flag::DELTA != 0 {
            (1.0, None)
        } else {
            match m.pdf(ctx, g, wo, wi, lobe::ALL) {
                Some(pb) => (power(pl, pb), Some(true)),
                None => (1.0, Some(false)),
            }
        };
        let mut shadow = spawn_ray(g, wi, ray);
        if ls.dist.is_finite() {
            shadow.t_max = ls.dist * (1.0 - SHADOW_EPSILON);
        }
        if scene.occluded(ctx, &shadow) {
            return (Color::BLACK, known);
        }
        (f.times(ls.li).scale(cos * w / pl), known)
    }

    /// Weight of light found along `ray` (at `geom`, or leaving the scene).
    fn found_weight(
        &self,
        ctx: &mut TraceCtx,
        scene: &Scene,
        ray: &Ray,
        geom: Option<&LocalGeom>,
        found: Found,
        n_lights: u32,
    ) -> f32 {
        match found {
            Found::Unweighted => 1.0,
            Found::Weighed { p, pdf } => {
                let pl = scene.light_pdf(ctx, p, ray, geom) / n_lights.max(1) as f32;
                power(pdf, pl)
            }
            Found::NextEventOnly => {
                // Light no light sample could reach (a plain background)
                // is this path's alone.
                if scene.light_pdf(ctx, ray.origin.v(), ray, geom) > 0.0 {
                    0.0
                } else {
                    1.0
                }
            }
        }
    }
}

/// How light found along the sampled direction `bs` is weighted.
/// `pdf_known`: whether the material reports densities, if the light
/// sample learnt it.
fn found_along(
    ctx: &mut TraceCtx,
    g: &LocalGeom,
    m: &Material,
    wo: Vec3,
    bs: &BsdfSample,
    pdf_known: Option<bool>,
) -> Found {
    if bs.lobe & lobe::SPECULAR != 0 {
        return Found::Unweighted;
    }
    // `sample`'s density is the one MIS needs (that of all the lobes it may
    // choose); ask `pdf` only to learn whether the material reports
    // densities at all, if the light sample did not already.
    let known = match pdf_known {
        Some(k) => k,
        None => m.pdf(ctx, g, wo, bs.wi.v(), lobe::ALL).is_some(),
    };
    if known {
        Found::Weighed {
            p: g.p.v(),
            pdf: bs.pdf,
        }
    } else {
        Found::NextEventOnly
    }
}

/// The throughput `beta` of a path that survives Russian roulette
/// (continued with probability `q`, its largest component up to 0.95,
/// and reweighted by 1/q), or `None` when it ends.
fn survive_roulette(ctx: &mut TraceCtx, beta: Color) -> Option<Color> {
    let q = max_component(beta).min(0.95);
    if !(ctx.rng.next_f32() < q) {
        return None;
    }
    Some(beta.scale(1.0 / q))
}

/// The kind of ray a segment sampled from the lobe `sampled` is traced as.
fn segment_kind(sampled: u32) -> u32 {
    if sampled & lobe::TRANSMISSION != 0 {
        ray_kind::REFRACTION
    } else if sampled & lobe::SPECULAR != 0 {
        ray_kind::REFLECTION
    } else {
        ray_kind::SCATTER
    }
}

impl Integrator for Path {
    fn li(&self, ctx: &mut TraceCtx, scene: &Scene, camera_ray: &Ray) -> Color {
        let n_lights = scene.light_count();
        let mut l = Color::BLACK;
        let mut beta = Color::splat(1.0);
        let mut ray = *camera_ray;
        let mut found = Found::Unweighted;
        let mut kind = ray_kind::TRACED;
        // Segments traced so far, this one included.
        let mut segments = 1u32;
        let mut hit = Hit::new();
        loop {
            hit.reset();
            if !scene.intersect(ctx, &ray, kind, &mut hit) {
                let le = scene.background(ctx, &ray);
                if !le.is_black() {
                    let w = self.found_weight(ctx, scene, &ray, None, found, n_lights);
                    l = l.plus(beta.times(le).scale(w));
                }
                break;
            }
            let g = scene.local_geom(ctx, &ray, &hit, MASK);
            let Some(m) = scene.material(&g) else {
                break;
            };
            let wo = -ray.dir.v().normalize();
            if m.lobes() & lobe::EMISSION != 0 {
                let le = m.emitted(ctx, &g, wo);
                if !le.is_black() {
                    let w = self.found_weight(ctx, scene, &ray, Some(&g), found, n_lights);
                    l = l.plus(beta.times(le).scale(w));
                }
            }
            if segments >= self.max_depth {
                break;
            }
            let mut pdf_known = None;
            if m.lobes() & (lobe::DIFFUSE | lobe::GLOSSY) != 0 && n_lights > 0 {
                let (d, known) = self.next_event(ctx, scene, &ray, &g, &m, wo, n_lights);
                l = l.plus(beta.times(d));
                pdf_known = known;
            }
            let u = [ctx.rng.next_f32(), ctx.rng.next_f32()];
            let Some(bs) = m.sample(ctx, &g, wo, u, lobe::ALL) else {
                break;
            };
            if bs.weight.is_black() || !bs.weight.is_finite() || !(bs.pdf > 0.0) {
                break;
            }
            beta = beta.times(bs.weight);
            found = found_along(ctx, &g, &m, wo, &bs, pdf_known);
            // Russian roulette after `rr_depth` scattering events (Mitsuba's
            // rule: the k-th hit, k ≥ rr_depth).
            if segments >= self.rr_depth {
                match survive_roulette(ctx, beta) {
                    Some(b) => beta = b,
                    None => break,
                }
            }
            ray = spawn_ray(&g, bs.wi.v(), &ray);
            kind = segment_kind(bs.lobe);
            segments += 1;
        }
        l
    }
}

rtk_kernel::export_integrator!(Path, class = "path", doc = include_str!("../README.md"));
