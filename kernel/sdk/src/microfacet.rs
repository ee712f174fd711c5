//! Isotropic microfacet distributions — GGX (Trowbridge–Reitz) and
//! Beckmann — shared by the rough shaders so that each states only its own
//! lobes.
//!
//! Everything works in a local frame whose +z is the (shading) normal; the
//! distribution is isotropic, so any tangent frame about it will do. The
//! formulas are Walter et al. 2007 (D, Smith's G1 for GGX) and Heitz 2018,
//! "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), listing 1
//! (visible-normal sampling). `g1` includes Mitsuba 3's orientation rule
//! (`src/render/microfacet.h`): a facet seen from its back masks fully, so
//! shaders that mean to match Mitsuba's tables get the same integrand.

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// GGX with roughness `alpha` (α = perceptual roughness²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    /// α > 0; 1 is very rough, small is near-mirror.
    pub alpha: f32,
}

impl Ggx {
    /// D(m) for a unit local normal; 0 for facets below the surface.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if !(m.z > 0.0) {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let k = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
        1.0 / (PI * a2 * k * k)
    }

    /// Smith's Λ(w), `w` local (either hemisphere):
    /// (−1 + √(1 + α² tan²θ)) / 2, written without the cancellation.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let x = self.alpha * self.alpha * (w.x * w.x + w.y * w.y) / (w.z * w.z);
        if !x.is_finite() {
            return f32::INFINITY;
        }
        0.5 * x / (1.0 + (1.0 + x).sqrt())
    }

    /// Smith's masking G1(w, m) = 1 / (1 + Λ(w)), and 0 when `w` sees the
    /// back of the facet `m` (`(w·m)·w.z ≤ 0`), as Mitsuba's `smith_g1`.
    #[inline]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        if !(w.dot(m) * w.z > 0.0) {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// A normal drawn from the distribution of normals visible from `lo`
    /// (local, `lo.z > 0`); its density is `g1(lo, m)·D(m)·(lo·m) / lo.z`
    /// ([`Self::visible_pdf`]). Heitz 2018, listing 1.
    pub fn visible_normal(&self, lo: Vec3, u: [f32; 2]) -> Vec3 {
        let a = self.alpha;
        // The view direction in the hemisphere configuration (α = 1).
        let vh = Vec3::new(a * lo.x, a * lo.y, lo.z).normalize();
        // An orthonormal basis about it (T1 horizontal).
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // A point on the projected area: a disk, its lower half squashed.
        let r = u[0].sqrt();
        let phi = TAU * u[1];
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * (r * phi.sin());
        // Reprojected onto the hemisphere, back to the ellipsoid.
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(0.0)).normalize()
    }

    /// Density of [`Self::visible_normal`] choosing `m` for `lo`.
    #[inline]
    pub fn visible_pdf(&self, lo: Vec3, m: Vec3) -> f32 {
        if !(lo.z > 0.0) {
            return 0.0;
        }
        self.g1(lo, m) * self.d(m) * lo.dot(m).max(0.0) / lo.z
    }
}

/// Beckmann's distribution with roughness `alpha` (the RMS slope / √2),
/// with Mitsuba 3's rational approximation of its Smith masking (within
/// 0.35 %), so that shaders translated from Mitsuba use the same G1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beckmann {
    /// α > 0.
    pub alpha: f32,
}

impl Beckmann {
    /// D(m) = exp(−tan²θ/α²) / (π α² cos⁴θ); 0 below the surface.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if !(m.z > 0.0) {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let c2 = m.z * m.z;
        let d = (-(m.x * m.x + m.y * m.y) / (c2 * a2)).exp() / (PI * a2 * c2 * c2);
        if d.is_finite() {
            d
        } else {
            0.0
        }
    }

    /// Mitsuba's `smith_g1` for Beckmann: with a = 1 / (α tanθ), 1 for
    /// a ≥ 1.6, else (3.535 a + 2.181 a²) / (1 + 2.276 a + 2.577 a²); 0
    /// where `w` sees the back of `m`.
    #[inline]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        if !(w.dot(m) * w.z > 0.0) {
            return 0.0;
        }
        let xy = self.alpha * self.alpha * (w.x * w.x + w.y * w.y);
        if xy == 0.0 {
            return 1.0;
        }
        let a = (w.z * w.z / xy).sqrt();
        if a >= 1.6 {
            1.0
        } else {
            (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
        }
    }

    /// A normal drawn with density D(m) cos θm (the classic sampler:
    /// tan²θ = −α² ln(1 − u₀), φ = 2π u₁).
    pub fn sample(&self, u: [f32; 2]) -> Vec3 {
        let t2 = -self.alpha * self.alpha * (1.0 - u[0]).max(f32::MIN_POSITIVE).ln();
        let c = 1.0 / (1.0 + t2).sqrt();
        let s = (1.0 - c * c).max(0.0).sqrt();
        let phi = TAU * u[1];
        Vec3::new(s * phi.cos(), s * phi.sin(), c)
    }
}

