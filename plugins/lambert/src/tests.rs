//! The bumped lambert against Mitsuba 3's `bumpmap` around a `diffuse`,
//! the opacity map against Mitsuba's `mask`, and both against themselves.

use super::*;

/// The 4 × 3 height field of the Mitsuba run below, an 8-bit grey PNG.
const HEIGHTS: [u8; 12] = [0, 40, 90, 200, 30, 60, 120, 150, 10, 100, 180, 250];

fn bumped(dir: &std::path::Path, two_sided: bool) -> Lambert {
    let png = dir.join("h.png");
    image::GrayImage::from_raw(4, 3, HEIGHTS.to_vec())
        .unwrap()
        .save(&png)
        .unwrap();
    let json = format!(
        r#"{{"albedo": [0.5, 0.5, 0.5], "two_sided": {two_sided}, "bump_scale": 0.3,
            "bump_map": {{"image_file": "h.png", "raw": true, "v_origin": "top"}}}}"#
    );
    Lambert::create(parse_params(&json).unwrap(), &env(dir.to_str().unwrap())).unwrap()
}

fn env(dir: &str) -> Env<'_> {
    Env {
        scene_dir: dir,
        name: "shaders.test",
        image_width: 1,
        image_height: 1,
        origin: [0.0; 3],
        arrays: Default::default(),
    }
}

/// A flat hit at `uv` with dp/du = x, dp/dv = y, both normals z.
fn hit(uv: [f32; 2]) -> LocalGeom {
    LocalGeom {
        ng: Vec3::Z.into(),
        ns: Vec3::Z.into(),
        dpdu: Vec3::X.into(),
        dpdv: Vec3::Y.into(),
        uv,
        filled: geom_mask::ALL,
        ..LocalGeom::EMPTY
    }
}

fn polar(theta: f32, phi: f32) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// (uv, [θ, φ of the viewer, θ, φ of the light], Mitsuba's `eval` (f·cos
/// θ of the light, the red channel) and `pdf`): Mitsuba 3.9.1,
/// `scalar_rgb`, `bumpmap` (scale 0.3, the PNG above as a raw `bitmap`)
/// around `diffuse` (0.5), `si` flat as [`hit`] builds it.
#[rustfmt::skip]
#[allow(clippy::excessive_precision)]
const MITSUBA: &[([f32; 2], [f32; 4], f32, f32)] = &[
    ([0.3, 0.4], [20.0, 0.0, 40.0, 180.0], 1.3564698e-01, 2.7147713e-01),
    ([0.3, 0.4], [50.0, 90.0, 30.0, 0.0], 1.2355167e-01, 2.4718234e-01),
    ([0.3, 0.4], [70.0, 200.0, 60.0, 20.0], 5.4645147e-02, 1.0960400e-01),
    ([0.3, 0.4], [10.0, 45.0, 80.0, 270.0], 3.8598016e-02, 7.9509184e-02),
    ([0.6, 0.7], [20.0, 0.0, 40.0, 180.0], 1.4509138e-01, 2.9117987e-01),
    ([0.6, 0.7], [50.0, 90.0, 30.0, 0.0], 1.0291849e-01, 2.0617244e-01),
    ([0.6, 0.7], [70.0, 200.0, 60.0, 20.0], 2.3869019e-02, 4.8429359e-02),
    ([0.6, 0.7], [10.0, 45.0, 80.0, 270.0], 4.8780032e-02, 1.1105869e-01),
    ([0.8, 0.2], [20.0, 0.0, 40.0, 180.0], 1.5285912e-01, 3.0731633e-01),
    ([0.8, 0.2], [50.0, 90.0, 30.0, 0.0], 8.9295879e-02, 1.7903495e-01),
    ([0.8, 0.2], [70.0, 200.0, 60.0, 20.0], 1.9108187e-02, 3.9053675e-02),
    ([0.8, 0.2], [10.0, 45.0, 80.0, 270.0], 9.9232094e-03, 2.3816276e-02),
];

#[test]
fn eval_and_pdf_are_mitsubas() {
    let dir = tempfile::tempdir().unwrap();
    let m = bumped(dir.path(), false);
    let mut ctx = TraceCtx::new(0, 1, 0);
    for &(uv, [to, po, ti, pi], want, want_pdf) in MITSUBA {
        let (g, wo, wi) = (hit(uv), polar(to, po), polar(ti, pi));
        let got = m.eval(&mut ctx, &g, wo, wi).r * wi.z;
        let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
        assert!(
            (got - want).abs() <= 1e-4 * want && (p - want_pdf).abs() <= 1e-4 * want_pdf,
            "uv {uv:?}, {to} {po} → {ti} {pi}: {got}, pdf {p} vs Mitsuba's {want}, {want_pdf}"
        );
    }
}

