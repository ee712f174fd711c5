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

fn plastic(alpha: f32, nonlinear: bool, rho: [f32; 3]) -> RoughPlastic {
    plastic_of("ggx", alpha, nonlinear, rho)
}

fn plastic_of(distribution: &str, alpha: f32, nonlinear: bool, rho: [f32; 3]) -> RoughPlastic {
    RoughPlastic::create(
        Params {
            distribution: distribution.into(),
            alpha,
            int_ior: 1.5046,
            ext_ior: 1.000277,
            diffuse_reflectance: TextureParam::constant(rho),
            specular_reflectance: [1.0; 3],
            nonlinear,
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

/// A unit vector at polar angle `theta`, azimuth `phi` (degrees) about +z.
fn polar(theta: f32, phi: f32) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// (alpha, nonlinear, [θ, φ of the viewer, θ, φ of the light], Mitsuba's
/// `eval` (f·cos θ of the light), Mitsuba's `pdf`): Mitsuba 3.9.1,
/// `scalar_rgb`, `roughplastic` with GGX, int_ior bk7, ext_ior air,
/// diffuse_reflectance (0.02, 0.2, 0.9), `si.wi` the viewer.
type MitsubaValue = (f32, bool, [f32; 4], [f32; 3], f32);

// As Mitsuba printed them (8 digits: more than an f32 holds).
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const MITSUBA: &[MitsubaValue] = &[
    (0.01, false, [0.0, 0.0, 30.0, 180.0], [5.5326410e-03, 5.4679938e-02, 2.4580830e-01], 2.4781875e-01),
    (0.01, false, [30.0, 0.0, 30.0, 180.0], [3.8660126e+01, 3.8709194e+01, 3.8900013e+01], 9.7011108e+01),
    (0.01, false, [60.0, 0.0, 20.0, 90.0], [5.6350641e-03, 5.6281012e-02, 2.5323746e-01], 2.3650450e-01),
    (0.01, false, [75.0, 0.0, 70.0, 180.0], [1.5943619e+00, 1.6074189e+00, 1.6581960e+00], 3.7075841e+00),
    (0.01, false, [10.0, 0.0, 45.0, 30.0], [4.4254549e-03, 4.4184845e-02, 1.9880468e-01], 2.0220628e-01),
    (0.01, true, [0.0, 0.0, 30.0, 180.0], [2.3381165e-03, 2.5462894e-02, 2.1490739e-01], 2.4781875e-01),
    (0.01, true, [30.0, 0.0, 30.0, 180.0], [3.8656937e+01, 3.8680023e+01, 3.8869164e+01], 9.7011108e+01),
    (0.01, true, [60.0, 0.0, 20.0, 90.0], [2.3431291e-03, 2.6173051e-02, 2.2139429e-01], 2.3650450e-01),
    (0.01, true, [75.0, 0.0, 70.0, 180.0], [1.5935133e+00, 1.5996568e+00, 1.6499865e+00], 3.7075841e+00),
    (0.01, true, [10.0, 0.0, 45.0, 30.0], [1.8411352e-03, 2.0548716e-02, 1.7380632e-01], 2.0220628e-01),
    (0.1, false, [0.0, 0.0, 30.0, 180.0], [1.0560022e-02, 5.5695858e-02, 2.3122410e-01], 2.6138538e-01),
    (0.1, false, [30.0, 0.0, 30.0, 180.0], [3.9091089e-01, 4.3591645e-01, 6.1093807e-01], 1.2478157e+00),
    (0.1, false, [60.0, 0.0, 20.0, 90.0], [5.8832304e-03, 5.2238092e-02, 2.3250699e-01], 2.3773423e-01),
    (0.1, false, [75.0, 0.0, 70.0, 180.0], [4.2996478e+00, 4.3121376e+00, 4.3607082e+00], 9.3958254e+00),
    (0.1, false, [10.0, 0.0, 45.0, 30.0], [4.7658128e-03, 4.1206397e-02, 1.8291977e-01], 2.0370938e-01),
    (0.1, true, [0.0, 0.0, 30.0, 180.0], [7.8046387e-03, 3.0678332e-02, 2.0625144e-01], 2.6138538e-01),
    (0.1, true, [30.0, 0.0, 30.0, 180.0], [3.8816345e-01, 4.1097113e-01, 5.8603752e-01], 1.2478157e+00),
    (0.1, true, [60.0, 0.0, 20.0, 90.0], [3.0534307e-03, 2.6544893e-02, 2.0685987e-01], 2.3773423e-01),
    (0.1, true, [75.0, 0.0, 70.0, 180.0], [4.2988853e+00, 4.3052149e+00, 4.3537984e+00], 9.3958254e+00),
    (0.1, true, [10.0, 0.0, 45.0, 30.0], [2.5412440e-03, 2.1008404e-02, 1.6275801e-01], 2.0370938e-01),
    (0.4, false, [0.0, 0.0, 30.0, 180.0], [1.4236826e-02, 4.4148427e-02, 1.6047131e-01], 2.7521461e-01),
    (0.4, false, [30.0, 0.0, 30.0, 180.0], [2.6819784e-02, 5.6373645e-02, 1.7130531e-01], 3.2100868e-01),
    (0.4, false, [60.0, 0.0, 20.0, 90.0], [9.1413958e-03, 3.9066367e-02, 1.5544125e-01], 2.5207368e-01),
    (0.4, false, [75.0, 0.0, 70.0, 180.0], [2.2621040e-01, 2.3459806e-01, 2.6721674e-01], 6.5124440e-01),
    (0.4, false, [10.0, 0.0, 45.0, 30.0], [7.2107357e-03, 3.1029399e-02, 1.2365752e-01], 2.1069184e-01),
    (0.4, true, [0.0, 0.0, 30.0, 180.0], [1.3087248e-02, 3.4127478e-02, 1.5281442e-01], 2.7521461e-01),
    (0.4, true, [30.0, 0.0, 30.0, 180.0], [2.5683954e-02, 4.6472546e-02, 1.6374001e-01], 3.2100868e-01),
    (0.4, true, [60.0, 0.0, 20.0, 90.0], [7.9913046e-03, 2.9040938e-02, 1.4778094e-01], 2.5207368e-01),
    (0.4, true, [75.0, 0.0, 70.0, 180.0], [2.2588804e-01, 2.3178804e-01, 2.6506963e-01], 6.5124440e-01),
    (0.4, true, [10.0, 0.0, 45.0, 30.0], [6.2953248e-03, 2.3049699e-02, 1.1756034e-01], 2.1069184e-01),
    (1.0, false, [0.0, 0.0, 30.0, 180.0], [5.0286120e-03, 2.3284474e-02, 9.4279490e-02], 2.2319053e-01),
    (1.0, false, [30.0, 0.0, 30.0, 180.0], [5.2525634e-03, 2.2552103e-02, 8.9828081e-02], 2.0942156e-01),
    (1.0, false, [60.0, 0.0, 20.0, 90.0], [6.0334024e-03, 2.1191120e-02, 8.0137797e-02], 1.8535393e-01),
    (1.0, false, [75.0, 0.0, 70.0, 180.0], [1.3689995e-02, 1.6346391e-02, 2.6676821e-02], 1.2178141e-01),
    (1.0, false, [10.0, 0.0, 45.0, 30.0], [4.2134547e-03, 1.7788885e-02, 7.0582218e-02], 1.8545057e-01),
    (1.0, true, [0.0, 0.0, 30.0, 180.0], [4.7924472e-03, 2.1314470e-02, 9.3068443e-02], 2.2319053e-01),
    (1.0, true, [30.0, 0.0, 30.0, 180.0], [5.0287698e-03, 2.0685297e-02, 8.8680476e-02], 2.0942156e-01),
    (1.0, true, [60.0, 0.0, 20.0, 90.0], [5.8373166e-03, 1.9555440e-02, 7.9132281e-02], 1.8535393e-01),
    (1.0, true, [75.0, 0.0, 70.0, 180.0], [1.3655631e-02, 1.6059738e-02, 2.6500601e-02], 1.2178141e-01),
    (1.0, true, [10.0, 0.0, 45.0, 30.0], [4.0378380e-03, 1.6323950e-02, 6.9681659e-02], 1.8545057e-01),
];

/// Every value Mitsuba gives, to 2e-4 relative: the same lobes, tables
/// and sampling probabilities.
#[test]
fn eval_and_pdf_are_mitsubas() {
    let g = geom(Vec3::Z);
    let mut ctx = TraceCtx::new(0, 1, 0);
    for &(alpha, nonlinear, [to, po, ti, pi], want, want_pdf) in MITSUBA {
        let m = plastic(alpha, nonlinear, [0.02, 0.2, 0.9]);
        let (wo, wi) = (polar(to, po), polar(ti, pi));
        let got = m.eval(&mut ctx, &g, wo, wi).scale(wi.z).to_array();
        for (c, (x, y)) in got.iter().zip(want).enumerate() {
            assert!(
                (x - y).abs() <= 2e-4 * y.abs() + 1e-7,
                "α {alpha}, nonlinear {nonlinear}, {to} {po} {ti} {pi}, channel {c}: {x} vs Mitsuba's {y}"
            );
        }
        let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
        assert!(
            (p - want_pdf).abs() <= 2e-4 * want_pdf,
            "α {alpha}, {to} {po} {ti} {pi}: pdf {p} vs Mitsuba's {want_pdf}"
        );
    }
}

/// The same with Beckmann's distribution (Mitsuba 3.9.1, as above but
/// `distribution` beckmann). Only `eval`: Mitsuba samples Beckmann's
/// visible normals, rtk its D cos θ, so the densities differ (not the
/// image's mean). To 1e-3 up to α = 0.1; at α = 0.5 to 3e-3, because
/// there Mitsuba's own transmittance table is 0.2 % off: rtk's quadrature
/// gives 0.0512051 at (60°, 0°) → (20°, 90°) with 32² nodes and 0.0512055
/// with 128², where Mitsuba prints 0.0510914.
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const MITSUBA_BECKMANN: &[MitsubaValue] = &[
    (0.05, false, [0.0, 0.0, 30.0, 180.0], [5.4413211e-03, 5.4413214e-02, 2.4485944e-01], 2.4763899e-01),
    (0.05, false, [30.0, 0.0, 30.0, 180.0], [1.5516447e+00, 1.6005349e+00, 1.7906636e+00], 4.1210766e+00),
    (0.05, false, [60.0, 0.0, 20.0, 90.0], [5.6051062e-03, 5.6051068e-02, 2.5222978e-01], 2.3624019e-01),
    (0.05, false, [75.0, 0.0, 70.0, 180.0], [1.1971938e+01, 1.1984957e+01, 1.2035583e+01], 2.7435194e+01),
    (0.05, false, [10.0, 0.0, 45.0, 30.0], [4.4014440e-03, 4.4014443e-02, 1.9806498e-01], 2.0218590e-01),
    (0.05, true, [0.0, 0.0, 30.0, 180.0], [2.2661136e-03, 2.5381532e-02, 2.1422966e-01], 2.4763899e-01),
    (0.05, true, [30.0, 0.0, 30.0, 180.0], [1.5484748e+00, 1.5715517e+00, 1.7600849e+00], 4.1210766e+00),
    (0.05, true, [60.0, 0.0, 20.0, 90.0], [2.3343244e-03, 2.6145523e-02, 2.2067803e-01], 2.3624019e-01),
    (0.05, true, [75.0, 0.0, 70.0, 180.0], [1.1971094e+01, 1.1977239e+01, 1.2027441e+01], 2.7435194e+01),
    (0.05, true, [10.0, 0.0, 45.0, 30.0], [1.8330426e-03, 2.0530934e-02, 1.7328878e-01], 2.0218590e-01),
    (0.1, false, [0.0, 0.0, 30.0, 180.0], [5.6582666e-03, 5.4036550e-02, 2.4217431e-01], 2.4834561e-01),
    (0.1, false, [30.0, 0.0, 30.0, 180.0], [3.9191848e-01, 4.4020671e-01, 6.2799430e-01], 1.2191397e+00),
    (0.1, false, [60.0, 0.0, 20.0, 90.0], [5.5301073e-03, 5.5301078e-02, 2.4885483e-01], 2.3547401e-01),
    (0.1, false, [75.0, 0.0, 70.0, 180.0], [5.3031683e+00, 5.3161092e+00, 5.3664360e+00], 1.2027128e+01),
    (0.1, false, [10.0, 0.0, 45.0, 30.0], [4.3461965e-03, 4.3461967e-02, 1.9557884e-01], 2.0217545e-01),
    (0.1, true, [0.0, 0.0, 30.0, 180.0], [2.5483374e-03, 2.5630848e-02, 2.1245365e-01], 2.4834561e-01),
    (0.1, true, [30.0, 0.0, 30.0, 180.0], [3.8881433e-01, 4.1185388e-01, 5.9832895e-01], 1.2191397e+00),
    (0.1, true, [60.0, 0.0, 20.0, 90.0], [2.3306515e-03, 2.6077649e-02, 2.1827860e-01], 2.3547401e-01),
    (0.1, true, [75.0, 0.0, 70.0, 180.0], [5.3023362e+00, 5.3085108e+00, 5.3584857e+00], 1.2027128e+01),
    (0.1, true, [10.0, 0.0, 45.0, 30.0], [1.8316949e-03, 2.0494824e-02, 1.7154850e-01], 2.0217545e-01),
    (0.5, false, [0.0, 0.0, 30.0, 180.0], [1.5137472e-02, 5.1073030e-02, 1.9082242e-01], 2.7552938e-01),
    (0.5, false, [30.0, 0.0, 30.0, 180.0], [1.9422838e-02, 5.5069238e-02, 1.9369413e-01], 2.8695440e-01),
    (0.5, false, [60.0, 0.0, 20.0, 90.0], [1.4162906e-02, 5.1091395e-02, 1.9470218e-01], 2.8536212e-01),
    (0.5, false, [75.0, 0.0, 70.0, 180.0], [2.0235707e-01, 2.1398747e-01, 2.5921682e-01], 4.0185249e-01),
    (0.5, false, [10.0, 0.0, 45.0, 30.0], [1.0594977e-02, 3.9396949e-02, 1.5140462e-01], 2.2045007e-01),
    (0.5, true, [0.0, 0.0, 30.0, 180.0], [1.3382940e-02, 3.5492845e-02, 1.7751509e-01], 2.7552938e-01),
    (0.5, true, [30.0, 0.0, 30.0, 180.0], [1.7682424e-02, 3.9614420e-02, 1.8049388e-01], 2.8695440e-01),
    (0.5, true, [60.0, 0.0, 20.0, 90.0], [1.2359896e-02, 3.5080716e-02, 1.8102714e-01], 2.8536212e-01),
    (0.5, true, [75.0, 0.0, 70.0, 180.0], [2.0178922e-01, 2.0894501e-01, 2.5490993e-01], 4.0185249e-01),
    (0.5, true, [10.0, 0.0, 45.0, 30.0], [9.1887377e-03, 2.6909595e-02, 1.4073893e-01], 2.2045007e-01),
];

#[test]
fn beckmann_eval_is_mitsubas() {
    let g = geom(Vec3::Z);
    let mut ctx = TraceCtx::new(0, 1, 0);
    for &(alpha, nonlinear, [to, po, ti, pi], want, _) in MITSUBA_BECKMANN {
        let m = plastic_of("beckmann", alpha, nonlinear, [0.02, 0.2, 0.9]);
        let (wo, wi) = (polar(to, po), polar(ti, pi));
        let got = m.eval(&mut ctx, &g, wo, wi).scale(wi.z).to_array();
        let tol = if alpha <= 0.1 { 1e-3 } else { 3e-3 };
        for (c, (x, y)) in got.iter().zip(want).enumerate() {
            assert!(
                (x - y).abs() <= tol * y.abs() + 1e-7,
                "α {alpha}, nonlinear {nonlinear}, {to} {po} {ti} {pi}, channel {c}: {x} vs Mitsuba's {y}"
            );
        }
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

/// `sample` agrees with `pdf` and `eval` for the direction it returns, and
/// its mean weight (the albedo it sees) is ∫ f cos dωi estimated with
/// uniform directions, within 5 combined standard errors.
#[test]
fn samples_agree_with_eval_and_pdf() {
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    let g = geom(n);
    let (t, _) = n.any_orthonormal_pair();
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut rng = RngState::seeded(7);
    for (dist, alpha, nonlinear) in [
        ("ggx", 0.1f32, false),
        ("ggx", 0.4, true),
        ("ggx", 1.0, false),
        ("beckmann", 0.1, false),
        ("beckmann", 0.5, true),
    ] {
        let m = plastic_of(dist, alpha, nonlinear, [0.3, 0.6, 0.9]);
        for theta in [0.0f32, 50.0, 80.0] {
            let th = theta.to_radians();
            let wo = (n * th.cos() + t * th.sin()).normalize();
            let (a, se_a) = mean_se(200_000, || {
                let u = [rng.next_f32(), rng.next_f32()];
                let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) else {
                    return 0.0;
                };
                let wi = s.wi.v();
                let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
                assert!((p - s.pdf).abs() <= 1e-4 * s.pdf, "pdf {p} vs {}", s.pdf);
                let w = m.eval(&mut ctx, &g, wo, wi).scale(wi.dot(n) / s.pdf);
                assert!((w.g - s.weight.g).abs() <= 1e-3 * s.weight.g.max(1e-3));
                s.weight.g as f64
            });
            let (b, se_b) = mean_se(2_000_000, || {
                let d = uniform_sphere([rng.next_f32(), rng.next_f32()]);
                let wi = if d.dot(n) < 0.0 { -d } else { d };
                let f = m.eval(&mut ctx, &g, wo, wi).g as f64;
                f * wi.dot(n) as f64 * std::f64::consts::TAU
            });
            let tol = 5.0 * (se_a * se_a + se_b * se_b).sqrt();
            assert!(
                (a - b).abs() <= tol && tol < 0.03,
                "α {alpha}, θ {theta}: sampled {a} ± {se_a}, integrated {b} ± {se_b}"
            );
            assert!(a > 0.05 && a < 1.0, "α {alpha}, θ {theta}: albedo {a}");
        }
    }
}

/// One-sided, as Mitsuba's: nothing from behind, nothing through.
#[test]
fn black_from_behind() {
    let g = geom(Vec3::Z);
    let mut ctx = TraceCtx::new(0, 1, 0);
    let m = plastic(0.3, false, [0.5; 3]);
    let (up, down) = (polar(30.0, 0.0), polar(150.0, 0.0));
    assert!(!m.eval(&mut ctx, &g, up, polar(20.0, 90.0)).is_black());
    assert!(m.eval(&mut ctx, &g, down, polar(160.0, 0.0)).is_black());
    assert!(m.eval(&mut ctx, &g, up, down).is_black());
    assert_eq!(m.pdf(&mut ctx, &g, up, down, lobe::ALL), Some(0.0));
    assert!(m
        .sample(&mut ctx, &g, down, [0.3, 0.6], lobe::ALL)
        .is_none());
    // One lobe asked for: only its samples.
    let s = m.sample(&mut ctx, &g, up, [0.99, 0.6], DIFFUSE).unwrap();
    assert_eq!(s.lobe, DIFFUSE);
    let s = m.sample(&mut ctx, &g, up, [0.3, 0.6], GLOSSY).unwrap();
    assert_eq!(s.lobe, GLOSSY);
    assert!(m
        .sample(&mut ctx, &g, up, [0.5, 0.5], lobe::SPECULAR)
        .is_none());
}

#[test]
fn parameters_are_checked() {
    let base = || Params {
        distribution: "ggx".into(),
        alpha: 0.2,
        int_ior: 1.5,
        ext_ior: 1.0,
        diffuse_reflectance: TextureParam::constant([0.5; 3]),
        specular_reflectance: [1.0; 3],
        nonlinear: false,
    };
    let key = |p: Params| RoughPlastic::create(p, &env()).err().unwrap().key;
    for alpha in [0.0, 1.5, f32::NAN] {
        assert_eq!(key(Params { alpha, ..base() }), "alpha");
    }
    assert_eq!(
        key(Params {
            int_ior: -1.0,
            ..base()
        }),
        "int_ior"
    );
    assert_eq!(
        key(Params {
            ext_ior: 0.0,
            ..base()
        }),
        "ext_ior"
    );
    assert_eq!(
        key(Params {
            int_ior: 1.0,
            ..base()
        }),
        "int_ior"
    );
    assert_eq!(
        key(Params {
            specular_reflectance: [1.0, 2.0, 1.0],
            ..base()
        }),
        "specular_reflectance"
    );
    let p: Params = parse_params("{}").unwrap();
    assert_eq!(
        (p.alpha, p.int_ior, p.ext_ior, p.nonlinear),
        (0.1, 1.49, 1.000277, false)
    );
}
