//! Per-pixel hypothesis tests of "these two images have the same mean",
//! the way renderers are tested against each other without either being
//! converged.
//!
//! - [`z_test`] is Mitsuba 3's render-test criterion
//!   (`src/render/tests/test_renders.py`): an image of `spp` samples
//!   against a reference whose own noise is negligible, with the
//!   reference's per-sample variance.
//! - [`welch_test`] is Welch's unequal-variance t-test per pixel (Jung,
//!   Hanika and Dachsbacher, "Detecting Bias in Monte Carlo Renderers
//!   using Welch's t-test", JCGT 9(2), 2020): both images noisy, each with
//!   its own per-sample variance and sample count.
//!
//! Both work in CIE XYZ, as Mitsuba's test does: the images and the
//! variances are converted by the same Rec. 709 → XYZ matrix (for the
//! variance this is Mitsuba's convention, not a propagation of variance;
//! it is kept so that a pass here is a pass there), and each variance is
//! floored at [`VARIANCE_FLOOR`]. A scene passes when at least
//! [`PASS_FRACTION`] of its pixel-channels have a two-sided p-value above
//! the Šidák-corrected level `1 − (1 − 0.01)^(1/pixels)`.

/// Mitsuba's floor under each variance: a pixel of zero variance (a black
/// background) would otherwise make any difference infinitely significant.
pub const VARIANCE_FLOOR: f64 = 1e-4;

/// The share of pixel-channels that must pass (Mitsuba's 99.75 %).
pub const PASS_FRACTION: f64 = 0.9975;

/// The significance level of the whole image before the Šidák correction.
pub const SIGNIFICANCE: f64 = 0.01;

/// Rec. 709 linear RGB to CIE XYZ, the matrix of Mitsuba's `srgb_to_xyz`
/// (`include/mitsuba/core/spectrum.h`).
const RGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.412453, 0.357580, 0.180423],
    [0.212671, 0.715160, 0.072169],
    [0.019334, 0.119193, 0.950227],
];

/// `rgb` (RGB triples) converted to XYZ triples, in f32 as Mitsuba's
/// `Bitmap.convert(XYZ, Float32)` stores them.
pub fn to_xyz(rgb: &[f32]) -> Vec<f64> {
    let mut out = Vec::with_capacity(rgb.len());
    for p in rgb.chunks_exact(3) {
        for row in RGB_TO_XYZ {
            let v = row[0] * p[0] as f64 + row[1] * p[1] as f64 + row[2] * p[2] as f64;
            out.push(v as f32 as f64);
        }
    }
    out
}

/// The outcome of a test over an image.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The two-sided p-value of each pixel-channel (XYZ triples).
    pub p: Vec<f64>,
    /// The per-test level after the Šidák correction.
    pub alpha: f64,
    /// Pixel-channels whose p is at or below `alpha`.
    pub failing: usize,
    /// Pixels of the image.
    pub pixels: usize,
}

impl Outcome {
    fn new(p: Vec<f64>) -> Outcome {
        let pixels = p.len() / 3;
        let alpha = 1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / pixels.max(1) as f64);
        let failing = p.iter().filter(|&&p| !(p > alpha)).count();
        Outcome {
            p,
            alpha,
            failing,
            pixels,
        }
    }

    /// Mitsuba's rule: passing pixel-channels / 3 ≥ 99.75 % of the pixels.
    pub fn passed(&self) -> bool {
        let passing = self.p.len() - self.failing;
        passing as f64 / 3.0 >= PASS_FRACTION * self.pixels as f64
    }

    /// The smallest p-value.
    pub fn min_p(&self) -> f64 {
        self.p.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// Mitsuba's z-test: `img` (of `spp` samples a pixel) against `reference`
/// with the reference's per-sample variance `reference_var`, all XYZ.
/// z = |img − ref| · sqrt(spp / max(var, 1e-4)), p = 2 (1 − Φ(z)).
pub fn z_test(img: &[f64], reference: &[f64], reference_var: &[f64], spp: u64) -> Outcome {
    let p = (img.iter().zip(reference).zip(reference_var))
        .map(|((&a, &r), &v)| {
            let z = (a - r).abs() * (spp as f64 / v.max(VARIANCE_FLOOR)).sqrt();
            two_sided_normal(z)
        })
        .collect();
    Outcome::new(p)
}

/// One image of a Welch test: its mean, its per-sample variance (XYZ) and
/// its samples per pixel.
pub struct Sampled<'a> {
    /// The pixel means.
    pub mean: &'a [f64],
    /// The variance of one sample.
    pub var: &'a [f64],
    /// Samples per pixel.
    pub spp: u64,
}

