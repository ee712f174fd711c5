#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::microfacet::Ggx;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "rough")]
    alpha: f32,
    #[serde(default = "white")]
    reflectance: [f32; 3],
}

fn rough() -> f32 {
    0.1
}
fn white() -> [f32; 3] {
    [1.0; 3]
}

/// Range of `alpha`: below 1e-3 the lobe is a mirror that f32 densities
/// (up to ~1/α²) resolve poorly; use `conductor`.
const ALPHA_MIN: f32 = 1e-3;
const ALPHA_MAX: f32 = 1.0;

/// The one lobe.
const LOBE: u32 = lobe::GLOSSY | lobe::REFLECTION;

struct RoughConductor {
    ggx: Ggx,
    r: Color,
}

impl Plugin for RoughConductor {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(p.alpha >= ALPHA_MIN && p.alpha <= ALPHA_MAX) {
            return Err(PluginError::key(
                "alpha",
                format!("must be a number in [0.001, 1], got {}", p.alpha),
            ));
        }
        Ok(RoughConductor {
            ggx: Ggx { alpha: p.alpha },
            r: params::reflectance("reflectance", p.reflectance)?,
        })
    }
}

/// Orthonormal frame about the shading normal turned towards `wo`.
struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    fn new(g: &LocalGeom, wo: Vec3) -> Frame {
        let ns = g.ns.v();
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        let (t, b) = n.any_orthonormal_pair();
        Frame { t, b, n }
    }
    #[inline]
    fn local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }
    #[inline]
    fn world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// `wo` and `wi` leave on the same side of the geometric surface.
#[inline]
fn same_geometric_side(g: &LocalGeom, wo: Vec3, wi: Vec3) -> bool {
    let ng = g.ng.v();
    ng.dot(wo) * ng.dot(wi) > 0.0
}

impl RoughConductor {
    /// The half vector of two local directions above the surface, if any.
    #[inline]
    fn half(lo: Vec3, li: Vec3) -> Option<Vec3> {
        if !(lo.z > 0.0 && li.z > 0.0) {
            return None;
        }
        let m = (lo + li).normalize_or_zero();
        (m.z > 0.0).then_some(m)
    }

    /// f(wo, wi) / R, local.
    fn brdf(&self, lo: Vec3, li: Vec3) -> f32 {
        let Some(m) = Self::half(lo, li) else {
            return 0.0;
        };
        let g2 = 1.0 / (1.0 + self.ggx.lambda(lo) + self.ggx.lambda(li));
        let f = self.ggx.d(m) * g2 / (4.0 * lo.z * li.z);
        if f.is_finite() {
            f
        } else {
            0.0
        }
    }

    /// Density of [`Self::sample_local`]'s `li`: D_wo(m) / (4 wo·m) =
    /// G1(wo) D(m) / (4 cos θo).
    fn density(&self, lo: Vec3, li: Vec3) -> f32 {
        let Some(m) = Self::half(lo, li) else {
            return 0.0;
        };
        if !(lo.dot(m) > 0.0) {
            return 0.0;
        }
        let g1 = 1.0 / (1.0 + self.ggx.lambda(lo));
        let p = g1 * self.ggx.d(m) / (4.0 * lo.z);
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }
}

impl Shader for RoughConductor {
    fn lobes(&self) -> u32 {
        LOBE
    }

