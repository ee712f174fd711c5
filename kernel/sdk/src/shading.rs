//! Shading helpers shared by integrators and shaders: direct light with
//! shadow rays through `occluded` (never a nearest-hit query), mirror
//! reflection, refraction, the dielectric Fresnel term, and the cosine lobe.

use super::Scene;
use glam::Vec3;
use rtk_abi::*;
use rtk_geom::spawn_ray;

/// Sum over every light of `f(wi) * Li * |cos θ| / pdf`, each light's sample
/// tested with one shadow ray (offset past the hit's error bound). `f` gets
/// the context and the unit direction towards the light.
pub fn direct_light(
    ctx: &mut TraceCtx,
    scene: &Scene,
    ray: &Ray,
    g: &LocalGeom,
    mut f: impl FnMut(&mut TraceCtx, Vec3) -> Color,
) -> Color {
    let n = g.ns.v();
    let mut sum = Color::BLACK;
    for i in 0..scene.light_count() {
        let u = [ctx.rng.next_f32(), ctx.rng.next_f32()];
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
        let fv = f(ctx, wi);
        if fv.is_black() {
            continue;
        }
        let mut shadow = spawn_ray(g, wi, ray);
        if ls.dist.is_finite() {
            // Stop short of the light: point lights sit at `dist`.
            shadow.t_max = ls.dist * (1.0 - rtk_geom::SHADOW_EPSILON);
        }
        if scene.occluded(ctx, &shadow) {
            continue;
        }
        sum = sum.plus(fv.times(ls.li).scale(cos / ls.pdf));
    }
    sum
}

/// Mirror `wo` (pointing away from the surface) about `n`.
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// `w`, turned if it must be so that it leaves on the side of the geometric
/// normal `ng` that `side` points to (`side·ng > 0`; a zero `side` counts as
/// the side `ng` faces, as in [`spawn_ray`]'s choice of offset).
///
/// Why: a direction computed about the shading normal, or rounded at grazing
/// incidence, can cross the geometric surface, and the spawned ray is offset
/// to the side its direction says: a reflected ray that dips below the
/// surface by one rounding starts behind it and leaks (numerics.md S2, S5).
/// Directions already on their side are returned unchanged; others are
/// mirrored across the surface's plane and, if still within rounding of it,
/// tipped by 1e-5 rad.
#[inline]
pub fn on_side(w: Vec3, ng: Vec3, side: f32) -> Vec3 {
    let s = if side < 0.0 { -1.0 } else { 1.0 };
    let c = w.dot(ng);
    if c * s > 0.0 {
        return w;
    }
    let m = w - ng * (2.0 * c);
    if m.dot(ng) * s > 1e-6 {
        return m;
    }
    (m + ng * (s * 1e-5)).normalize()
}

/// [`reflect`] about the shading normal `n`, on the side of the geometric
/// normal that `wo` is on ([`on_side`]): what a mirror lobe returns.
#[inline]
pub fn reflect_at(g: &LocalGeom, wo: Vec3, n: Vec3) -> Vec3 {
    let ng = g.ng.v();
    on_side(reflect(wo, n), ng, wo.dot(ng))
}

/// [`refract`] about the shading normal `n`, on the other side of the
/// geometric normal from `wo` ([`on_side`]).
#[inline]
pub fn refract_at(g: &LocalGeom, wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let ng = g.ng.v();
    refract(wo, n, eta).map(|t| on_side(t, ng, -wo.dot(ng)))
}

/// Refract `wo` (pointing away from the surface, on the side `n` faces)
/// with relative index `eta` = n_transmitted / n_incident; `None` on total
/// internal reflection.
#[inline]
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + (cos_i / eta - cos_t) * n).normalize())
}

/// Unpolarised Fresnel reflectance of a dielectric interface, for the cosine
/// of the incident angle (on the side of the normal) and relative index `eta`.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_par * r_par + r_perp * r_perp)
}

/// Unpolarised Fresnel reflectance of a conductor of complex index
/// `eta + i k` (relative to the outside) for the cosine of the incident
/// angle: Mitsuba 3's `fresnel_conductor` (after Moeller, "Optics", 1988),
/// the same arithmetic so imported metals match its values.
#[inline]
pub fn fresnel_conductor(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - s2;
    let a2b2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
    let a = (0.5 * (a2b2 + t1)).max(0.0).sqrt();
    let (term1, term2) = (a2b2 + c2, 2.0 * cos_i * a);
    let rs = (term1 - term2) / (term1 + term2);
    let (term3, term4) = (a2b2 * c2 + s4, term2 * s2);
    let rp = rs * (term3 - term4) / (term3 + term4);
    0.5 * (rs + rp)
}