/// Anisotropic GGX: roughness `ax` along the tangent frame's x (dp/du),
/// `ay` along y. The same formulas as [`Ggx`] with the slopes stretched
/// (Mitsuba's `alpha_u`, `alpha_v`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GgxAniso {
    /// α along x.
    pub ax: f32,
    /// α along y.
    pub ay: f32,
}

impl GgxAniso {
    /// D(m); 0 below the surface.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        if !(m.z > 0.0) {
            return 0.0;
        }
        let (x, y) = (m.x / self.ax, m.y / self.ay);
        let k = x * x + y * y + m.z * m.z;
        1.0 / (PI * self.ax * self.ay * k * k)
    }

    /// Smith's Λ(w) with the stretched tangent.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let (x, y) = (self.ax * w.x, self.ay * w.y);
        let t = (x * x + y * y) / (w.z * w.z);
        if !t.is_finite() {
            return f32::INFINITY;
        }
        0.5 * t / (1.0 + (1.0 + t).sqrt())
    }

    /// G1(w, m) as [`Ggx::g1`].
    #[inline]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        if !(w.dot(m) * w.z > 0.0) {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// A visible normal for `lo` (Heitz 2018 with the stretch per axis).
    pub fn visible_normal(&self, lo: Vec3, u: [f32; 2]) -> Vec3 {
        let vh = Vec3::new(self.ax * lo.x, self.ay * lo.y, lo.z).normalize();
        let nh = Ggx { alpha: 1.0 }.visible_normal(vh, u);
        Vec3::new(self.ax * nh.x, self.ay * nh.y, nh.z.max(0.0)).normalize()
    }

    /// Density of [`Self::visible_normal`] choosing `m`.
    #[inline]
    pub fn visible_pdf(&self, lo: Vec3, m: Vec3) -> f32 {
        if !(lo.z > 0.0) {
            return 0.0;
        }
        self.g1(lo, m) * self.d(m) * lo.dot(m).max(0.0) / lo.z
    }
}

/// A distribution of normals as the rough shaders use it: its D, Mitsuba's
/// G1, and a sampler with its density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Normals {
    /// GGX, sampled by visible normals.
    Ggx(Ggx),
    /// Beckmann, sampled by D cos θ.
    Beckmann(Beckmann),
    /// Anisotropic GGX, sampled by visible normals (needs the tangent frame).
    GgxAniso(GgxAniso),
}

impl Normals {
    /// The distribution by Mitsuba's name (`ggx`, `beckmann`).
    pub fn named(name: &str, alpha: f32) -> Option<Normals> {
        match name {
            "ggx" => Some(Normals::Ggx(Ggx { alpha })),
            "beckmann" => Some(Normals::Beckmann(Beckmann { alpha })),
            _ => None,
        }
    }

    /// D(m).
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        match self {
            Normals::Ggx(g) => g.d(m),
            Normals::Beckmann(b) => b.d(m),
            Normals::GgxAniso(a) => a.d(m),
        }
    }

    /// Mitsuba's G1(w, m).
    #[inline]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        match self {
            Normals::Ggx(g) => g.g1(w, m),
            Normals::Beckmann(b) => b.g1(w, m),
            Normals::GgxAniso(a) => a.g1(w, m),
        }
    }

    /// A normal for the viewer `lo` (local, above the surface).
    #[inline]
    pub fn sample(&self, lo: Vec3, u: [f32; 2]) -> Vec3 {
        match self {
            Normals::Ggx(g) => g.visible_normal(lo, u),
            Normals::Beckmann(b) => b.sample(u),
            Normals::GgxAniso(a) => a.visible_normal(lo, u),
        }
    }

    /// Density (solid angle of m) of [`Self::sample`] choosing `m`.
    #[inline]
    pub fn pdf(&self, lo: Vec3, m: Vec3) -> f32 {
        match self {
            Normals::Ggx(g) => g.visible_pdf(lo, m),
            Normals::Beckmann(b) => b.d(m) * m.z.max(0.0),
            Normals::GgxAniso(a) => a.visible_pdf(lo, m),
        }
    }
}

