//! The shader against Mitsuba 3's values and against itself.

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

fn glass(distribution: &str, alpha: f32) -> RoughDielectric {
    RoughDielectric::create(
        Params {
            distribution: distribution.into(),
            alpha,
            eta: 1.5046 / 1.000277,
            reflectance: [1.0; 3],
            transmittance: [1.0; 3],
            scale_radiance: true,
        },
        &env(),
    )
    .unwrap()
}

fn geom() -> LocalGeom {
    LocalGeom {
        ng: Vec3::Z.into(),
        ns: Vec3::Z.into(),
        ..LocalGeom::EMPTY
    }
}

fn polar(theta: f32, phi: f32) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// (distribution, α, [θ, φ of the viewer, θ, φ of the light], Mitsuba's
/// `eval` (f·|cos θ| of the light) and `pdf`): Mitsuba 3.9.1 `scalar_rgb`,
/// `roughdielectric`, int_ior bk7, ext_ior air; reflections and
/// transmissions from both sides.
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const MITSUBA: &[(&str, f32, [f32; 4], f32, f32)] = &[
    ("ggx", 0.1, [30.0, 0.0, 31.0, 180.0], 3.8118654e-01, 3.8153028e-01),
    ("ggx", 0.1, [45.0, 0.0, 60.0, 170.0], 4.6283431e-02, 4.6627991e-02),
    ("ggx", 0.1, [20.0, 0.0, 150.0, 180.0], 2.8219193e-02, 6.3900970e-02),
    ("ggx", 0.1, [40.0, 0.0, 165.0, 185.0], 1.6258569e-01, 3.6792707e-01),
    ("ggx", 0.1, [160.0, 0.0, 140.0, 180.0], 2.9848067e-02, 2.9900512e-02),
    ("ggx", 0.1, [150.0, 0.0, 30.0, 180.0], 4.7260195e-01, 2.0905255e-01),
    ("ggx", 0.1, [10.0, 0.0, 175.0, 0.0], 8.2334258e-02, 1.8629034e-01),
    ("ggx", 0.4, [30.0, 0.0, 31.0, 180.0], 2.3557473e-02, 2.3892900e-02),
    ("ggx", 0.4, [45.0, 0.0, 60.0, 170.0], 2.8916439e-02, 3.2047402e-02),
    ("ggx", 0.4, [20.0, 0.0, 150.0, 180.0], 3.5596612e-01, 8.1599641e-01),
    ("ggx", 0.4, [40.0, 0.0, 165.0, 185.0], 6.3331026e-01, 1.4370104e+00),
    ("ggx", 0.4, [160.0, 0.0, 140.0, 180.0], 2.1425487e-02, 2.2012804e-02),
    ("ggx", 0.4, [150.0, 0.0, 30.0, 180.0], 3.5738244e+00, 1.6003309e+00),
    ("ggx", 0.4, [10.0, 0.0, 175.0, 0.0], 6.5757620e-01, 1.4882659e+00),
    ("beckmann", 0.02, [30.0, 0.0, 31.0, 180.0], 8.0118465e+00, 8.0118475e+00),
    ("beckmann", 0.02, [45.0, 0.0, 60.0, 170.0], 0.0000000e+00, 0.0000000e+00),
    ("beckmann", 0.02, [20.0, 0.0, 150.0, 180.0], 0.0000000e+00, 0.0000000e+00),
    ("beckmann", 0.02, [40.0, 0.0, 165.0, 185.0], 0.0000000e+00, 0.0000000e+00),
    ("beckmann", 0.02, [160.0, 0.0, 140.0, 180.0], 0.0000000e+00, 0.0000000e+00),
    ("beckmann", 0.02, [150.0, 0.0, 30.0, 180.0], 0.0000000e+00, 0.0000000e+00),
    ("beckmann", 0.02, [10.0, 0.0, 175.0, 0.0], 0.0000000e+00, 0.0000000e+00),
    ("beckmann", 0.3, [30.0, 0.0, 31.0, 180.0], 4.3039806e-02, 4.3039810e-02),
    ("beckmann", 0.3, [45.0, 0.0, 60.0, 170.0], 5.9780590e-02, 5.9780587e-02),
    ("beckmann", 0.3, [20.0, 0.0, 150.0, 180.0], 3.6004771e-05, 8.1463215e-05),
    ("beckmann", 0.3, [40.0, 0.0, 165.0, 185.0], 8.6000222e-01, 1.9458129e+00),
    ("beckmann", 0.3, [160.0, 0.0, 140.0, 180.0], 3.9723471e-02, 3.9723467e-02),
    ("beckmann", 0.3, [150.0, 0.0, 30.0, 180.0], 1.5272491e+00, 6.7500722e-01),
    ("beckmann", 0.3, [10.0, 0.0, 175.0, 0.0], 2.4000993e-01, 5.4303855e-01),
];