/// Sample a diffuse lobe: a cosine-distributed `wi` on the side of the
/// shading normal that `wo` is on, and its density.
#[inline]
pub fn cosine_sample(g: &LocalGeom, wo: Vec3, u: [f32; 2]) -> Option<(Vec3, f32)> {
    let n = g.ns.v();
    let n = if n.dot(wo) < 0.0 { -n } else { n };
    let wi = cosine_hemisphere(n, u);
    let pdf = n.dot(wi).max(0.0) * std::f32::consts::FRAC_1_PI;
    (pdf > 0.0).then_some((wi, pdf))
}

/// Are `wo` and `wi` on the same side of the shading normal (a reflection)?
#[inline]
pub fn same_side(g: &LocalGeom, wo: Vec3, wi: Vec3) -> bool {
    let n = g.ns.v();
    n.dot(wo) * n.dot(wi) > 0.0
}

/// Sample a reflection lobe by its cosine: `wi` from [`cosine_sample`], and
/// the sample's weight `f(wi)·|cos θi| / pdf` for the BRDF `f`.
#[inline]
pub fn cosine_lobe_sample(
    g: &LocalGeom,
    wo: Vec3,
    u: [f32; 2],
    lobe_bits: u32,
    f: impl FnOnce(Vec3) -> Color,
) -> Option<BsdfSample> {
    let (wi, pdf) = cosine_sample(g, wo, u)?;
    let cos = g.ns.v().dot(wi).abs();
    Some(BsdfSample {
        wi: wi.into(),
        weight: f(wi).scale(cos / pdf),
        pdf,
        lobe: lobe_bits,
        eta: 1.0,
    })
}

/// Density of [`cosine_sample`] choosing `wi` (0 on the other side).
#[inline]
pub fn cosine_pdf(g: &LocalGeom, wo: Vec3, wi: Vec3) -> f32 {
    if same_side(g, wo, wi) {
        g.ns.v().dot(wi).abs() * std::f32::consts::FRAC_1_PI
    } else {
        0.0
    }
}

/// A cosine-distributed direction around `n`, from two uniform numbers.
#[inline]
pub fn cosine_hemisphere(n: Vec3, u: [f32; 2]) -> Vec3 {
    let r = u[0].sqrt();
    let phi = std::f32::consts::TAU * u[1];
    let (t, b) = n.any_orthonormal_pair();
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u[0]).max(0.0).sqrt()).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reflections and refractions leave on their side of the geometric
    /// normal even at grazing incidence and with shading normals tilted
    /// away from it; correct directions are untouched.
    #[test]
    fn directions_keep_their_side() {
        let mut s = rtk_abi::RngState::seeded(11);
        let mut turned = 0;
        for _ in 0..200_000 {
            let ng = Vec3::new(
                s.range_f32(-1.0, 1.0),
                s.range_f32(-1.0, 1.0),
                s.range_f32(-1.0, 1.0),
            )
            .normalize();
            // Grazing: wo within 1e-6..1e-1 of the plane.
            let t = ng.any_orthonormal_vector();
            let lift = 10f32.powf(s.range_f32(-7.0, -1.0));
            let wo = (t + ng * lift).normalize();
            let ns = (ng + t * s.range_f32(-0.3, 0.3)).normalize();
            let g = LocalGeom {
                ng: ng.into(),
                ns: ns.into(),
                ..LocalGeom::EMPTY
            };
            let n = if ns.dot(wo) > 0.0 { ns } else { -ns };
            let r = reflect_at(&g, wo, n);
            // The side wo is on, a grazing zero counting as ng's (as spawn_ray does).
            let side = if wo.dot(ng) < 0.0 { -1.0 } else { 1.0 };
            assert!(
                r.dot(ng) * side > 0.0,
                "reflection crossed: wo {wo:?} ng {ng:?}"
            );
            assert!((r.length() - 1.0).abs() < 1e-5);
            if reflect(wo, n) != r {
                turned += 1;
            }
            if let Some(tr) = refract_at(&g, wo, n, 1.0 / 1.5) {
                assert!(tr.dot(ng) * side < 0.0, "refraction stayed: wo {wo:?}");
            }
        }
        // The plain formulas do cross at these angles: the guard is exercised.
        assert!(turned > 1000, "only {turned} turned");
    }

    #[test]
    fn fresnel_limits() {
        // Normal incidence on glass: ((1.5-1)/(1.5+1))^2 = 0.04.
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert_eq!(fresnel_dielectric(0.1, 1.0 / 1.5), 1.0);
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn refraction_obeys_snell() {
        let n = Vec3::Z;
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let t = refract(wo, n, 1.5).unwrap();
        let sin_i = 0.6;
        let sin_t = (t.x * t.x + t.y * t.y).sqrt();
        assert!((sin_i - 1.5 * sin_t).abs() < 1e-6);
        assert!(t.z < 0.0);
        assert!(refract(Vec3::new(0.9, 0.0, (1.0f32 - 0.81).sqrt()), n, 1.0 / 1.5).is_none());
    }

    #[test]
    fn reflect_mirrors() {
        assert_eq!(
            reflect(Vec3::new(1.0, 0.0, 1.0), Vec3::Z),
            Vec3::new(-1.0, 0.0, 1.0)
        );
    }
}

