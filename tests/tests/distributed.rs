//! Distributed ray tracing: soft shadows from an area light against the
//! visible fraction of the light in closed form, and Whitted's image where
//! there is nothing to distribute.

use rtk_tests::*;

const W: u32 = 96;
const H: u32 = 64;
const FOV_Y: f64 = 30.0;
const EYE: [f64; 3] = [1.2, 5.0, 4.0];
const LOOK_AT: [f64; 3] = [1.2, 0.0, 0.0];
/// The spherical light: centre and radius.
const LIGHT: ([f64; 3], f64) = ([-2.0, 4.0, 0.0], 0.3);
/// The blocker: centre and radius.
const BLOCKER: ([f64; 3], f64) = ([0.0, 1.5, 0.0], 0.4);
const LIGHT_SAMPLES: u32 = 256;

/// A Lambert floor (the plane y = 0), a Lambert blocker sphere (if
/// `blocker`), and `light`: the lights table and any extra instance.
fn shadow_scene(integrator: &str, light: &str, light_instance: &str, blocker: bool) -> String {
    let blocker_inst = if blocker {
        r#", { object = "blocker", shader = "matte" }"#
    } else {
        ""
    };
    format!(
        r#"
[render]
width = {W}
height = {H}
root = "world"
integrator = {integrator}
[cameras.c]
class = "pinhole"
eye = {EYE:?}
look_at = {LOOK_AT:?}
up = [0.0, 0.0, -1.0]
fov_y = {FOV_Y}
{light}
[shaders.matte]
class = "lambert"
albedo = [0.5, 0.5, 0.5]
[shaders.lamp]
class = "lambert"
albedo = [0.0, 0.0, 0.0]
emission = [10.0, 10.0, 10.0]
[objects.floor]
class = "disk"
radius = 50.0
[objects.blocker]
class = "sphere"
center = {:?}
radius = {}
[objects.lamp]
class = "sphere"
center = {:?}
radius = {}
[objects.world]
class = "list"
children = [{{ object = "floor", shader = "matte" }}{blocker_inst}{light_instance}]
"#,
        BLOCKER.0, BLOCKER.1, LIGHT.0, LIGHT.1
    )
}