/// Nodes and weights of the `n`-point Gauss–Legendre rule on [−1, 1]
/// (Newton's iteration on Pₙ from Chebyshev guesses, in f64): the rule
/// Mitsuba's `quad::gauss_legendre` gives, for the tables rough shaders
/// precompute.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = -(std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let step = p1 / dp;
            x -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule integrates polynomials of degree 2n − 1 exactly.
    #[test]
    fn gauss_legendre_is_exact_to_degree_2n_minus_1() {
        for n in [1usize, 2, 5, 32] {
            let rule = gauss_legendre(n);
            assert_eq!(rule.len(), n);
            for deg in 0..2 * n {
                let q: f64 = rule.iter().map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!((q - exact).abs() < 1e-12, "n {n}, x^{deg}: {q} vs {exact}");
            }
        }
    }

    /// ∫ D(m) cos θm dm = 1 (the projected facet area is the surface's),
    /// and ∫ G1(wo, m) D(m) (wo·m)⁺ dm = wo.z (the visible projected area),
    /// by a midpoint rule over the hemisphere of normals.
    #[test]
    fn d_and_g1_conserve_projected_area() {
        for alpha in [0.2f32, 0.5, 1.0] {
            let ggx = Ggx { alpha };
            let wo = Vec3::new(0.6, 0.0, 0.8);
            let (nt, np) = (2000, 400);
            let (mut area, mut visible) = (0.0f64, 0.0f64);
            for i in 0..nt {
                let t = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
                for j in 0..np {
                    let p = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                    let m = Vec3::new(
                        (t.sin() * p.cos()) as f32,
                        (t.sin() * p.sin()) as f32,
                        t.cos() as f32,
                    );
                    let dw = t.sin()
                        * (std::f64::consts::FRAC_PI_2 / nt as f64)
                        * (std::f64::consts::TAU / np as f64);
                    let d = ggx.d(m) as f64;
                    area += d * m.z as f64 * dw;
                    visible += (ggx.g1(wo, m) * wo.dot(m).max(0.0)) as f64 * d * dw;
                }
            }
            assert!((area - 1.0).abs() < 2e-3, "α {alpha}: ∫D cos = {area}");
            assert!(
                (visible - 0.8).abs() < 2e-3,
                "α {alpha}: ∫G1 D (wo·m) = {visible}"
            );
        }
    }

    /// Beckmann: ∫ D cos = 1, its sampler's density integrates to 1
    /// (checked by E[1/pdf] over its samples against the hemisphere's
    /// area in the region reached), and Mitsuba's G1 is within 0.35 % of
    /// the exact Smith term (erf form) at a few angles.
    #[test]
    fn beckmann_is_normalised_and_its_g1_is_smiths() {
        let b = Beckmann { alpha: 0.3 };
        let n = 4000;
        let mut area = 0.0f64;
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
            let m = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
            area += b.d(m) as f64
                * m.z as f64
                * t.sin()
                * std::f64::consts::TAU
                * (std::f64::consts::FRAC_PI_2 / n as f64);
        }
        assert!((area - 1.0).abs() < 1e-3, "{area}");
        let mut mean = 0.0f64;
        for i in 0..256 {
            for j in 0..256 {
                let u = [(i as f32 + 0.5) / 256.0, (j as f32 + 0.5) / 256.0];
                let m = b.sample(u);
                let p = Normals::Beckmann(b).pdf(Vec3::Z, m) as f64;
                mean += b.d(m) as f64 * m.z as f64 / p;
            }
        }
        assert!((mean / 65536.0 - 1.0).abs() < 1e-4);
        // Exact Smith G1 for Beckmann: 2 / (1 + erf(a) + exp(−a²)/(a√π)).
        fn erf(x: f64) -> f64 {
            // Abramowitz–Stegun 7.1.26 is too coarse; integrate instead.
            let n = 20000;
            let h = x / n as f64;
            (0..n)
                .map(|i| (-((i as f64 + 0.5) * h).powi(2)).exp())
                .sum::<f64>()
                * h
                * 2.0
                / std::f64::consts::PI.sqrt()
        }
        for theta in [30.0f64, 60.0, 80.0, 88.0] {
            let t = theta.to_radians();
            let w = Vec3::new(t.sin() as f32, 0.0, t.cos() as f32);
            let a = 1.0 / (0.3 * t.tan());
            let exact = 2.0 / (1.0 + erf(a) + (-a * a).exp() / (a * std::f64::consts::PI.sqrt()));
            let g = b.g1(w, Vec3::Z) as f64;
            assert!(
                (g - exact).abs() <= 0.0035 * exact + 1e-6,
                "θ {theta}: {g} vs {exact}"
            );
        }
    }

    /// Visible normals face `lo`, and their mean density is that of
    /// `visible_pdf` (checked by the mean of 1/pdf over samples: the
    /// area of the support, ≤ 2π).
    #[test]
    fn visible_normals_face_the_viewer() {
        let ggx = Ggx { alpha: 0.4 };
        let lo = Vec3::new(0.5, 0.2, 0.84).normalize();
        for i in 0..64 {
            for j in 0..64 {
                let u = [(i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0];
                let m = ggx.visible_normal(lo, u);
                assert!(m.z > 0.0 && lo.dot(m) > 0.0, "{m:?}");
                assert!((m.length() - 1.0).abs() < 1e-5);
                assert!(ggx.visible_pdf(lo, m) > 0.0);
            }
        }
        assert_eq!(ggx.g1(Vec3::Z, Vec3::Z), 1.0);
        assert_eq!(
            ggx.g1(Vec3::new(0.8, 0.0, 0.6), Vec3::new(-0.8, 0.0, 0.6)),
            0.0
        );
        assert_eq!(ggx.d(Vec3::new(1.0, 0.0, 0.0)), 0.0);
    }
}