/// A direction uniform over the unit sphere (density 1/4π).
#[inline]
pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Barycentric weights (b0, b1, b2) of a point uniform by area over a
/// triangle (Pharr et al., pbrt-v4 §A.5.5's square-root map).
#[inline]
pub fn uniform_triangle(u: [f32; 2]) -> [f32; 3] {
    let s = u[0].sqrt();
    let (b1, b2) = (1.0 - s, u[1] * s);
    [1.0 - b1 - b2, b1, b2]
}

/// Index of the entry of a cumulative table (`cdf[i]` = sum of the first
/// `i + 1` weights, the last one the total) that `u` ∈ [0, 1) picks, and
/// `u` rescaled into [0, 1) within that entry, so one number serves both.
#[inline]
pub fn pick_from_cdf(cdf: &[f64], u: f32) -> Option<(usize, f32)> {
    let total = *cdf.last()?;
    let x = u as f64 * total;
    let i = cdf.partition_point(|&c| c <= x).min(cdf.len() - 1);
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let w = cdf[i] - lo;
    let r = if w > 0.0 { ((x - lo) / w) as f32 } else { 0.5 };
    Some((i, r.clamp(0.0, 1.0 - f32::EPSILON / 2.0)))
}

#[cfg(test)]
mod sampling_tests {
    use super::*;

    #[test]
    fn cdf_picks_by_weight_and_reuses_the_number() {
        let cdf = [1.0, 1.0, 4.0]; // weights 1, 0, 3
        assert_eq!(pick_from_cdf(&cdf, 0.0), Some((0, 0.0)));
        assert_eq!(pick_from_cdf(&cdf, 0.125).map(|p| p.0), Some(0));
        let (i, r) = pick_from_cdf(&cdf, 0.625).unwrap();
        assert_eq!(i, 2);
        assert!((r - 0.5).abs() < 1e-6);
        assert_eq!(pick_from_cdf(&cdf, 0.9999999).map(|p| p.0), Some(2));
        assert_eq!(pick_from_cdf(&[], 0.5), None);
    }

    #[test]
    fn uniform_triangle_mean_is_the_centroid() {
        let mut rng = rtk_abi::RngState::seeded(7);
        let mut m = [0.0f64; 3];
        let n = 100_000;
        for _ in 0..n {
            let b = uniform_triangle([rng.next_f32(), rng.next_f32()]);
            assert!(b.iter().all(|&x| (-1e-6..=1.0 + 1e-6).contains(&x)));
            for k in 0..3 {
                m[k] += b[k] as f64 / n as f64;
            }
        }
        // Standard error of a mean of Beta(1,2)-like weights is ~0.0008.
        assert!(m.iter().all(|&x| (x - 1.0 / 3.0).abs() < 0.004), "{m:?}");
    }

    #[test]
    fn uniform_sphere_is_unit_and_centred() {
        let mut rng = rtk_abi::RngState::seeded(3);
        let mut m = Vec3::ZERO;
        for _ in 0..100_000 {
            let d = uniform_sphere([rng.next_f32(), rng.next_f32()]);
            assert!((d.length() - 1.0).abs() < 1e-5);
            m += d / 100_000.0;
        }
        assert!(m.length() < 0.01, "{m}");
    }
}
