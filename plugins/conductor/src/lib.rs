#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::{fresnel_conductor, reflect_at};
use rtk_kernel::serde::Deserialize;
use rtk_kernel::*;

#[derive(Deserialize)]
#[serde(crate = "rtk_kernel::serde", deny_unknown_fields)]
struct Params {
    #[serde(default = "white")]
    reflectance: [f32; 3],
    #[serde(default)]
    eta: Option<[f32; 3]>,
    #[serde(default)]
    k: Option<[f32; 3]>,
    #[serde(default = "yes")]
    two_sided: bool,
}

fn yes() -> bool {
    true
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

struct Conductor {
    reflectance: Color,
    /// The metal's complex index per channel (real, imaginary), when its
    /// Fresnel term is computed; `None`: the reflectance is constant.
    index: Option<([f32; 3], [f32; 3])>,
    /// Reflects on both faces; false: nothing from behind the shading
    /// normal (Mitsuba's `conductor`).
    two_sided: bool,
}

/// The one lobe.
const LOBE: u32 = lobe::SPECULAR | lobe::REFLECTION;

impl Plugin for Conductor {
    type Params = Params;

    fn create(p: Params, _env: &Env) -> Result<Self, PluginError> {
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
        Ok(Conductor {
            reflectance: params::reflectance("reflectance", p.reflectance)?,
            index,
            two_sided: p.two_sided,
        })
    }
}

impl Shader for Conductor {
    fn lobes(&self) -> u32 {
        LOBE
    }

    /// A delta lobe: no value for any pair of directions.
    fn eval(&self, _ctx: &mut TraceCtx, _g: &LocalGeom, _wo: Vec3, _wi: Vec3) -> Color {
        Color::BLACK
    }

    fn sample(
        &self,
        _ctx: &mut TraceCtx,
        g: &LocalGeom,
        wo: Vec3,
        _u: [f32; 2],
        lobes: u32,
    ) -> Option<BsdfSample> {
        if lobes & LOBE != LOBE || self.reflectance.is_black() {
            return None;
        }
        // Two-sided: mirror about the shading normal on wo's side.
        let ns = g.ns.v();
        if !self.two_sided && !(ns.dot(wo) > 0.0) {
            return None;
        }
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        let weight = match &self.index {
            None => self.reflectance,
            Some((eta, k)) => {
                let c = wo.dot(n).min(1.0);
                let f = [0, 1, 2].map(|i| fresnel_conductor(c, eta[i], k[i]));
                self.reflectance.times(Color::from_array(f))
            }
        };
        Some(BsdfSample {
            wi: reflect_at(g, wo, n).into(),
            weight,
            pdf: 1.0,
            lobe: LOBE,
            eta: 1.0,
        })
    }

    /// 0: only a delta lobe could return `wi`.
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
    Conductor,
    class = "conductor",
    doc = include_str!("../README.md")
);

#[cfg(test)]
mod tests {
    use super::*;

    fn geom(ng: Vec3, ns: Vec3) -> LocalGeom {
        LocalGeom {
            ng: ng.into(),
            ns: ns.into(),
            ..LocalGeom::EMPTY
        }
    }

    fn params(r: [f32; 3]) -> Params {
        Params {
            reflectance: r,
            eta: None,
            k: None,
            two_sided: true,
        }
    }

    /// With `eta` and `k`, the weight is Mitsuba's conductor Fresnel term
    /// (Mitsuba 3.9.1 `scalar_rgb`, eta (0.2, 0.789, 1.5), k (3.9, 6.15,
    /// 2.0), at θ degrees); one-sided, nothing from behind.
    #[test]
    fn complex_index_gives_mitsubas_fresnel() {
        #[allow(clippy::excessive_precision)]
        const MITSUBA: [(f32, [f32; 3]); 4] = [
            (0.0, [9.5195198e-01, 9.2306757e-01, 4.1463414e-01]),
            (30.0, [9.5158803e-01, 9.2242301e-01, 4.1552275e-01]),
            (60.0, [9.4588256e-01, 9.0964472e-01, 4.4014394e-01]),
            (85.0, [9.6660948e-01, 8.9881551e-01, 7.5428689e-01]),
        ];
        let m = Conductor::create(
            Params {
                eta: Some([0.2, 0.789, 1.5]),
                k: Some([3.9, 6.15, 2.0]),
                two_sided: false,
                ..params([1.0; 3])
            },
            &env(),
        )
        .unwrap();
        let g = geom(Vec3::Z, Vec3::Z);
        let mut ctx = TraceCtx::new(0, 1, 0);
        for (theta, want) in MITSUBA {
            let t = theta.to_radians();
            let wo = Vec3::new(t.sin(), 0.0, t.cos());
            let s = m.sample(&mut ctx, &g, wo, [0.5; 2], lobe::ALL).unwrap();
            for (x, y) in s.weight.to_array().iter().zip(want) {
                assert!(
                    (x - y).abs() < 1e-5,
                    "θ {theta}: {:?} vs {want:?}",
                    s.weight
                );
            }
            let below = Vec3::new(wo.x, 0.0, -wo.z.max(0.1));
            assert!(m.sample(&mut ctx, &g, below, [0.5; 2], lobe::ALL).is_none());
        }
        let e = Conductor::create(
            Params {
                eta: Some([0.2; 3]),
                ..params([1.0; 3])
            },
            &env(),
        )
        .err()
        .unwrap();
        assert_eq!(e.key, "k");
    }

    fn shader(r: [f32; 3]) -> Conductor {
        Conductor::create(params(r), &env()).unwrap()
    }

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

    /// The mirror direction, exactly, from either side; weight = reflectance.
    #[test]
    fn mirror_direction_is_exact() {
        let m = shader([0.9, 0.5, 0.25]);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let g = geom(Vec3::Z, Vec3::Z);
        for (wo, want) in [
            (Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.6, 0.0, 0.8)),
            (Vec3::new(0.0, -0.8, 0.6), Vec3::new(0.0, 0.8, 0.6)),
            (Vec3::Z, Vec3::Z),
            // From below: reflected below (two-sided).
            (Vec3::new(0.6, 0.0, -0.8), Vec3::new(-0.6, 0.0, -0.8)),
        ] {
            for u in [[0.0, 0.0], [0.5, 0.5], [0.99, 0.3]] {
                let s = m.sample(&mut ctx, &g, wo, u, lobe::ALL).unwrap();
                assert_eq!(s.wi.v(), want, "wo {wo}");
                assert_eq!(s.weight, Color::new(0.9, 0.5, 0.25));
                assert_eq!(s.pdf, 1.0);
                assert_eq!(s.lobe, lobe::SPECULAR | lobe::REFLECTION);
                assert_eq!(m.eval(&mut ctx, &g, wo, s.wi.v()), Color::BLACK);
                assert_eq!(m.pdf(&mut ctx, &g, wo, s.wi.v(), lobe::ALL), Some(0.0));
            }
        }
        // An arbitrary normal: angle in equals angle out, in the plane of
        // wo and n.
        let n = Vec3::new(1.0, 2.0, -0.5).normalize();
        let g = geom(n, n);
        let wo = Vec3::new(0.3, 0.9, 0.2).normalize();
        let wi = m
            .sample(&mut ctx, &g, wo, [0.5; 2], lobe::ALL)
            .unwrap()
            .wi
            .v();
        assert!((wi.dot(n) - wo.dot(n)).abs() < 1e-6);
        assert!(((wi + wo).normalize() - n).length() < 1e-6);
        assert!((wi.length() - 1.0).abs() < 1e-6);
    }

    /// Whitted's requests: only the reflection lobe answers; a black
    /// mirror answers none.
    #[test]
    fn lobe_filter() {
        let m = shader([1.0; 3]);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let g = geom(Vec3::Z, Vec3::Z);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = |l| m.sample(&mut TraceCtx::new(0, 1, 0), &g, wo, [0.5; 2], l);
        assert!(s(lobe::SPECULAR | lobe::REFLECTION).is_some());
        assert!(s(lobe::SPECULAR | lobe::TRANSMISSION).is_none());
        assert!(s(lobe::DIFFUSE | lobe::GLOSSY | lobe::REFLECTION).is_none());
        assert_eq!(m.lobes(), lobe::SPECULAR | lobe::REFLECTION);
        let black = shader([0.0; 3]);
        assert!(black
            .sample(&mut ctx, &g, wo, [0.5; 2], lobe::ALL)
            .is_none());
    }

    /// A shading normal tilted away from the geometric one cannot send the
    /// reflection through the surface.
    #[test]
    fn reflection_keeps_its_side() {
        let m = shader([1.0; 3]);
        let mut ctx = TraceCtx::new(0, 1, 0);
        let ns = Vec3::new(0.5, 0.0, 1.0).normalize();
        let g = geom(Vec3::Z, ns);
        let wo = Vec3::new(-0.99, 0.0, 0.1).normalize();
        let wi = m
            .sample(&mut ctx, &g, wo, [0.5; 2], lobe::ALL)
            .unwrap()
            .wi
            .v();
        assert!(wi.z > 0.0, "{wi}");
    }

    #[test]
    fn parameters_are_checked() {
        let e = Conductor::create(params([1.2, 0.0, 0.0]), &env())
            .err()
            .unwrap();
        assert_eq!(e.key, "reflectance");
        let p: Params = parse_params("{}").unwrap();
        assert_eq!(p.reflectance, [1.0; 3]);
        assert_eq!(
            parse_params::<Params>(r#"{"reflectivity": [1, 1, 1]}"#)
                .err()
                .unwrap()
                .key,
            "reflectivity"
        );
    }
}