/// Samples agree with `eval` and `pdf` for the direction they return,
/// and the mean weight is ∫ f cos over uniform directions.
#[test]
fn samples_agree_with_eval_and_pdf() {
    let dir = tempfile::tempdir().unwrap();
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut rng = RngState::seeded(5);
    for two_sided in [false, true] {
        let m = bumped(dir.path(), two_sided);
        for (uv, wo) in [
            ([0.3, 0.4], polar(30.0, 20.0)),
            ([0.8, 0.2], polar(75.0, 200.0)),
        ] {
            let g = hit(uv);
            let n = 200_000;
            let (mut sampled, mut uniform) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let u = [rng.next_f32(), rng.next_f32()];
                if let Some(s) = m.sample(&mut ctx, &g, wo, u, lobe::ALL) {
                    let wi = s.wi.v();
                    let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
                    assert!((p - s.pdf).abs() <= 1e-5 * s.pdf);
                    let w = m.eval(&mut ctx, &g, wo, wi).r * wi.z / s.pdf;
                    assert!((w - s.weight.r).abs() <= 1e-4, "{w} vs {}", s.weight.r);
                    sampled += s.weight.r as f64;
                }
                let d = rtk_kernel::sdk::shading::uniform_sphere([rng.next_f32(), rng.next_f32()]);
                let wi = Vec3::new(d.x, d.y, d.z.abs());
                uniform += (m.eval(&mut ctx, &g, wo, wi).r * wi.z) as f64 * std::f64::consts::TAU;
            }
            let (a, b) = (sampled / n as f64, uniform / n as f64);
            assert!(
                (a - b).abs() < 0.01,
                "uv {uv:?}: sampled {a}, integrated {b}"
            );
            assert!(a > 0.2 && a <= 0.5, "{a}");
        }
    }
    // Two-sided, the back mirrors the front: the bump seen from below is
    // a dent, and the lobe stays on the viewer's side.
    let m = bumped(dir.path(), true);
    let flip = Vec3::new(1.0, 1.0, -1.0);
    let (wo, wi) = (polar(30.0, 20.0), polar(40.0, 160.0));
    assert!(!m
        .eval(&mut ctx, &hit([0.3, 0.4]), wo * flip, wi * flip)
        .is_black());
    assert!(m.eval(&mut ctx, &hit([0.3, 0.4]), wo * flip, wi).is_black());
}

