//! The thin-lens camera: a pinhole at aperture 0, depth of field otherwise.

use rtk_tests::*;

/// A lit Lambert scene seen by `camera` (the body of `[cameras.c]`).
fn lit_scene(camera: &str) -> String {
    format!(
        r#"
[render]
width = 64
height = 48
spp = 4
root = "world"
integrator = "distributed"
[cameras.c]
{camera}
eye = [0.5, 1.0, 6.0]
look_at = [0.0, 0.3, 0.0]
fov_y = 35.0
[lights.key]
class = "point"
position = [3.0, 5.0, 4.0]
intensity = [40.0, 40.0, 40.0]
[shaders.matte]
class = "lambert"
albedo = [0.6, 0.5, 0.4]
[objects.ball]
class = "sphere"
center = [0.0, 1.0, 0.0]
[objects.floor]
class = "disk"
radius = 20.0
[objects.world]
class = "list"
children = [{{ object = "ball", shader = "matte" }}, {{ object = "floor", shader = "matte" }}]
"#
    )
}

#[test]
fn zero_aperture_is_the_pinhole_bit_for_bit() {
    let (rp, pin) = render_scene(&lit_scene("class = \"pinhole\""), &[]);
    assert!(rp.ok, "{}", rp.stderr);
    // The focus distance does not matter without a lens.
    let (rt, thin) = render_scene(
        &lit_scene("class = \"thinlens\"\naperture_radius = 0.0\nfocus_distance = 2.5"),
        &[],
    );
    assert!(rt.ok, "{}", rt.stderr);
    let (pin, thin) = (pin.unwrap(), thin.unwrap());
    assert!(pin.data.iter().any(|&v| v > 0.05));
    assert_eq!(pin, thin);
    // The default aperture is 0 too.
    let (rd, default) = render_scene(&lit_scene("class = \"thinlens\""), &[]);
    assert!(rd.ok, "{}", rd.stderr);
    assert_eq!(pin, default.unwrap());
}

const W: u32 = 192;
const H: u32 = 64;
const FOV_Y: f64 = 30.0;
const EYE_Z: f64 = 10.0;
const APERTURE: f64 = 0.5;
/// The sphere in focus: centre x, z and radius.
const NEAR: (f64, f64, f64) = (-3.0, 0.0, 0.8);
/// The sphere far behind the plane of focus (z = 0).
const FAR: (f64, f64, f64) = (5.0, -10.0, 1.6);

/// White flat spheres on black, seen by `camera` through `integrator`, at
/// 256 samples per pixel: pixel values are the fraction of each pixel's
/// rays (film and lens samples) that hit a sphere.
fn coverage_scene(camera: &str) -> String {
    format!(
        r#"
[render]
width = {W}
height = {H}
spp = 256
root = "world"
integrator = "distributed"
[cameras.c]
{camera}
eye = [0.0, 0.0, {EYE_Z}]
look_at = [0.0, 0.0, 0.0]
fov_y = {FOV_Y}
[shaders.white]
class = "flat"
[objects.near]
class = "sphere"
center = [{}, 0.0, {}]
radius = {}
[objects.far]
class = "sphere"
center = [{}, 0.0, {}]
radius = {}
[objects.world]
class = "list"
children = [{{ object = "near", shader = "white" }}, {{ object = "far", shader = "white" }}]
"#,
        NEAR.0, NEAR.1, NEAR.2, FAR.0, FAR.1, FAR.2
    )
}

/// Image column of world x on the plane z = `z`.
fn column(x: f64, z: f64) -> f64 {
    let half_w = (FOV_Y.to_radians() * 0.5).tan() * W as f64 / H as f64;
    (x / (EYE_Z - z) / half_w + 1.0) * 0.5 * W as f64
}

/// The centre row's values over columns `x0..x1`.
fn row(img: &Image, x0: u32, x1: u32) -> Vec<f32> {
    (x0..x1).map(|x| img.px(x, H / 2)[0]).collect()
}

