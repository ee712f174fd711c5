#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{fresnel_dielectric, reflect_at, refract_at};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "glass")]
    eta: f32,
    #[serde(default = "white")]
    reflectance: [f32; 3],
    #[serde(default = "white")]
    transmittance: [f32; 3],
    #[serde(default)]
    scale_radiance: bool,
}

fn glass() -> f32 {
    1.5
}
fn white() -> [f32; 3] {
    [1.0; 3]
}

struct Dielectric {
    eta: f32,
    kr: Color,
    kt: Color,
    /// Scale transmitted radiance by 1/η² (Mitsuba's and pbrt's convention).
    scale_radiance: bool,
}

const REFLECT: u32 = lobe::SPECULAR | lobe::REFLECTION;
const TRANSMIT: u32 = lobe::SPECULAR | lobe::TRANSMISSION;

impl Plugin for Dielectric {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
        if !(p.eta.is_finite() && p.eta > 0.0) {
            return Err(PluginError::key(
                "eta",
                format!("must be a positive finite number, got {}", p.eta),
            ));
        }
        Ok(Dielectric {
            eta: p.eta,
            kr: params::reflectance("reflectance", p.reflectance)?,
            kt: params::reflectance("transmittance", p.transmittance)?,
            scale_radiance: p.scale_radiance,
        })
    }
}

/// The interface as seen from `wo`.
struct Interface {
    /// Shading normal turned towards `wo`.
    n: Vec3,
    /// Fresnel reflectance (1 on total internal reflection).
    f: f32,
    /// Refracted direction; `None` on total internal reflection.
    t: Option<Vec3>,
    /// Relative index of refraction across the interface (η_t/η_i).
    eta: f32,
}

impl Dielectric {
    fn interface(&self, g: &LocalGeom, wo: Vec3) -> Interface {
        // Entering when wo is on the side the geometric normal faces.
        let eta = if g.ng.v().dot(wo) > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let ns = g.ns.v();
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        let t = refract_at(g, wo, n, eta);
        // The two tests of the critical angle round differently: trust
        // the one that found no refracted ray.
        let f = if t.is_some() {
            fresnel_dielectric(wo.dot(n), eta)
        } else {
            1.0
        };
        Interface { n, f, t, eta }
    }
}

impl Dielectric {
    /// The radiance factor of a crossing with relative index `eta`: 1, or
    /// 1/η² with `scale_radiance` (the solid angle compressed).
    #[inline]
    fn crossing(&self, eta: f32) -> f32 {
        if self.scale_radiance {
            1.0 / (eta * eta)
        } else {
            1.0
        }
    }
}

fn delta(wi: Vec3, weight: Color, lobe: u32, eta: f32) -> Option<BsdfSample> {
    (!weight.is_black()).then(|| BsdfSample {
        wi: wi.into(),
        weight,
        pdf: 1.0,
        lobe,
        eta,
    })
}

impl Shader for Dielectric {
    fn lobes(&self) -> u32 {
        lobe::SPECULAR | lobe::REFLECTION | lobe::TRANSMISSION
    }

    /// Delta lobes only: no value for any pair of directions.
    fn eval(&self, _ctx: &mut TraceCtx, _g: &LocalGeom, _wo: Vec3, _wi: Vec3) -> Color {
        Color::BLACK
    }

    /// Both lobes allowed: one chosen by Fresnel with `u[0]`, weight its
    /// tint. One lobe allowed: that lobe, weight its Fresnel share × tint.
    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        let want_r = lobes & REFLECT == REFLECT;
        let want_t = lobes & TRANSMIT == TRANSMIT;
        if !(want_r || want_t) {
            return None;
        }
        let s = self.interface(g, wo);
        let reflected = || reflect_at(g, wo, s.n);
        match (want_r, want_t) {
            (true, true) => {
                if u[0] < s.f {
                    delta(reflected(), self.kr, REFLECT, 1.0)
                } else {
                    delta(s.t?, self.kt.scale(self.crossing(s.eta)), TRANSMIT, s.eta)
                }
            }
            (true, false) => delta(reflected(), self.kr.scale(s.f), REFLECT, 1.0),
            _ => delta(
                s.t?,
                self.kt.scale((1.0 - s.f) * self.crossing(s.eta)),
                TRANSMIT,
                s.eta,
            ),
        }
    }

    /// 0: only delta lobes could return `wi`.
    fn pdf(
        &self,
        _ctx: &mut TraceCtx,
        _g: &LocalGeom,
        _wo: Vec3,
        _wi: Vec3,
        _lobes: u32,
    ) -> Option<f32> {
        Some(0.0)
    }
}