/// `eval` equals Mitsuba's; so does `pdf` for GGX (both sample visible
/// normals; rtk samples Beckmann by D cos θ, Mitsuba by visible normals).
#[test]
fn eval_and_pdf_are_mitsubas() {
    let g = geom();
    let mut ctx = TraceCtx::new(0, 1, 0);
    for &(dist, alpha, [to, po, ti, pi], want, want_pdf) in MITSUBA {
        let m = glass(dist, alpha);
        let (wo, wi) = (polar(to, po), polar(ti, pi));
        let got = m.eval(&mut ctx, &g, wo, wi).r * wi.z.abs();
        assert!(
            (got - want).abs() <= 1e-3 * want + 1e-7,
            "{dist} {alpha} {to} {po} {ti} {pi}: {got} vs Mitsuba's {want}"
        );
        if dist == "ggx" {
            let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
            assert!(
                (p - want_pdf).abs() <= 1e-3 * want_pdf,
                "pdf {p} vs {want_pdf}"
            );
        }
    }
}

/// Samples agree with `eval` and `pdf`; ∫ pdf over the sphere is the
/// probability that `sample` returns a direction; the mean weight (the
/// albedo with 1/η² on transmission undone) is at most 1.
#[test]
fn samples_agree_and_the_pdf_integrates() {
    let g = geom();
    let mut ctx = TraceCtx::new(0, 1, 0);
    // The lobe choice draws from the context's stream, as in a render.
    ctx.rng = RngState::seeded(17);
    let mut rng = RngState::seeded(4);
    for (dist, alpha) in [("ggx", 0.3f32), ("beckmann", 0.3), ("ggx", 0.8)] {
        let m = glass(dist, alpha);
        for theta in [20.0f32, 70.0, 160.0] {
            let wo = polar(theta, 40.0);
            let n = 200_000;
            let (mut got, mut energy) = (0u32, 0.0f64);
            for _ in 0..n {
                let u = [rng.next_f32(), rng.next_f32()];
                let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) else {
                    continue;
                };
                got += 1;
                let wi = s.wi.v();
                let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
                assert!((p - s.pdf).abs() <= 1e-4 * p, "pdf {p} vs {}", s.pdf);
                let w = m.eval(&mut ctx, &g, wo, wi).r * wi.z.abs() / p;
                assert!((w - s.weight.r).abs() <= 1e-3 * w.max(1e-3));
                let undo = if s.lobe == TRANSMIT {
                    s.eta * s.eta
                } else {
                    1.0
                };
                energy += (s.weight.r * undo) as f64;
            }
            let share = got as f64 / n as f64;
            let (mut integral, nu) = (0.0f64, 2_000_000);
            for _ in 0..nu {
                let wi = uniform_sphere([rng.next_f32(), rng.next_f32()]);
                integral += m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap() as f64;
            }
            let integral = integral * 4.0 * std::f64::consts::PI / nu as f64;
            assert!(
                (integral - share).abs() < 0.02,
                "{dist} {alpha} θ {theta}: ∫pdf {integral} vs P(sample) {share}"
            );
            assert!(energy / (n as f64) < 1.0 + 1e-3, "{}", energy / n as f64);
        }
    }
}

#[test]
fn parameters_are_checked() {
    let p = |eta: f32, alpha: f32, d: &str| Params {
        distribution: d.into(),
        alpha,
        eta,
        reflectance: [1.0; 3],
        transmittance: [1.0; 3],
        scale_radiance: false,
    };
    let key = |p: Params| RoughDielectric::create(p, &env()).err().unwrap().key;
    assert_eq!(key(p(1.0, 0.1, "ggx")), "eta");
    assert_eq!(key(p(-2.0, 0.1, "ggx")), "eta");
    assert_eq!(key(p(1.5, 0.0, "ggx")), "alpha");
    assert_eq!(key(p(1.5, 0.1, "phong")), "distribution");
    let d: Params = parse_params("{}").unwrap();
    assert_eq!((d.eta, d.alpha, d.distribution.as_str()), (1.5, 0.1, "ggx"));
}
