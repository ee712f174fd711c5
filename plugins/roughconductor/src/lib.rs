#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::microfacet::{GgxAniso, Normals};
use rtk_kernel::sdk::shading::fresnel_conductor;
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "rough")]
    alpha: f32,
    #[serde(default = "white")]
    reflectance: [f32; 3],
    #[serde(default = "ggx")]
    distribution: String,
    #[serde(default)]
    masking: Option<String>,
    #[serde(default)]
    eta: Option<[f32; 3]>,
    #[serde(default)]
    k: Option<[f32; 3]>,
    #[serde(default = "yes")]
    two_sided: bool,
    #[serde(default)]
    alpha_u: Option<f32>,
    #[serde(default)]
    alpha_v: Option<f32>,
}

fn rough() -> f32 {
    0.1
}
fn white() -> [f32; 3] {
    [1.0; 3]
}
fn ggx() -> String {
    "ggx".into()
}
fn yes() -> bool {
    true
}

/// Range of `alpha`: below 1e-3 the lobe is a mirror that f32 densities
/// (up to ~1/α²) resolve poorly; use `conductor`.
const ALPHA_MIN: f32 = 1e-3;
const ALPHA_MAX: f32 = 1.0;

/// The one lobe.
const LOBE: u32 = lobe::GLOSSY | lobe::REFLECTION;

/// How shadowing and masking combine.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Masking {
    /// Height-correlated: 1 / (1 + Λ(wo) + Λ(wi)) (Heitz 2014; GGX).
    Correlated,
    /// G1(wo) G1(wi), Mitsuba's.
    Separable,
}

struct RoughConductor {
    normals: Normals,
    masking: Masking,
    r: Color,
    /// The complex index per channel, when the Fresnel term is computed.
    index: Option<([f32; 3], [f32; 3])>,
    /// Both faces reflect; false: Mitsuba's one-sided rule.
    two_sided: bool,
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
        let mut normals = Normals::named(&p.distribution, p.alpha).ok_or_else(|| {
            PluginError::key(
                "distribution",
                format!("`{}`: use \"ggx\" or \"beckmann\"", p.distribution),
            )
        })?;
        match (p.alpha_u, p.alpha_v, normals) {
            (None, None, _) => {}
            (Some(ax), Some(ay), Normals::Ggx(_)) => {
                for (key, a) in [("alpha_u", ax), ("alpha_v", ay)] {
                    if !(ALPHA_MIN..=ALPHA_MAX).contains(&a) {
                        return Err(PluginError::key(
                            key,
                            format!("must be a number in [0.001, 1], got {a}"),
                        ));
                    }
                }
                normals = Normals::GgxAniso(GgxAniso { ax, ay });
            }
            (Some(_), Some(_), _) => {
                return Err(PluginError::key(
                    "alpha_u",
                    "anisotropic roughness is offered for GGX only",
                ))
            }
            _ => {
                return Err(PluginError::key(
                    "alpha_v",
                    "`alpha_u` and `alpha_v` go together",
                ))
            }
        }
        let masking = match (p.masking.as_deref(), normals) {
            (None | Some("correlated"), Normals::Ggx(_)) => Masking::Correlated,
            (None | Some("separable"), _) => Masking::Separable,
            (Some("correlated"), Normals::Beckmann(_)) => {
                return Err(PluginError::key(
                    "masking",
                    "Beckmann normals take \"separable\" masking",
                ))
            }
            (Some(o), _) => {
                return Err(PluginError::key(
                    "masking",
                    format!("`{o}`: use \"correlated\" or \"separable\""),
                ))
            }
        };
        let index = match (p.eta, p.k) {
            (Some(eta), Some(k)) => {
                params::color("eta", eta)?;
                params::color("k", k)?;
                Some((eta, k))
            }
            (None, None) => None,
            (Some(_), None) => return Err(PluginError::key("k", "`eta` needs `k` beside it")),
            (None, Some(_)) => return Err(PluginError::key("eta", "`k` needs `eta` beside it")),
        };
        Ok(RoughConductor {
            normals,
            masking,
            r: params::reflectance("reflectance", p.reflectance)?,
            index,
            two_sided: p.two_sided,
        })
    }
}