/// Welch's t-test per pixel-channel: t = (μa − μb) / sqrt(sa²/na + sb²/nb),
/// with the Welch–Satterthwaite degrees of freedom, p = 2 (1 − T_ν(|t|)).
pub fn welch_test(a: &Sampled, b: &Sampled) -> Outcome {
    let (na, nb) = (a.spp as f64, b.spp as f64);
    let p = (0..a.mean.len())
        .map(|i| {
            let ea = a.var[i].max(VARIANCE_FLOOR) / na;
            let eb = b.var[i].max(VARIANCE_FLOOR) / nb;
            let t = (a.mean[i] - b.mean[i]).abs() / (ea + eb).sqrt();
            let dof = (ea + eb).powi(2) / (ea * ea / (na - 1.0) + eb * eb / (nb - 1.0));
            two_sided_t(t, dof)
        })
        .collect();
    Outcome::new(p)
}

/// 2 (1 − Φ(z)) for z ≥ 0, computed as 2 Φ(−z) (no cancellation).
fn two_sided_normal(z: f64) -> f64 {
    if z.is_nan() {
        return 0.0;
    }
    2.0 * distrs::Normal::cdf(-z, 0.0, 1.0)
}

/// 2 (1 − T_ν(t)) for t ≥ 0.
fn two_sided_t(t: f64, dof: f64) -> f64 {
    if t.is_nan() {
        return 0.0;
    }
    2.0 * distrs::StudentsT::cdf(-t, dof)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn p_values_match_the_normal_and_t_tables() {
        // Φ(−1.959964) = 0.025: the two-sided 5 % point.
        assert!((two_sided_normal(1.959964) - 0.05).abs() < 1e-6);
        assert!((two_sided_normal(0.0) - 1.0).abs() < 1e-12);
        // t = 2.228 with 10 dof is the two-sided 5 % point (Student's table).
        assert!((two_sided_t(2.228139, 10.0) - 0.05).abs() < 1e-5);
        // Many dof: the normal's.
        assert!((two_sided_t(1.959964, 1e7) - 0.05).abs() < 1e-5);
    }

    #[test]
    fn the_sidak_level_and_the_pass_rule_are_mitsubas() {
        // 48x48 pixels: α = 1 − 0.99^(1/2304).
        let o = Outcome::new(vec![1.0; 3 * 2304]);
        assert!((o.alpha - 4.3621e-6).abs() < 1e-9, "{}", o.alpha);
        assert!(o.passed());
        // 0.25 % of the pixel-channels may fail: 17 of 6912 pass, 18 fail.
        let mut p = vec![1.0; 3 * 2304];
        for v in p.iter_mut().take(17) {
            *v = 0.0;
        }
        assert!(Outcome::new(p.clone()).passed());
        p[17] = 0.0;
        let o = Outcome::new(p);
        assert_eq!(o.failing, 18);
        assert!(!o.passed());
    }

    #[test]
    fn a_z_test_sees_a_bias_of_a_few_standard_errors() {
        // Mean 1 against 1 + 6 standard errors of the mean: fails; 1 +
        // 1 standard error: passes.
        let n = 300;
        let (spp, var) = (100u64, 0.04);
        let se = (var / spp as f64).sqrt();
        let reference = vec![1.0; 3 * n];
        let v = vec![var; 3 * n];
        assert!(z_test(&vec![1.0 + se; 3 * n], &reference, &v, spp).passed());
        assert!(!z_test(&vec![1.0 + 6.0 * se; 3 * n], &reference, &v, spp).passed());
        // The floor: a zero variance is read as 1e-4.
        let zero = vec![0.0; 3 * n];
        let o = z_test(&vec![1.001; 3 * n], &reference, &zero, 1);
        assert!((o.p[0] - two_sided_normal(0.1)).abs() < 1e-9);
    }

    #[test]
    fn welch_reduces_to_the_z_test_when_one_side_is_exact() {
        // b with a huge sample count: its error vanishes, and t → z.
        let (m, r, v) = (vec![1.02; 30], vec![1.0; 30], vec![0.09; 30]);
        let z = z_test(&m, &r, &v, 400);
        let w = welch_test(
            &Sampled {
                mean: &m,
                var: &v,
                spp: 400,
            },
            &Sampled {
                mean: &r,
                var: &v,
                spp: 1 << 40,
            },
        );
        assert!((z.p[0] - w.p[0]).abs() < 3e-3, "{} {}", z.p[0], w.p[0]);
    }

    #[test]
    fn xyz_is_mitsubas_matrix() {
        let x = to_xyz(&[1.0, 1.0, 1.0]);
        // The white point D65 in Mitsuba's matrix: rows sum to it.
        assert!((x[0] - 0.950456).abs() < 1e-6);
        assert!((x[1] - 1.0).abs() < 1e-6);
        assert!((x[2] - 1.088754).abs() < 1e-6);
    }
}
