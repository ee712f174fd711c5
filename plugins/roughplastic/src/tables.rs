//! The two integrals the diffuse base of a rough plastic needs, tabulated
//! once per shader as Mitsuba 3 does (`eval_transmittance`,
//! `eval_reflectance` in `include/mitsuba/render/microfacet.h`, and
//! `RoughPlastic::parameters_changed`): same cosines, same Gauss–Legendre
//! rules, same integrands, so the shaded values agree with Mitsuba's to the
//! float rounding. The quadrature nodes map to visible normals through
//! Mitsuba's own GGX sampler ([`mitsuba_visible_normal`]), not the SDK's
//! (Heitz 2018): both draw the same distribution, but a 32² rule sees
//! their different parametrisations, and T would differ by ~2e-4.

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::microfacet::{gauss_legendre, Ggx, Normals};
use rtk_kernel::sdk::shading::fresnel_dielectric;

/// Cosines at which the transmittance is tabulated (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const RES: usize = 64;

/// The tabulated cosines: 0 to 1 evenly, the first raised to 1e-6.
fn cosines() -> impl Iterator<Item = f32> {
    (0..RES).map(|k| (k as f32 / (RES - 1) as f32).max(1e-6))
}

/// A direction at cosine `mu` from the normal, in the xz plane.
fn at_cosine(mu: f32) -> Vec3 {
    Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// ∫ over visible normals of `term(m)`, by Mitsuba's rule: the `n × n`
/// Gauss–Legendre nodes mapped to [0, 1]², weights × ¼. GGX maps the
/// nodes through Mitsuba's visible-normal sampler; Beckmann through its
/// D cos θ sampler, each node weighted by the visible density over that
/// one, G1(wi, m) (wi·m)⁺ / (cos θi cos θm), so the integral is the same.
fn over_visible_normals(normals: Normals, wi: Vec3, n: usize, term: impl Fn(Vec3) -> f32) -> f32 {
    let rule = gauss_legendre(n);
    let mut sum = 0.0f64;
    for &(x, wx) in &rule {
        for &(y, wy) in &rule {
            let u = [(0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32];
            let (m, w) = match normals {
                Normals::Ggx(g) => (mitsuba_visible_normal(g, wi, u), 1.0),
                Normals::Beckmann(b) => {
                    let m = b.sample(u);
                    let w = b.g1(wi, m) * wi.dot(m).max(0.0) / (wi.z * m.z);
                    (m, if w.is_finite() { w } else { 0.0 })
                }
                // Any other sampler: weighted by the visible density over its own.
                other => {
                    let m = other.sample(wi, u);
                    let visible = other.g1(wi, m) * other.d(m) * wi.dot(m).max(0.0) / wi.z;
                    let w = visible / other.pdf(wi, m);
                    (m, if w.is_finite() { w } else { 0.0 })
                }
            };
            if w > 0.0 {
                sum += (term(m) * w) as f64 * wx * wy * 0.25;
            }
        }
    }
    sum as f32
}

/// Mitsuba's GGX visible-normal sampler (`MicrofacetDistribution::sample`
/// with `sample_visible_11`): stretch, a concentric-disk point projected
/// as Heitz 2014 does, converted to a slope, rotated and unstretched.
fn mitsuba_visible_normal(ggx: Ggx, wi: Vec3, u: [f32; 2]) -> Vec3 {
    let a = ggx.alpha;
    let wp = Vec3::new(a * wi.x, a * wi.y, wi.z).normalize();
    let sin2 = wp.x * wp.x + wp.y * wp.y;
    let (sin_phi, cos_phi) = if sin2 <= 4.0 * f32::EPSILON {
        (0.0, 1.0)
    } else {
        let r = 1.0 / sin2.sqrt();
        ((wp.y * r).clamp(-1.0, 1.0), (wp.x * r).clamp(-1.0, 1.0))
    };
    let cos_t = wp.z;
    let (px, py) = concentric_disk(u);
    let s = 0.5 * (1.0 + cos_t);
    let py = (1.0 - px * px).max(0.0).sqrt() * (1.0 - s) + py * s;
    let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let norm = 1.0 / (sin_t * py + cos_t * pz);
    let (sx, sy) = ((cos_t * py - sin_t * pz) * norm, px * norm);
    let slope_x = (cos_phi * sx - sin_phi * sy) * a;
    let slope_y = (sin_phi * sx + cos_phi * sy) * a;
    Vec3::new(-slope_x, -slope_y, 1.0).normalize()
}

/// Shirley and Chiu's concentric map of the unit square onto the unit
/// disk, in Dave Cline's form (Mitsuba's `square_to_uniform_disk_concentric`).
fn concentric_disk(u: [f32; 2]) -> (f32, f32) {
    let (x, y) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if x == 0.0 && y == 0.0 {
        return (0.0, 0.0);
    }
    let q13 = x.abs() < y.abs();
    let (r, rp) = if q13 { (y, x) } else { (x, y) };
    let phi = std::f32::consts::FRAC_PI_4 * rp / r;
    let phi = if q13 {
        std::f32::consts::FRAC_PI_2 - phi
    } else {
        phi
    };
    (r * phi.cos(), r * phi.sin())
}

/// Mitsuba's rule size: 32² nodes entering a denser medium, 128² leaving
/// it (total internal reflection makes that integrand steeper).
fn nodes(eta: f32) -> usize {
    if eta > 1.0 {
        32
    } else {
        128
    }
}

/// T(μ): the fraction of light arriving at cosine μ that the rough
/// interface (relative index `eta`) transmits, single scattering: the mean
/// over visible normals of (1 − F)·G1(refracted). At the `RES` cosines.
pub fn transmittance(normals: Normals, eta: f32) -> [f32; RES] {
    let mut out = [0.0; RES];
    for (t, mu) in out.iter_mut().zip(cosines()) {
        let wi = at_cosine(mu);
        *t = over_visible_normals(normals, wi, nodes(eta), |m| {
            let c = wi.dot(m);
            let f = fresnel_dielectric(c, eta);
            let Some(wt) = refract_down(wi, m, c, eta) else {
                return 0.0;
            };
            if wt.z * wi.z >= 0.0 {
                return 0.0;
            }
            normals.g1(wt, m) * (1.0 - f)
        });
    }
    out
}

/// Mitsuba's `refract(wi, m, cos_theta_t, eta_ti)` for light entering
/// across the facet `m` (`c = wi·m > 0`); `None` on total internal
/// reflection.
fn refract_down(wi: Vec3, m: Vec3, c: f32, eta: f32) -> Option<Vec3> {
    let cos_t2 = 1.0 - (1.0 - c * c) / (eta * eta);
    if !(cos_t2 > 0.0) {
        return None;
    }
    Some(m * (c / eta - cos_t2.sqrt()) - wi / eta)
}

/// The diffuse base's internal reflectance: light leaving the base is
/// reflected back by the interface seen from inside (relative index
/// 1/`eta`) with probability 2 ∫ R(μ) μ dμ, which Mitsuba takes as twice
/// the mean of R(μ)·μ over the `RES` cosines.
pub fn internal_reflectance(normals: Normals, eta: f32) -> f32 {
    let inv = 1.0 / eta;
    let sum: f32 = cosines()
        .map(|mu| {
            let wi = at_cosine(mu);
            let r = over_visible_normals(normals, wi, nodes(inv), |m| {
                let c = wi.dot(m);
                let wr = 2.0 * c * m - wi;
                if !(wr.z > 0.0 && wi.z > 0.0) {
                    return 0.0;
                }
                normals.g1(wr, m) * fresnel_dielectric(c, inv)
            });
            r * wi.z
        })
        .sum();
    2.0 * sum / RES as f32
}

/// `table` read at cosine `x` ∈ [0, 1], linearly between entries
/// (Mitsuba's `lerp_gather`).
#[inline]
pub fn lookup(table: &[f32; RES], x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0) * (RES - 1) as f32;
    let i = (x as usize).min(RES - 2);
    let t = x - i as f32;
    table[i] * (1.0 - t) + table[i + 1] * t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nearly smooth (α = 0.001), the tables are the smooth interface's:
    /// T(μ) = 1 − F(μ), and 2 ∫ R μ dμ for glass of index 1.5 seen from
    /// inside is 1 − (1 − 0.0918)/1.5² = 0.5963 (its exterior reflectance
    /// 0.0918 by reciprocity; Mitsuba's 64-point mean reads about 1/64 low).
    #[test]
    fn the_smooth_limit_is_fresnel() {
        let ggx = Normals::Ggx(Ggx { alpha: 0.001 });
        let t = transmittance(ggx, 1.5);
        for (k, mu) in cosines().enumerate().skip(8) {
            let want = 1.0 - fresnel_dielectric(mu, 1.5);
            assert!((t[k] - want).abs() < 2e-3, "μ {mu}: {} vs {want}", t[k]);
        }
        let fint = internal_reflectance(ggx, 1.5);
        let mean: f32 = cosines()
            .map(|mu| fresnel_dielectric(mu, 1.0 / 1.5) * mu)
            .sum();
        let smooth = 2.0 * mean / RES as f32;
        assert!((fint - smooth).abs() < 2e-3, "{fint} vs {smooth}");
        assert!((fint - 0.5963).abs() < 0.015, "{fint}");
    }

    /// Rougher interfaces transmit less at normal incidence and more at
    /// grazing; nothing leaves [0, 1].
    #[test]
    fn roughness_spreads_the_transmittance() {
        let smooth = transmittance(Normals::Ggx(Ggx { alpha: 0.01 }), 1.5);
        let rough = transmittance(Normals::Ggx(Ggx { alpha: 1.0 }), 1.5);
        assert!(rough[RES - 1] < smooth[RES - 1]);
        assert!(rough[2] > smooth[2]);
        assert!(rough.iter().chain(&smooth).all(|t| (0.0..=1.0).contains(t)));
        assert_eq!(lookup(&rough, 1.0), rough[RES - 1]);
        assert_eq!(lookup(&rough, 0.0), rough[0]);
        let mid = lookup(&rough, 0.5 / (RES - 1) as f32);
        assert!((mid - 0.5 * (rough[0] + rough[1])).abs() < 1e-6);
    }
}
