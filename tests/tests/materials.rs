//! The physically based shaders and textures end to end: `conductor`,
//! `dielectric` and `roughconductor` under `path` and `whitted` against
//! closed forms, `lambert` albedo textures (checker, image) under a
//! directional light, parameter refusals naming their keys, `--safe` on
//! image files, and `scenes/materials.toml`.

use rtk_tests::*;

const BG: [f32; 3] = [0.2, 0.4, 0.6];

/// A unit sphere seen from z = 4 against a uniform background, no lights.
fn sphere_scene(integrator: &str, shader: &str) -> String {
    format!(
        r#"
[render]
width = 48
height = 48
root = "world"
background = [0.2, 0.4, 0.6]
integrator = {integrator}
[cameras.c]
class = "pinhole"
eye = [0.0, 0.0, 4.0]
fov_y = 40.0
[shaders.s]
{shader}
[objects.ball]
class = "sphere"
[objects.world]
class = "list"
children = [{{ object = "ball", shader = "s" }}]
"#
    )
}

/// Pixels whose centre ray hits the unit sphere well inside its silhouette.
fn interior_pixels() -> Vec<(u32, u32)> {
    let t = (20f64).to_radians().tan();
    let mut v = vec![];
    for y in 0..48 {
        for x in 0..48 {
            let (sx, sy) = (
                (2.0 * (x as f64 + 0.5) / 48.0 - 1.0) * t,
                (1.0 - 2.0 * (y as f64 + 0.5) / 48.0) * t,
            );
            let d = 4.0 * (sx * sx + sy * sy).sqrt() / (1.0 + sx * sx + sy * sy).sqrt();
            if d < 0.9 {
                v.push((x, y));
            }
        }
    }
    assert!(v.len() > 300);
    v
}

fn render_ok(scene: &str, args: &[&str]) -> (Run, Image) {
    let (run, img) = render_scene(scene, args);
    assert!(run.ok, "{}", run.stderr);
    (run, img.unwrap())
}

/// A convex mirror never sees itself: every path is camera → mirror →
/// background, weight `reflectance`, under both integrators.
#[test]
fn conductor_sphere_reflects_the_background_times_its_reflectance() {
    let shader = "class = \"conductor\"\nreflectance = [0.5, 0.25, 1.0]";
    for integrator in ["{ class = \"whitted\" }", "{ class = \"path\" }"] {
        let (run, img) = render_ok(
            &sphere_scene(integrator, shader),
            &["--stats", "--spp", "4"],
        );
        for (x, y) in interior_pixels() {
            let p = img.px(x, y);
            for (c, e) in p.iter().zip([0.5 * BG[0], 0.25 * BG[1], BG[2]]) {
                assert!((c - e).abs() < 1e-6, "{integrator} ({x},{y}): {p:?}");
            }
        }
        assert!(run.stats()["rays"]["reflection"].as_u64().unwrap() > 300 * 4);
    }
}

/// Clear glass in a uniform background: reflection and transmission are
/// chosen with probabilities F and 1 − F and each carries weight 1, so
/// every path (they all escape: no internal ray of a sphere is totally
/// reflected) brings back exactly the background. Russian roulette is
/// pushed out of reach so no weight is divided by a survival probability.
#[test]
fn glass_sphere_under_path_returns_the_background_exactly() {
    let (run, img) = render_ok(
        &sphere_scene(
            "{ class = \"path\", rr_depth = 100000 }",
            "class = \"dielectric\"\neta = 1.5",
        ),
        &["--stats", "--spp", "8"],
    );
    for (x, y) in interior_pixels() {
        let p = img.px(x, y);
        for (c, e) in p.iter().zip(BG) {
            assert!((c - e).abs() < 1e-6, "({x},{y}): {p:?}");
        }
    }
    let s = run.stats();
    assert!(s["rays"]["refraction"].as_u64().unwrap() > 300 * 8, "{s}");
    assert!(s["rays"]["reflection"].as_u64().unwrap() > 0, "{s}");
}

/// Whitted asks for each lobe alone and sums them: F·bg + (1 − F)·bg per
/// interface, so the background comes back up to the depth limit's loss.
#[test]
fn glass_sphere_under_whitted_conserves_the_background() {
    let (_, img) = render_ok(
        &sphere_scene(
            "{ class = \"whitted\", max_depth = 64 }",
            "class = \"dielectric\"\neta = 1.5\ntransmittance = [1.0, 1.0, 1.0]",
        ),
        &[],
    );
    for (x, y) in interior_pixels() {
        let p = img.px(x, y);
        for (c, e) in p.iter().zip(BG) {
            assert!((c - e).abs() < 1e-4 * e, "({x},{y}): {p:?}");
        }
    }
    // Tinted transmission darkens what is seen through the ball.
    let (_, img) = render_ok(
        &sphere_scene(
            "{ class = \"whitted\", max_depth = 64 }",
            "class = \"dielectric\"\ntransmittance = [0.5, 0.5, 0.5]",
        ),
        &[],
    );
    let p = img.px(24, 24);
    assert!(p[2] < 0.5 * BG[2] && p[2] > 0.25 * BG[2], "{p:?}");
}