    fn eval(&self, _ctx: &mut TraceCtx, g: &LocalGeom, wo: Vec3, wi: Vec3) -> Color {
        if !same_geometric_side(g, wo, wi) {
            return Color::BLACK;
        }
        let fr = Frame::new(g, wo);
        self.r.scale(self.brdf(fr.local(wo), fr.local(wi)))
    }

    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        if lobes & LOBE != LOBE || self.r.is_black() {
            return None;
        }
        let fr = Frame::new(g, wo);
        let lo = fr.local(wo);
        if !(lo.z > 0.0) {
            return None;
        }
        let m = self.ggx.visible_normal(lo, u);
        let li = 2.0 * lo.dot(m) * m - lo;
        if !(li.z > 0.0) {
            return None; // reflected into the surface: absorbed
        }
        let wi = fr.world(li).normalize();
        if !same_geometric_side(g, wo, wi) {
            return None;
        }
        // Density and weight from wi as returned, so they agree with
        // `pdf` and `eval` for it.
        let li = fr.local(wi);
        let pdf = self.density(lo, li);
        if !(pdf > 0.0) {
            return None;
        }
        let (l_o, l_i) = (self.ggx.lambda(lo), self.ggx.lambda(li));
        // f·cos/pdf = R · G2 / G1(wo).
        let w = (1.0 + l_o) / (1.0 + l_o + l_i);
        if !w.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: wi.into(),
            weight: self.r.scale(w),
            pdf,
            lobe: LOBE,
            eta: 1.0,
        })
    }

    fn pdf(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        wi: Vec3,
        lobes: u32,
    ) -> Option<f32> {
        if lobes & LOBE != LOBE || self.r.is_black() || !same_geometric_side(g, wo, wi) {
            return Some(0.0);
        }
        let fr = Frame::new(g, wo);
        Some(self.density(fr.local(wo), fr.local(wi)))
    }
}