type V = [f64; 3];
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: V) -> V {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// The centre ray of pixel (x, y), as the pinhole makes it (f64).
fn pixel_ray(x: u32, y: u32) -> V {
    let f = unit(sub(LOOK_AT, EYE));
    let r = unit(cross(f, [0.0, 0.0, -1.0]));
    let u = cross(r, f);
    let t = (FOV_Y.to_radians() * 0.5).tan();
    let sx = (2.0 * (x as f64 + 0.5) / W as f64 - 1.0) * t * W as f64 / H as f64;
    let sy = (1.0 - 2.0 * (y as f64 + 0.5) / H as f64) * t;
    unit([
        f[0] + r[0] * sx + u[0] * sy,
        f[1] + r[1] * sx + u[1] * sy,
        f[2] + r[2] * sx + u[2] * sy,
    ])
}

/// Does the ray from `o` along unit `d` pass within `r` of `c`?
fn passes_near(o: V, d: V, c: V, r: f64) -> bool {
    let oc = sub(c, o);
    let t = dot(oc, d);
    t > 0.0 && dot(oc, oc) - t * t < r * r
}

/// Area of the overlap of two discs of radii `a` and `b`, centres `d` apart.
fn lens_area(a: f64, b: f64, d: f64) -> f64 {
    use std::f64::consts::PI;
    if d >= a + b {
        return 0.0;
    }
    if d <= (a - b).abs() {
        return PI * a.min(b).powi(2);
    }
    let ca = ((d * d + a * a - b * b) / (2.0 * d * a)).clamp(-1.0, 1.0);
    let cb = ((d * d + b * b - a * a) / (2.0 * d * b)).clamp(-1.0, 1.0);
    a * a * ca.acos() + b * b * cb.acos()
        - 0.5
            * ((-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b))
                .max(0.0)
                .sqrt()
}

/// What a floor point sees: the light's and the blocker's angular radii,
/// the angle between their centres, and the fraction of the light's solid
/// angle the blocker leaves visible (small angles: discs in the plane).
fn view_from(p: V) -> (f64, f64, f64, f64) {
    let (tl, tb) = (sub(LIGHT.0, p), sub(BLOCKER.0, p));
    let (dl, db) = (dot(tl, tl).sqrt(), dot(tb, tb).sqrt());
    let al = (LIGHT.1 / dl).asin();
    let ab = (BLOCKER.1 / db).asin();
    let theta = (dot(tl, tb) / (dl * db)).clamp(-1.0, 1.0).acos();
    let visible = 1.0 - lens_area(al, ab, theta) / (std::f64::consts::PI * al * al);
    (al, ab, theta, visible)
}

/// An area light behind a blocker casts an umbra (exactly black: every
/// shadow ray blocked, no interreflection), a penumbra (strictly between)
/// and lit floor. With and without the blocker, the same seed draws the
/// same light samples, so their ratio is the fraction of the light's
/// samples the blocker leaves visible: exactly 0 in the umbra, exactly 1
/// outside the shadow, and in the penumbra the visible fraction of the
/// light's disc within sampling noise.
#[test]
fn an_area_light_casts_a_penumbra() {
    let integ = format!("{{ class = \"distributed\", light_samples = {LIGHT_SAMPLES} }}");
    let lamp = r#", { object = "lamp", shader = "lamp" }"#;
    let (ra, a) = render_scene(&shadow_scene(&integ, "", lamp, true), &[]);
    assert!(ra.ok, "{}", ra.stderr);
    let (ru, u) = render_scene(&shadow_scene(&integ, "", lamp, false), &[]);
    assert!(ru.ok, "{}", ru.stderr);
    let (a, u) = (a.unwrap(), u.unwrap());
    let margin = 0.01; // radians, beyond the small-angle model's error
    let (mut umbra, mut lit, mut pen) = (0, 0, 0);
    let (mut err_sum, mut abs_sum) = (0.0f64, 0.0f64);
    for y in 0..H {
        for x in 0..W {
            let d = pixel_ray(x, y);
            if d[1] >= 0.0
                || passes_near(EYE, d, BLOCKER.0, BLOCKER.1 + 0.05)
                || passes_near(EYE, d, LIGHT.0, LIGHT.1 + 0.05)
            {
                continue;
            }
            let t = -EYE[1] / d[1];
            let p = [EYE[0] + t * d[0], 0.0, EYE[2] + t * d[2]];
            let (al, ab, theta, visible) = view_from(p);
            let (va, vu) = (a.px(x, y), u.px(x, y));
            assert!(
                vu[0] > 0.0,
                "pixel ({x},{y}) at {p:?} is unlit without the blocker"
            );
            if theta + al < ab - margin {
                umbra += 1;
                assert_eq!(va, [0.0; 3], "umbra pixel ({x},{y}) at {p:?}");
            } else if theta > ab + al + margin {
                lit += 1;
                assert_eq!(va, vu, "lit pixel ({x},{y}) at {p:?}");
            } else if (0.2..=0.8).contains(&visible) {
                pen += 1;
                let r = (va[0] / vu[0]) as f64;
                assert!(
                    r > 0.0 && r < 1.0,
                    "penumbra pixel ({x},{y}) at {p:?}: {r} of the light, {visible:.3} expected"
                );
                err_sum += r - visible;
                abs_sum += (r - visible).abs();
            }
        }
    }
    assert!(umbra > 40 && lit > 1000 && pen > 40, "{umbra} {lit} {pen}");
    // 256 samples jittered over the light, half of them on its far side:
    // a hard shadow would be off by about 0.25 on average here.
    let (bias, mad) = (err_sum / pen as f64, abs_sum / pen as f64);
    assert!(
        bias.abs() < 0.015 && mad < 0.04,
        "penumbra against the visible fraction: mean error {bias:.4}, mean |error| {mad:.4}"
    );
}

/// Mean of channel 0 over pixels (x, y) with x0 ≤ x < x1, y0 ≤ y < y1.
fn mean(img: &Image, (x0, y0, x1, y1): (u32, u32, u32, u32)) -> f64 {
    let mut s = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            s += img.px(x, y)[0] as f64;
        }
    }
    s / ((x1 - x0) * (y1 - y0)) as f64
}