/// Without tangents (an integrator that does not ask for them) or with
/// a flat height field, the surface is plain lambert.
#[test]
fn flat_or_tangentless_is_plain_lambert() {
    let dir = tempfile::tempdir().unwrap();
    let m = bumped(dir.path(), false);
    let mut ctx = TraceCtx::new(0, 1, 0);
    let g = LocalGeom {
        filled: geom_mask::ALL & !geom_mask::TANGENTS,
        ..hit([0.3, 0.4])
    };
    let (wo, wi) = (polar(30.0, 0.0), polar(50.0, 120.0));
    let f = m.eval(&mut ctx, &g, wo, wi).r;
    assert!((f - 0.5 * std::f32::consts::FRAC_1_PI).abs() < 1e-7, "{f}");
    let e = Lambert::create(
        parse_params(r#"{"bump_map": [0.5, 0.5, 0.5], "bump_scale": 1e40}"#).unwrap(),
        &env("."),
    )
    .err()
    .unwrap();
    assert_eq!(e.key, "bump_scale");
    let flat = Lambert::create(
        parse_params(r#"{"bump_map": [0.5, 0.5, 0.5], "two_sided": false}"#).unwrap(),
        &env("."),
    )
    .unwrap();
    let g = hit([0.3, 0.4]);
    // Flat: no tilt, and the shadowing term is 1 (α = 0).
    let f = flat.eval(&mut ctx, &g, wo, wi).r;
    assert!((f - 0.5 * std::f32::consts::FRAC_1_PI).abs() < 1e-6, "{f}");
}

/// An opacity map (a constant 0.3 here, its luminance): `eval` and `pdf`
/// are 0.3 of the diffuse lobe's, `sample` passes straight through with
/// probability 0.7 (weight 1, SPECULAR | TRANSMISSION), and its diffuse
/// samples agree with `eval` and `pdf` — Mitsuba's `mask`.
#[test]
fn opacity_passes_light_through_as_mitsubas_mask() {
    let mk = |json: &str| Lambert::create(parse_params(json).unwrap(), &env(".")).unwrap();
    let masked =
        mk(r#"{"albedo": [0.5, 0.5, 0.5], "two_sided": false, "opacity": [0.3, 0.3, 0.3]}"#);
    let plain = mk(r#"{"albedo": [0.5, 0.5, 0.5], "two_sided": false}"#);
    let g = hit([0.3, 0.4]);
    let mut ctx = TraceCtx::new(0, 1, 0);
    let (wo, wi) = (polar(30.0, 0.0), polar(50.0, 120.0));
    let f = masked.eval(&mut ctx, &g, wo, wi).r;
    assert!((f - 0.3 * plain.eval(&mut ctx, &g, wo, wi).r).abs() < 1e-7);
    let p = masked.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
    assert!((p - 0.3 * plain.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap()).abs() < 1e-7);
    assert_eq!(masked.lobes() & NULL, NULL);
    assert_eq!(plain.lobes() & NULL, 0);
    let mut rng = RngState::seeded(11);
    let (mut through, n) = (0, 100_000);
    for _ in 0..n {
        let u = [rng.next_f32(), rng.next_f32()];
        let s = masked.sample(&mut ctx, &g, wo, u, lobe::ALL).unwrap();
        if s.lobe == NULL {
            through += 1;
            assert_eq!(s.wi.v(), -wo);
            assert!((s.pdf - 0.7).abs() < 1e-6 && s.weight.r == 1.0);
        } else {
            let p = masked.pdf(&mut ctx, &g, wo, s.wi.v(), lobe::ALL).unwrap();
            assert!((p - s.pdf).abs() <= 1e-5 * p);
            assert!((s.weight.r - 0.5).abs() < 1e-5, "{:?}", s.weight);
        }
    }
    let share = through as f64 / n as f64;
    assert!((share - 0.7).abs() < 0.005, "{share}");
    // Asked for one lobe: only that one.
    let s = masked.sample(&mut ctx, &g, wo, [0.1, 0.5], NULL).unwrap();
    assert_eq!((s.lobe, s.pdf), (NULL, 1.0));
    let s = masked
        .sample(&mut ctx, &g, wo, [0.9, 0.5], DIFFUSE)
        .unwrap();
    assert_eq!(s.lobe, DIFFUSE);
    // One-sided from behind: no reflection, but still passes through.
    let behind = polar(150.0, 0.0);
    assert!(masked
        .sample(&mut ctx, &g, behind, [0.1, 0.5], lobe::ALL)
        .is_none());
    let s = masked
        .sample(&mut ctx, &g, behind, [0.9, 0.5], lobe::ALL)
        .unwrap();
    assert_eq!(s.lobe, NULL);
}

/// A normal map (the constant texel (0.7, 0.4, 0.9)) against Mitsuba
/// 3.9.1's `normalmap` with a `rawconstant` of that value around
/// `diffuse` (0.5), the hit flat as [`hit`] builds it: `eval` (f·cos of the
/// light) and `pdf`.
#[test]
fn normal_map_is_mitsubas() {
    #[rustfmt::skip]
    #[allow(clippy::excessive_precision)]
    const MITSUBA: &[([f32; 4], f32, f32)] = &[
        ([20.0, 0.0, 40.0, 180.0], 6.1352674e-02, 1.2354334e-01),
        ([50.0, 90.0, 30.0, 0.0], 1.5453884e-01, 3.1008053e-01),
        ([70.0, 200.0, 60.0, 20.0], 2.2577738e-02, 4.6441756e-02),
        ([10.0, 45.0, 80.0, 270.0], 4.6621412e-02, 1.1665268e-01),
        ([60.0, 180.0, 50.0, 10.0], 1.3522878e-01, 2.7415812e-01),
    ];
    let m = Lambert::create(
        parse_params(
            r#"{"albedo": [0.5, 0.5, 0.5], "two_sided": false, "normal_map": [0.7, 0.4, 0.9]}"#,
        )
        .unwrap(),
        &env("."),
    )
    .unwrap();
    let g = hit([0.3, 0.4]);
    let mut ctx = TraceCtx::new(0, 1, 0);
    for &([to, po, ti, pi], want, want_pdf) in MITSUBA {
        let (wo, wi) = (polar(to, po), polar(ti, pi));
        let got = m.eval(&mut ctx, &g, wo, wi).r * wi.z;
        let p = m.pdf(&mut ctx, &g, wo, wi, lobe::ALL).unwrap();
        assert!(
            (got - want).abs() <= 1e-4 * want && (p - want_pdf).abs() <= 1e-4 * want_pdf,
            "{to} {po} → {ti} {pi}: {got}, pdf {p} vs Mitsuba's {want}, {want_pdf}"
        );
    }
}