/// Pixels strictly between background and sphere (0.1 < v < 0.9): the
/// width of the silhouette's edges along the row.
fn partial(r: &[f32]) -> usize {
    r.iter().filter(|&&v| v > 0.1 && v < 0.9).count()
}

#[test]
fn a_wide_aperture_keeps_the_focus_plane_sharp_and_blurs_the_rest() {
    let (rp, pin) = render_scene(&coverage_scene("class = \"pinhole\""), &[]);
    assert!(rp.ok, "{}", rp.stderr);
    let (rt, thin) = render_scene(
        &coverage_scene(&format!(
            "class = \"thinlens\"\naperture_radius = {APERTURE}\nfocus_distance = {EYE_Z}"
        )),
        &[],
    );
    assert!(rt.ok, "{}", rt.stderr);
    let (pin, thin) = (pin.unwrap(), thin.unwrap());
    // Windows around each sphere's image, with room for the blur.
    let win = |(x, z, r): (f64, f64, f64)| {
        let (a, b) = (column(x - r, z), column(x + r, z));
        ((a - 12.0).floor() as u32, (b + 12.0).ceil() as u32)
    };
    let (n0, n1) = win(NEAR);
    let (f0, f1) = win(FAR);
    assert!(n1 < f0 && f1 <= W, "{n0}..{n1} {f0}..{f1}");

    // In focus: the silhouette's edges are as sharp as the pinhole's and
    // every pixel matches it within the noise of 256 samples.
    let (pn, tn) = (row(&pin, n0, n1), row(&thin, n0, n1));
    assert!(pn.contains(&1.0) && pn[0] == 0.0);
    for (i, (p, t)) in pn.iter().zip(&tn).enumerate() {
        assert!(
            (p - t).abs() < 0.15,
            "in focus, column {}: pinhole {p}, thin lens {t}",
            n0 + i as u32
        );
    }
    let (ep, et) = (partial(&pn), partial(&tn));
    assert!(
        ep <= 4 && et <= 4,
        "in-focus edges: pinhole {ep}, thin lens {et} pixels"
    );

    // Out of focus: the circle of confusion, 2·a·|d − f|/d on the plane of
    // focus, spreads each edge over about its diameter in pixels.
    let pixel = 2.0 * EYE_Z * (FOV_Y.to_radians() * 0.5).tan() / H as f64;
    let d = EYE_Z - FAR.1;
    let coc_px = 2.0 * APERTURE * (d - EYE_Z).abs() / d / pixel;
    assert!(coc_px > 5.0, "{coc_px}");
    let (pf, tf) = (row(&pin, f0, f1), row(&thin, f0, f1));
    let (ep, et) = (partial(&pf), partial(&tf));
    assert!(ep <= 4, "the pinhole's far edges span {ep} pixels");
    // Two edges, each spread over roughly 0.6 to 1.0 of the diameter
    // between the 10% and 90% levels.
    assert!(
        et as f64 >= 2.0 * 0.5 * coc_px && et as f64 <= 2.0 * (1.1 * coc_px + 1.0),
        "blurred edges span {et} pixels; circle of confusion {coc_px:.1} pixels\n{tf:?}"
    );
    // Blurring moves light, it does not make or lose it: the row's sum
    // stays within a few percent of the pinhole's.
    let (sp, st): (f32, f32) = (pf.iter().sum(), tf.iter().sum());
    assert!((st - sp).abs() < 0.05 * sp, "{st} vs {sp}");
    // And the blur is gradual: values rise monotonically (within noise)
    // across the left edge.
    let peak = tf
        .iter()
        .position(|&v| v > 0.99)
        .expect("a fully covered pixel");
    for w in tf[..=peak].windows(2) {
        assert!(w[1] >= w[0] - 0.06, "{tf:?}");
    }
}