/// Rough metal on a convex sphere: each sample's weight G2/G1 ≤ 1, so no
/// pixel exceeds the background; single scattering loses 12–18% at α = 0.3.
#[test]
fn rough_conductor_loses_a_little_energy_and_never_gains() {
    let (_, img) = render_ok(
        &sphere_scene(
            "{ class = \"path\" }",
            "class = \"roughconductor\"\nalpha = 0.3",
        ),
        &["--spp", "16"],
    );
    let mut mean = 0.0;
    let px = interior_pixels();
    for &(x, y) in &px {
        let p = img.px(x, y);
        for (c, e) in p.iter().zip(BG) {
            assert!(*c <= e * (1.0 + 1e-5) && *c > 0.0, "({x},{y}): {p:?}");
        }
        mean += p[2] as f64 / px.len() as f64;
    }
    // The directional albedo of GGX α = 0.3 (height-correlated Smith) is
    // 0.877 at normal incidence and 0.817 at 64° (quadrature of the BRDF):
    // the disk's mean lies between.
    let m = mean / BG[2] as f64;
    assert!(m > 0.82 && m < 0.877, "{m}");
}

/// A square floor seen from straight above, lit by a directional light of
/// irradiance π from above: a lambert floor's radiance is its albedo. The
/// `path` integrator asks the surface for uv (`whitted` does not) and,
/// with one delta light and `max_depth = 2`, computes exactly that.
/// The camera is placed so that the view covers exactly the floor's
/// [0, 1]² of uv, or `frac` of it about the centre.
fn floor_scene(albedo: &str, frac: f64) -> String {
    // The view's half-width at the floor is frac (the floor spans ±1).
    let h = frac / 20f64.to_radians().tan();
    format!(
        r#"
[render]
width = 32
height = 32
root = "world"
integrator = {{ class = "path", max_depth = 2 }}
[cameras.c]
class = "pinhole"
eye = [0.0, {h}, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = 40.0
[lights.sun]
class = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = [3.141592653589793, 3.141592653589793, 3.141592653589793]
[shaders.floor]
class = "lambert"
albedo = {albedo}
[objects.floor]
class = "polygon"
points = [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]]
[objects.world]
class = "list"
children = [{{ object = "floor", shader = "floor" }}]
"#
    )
}

fn close(p: [f32; 3], e: [f32; 3], tol: f32) -> bool {
    p.iter().zip(e).all(|(a, b)| (a - b).abs() <= tol)
}

/// A 2 × 2 checker over the floor's uv: four quadrants, opposite ones
/// equal, each exactly its colour.
#[test]
fn checker_albedo_shows_its_cells() {
    let even = [0.9, 0.6, 0.3];
    let odd = [0.1, 0.2, 0.05];
    let (_, img) = render_ok(
        &floor_scene(
            "{ checker = { even = [0.9, 0.6, 0.3], odd = [0.1, 0.2, 0.05], scale = [2.0, 2.0] } }",
            0.8,
        ),
        &[],
    );
    let (a, b) = (img.px(8, 8), img.px(24, 8));
    assert!(close(img.px(24, 24), a, 0.0) && close(img.px(8, 24), b, 0.0));
    assert!(
        (close(a, even, 1e-5) && close(b, odd, 1e-5))
            || (close(a, odd, 1e-5) && close(b, even, 1e-5)),
        "{a:?} {b:?}"
    );
    // Every pixel is one of the two colours.
    for y in 0..32 {
        for x in 0..32 {
            let p = img.px(x, y);
            assert!(
                close(p, even, 1e-5) || close(p, odd, 1e-5),
                "({x},{y}) {p:?}"
            );
        }
    }
}

fn write_png(path: &std::path::Path) {
    let mut img = image::RgbImage::new(2, 2);
    img.put_pixel(0, 0, image::Rgb([255, 0, 0]));
    img.put_pixel(1, 0, image::Rgb([0, 255, 0]));
    img.put_pixel(0, 1, image::Rgb([0, 0, 255]));
    img.put_pixel(1, 1, image::Rgb([128, 128, 128]));
    img.save(path).unwrap();
}