/// With a point light there is nothing to distribute over the light: the
/// image is Whitted's (hard shadow included), whatever `light_samples` says.
#[test]
fn with_a_point_light_it_renders_whitted_s_image() {
    let point = format!(
        "[lights.bulb]\nclass = \"point\"\nposition = {:?}\nintensity = [20.0, 20.0, 20.0]",
        LIGHT.0
    );
    let (rw, w) = render_scene(
        &shadow_scene("\"whitted\"", &point, "", true),
        &["--spp", "4"],
    );
    assert!(rw.ok, "{}", rw.stderr);
    let integ = "{ class = \"distributed\", light_samples = 16 }";
    let (rd, d) = render_scene(&shadow_scene(integ, &point, "", true), &["--spp", "4"]);
    assert!(rd.ok, "{}", rd.stderr);
    let (w, d) = (w.unwrap(), d.unwrap());
    let whole = mean(&w, (0, 0, W, H));
    assert!(whole > 0.01, "{whole}");
    // The whole image, the shadow's quarter, and a lit band.
    for region in [(0, 0, W, H), (W / 2, H / 4, W, 3 * H / 4), (0, 0, W, H / 4)] {
        let (mw, md) = (mean(&w, region), mean(&d, region));
        assert!(
            (mw - md).abs() <= 1e-4 * mw.max(1e-3),
            "region {region:?}: whitted {mw}, distributed {md}"
        );
    }
}

/// Where nothing is distributed — delta lights, mirror, glass, Phong
/// highlights — the default scene renders as Whitted renders it.
#[test]
fn the_default_scene_matches_whitted() {
    let scene = root().join("scenes/default.toml");
    let dir = tempfile::tempdir().unwrap();
    let args = |integ: &'static str| {
        [
            "--set",
            "render.width=96",
            "--set",
            "render.height=72",
            "--set",
            integ,
        ]
    };
    let (rw, w) = render_file(
        &scene,
        dir.path(),
        &args("render.integrator={ class = \"whitted\", max_depth = 32 }"),
    );
    assert!(rw.ok, "{}", rw.stderr);
    let (rd, d) = render_file(
        &scene,
        dir.path(),
        &args("render.integrator={ class = \"distributed\", max_depth = 32, light_samples = 4 }"),
    );
    assert!(rd.ok, "{}", rd.stderr);
    let (w, d) = (w.unwrap(), d.unwrap());
    let worst = w
        .data
        .iter()
        .zip(&d.data)
        .map(|(a, b)| (a - b).abs() / a.abs().max(1e-3))
        .fold(0.0f32, f32::max);
    assert!(worst <= 1e-5, "largest relative difference {worst}");
}

#[test]
fn bad_parameters_are_refused() {
    for (param, needle) in [
        ("max_depth = 2000", "max_depth"),
        ("light_samples = 0", "light_samples"),
        ("glossy_samples = 100000", "glossy_samples"),
        ("shadows = 2", "unknown field"),
    ] {
        let scene = shadow_scene(
            &format!("{{ class = \"distributed\", {param} }}"),
            "",
            "",
            false,
        );
        let (r, _) = render_scene(&scene, &[]);
        assert!(!r.ok && r.stderr.contains(needle), "{param}: {}", r.stderr);
    }
}

/// A rough-conductor floor (GGX roughness `alpha`, reflectance 0.8) under
/// `above`, seen from above and in front; black background. (The glossy
/// lobe comes from the `roughconductor` shader: a `GLOSSY | REFLECTION`
/// lobe sampled on its own, which `phong` does not offer.)
fn glossy_floor(alpha: f64, integrator: &str, spp: u32, above: &str) -> String {
    format!(
        r#"
[render]
width = 64
height = 48
spp = {spp}
root = "world"
integrator = {integrator}
[cameras.c]
class = "pinhole"
eye = [0.0, 1.0, 6.0]
look_at = [0.0, 0.2, 0.0]
fov_y = 40.0
[shaders.metal]
class = "roughconductor"
alpha = {alpha}
reflectance = [0.8, 0.8, 0.8]
[shaders.paint]
class = "flat"
color = [1.0, 0.5, 0.25]
[shaders.lamp]
class = "lambert"
albedo = [0.0, 0.0, 0.0]
emission = [5.0, 5.0, 5.0]
[objects.floor]
class = "disk"
radius = 50.0
[objects.ball]
class = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.8
[objects.world]
class = "list"
children = [{{ object = "floor", shader = "metal" }}, {above}]
"#
    )
}