/// Orthonormal frame about the shading normal (turned towards `wo` when
/// two-sided).
struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    fn new(g: &LocalGeom, wo: Vec3, two_sided: bool) -> Frame {
        let ns = g.ns.v();
        let n = if two_sided && ns.dot(wo) < 0.0 {
            -ns
        } else {
            ns
        };
        // Anisotropy is measured in Mitsuba's shading frame: x along dp/du
        // made perpendicular to the normal, where the hit has tangents.
        let dpdu = g.dpdu.v();
        let s = if g.filled & geom_mask::TANGENTS != 0 {
            (dpdu - n * n.dot(dpdu)).normalize_or_zero()
        } else {
            Vec3::ZERO
        };
        let (t, b) = if s == Vec3::ZERO || !s.is_finite() {
            n.any_orthonormal_pair()
        } else {
            (s, n.cross(s))
        };
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

impl RoughConductor {
    /// Does this pair leave where the lobe lives? Two-sided (rtk's own
    /// rule): on one side of the geometric surface, so a tilted shading
    /// normal cannot send light through; one-sided (Mitsuba's): both above
    /// the shading normal, which [`Self::half`] checks.
    #[inline]
    fn admits(&self, g: &LocalGeom, wo: Vec3, wi: Vec3) -> bool {
        let ng = g.ng.v();
        !self.two_sided || ng.dot(wo) * ng.dot(wi) > 0.0
    }

    /// The half vector of two local directions above the surface, if any.
    #[inline]
    fn half(lo: Vec3, li: Vec3) -> Option<Vec3> {
        if !(lo.z > 0.0 && li.z > 0.0) {
            return None;
        }
        let m = (lo + li).normalize_or_zero();
        (m.z > 0.0).then_some(m)
    }

    /// Shadowing-masking of the pair about `m`.
    fn g2(&self, lo: Vec3, li: Vec3, m: Vec3) -> f32 {
        match (self.masking, self.normals) {
            (Masking::Correlated, Normals::Ggx(g)) => 1.0 / (1.0 + g.lambda(lo) + g.lambda(li)),
            _ => self.normals.g1(lo, m) * self.normals.g1(li, m),
        }
    }

    /// f(wo, wi), local: the Fresnel colour times D G / (4 cos θo cos θi).
    fn brdf(&self, lo: Vec3, li: Vec3) -> Color {
        let Some(m) = Self::half(lo, li) else {
            return Color::BLACK;
        };
        let f = self.normals.d(m) * self.g2(lo, li, m) / (4.0 * lo.z * li.z);
        if !(f.is_finite() && f > 0.0) {
            return Color::BLACK;
        }
        self.fresnel(lo.dot(m)).scale(f)
    }

    /// The reflectance at cosine `c` to the facet: constant, or Mitsuba's
    /// conductor Fresnel term per channel.
    fn fresnel(&self, c: f32) -> Color {
        match &self.index {
            None => self.r,
            Some((eta, k)) => {
                let f = [0, 1, 2].map(|i| fresnel_conductor(c.min(1.0), eta[i], k[i]));
                self.r.times(Color::from_array(f))
            }
        }
    }

    /// f·cos θi / pdf over the Fresnel colour, for a sample of density
    /// `pdf` about `m`. With GGX's visible normals the quotient is known in
    /// closed form (at most 1, exactly: G2 / G1(wo)); otherwise divided out.
    fn weight(&self, lo: Vec3, li: Vec3, m: Vec3, pdf: f32) -> f32 {
        match (self.masking, self.normals) {
            (Masking::Correlated, Normals::Ggx(g)) => {
                let (l_o, l_i) = (g.lambda(lo), g.lambda(li));
                (1.0 + l_o) / (1.0 + l_o + l_i)
            }
            (Masking::Separable, Normals::Ggx(g)) => g.g1(li, m),
            _ => self.normals.d(m) * self.g2(lo, li, m) / (4.0 * lo.z) / pdf,
        }
    }

    /// Density of `sample`'s `li`: the normals' density over 4 wo·m.
    fn density(&self, lo: Vec3, li: Vec3) -> f32 {
        let Some(m) = Self::half(lo, li) else {
            return 0.0;
        };
        if !(lo.dot(m) > 0.0) {
            return 0.0;
        }
        let p = self.normals.pdf(lo, m) / (4.0 * lo.dot(m));
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
        if !self.admits(g, wo, wi) {
            return Color::BLACK;
        }
        let fr = Frame::new(g, wo, self.two_sided);
        self.brdf(fr.local(wo), fr.local(wi))
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
        let fr = Frame::new(g, wo, self.two_sided);
        let lo = fr.local(wo);
        if !(lo.z > 0.0) {
            return None;
        }
        let m = self.normals.sample(lo, u);
        let li = 2.0 * lo.dot(m) * m - lo;
        if !(li.z > 0.0) {
            return None; // reflected into the surface: absorbed
        }
        let wi = fr.world(li).normalize();
        if !self.admits(g, wo, wi) {
            return None;
        }
        // Density and weight from wi as returned, so they agree with
        // `pdf` and `eval` for it.
        let li = fr.local(wi);
        let pdf = self.density(lo, li);
        if !(pdf > 0.0) {
            return None;
        }
        let m = Self::half(lo, li)?;
        let weight = self.fresnel(lo.dot(m)).scale(self.weight(lo, li, m, pdf));
        if !weight.is_finite() || weight.is_black() {
            return None;
        }
        Some(BsdfSample {
            wi: wi.into(),
            weight,
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
        if lobes & LOBE != LOBE || self.r.is_black() || !self.admits(g, wo, wi) {
            return Some(0.0);
        }
        let fr = Frame::new(g, wo, self.two_sided);
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

    fn params(alpha: f32, reflectance: [f32; 3]) -> Params {
        Params {
            alpha,
            reflectance,
            distribution: "ggx".into(),
            masking: None,
            eta: None,
            k: None,
            two_sided: true,
            alpha_u: None,
            alpha_v: None,
        }
    }

    /// Mitsuba's `roughconductor` (one-sided, separable masking, the
    /// conductor Fresnel term): `eval` (f·cos of the light) from Mitsuba
    /// 3.9.1 `scalar_rgb`, eta (0.2, 0.789, 1.5), k (3.9, 6.15, 2.0),
    /// (distribution, α, [θ, φ of the viewer, θ, φ of the light]).
    #[test]
    fn mitsuba_mode_is_mitsubas() {
        #[rustfmt::skip]
        #[allow(clippy::excessive_precision)]
        const MITSUBA: &[(&str, f32, [f32; 4], [f32; 3])] = &[
        ("beckmann", 0.05, [0.0, 0.0, 3.0, 180.0], [2.3064392e+01, 2.2364565e+01, 1.0045971e+01]),
        ("beckmann", 0.05, [30.0, 0.0, 31.0, 180.0], [3.3930714e+01, 3.2890018e+01, 1.4818993e+01]),
        ("beckmann", 0.05, [60.0, 0.0, 55.0, 170.0], [1.6517188e-02, 1.5914980e-02, 7.5679985e-03]),
        ("beckmann", 0.05, [75.0, 0.0, 70.0, 180.0], [5.4248577e+01, 5.1248966e+01, 2.9050606e+01]),
        ("beckmann", 0.05, [20.0, 0.0, 40.0, 180.0], [1.3608570e-04, 1.3191484e-04, 5.9423513e-05]),
        ("beckmann", 0.3, [0.0, 0.0, 3.0, 180.0], [8.3646798e-01, 8.1108761e-01, 3.6433360e-01]),
        ("beckmann", 0.3, [30.0, 0.0, 31.0, 180.0], [9.7085196e-01, 9.4107479e-01, 4.2401254e-01]),
        ("beckmann", 0.3, [60.0, 0.0, 55.0, 170.0], [1.3872765e+00, 1.3366972e+00, 6.3563526e-01]),
        ("beckmann", 0.3, [75.0, 0.0, 70.0, 180.0], [3.0212851e+00, 2.8542268e+00, 1.6179256e+00]),
        ("beckmann", 0.3, [20.0, 0.0, 40.0, 180.0], [6.7386740e-01, 6.5321416e-01, 2.9425257e-01]),
        ("ggx", 0.2, [0.0, 0.0, 3.0, 180.0], [1.8330110e+00, 1.7773932e+00, 7.9838985e-01]),
        ("ggx", 0.2, [30.0, 0.0, 31.0, 180.0], [2.1629720e+00, 2.0966311e+00, 9.4466233e-01]),
        ("ggx", 0.2, [60.0, 0.0, 55.0, 170.0], [1.6284422e+00, 1.5690700e+00, 7.4613470e-01]),
        ("ggx", 0.2, [75.0, 0.0, 70.0, 180.0], [5.5036988e+00, 5.1993785e+00, 2.9472809e+00]),
        ("ggx", 0.2, [20.0, 0.0, 40.0, 180.0], [6.7247391e-01, 6.5186340e-01, 2.9364410e-01]),
        ];
        let g = geom(Vec3::Z);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let mut rng = RngState::seeded(9);
        for &(dist, alpha, [to, po, ti, pi], want) in MITSUBA {
            let m = RoughConductor::create(
                Params {
                    distribution: dist.into(),
                    masking: Some("separable".into()),
                    eta: Some([0.2, 0.789, 1.5]),
                    k: Some([3.9, 6.15, 2.0]),
                    two_sided: false,
                    ..params(alpha, [1.0; 3])
                },
                &env(),
            )
            .unwrap();
            let polar = |t: f32, p: f32| {
                let (t, p) = (t.to_radians(), p.to_radians());
                Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
            };
            let (wo, wi) = (polar(to, po), polar(ti, pi));
            let got = m.eval(&mut ctx, &g, wo, wi).scale(wi.z).to_array();
            for (x, y) in got.iter().zip(want) {
                assert!(
                    (x - y).abs() <= 2e-4 * y + 1e-9,
                    "{dist} {alpha} {to} {po} {ti} {pi}: {got:?} vs Mitsuba's {want:?}"
                );
            }
            // Samples agree with eval and pdf; nothing from behind.
            for _ in 0..200 {
                let u = [rng.next_f32(), rng.next_f32()];
                if let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) {
                    let p = m.pdf(&mut ctx, &g, wo, s.wi.v(), lobe::ALL).unwrap();
                    assert!((p - s.pdf).abs() <= 1e-4 * p);
                    let w = m.eval(&mut ctx, &g, wo, s.wi.v()).scale(s.wi.v().z / p);
                    assert!((w.g - s.weight.g).abs() <= 1e-3 * w.g.max(1e-3));
                }
            }
            let below = Vec3::new(wo.x, wo.y, -wo.z.max(0.1));
            assert!(m.eval(&mut ctx, &g, below, wi).is_black());
        }
    }

    /// Anisotropic GGX (α 0.25 along dp/du, 0.05 across) in Mitsuba's
    /// shading frame: `eval` and `pdf` from Mitsuba 3.9.1 `scalar_rgb`,
    /// the frame (x, y, z) with dp/du = x, eta and k as above.
    #[test]
    fn anisotropy_follows_dpdu_as_mitsubas() {
        #[rustfmt::skip]
        #[allow(clippy::excessive_precision)]
        const MITSUBA: &[([f32; 4], [f32; 3], f32)] = &[
            ([30.0, 0.0, 32.0, 180.0], [6.8540163e+00, 6.6436334e+00, 2.9940240e+00], 7.2467885e+00),
            ([30.0, 90.0, 32.0, 270.0], [5.5584855e+00, 5.3878684e+00, 2.4281001e+00], 5.8430171e+00),
            ([45.0, 20.0, 40.0, 210.0], [1.6782240e+00, 1.6249632e+00, 7.3937464e-01], 1.7803172e+00),
            ([60.0, 100.0, 55.0, 290.0], [9.4470090e-01, 9.1025758e-01, 4.3285182e-01], 1.0024798e+00),
            ([20.0, 0.0, 25.0, 170.0], [2.3482058e+00, 2.2767444e+00, 1.0235527e+00], 2.4751294e+00),
        ];
        let m = RoughConductor::create(
            Params {
                masking: Some("separable".into()),
                eta: Some([0.2, 0.789, 1.5]),
                k: Some([3.9, 6.15, 2.0]),
                two_sided: false,
                alpha_u: Some(0.25),
                alpha_v: Some(0.05),
                ..params(0.1, [1.0; 3])
            },
            &env(),
        )
        .unwrap();
        let g = LocalGeom {
            dpdu: Vec3::X.into(),
            dpdv: Vec3::Y.into(),
            filled: geom_mask::ALL,
            ..geom(Vec3::Z)
        };
        let mut ctx = TraceCtx::new(0, 1, 0);
        let polar = |t: f32, p: f32| {
            let (t, p) = (t.to_radians(), p.to_radians());
            Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
        };
        for &([to, po, ti, pi], want, want_pdf) in MITSUBA {
            let (wo, wi) = (polar(to, po), polar(ti, pi));
            let got = m.eval(&mut ctx, &g, wo, wi).scale(wi.z).to_array();
            for (x, y) in got.iter().zip(want) {
                assert!(
                    (x - y).abs() <= 2e-4 * y,
                    "{to} {po} {ti} {pi}: {got:?} vs {want:?}"
                );
            }
            let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
            assert!(
                (p - want_pdf).abs() <= 2e-4 * want_pdf,
                "pdf {p} vs {want_pdf}"
            );
        }
        // Samples agree with eval and pdf (the tilted frame included).
        let mut rng = RngState::seeded(21);
        let wo = polar(40.0, 30.0);
        let mut mean = 0.0f64;
        for _ in 0..100_000 {
            let u = [rng.next_f32(), rng.next_f32()];
            if let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) {
                let wi = s.wi.v();
                let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
                assert!((p - s.pdf).abs() <= 1e-3 * p, "pdf {p} vs {}", s.pdf);
                let w = m.eval(&mut ctx, &g, wo, wi).scale(wi.z / p);
                assert!(
                    (w.g - s.weight.g).abs() <= 1e-3 * w.g.max(1e-3),
                    "{w:?} {:?}",
                    s.weight
                );
                mean += s.weight.g as f64;
            }
        }
        assert!(mean / 100_000.0 < 1.0, "{}", mean / 100_000.0);
        let e = RoughConductor::create(
            Params {
                alpha_u: Some(0.2),
                ..params(0.1, [1.0; 3])
            },
            &env(),
        )
        .err()
        .unwrap();
        assert_eq!(e.key, "alpha_v");
    }

    fn metal(alpha: f32, r: [f32; 3]) -> RoughConductor {
        RoughConductor::create(params(alpha, r), &env()).unwrap()
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
            let e = RoughConductor::create(params(alpha, [1.0; 3]), &env())
                .err()
                .unwrap();
            assert_eq!(e.key, "alpha");
        }
        let e = RoughConductor::create(params(0.2, [1.0, -0.1, 1.0]), &env())
            .err()
            .unwrap();
        assert_eq!(e.key, "reflectance");
        let p: Params = parse_params("{}").unwrap();
        assert_eq!((p.alpha, p.reflectance), (0.1, [1.0; 3]));
    }

    /// Anisotropy follows dp/du: the lobe on a tilted surface, its frame
    /// from dp/du made perpendicular to the normal, is the flat one turned.
    #[test]
    fn anisotropy_turns_with_the_frame() {
        let m = RoughConductor::create(
            Params {
                masking: Some("separable".into()),
                two_sided: false,
                alpha_u: Some(0.25),
                alpha_v: Some(0.05),
                ..params(0.1, [1.0; 3])
            },
            &env(),
        )
        .unwrap();
        let flat = LocalGeom {
            dpdu: Vec3::X.into(),
            dpdv: Vec3::Y.into(),
            filled: geom_mask::ALL,
            ..geom(Vec3::Z)
        };
        let n = Vec3::new(-0.932725, 0.300005, 0.200054).normalize();
        let dpdu = Vec3::new(1.30692, 0.0, 5.82017);
        let s = (dpdu - n * n.dot(dpdu)).normalize();
        let t = n.cross(s);
        let g = LocalGeom {
            ns: n.into(),
            ng: n.into(),
            dpdu: dpdu.into(),
            dpdv: t.into(),
            filled: geom_mask::ALL,
            ..LocalGeom::EMPTY
        };
        let mut ctx = TraceCtx::new(0, 1, 0);
        let world = |v: Vec3| s * v.x + t * v.y + n * v.z;
        for (lo, li) in [
            (Vec3::new(0.3, 0.2, 0.9), Vec3::new(-0.2, -0.1, 0.95)),
            (Vec3::new(0.5, -0.3, 0.6), Vec3::new(-0.6, 0.2, 0.5)),
        ] {
            let (lo, li) = (lo.normalize(), li.normalize());
            let a = m.eval(&mut ctx, &flat, lo, li).r;
            let b = m.eval(&mut ctx, &g, world(lo), world(li)).r;
            assert!((a - b).abs() <= 1e-4 * a, "flat {a}, turned {b}");
            let (pa, pb) = (
                m.pdf(&mut ctx, &flat, lo, li, lobe::ALL).unwrap(),
                m.pdf(&mut ctx, &g, world(lo), world(li), lobe::ALL)
                    .unwrap(),
            );
            assert!((pa - pb).abs() <= 1e-4 * pa, "pdf flat {pa}, turned {pb}");
        }
    }
}