/// An image albedo repeated twice over the floor, the view covering
/// exactly one period: the mean over the pixel grid of a periodic bilinear
/// interpolant is the mean of its texels — decoded from sRGB (128 is
/// 0.2158 linear, not 0.502).
#[test]
fn image_albedo_is_decoded_from_srgb_and_repeats() {
    let dir = tempfile::tempdir().unwrap();
    write_png(&dir.path().join("t.png"));
    let sp = dir.path().join("scene.toml");
    std::fs::write(
        &sp,
        floor_scene("{ image_file = \"t.png\", scale = [2.0, 2.0] }", 0.5),
    )
    .unwrap();
    let (run, img) = render_file(&sp, dir.path(), &[]);
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    let mut mean = [0.0f64; 3];
    for y in 0..32 {
        for x in 0..32 {
            for (m, c) in mean.iter_mut().zip(img.px(x, y)) {
                *m += c as f64 / 1024.0;
            }
        }
    }
    let grey = ((128.0 / 255.0 + 0.055) / 1.055f64).powf(2.4);
    let want = (1.0 + grey) / 4.0;
    for m in mean {
        assert!((m - want).abs() < 2e-3, "{mean:?} vs {want}");
    }
}

/// `image_file` is a file parameter: `--safe` refuses one outside the
/// scene's folder and the working directory, naming the key.
#[test]
fn safe_mode_checks_image_files() {
    let dir = tempfile::tempdir().unwrap();
    write_png(&dir.path().join("t.png"));
    let sub = dir.path().join("scene");
    std::fs::create_dir(&sub).unwrap();
    let sp = sub.join("scene.toml");
    std::fs::write(&sp, floor_scene("{ image_file = \"../t.png\" }", 0.5)).unwrap();
    let (run, _) = render_file(&sp, tempfile::tempdir().unwrap().path(), &[]);
    assert!(run.ok, "{}", run.stderr);
    let (run, _) = render_file(&sp, tempfile::tempdir().unwrap().path(), &["--safe"]);
    assert!(!run.ok);
    assert!(run.stderr.contains("albedo.image_file"), "{}", run.stderr);
    assert!(run.stderr.contains("--safe"), "{}", run.stderr);
}

/// Bad parameters are refused with the key named (nested keys of a
/// texture included) and the scene's line.
#[test]
fn bad_parameters_name_their_keys() {
    for (shader, key) in [
        ("class = \"lambert\"\nalbedo = [1.5, 0.0, 0.0]", "albedo"),
        (
            "class = \"lambert\"\nalbedo = { checker = { odd = [0.0, 2.0, 0.0] } }",
            "albedo.checker.odd",
        ),
        (
            "class = \"lambert\"\nalbedo = { image_file = \"nope.png\" }",
            "albedo.image_file",
        ),
        (
            "class = \"lambert\"\nalbedo = { checker = { evn = [0.0, 0.0, 0.0] } }",
            "evn",
        ),
        (
            "class = \"conductor\"\nreflectance = [1.0, 1.0, 1.1]",
            "reflectance",
        ),
        ("class = \"dielectric\"\neta = -1.5", "eta"),
        ("class = \"dielectric\"\neta = 0.0", "eta"),
        (
            "class = \"dielectric\"\ntransmittance = [1.0, -1.0, 1.0]",
            "transmittance",
        ),
        ("class = \"roughconductor\"\nalpha = 2.0", "alpha"),
        ("class = \"roughconductor\"\nalpha = 0.0", "alpha"),
    ] {
        let (run, _) = render_scene(&sphere_scene("{ class = \"path\" }", shader), &[]);
        assert!(!run.ok, "{shader}");
        assert!(run.stderr.contains(key), "{shader}: {}", run.stderr);
        assert!(
            run.stderr.contains("scene.toml:"),
            "{shader}: {}",
            run.stderr
        );
    }
}

/// The example scene renders, every pixel finite, every kind of ray used.
#[test]
fn materials_scene_renders() {
    let (run, img) = render_file(
        &root().join("scenes/materials.toml"),
        tempfile::tempdir().unwrap().path(),
        &[
            "--stats",
            "--spp",
            "2",
            "--set",
            "render.width=64",
            "--set",
            "render.height=48",
        ],
    );
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    assert!(img.data.iter().all(|c| c.is_finite() && *c >= 0.0));
    let s = run.stats();
    for kind in ["reflection", "refraction", "scatter", "shadow"] {
        assert!(s["rays"][kind].as_u64().unwrap() > 0, "{kind}: {s}");
    }
    assert_eq!(s["shaders_created"], 9);
}