/// Glossy lobes are followed: a near-mirror rough conductor shows the
/// flat-shaded ball's reflection at reflectance × colour (no light in the
/// scene: Whitted, which follows delta lobes only, sees a black floor); a
/// rougher one blurs it.
#[test]
fn glossy_reflections_are_traced() {
    let ball = r#"{ object = "ball", shader = "paint" }"#;
    let want = [0.8f32, 0.4, 0.2]; // reflectance 0.8 × the flat colour
    let render = |alpha: f64, integrator: &str| {
        let (r, img) = render_scene(&glossy_floor(alpha, integrator, 64, ball), &["--stats"]);
        assert!(r.ok, "{}", r.stderr);
        (r.stats(), img.unwrap())
    };
    let full = |img: &Image| {
        let mut n = 0;
        for y in 24..48 {
            for x in 0..64 {
                let v = img.px(x, y);
                if v.iter().zip(want).all(|(a, b)| (a - b).abs() <= 0.01 * b) {
                    n += 1;
                }
            }
        }
        n
    };
    // Pixels of the floor between 10% and 90% of the reflection's value.
    let partial = |img: &Image| {
        let mut n = 0;
        for y in 24..48 {
            for x in 0..64 {
                let v = img.px(x, y)[0];
                if v > 0.1 * want[0] && v < 0.9 * want[0] {
                    n += 1;
                }
            }
        }
        n
    };
    let (stats, sharp) = render(0.001, "\"distributed\"");
    assert!(stats["rays"]["reflection"].as_u64().unwrap() > 0);
    let (ns, ps) = (full(&sharp), partial(&sharp));
    assert!(ns > 150, "{ns} pixels reflect the ball in full");
    let (_, rough) = render(0.2, "\"distributed\"");
    let (nr, pr) = (full(&rough), partial(&rough));
    assert!(
        nr < ns / 10 && pr > 3 * ps,
        "sharp: {ns} full, {ps} partial; rough: {nr} full, {pr} partial"
    );
    // No glossy rays: the floor is black, as Whitted renders it.
    for integ in [
        "{ class = \"distributed\", glossy_samples = 0 }",
        "\"whitted\"",
    ] {
        let (stats, img) = render(0.001, integ);
        assert_eq!(stats["rays"]["reflection"], 0, "{integ}");
        assert_eq!(full(&img) + partial(&img), 0, "{integ}");
    }
}

/// Light reaching a glossy surface from an area light is counted once: by
/// the light samples, not again by the glossy rays that hit the light. With
/// no diffuse surface in the scene, distributed ray tracing and the path
/// tracer estimate the same image.
#[test]
fn glossy_light_is_counted_once() {
    let lamp = r#"{ object = "ball", shader = "lamp" }"#;
    let integ = "{ class = \"distributed\", light_samples = 4 }";
    let (rd, d) = render_scene(&glossy_floor(0.3, integ, 64, lamp), &[]);
    assert!(rd.ok, "{}", rd.stderr);
    let (rp, p) = render_scene(&glossy_floor(0.3, "\"path\"", 256, lamp), &[]);
    assert!(rp.ok, "{}", rp.stderr);
    let (d, p) = (d.unwrap(), p.unwrap());
    // The floor below the lamp (its highlight), and the whole image.
    for region in [(0, 24, 64, 48), (16, 30, 48, 48), (0, 0, 64, 48)] {
        let (md, mp) = (mean(&d, region), mean(&p, region));
        assert!(md > 0.05, "{md}");
        assert!(
            (md - mp).abs() < 0.03 * mp,
            "region {region:?}: distributed {md}, path {mp}"
        );
    }
}