rtk_kernel::export_shader!(
    Dielectric,
    class = "dielectric",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests {
    use super::*;

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

    fn glass(eta: f32) -> Dielectric {
        Dielectric::create(
            Params {
                eta,
                reflectance: [1.0; 3],
                transmittance: [1.0; 3],
                scale_radiance: false,
            },
            &env(),
        )
        .unwrap()
    }

    fn flat() -> LocalGeom {
        LocalGeom {
            ng: Vec3::Z.into(),
            ns: Vec3::Z.into(),
            ..LocalGeom::EMPTY
        }
    }

    fn dir(theta_deg: f32, below: bool) -> Vec3 {
        let t = theta_deg.to_radians();
        Vec3::new(t.sin(), 0.0, if below { -t.cos() } else { t.cos() })
    }

    /// Fraction of `n` stratified choices that reflect, and the sample of
    /// each lobe.
    fn split(m: &Dielectric, wo: Vec3, n: u32) -> (f64, Option<BsdfSample>, Option<BsdfSample>) {
        let mut ctx = TraceCtx::new(0, 1, 0);
        let g = flat();
        let (mut refl, mut r, mut t) = (0u32, None, None);
        for i in 0..n {
            let u = [(i as f32 + 0.5) / n as f32, 0.5];
            let s = m.sample(&mut ctx, &g, wo, u, lobe::ALL).unwrap();
            assert_eq!(s.pdf, 1.0);
            assert_eq!(s.weight, Color::splat(1.0), "white glass: the tint alone");
            if s.lobe == REFLECT {
                refl += 1;
                r = Some(s);
            } else {
                assert_eq!(s.lobe, TRANSMIT);
                t = Some(s);
            }
        }
        (refl as f64 / n as f64, r, t)
    }

    /// Reflection and transmission are chosen with probabilities F and
    /// 1 − F, which sum to 1, and the lobes asked for alone (as Whitted
    /// asks) carry F and 1 − F in their weights, summing to 1; at normal
    /// incidence F = ((eta − 1) / (eta + 1))².
    #[test]
    fn energy_is_conserved() {
        let mut ctx = TraceCtx::new(0, 1, 0);
        let g = flat();
        for eta in [1.33f32, 1.5, 2.4] {
            let m = glass(eta);
            let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
            for (theta, below) in [(0.0, false), (30.0, false), (75.0, false), (20.0, true)] {
                let wo = dir(theta, below);
                let s = m.interface(&g, wo);
                if theta == 0.0 {
                    assert!((s.f - f0).abs() < 1e-6, "eta {eta}: F {} vs {f0}", s.f);
                }
                let n = 100_000;
                let (p_r, _, _) = split(&m, wo, n);
                // Stratified u: the fraction is F to within 1/n.
                assert!(
                    (p_r - s.f as f64).abs() <= 1.0 / n as f64 + 1e-6,
                    "eta {eta}, θ {theta}: {p_r} vs F {}",
                    s.f
                );
                let r = m.sample(&mut ctx, &g, wo, [0.5; 2], REFLECT).unwrap();
                let t = m.sample(&mut ctx, &g, wo, [0.5; 2], TRANSMIT).unwrap();
                assert_eq!(r.lobe, REFLECT);
                assert_eq!(t.lobe, TRANSMIT);
                for (a, b) in r.weight.to_array().iter().zip(t.weight.to_array()) {
                    assert!((a + b - 1.0).abs() < 1e-6, "{a} + {b}");
                }
                assert!((r.weight.r - s.f).abs() < 1e-7);
            }
        }
        // Tints scale their lobes.
        let tinted = Dielectric::create(
            Params {
                eta: 1.5,
                reflectance: [0.5, 0.5, 0.5],
                transmittance: [0.25, 0.5, 1.0],
                scale_radiance: false,
            },
            &env(),
        )
        .unwrap();
        let wo = dir(0.0, false);
        let t = tinted.sample(&mut ctx, &g, wo, [0.5; 2], TRANSMIT).unwrap();
        assert!((t.weight.r - 0.25 * 0.96).abs() < 1e-6);
        assert!((t.weight.b - 0.96).abs() < 1e-6);
        let r = tinted
            .sample(&mut ctx, &g, wo, [0.01, 0.5], lobe::ALL)
            .unwrap();
        assert_eq!((r.lobe, r.weight), (REFLECT, Color::splat(0.5)));
    }

    /// Directions: mirror on wo's side, Snell's law across; leaving the
    /// glass beyond the critical angle everything reflects.
    #[test]
    fn directions_and_total_internal_reflection() {
        let mut ctx = TraceCtx::new(0, 1, 0);
        let g = flat();
        let m = glass(1.5);
        // Entering at 40°.
        let wo = dir(40.0, false);
        let r = m
            .sample(&mut ctx, &g, wo, [0.5; 2], REFLECT)
            .unwrap()
            .wi
            .v();
        assert!((r - Vec3::new(-wo.x, 0.0, wo.z)).length() < 1e-6);
        let t = m
            .sample(&mut ctx, &g, wo, [0.5; 2], TRANSMIT)
            .unwrap()
            .wi
            .v();
        assert!(t.z < 0.0 && t.x < 0.0);
        assert!((wo.x - 1.5 * -t.x).abs() < 1e-6, "Snell: {wo} {t}");
        // Leaving at 30° (below the critical angle, 41.8°).
        let wo = dir(30.0, true);
        let t = m
            .sample(&mut ctx, &g, wo, [0.5; 2], TRANSMIT)
            .unwrap()
            .wi
            .v();
        assert!(t.z > 0.0);
        assert!((1.5 * wo.x - -t.x).abs() < 1e-6, "Snell: {wo} {t}");
        // Leaving at 45°: total internal reflection.
        let wo = dir(45.0, true);
        assert_eq!(m.interface(&g, wo).f, 1.0);
        assert!(m.sample(&mut ctx, &g, wo, [0.5; 2], TRANSMIT).is_none());
        let r = m.sample(&mut ctx, &g, wo, [0.5; 2], REFLECT).unwrap();
        assert_eq!(r.weight, Color::splat(1.0));
        assert!((r.wi.v() - Vec3::new(-wo.x, 0.0, wo.z)).length() < 1e-6);
        let (p_r, _, t) = split(&m, wo, 1000);
        assert_eq!(p_r, 1.0);
        assert!(t.is_none());
        // eta = 1: nothing reflects, the ray goes straight on.
        let m = glass(1.0);
        let wo = dir(60.0, false);
        let (p_r, _, t) = split(&m, wo, 1000);
        assert_eq!(p_r, 0.0);
        assert!((t.unwrap().wi.v() + wo).length() < 1e-6);
        // Delta lobes: no density, no value.
        assert_eq!(m.eval(&mut ctx, &g, wo, -wo), Color::BLACK);
        assert_eq!(m.pdf(&mut ctx, &g, wo, -wo, lobe::ALL), Some(0.0));
        assert!(m
            .sample(&mut ctx, &g, wo, [0.5; 2], lobe::DIFFUSE | lobe::REFLECTION)
            .is_none());
    }

    #[test]
    fn parameters_are_checked() {
        for eta in [0.0, -1.5, f32::NAN, f32::INFINITY] {
            let e = Dielectric::create(
                Params {
                    eta,
                    reflectance: [1.0; 3],
                    transmittance: [1.0; 3],
                    scale_radiance: false,
                },
                &env(),
            )
            .err()
            .unwrap();
            assert_eq!(e.key, "eta");
        }
        let e = Dielectric::create(
            Params {
                eta: 1.5,
                reflectance: [1.0; 3],
                transmittance: [1.0, 1.1, 1.0],
                scale_radiance: false,
            },
            &env(),
        )
        .err()
        .unwrap();
        assert_eq!(e.key, "transmittance");
        let p: Params = parse_params("{}").unwrap();
        assert_eq!(
            (p.eta, p.reflectance, p.transmittance),
            (1.5, [1.0; 3], [1.0; 3])
        );
    }

    /// `scale_radiance`: entering, the transmitted weight is (1 − F)/η²;
    /// leaving, (1 − F)·η² — their product over a slab is the unscaled one.
    #[test]
    fn scale_radiance_divides_by_eta_squared() {
        let g = LocalGeom {
            ng: Vec3::Z.into(),
            ns: Vec3::Z.into(),
            ..LocalGeom::EMPTY
        };
        let mut ctx = TraceCtx::new(0, 1, 0);
        let p = |scale| Params {
            eta: 1.5,
            reflectance: [1.0; 3],
            transmittance: [1.0; 3],
            scale_radiance: scale,
        };
        let scaled = Dielectric::create(p(true), &env()).unwrap();
        let plain = Dielectric::create(p(false), &env()).unwrap();
        for wo in [
            Vec3::new(0.3, 0.0, 0.954).normalize(),
            Vec3::new(0.2, 0.0, -0.98).normalize(),
        ] {
            let a = scaled
                .sample(&mut ctx, &g, wo, [0.5, 0.5], TRANSMIT)
                .unwrap();
            let b = plain
                .sample(&mut ctx, &g, wo, [0.5, 0.5], TRANSMIT)
                .unwrap();
            let eta = if wo.z > 0.0 { 1.5f32 } else { 1.0 / 1.5 };
            assert!(
                (a.weight.r - b.weight.r / (eta * eta)).abs() < 1e-6,
                "{a:?} {b:?}"
            );
            assert_eq!(a.wi, b.wi);
        }
    }
}