rtk_kernel::export_shader!(
    RoughConductor,
    class = "roughconductor",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests {
    use super::*;
    use rtk_kernel::sdk::shading::uniform_sphere;

    fn env() -> Env<'static> {
        Env {
            scene_dir: ".",
            name: "shaders.test",
            image_width: 1,
            image_height: 1,
            origin: [0.0; 3],
            arrays: Default::default(),
        }
    }

    fn metal(alpha: f32, r: [f32; 3]) -> RoughConductor {
        RoughConductor::create(
            Params {
                alpha,
                reflectance: r,
            },
            &env(),
        )
        .unwrap()
    }

    fn geom(n: Vec3) -> LocalGeom {
        LocalGeom {
            ng: n.into(),
            ns: n.into(),
            ..LocalGeom::EMPTY
        }
    }

    /// Mean and standard error of `n` draws of `f`.
    fn mean_se(n: u32, mut f: impl FnMut() -> f64) -> (f64, f64) {
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = f();
            s += x;
            s2 += x * x;
        }
        let m = s / n as f64;
        let var = (s2 / n as f64 - m * m).max(0.0);
        (m, (var / n as f64).sqrt())
    }

    /// A tilted surface, so that nothing depends on the frame being z-up.
    fn normal() -> Vec3 {
        Vec3::new(0.3, -0.5, 0.8).normalize()
    }

    /// `wo` at `theta` degrees from `n`.
    fn wo_at(n: Vec3, theta: f32) -> Vec3 {
        let (t, _) = n.any_orthonormal_pair();
        let th = theta.to_radians();
        (n * th.cos() + t * th.sin()).normalize()
    }

    /// The mean sample weight (the directional albedo as the sampler sees
    /// it) equals ∫ f·cos dωi estimated with uniform hemisphere directions,
    /// within 5 combined standard errors.
    #[test]
    fn sample_weight_matches_eval_integral() {
        let n = normal();
        let g = geom(n);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let mut rng = RngState::seeded(1);
        for alpha in [0.1f32, 0.3, 0.6, 1.0] {
            let m = metal(alpha, [1.0; 3]);
            for theta in [0.0f32, 45.0, 80.0] {
                let wo = wo_at(n, theta);
                let (a, se_a) = mean_se(400_000, || {
                    let u = [rng.next_f32(), rng.next_f32()];
                    match m.sample(&mut ctx, &g, wo, u, lobe::ALL) {
                        Some(s) => {
                            assert!(s.weight.r <= 1.0 + 1e-6, "{:?}", s.weight);
                            s.weight.r as f64
                        }
                        None => 0.0,
                    }
                });
                let (b, se_b) = mean_se(4_000_000, || {
                    let d = uniform_sphere([rng.next_f32(), rng.next_f32()]);
                    let wi = if d.dot(n) < 0.0 { -d } else { d };
                    let f = m.eval(&mut ctx, &g, wo, wi).r as f64;
                    f * wi.dot(n) as f64 * std::f64::consts::TAU
                });
                let tol = 5.0 * (se_a * se_a + se_b * se_b).sqrt();
                assert!(
                    (a - b).abs() <= tol,
                    "α {alpha}, θ {theta}: sampled {a} ± {se_a}, integrated {b} ± {se_b}"
                );
                // Single scattering loses energy, the more the rougher.
                assert!(a > 0.25 && a < 1.0, "α {alpha}, θ {theta}: albedo {a}");
                if alpha == 0.3 && theta == 0.0 {
                    // Midpoint quadrature of f·cos over the hemisphere
                    // (600 × 1200 cells, f64), done outside rtk.
                    assert!((a - 0.8774).abs() <= 5.0 * se_a + 1e-3, "{a} vs 0.8774");
                }
                if alpha == 1.0 && theta == 0.0 {
                    // Closed form: with α = 1 the visible normals from n are
                    // cosine-distributed, wi leaves when θm < 45°, with
                    // weight 1/(1 + Λ(wi)) = cos 2θm / cos² θm:
                    // ∫₀^{π/4} 2 tan θ cos 2θ dθ = 1 − ln 2.
                    let e = 1.0 - std::f64::consts::LN_2;
                    assert!((a - e).abs() <= 5.0 * se_a, "{a} vs 1 − ln 2 = {e}");
                }
                assert!(
                    tol < 0.03,
                    "α {alpha}, θ {theta}: tolerance {tol} too loose"
                );
            }
        }
    }

    /// pdf integrates over the sphere to the probability that `sample`
    /// returns a direction (≤ 1), and equals the density `sample` reports
    /// for the direction it returns; the weight is f·cos/pdf.
    #[test]
    fn pdf_is_the_density_of_sample() {
        let n = normal();
        let g = geom(n);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let mut rng = RngState::seeded(2);
        for alpha in [0.1f32, 0.3, 0.6, 1.0] {
            let m = metal(alpha, [0.9, 0.6, 0.3]);
            for theta in [0.0f32, 45.0, 80.0] {
                let wo = wo_at(n, theta);
                let (p_ok, se_ok) = mean_se(200_000, || {
                    let u = [rng.next_f32(), rng.next_f32()];
                    let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) else {
                        return 0.0;
                    };
                    let wi = s.wi.v();
                    assert_eq!(s.lobe, LOBE);
                    let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
                    assert!(
                        (p - s.pdf).abs() <= 1e-5 * s.pdf,
                        "pdf {p} vs sample's {}",
                        s.pdf
                    );
                    let f = m.eval(&mut ctx, &g, wo, wi);
                    let w = f.scale(wi.dot(n).abs() / s.pdf);
                    for (x, y) in w.to_array().iter().zip(s.weight.to_array()) {
                        assert!(
                            (x - y).abs() <= 2e-4 * y.max(1e-3),
                            "{w:?} vs {:?}",
                            s.weight
                        );
                    }
                    1.0
                });
                // The narrow lobe needs more uniform directions.
                let n_uniform = if alpha < 0.2 { 8_000_000 } else { 2_000_000 };
                let (integral, se_i) = mean_se(n_uniform, || {
                    let wi = uniform_sphere([rng.next_f32(), rng.next_f32()]);
                    let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap() as f64;
                    p * 4.0 * std::f64::consts::PI
                });
                let tol = 5.0 * (se_ok * se_ok + se_i * se_i).sqrt();
                assert!(
                    (integral - p_ok).abs() <= tol && integral <= 1.0 + tol,
                    "α {alpha}, θ {theta}: ∫pdf {integral} ± {se_i}, P(sample) {p_ok} ± {se_ok}"
                );
                assert!(tol < 0.03, "tolerance {tol}");
            }
        }
    }

    /// A near-mirror (α = 0.001): samples cluster at the mirror direction
    /// (GGX's tails are long: P(θm > x) ≈ α² / (α² + tan² x), so 1% of
    /// normals are farther than 0.57°, sending wi 1.15° away), their pdf and
    /// weight are finite and agree with `pdf`.
    #[test]
    fn smooth_limit_is_a_mirror() {
        let n = Vec3::Z;
        let g = geom(n);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let mut rng = RngState::seeded(3);
        let m = metal(ALPHA_MIN, [1.0; 3]);
        let wo = wo_at(n, 30.0);
        let mirror = 2.0 * wo.dot(n) * n - wo;
        let near = 1.2f32.to_radians().cos();
        let mut close = 0;
        for _ in 0..10_000 {
            let u = [rng.next_f32(), rng.next_f32()];
            let s = m.sample(&mut ctx, &g, wo, u, lobe::ALL).unwrap();
            close += (s.wi.v().dot(mirror) > near) as u32;
            assert!(s.weight.r > 0.999 && s.weight.r <= 1.0);
            let p = m.pdf(&mut ctx, &g, wo, s.wi.v(), lobe::ALL).unwrap();
            assert!(s.pdf.is_finite() && (p - s.pdf).abs() <= 1e-5 * s.pdf);
        }
        assert!(close >= 9850, "{close} of 10000 within 1.2°");
    }

    /// Two-sided: from below, the lobe mirrors the one above.
    #[test]
    fn two_sided() {
        let g = geom(Vec3::Z);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let m = metal(0.3, [1.0; 3]);
        let flip = Vec3::new(1.0, 1.0, -1.0);
        let wo = Vec3::new(0.3, 0.1, 0.9).normalize();
        let wi = Vec3::new(-0.5, 0.2, 0.7).normalize();
        let up = m.eval(&mut ctx, &g, wo, wi);
        let down = m.eval(&mut ctx, &g, wo * flip, wi * flip);
        assert!(up.r > 0.0);
        assert!((up.r - down.r).abs() <= 1e-6 * up.r);
        let pu = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
        let pd = m
            .pdf(&mut ctx, &g, wo * flip, wi * flip, lobe::ALL)
            .unwrap();
        assert!((pu - pd).abs() <= 1e-5 * pu);
        let s = m
            .sample(&mut ctx, &g, wo * flip, [0.3, 0.6], lobe::ALL)
            .unwrap();
        assert!(s.wi.v().z < 0.0);
        // Across the surface: nothing.
        assert_eq!(m.eval(&mut ctx, &g, wo, wi * flip), Color::BLACK);
        assert_eq!(m.pdf(&mut ctx, &g, wo, wi * flip, lobe::ALL), Some(0.0));
        // Lobes not asked for: nothing.
        assert!(m
            .sample(
                &mut ctx,
                &g,
                wo,
                [0.3, 0.6],
                lobe::SPECULAR | lobe::REFLECTION
            )
            .is_none());
        assert_eq!(
            m.pdf(&mut ctx, &g, wo, wi, lobe::DIFFUSE | lobe::REFLECTION),
            Some(0.0)
        );
        assert_eq!(m.lobes(), lobe::GLOSSY | lobe::REFLECTION);
    }

    /// A shading normal tilted from the geometric one: no sample crosses
    /// the geometric surface.
    #[test]
    fn samples_keep_the_geometric_side() {
        let g = LocalGeom {
            ng: Vec3::Z.into(),
            ns: Vec3::new(0.6, 0.0, 0.8).into(),
            ..LocalGeom::EMPTY
        };
        let mut ctx = TraceCtx::new(0, 1, 0);
        let mut rng = RngState::seeded(4);
        let m = metal(0.5, [1.0; 3]);
        // wo above both normals; its mirror about ns is below ng.
        let wo = Vec3::new(-0.7, 0.0, 0.714).normalize();
        let ns = g.ns.v();
        assert!(wo.dot(ns) > 0.0 && (2.0 * wo.dot(ns) * ns - wo).z < 0.0);
        let mut some = 0;
        for _ in 0..10_000 {
            let u = [rng.next_f32(), rng.next_f32()];
            if let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) {
                assert!(s.wi.v().z > 0.0);
                some += 1;
            }
        }
        // The rough lobe still reaches above the surface.
        assert!(some > 100 && some < 9000, "{some}");
    }

    #[test]
    fn parameters_are_checked() {
        for alpha in [0.0, 1e-4, 1.5, f32::NAN, -0.1] {
            let e = RoughConductor::create(
                Params {
                    alpha,
                    reflectance: [1.0; 3],
                },
                &env(),
            )
            .err()
            .unwrap();
            assert_eq!(e.key, "alpha");
        }
        let e = RoughConductor::create(
            Params {
                alpha: 0.2,
                reflectance: [1.0, -0.1, 1.0],
            },
            &env(),
        )
        .err()
        .unwrap();
        assert_eq!(e.key, "reflectance");
        let p: Params = parse_params("{}").unwrap();
        assert_eq!((p.alpha, p.reflectance), (0.1, [1.0; 3]));
    }
}
