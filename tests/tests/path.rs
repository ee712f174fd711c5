//! The `path` integrator against closed forms (white furnaces) and against
//! Mitsuba 3's Cornell box; Whitted's mirror corridor against its
//! geometric series.

use rtk_tests::*;

/// A closed box of half-extents (1, 1.5, 2) around the origin, made of six
/// instances of one unit square (`scenes/meshes/floor.obj`, facing +y),
/// each scaled, turned to face inwards and moved into place: non-uniform
/// scales, so the area lights' densities go through the transforms'
/// Jacobians. `shaders[i]` is bound to face i (−y, +y, −x, +x, −z, +z).
fn furnace(shaders: [&str; 6], defs: &str, spp: u32) -> String {
    let faces = [
        "{ scale = [2.0, 1.0, 4.0] }, { translate = [0.0, -1.5, 0.0] }",
        "{ scale = [2.0, 1.0, 4.0] }, { rotate_x = 180.0 }, { translate = [0.0, 1.5, 0.0] }",
        "{ scale = [3.0, 1.0, 4.0] }, { rotate_z = -90.0 }, { translate = [-1.0, 0.0, 0.0] }",
        "{ scale = [3.0, 1.0, 4.0] }, { rotate_z = 90.0 }, { translate = [1.0, 0.0, 0.0] }",
        "{ scale = [2.0, 1.0, 3.0] }, { rotate_x = 90.0 }, { translate = [0.0, 0.0, -2.0] }",
        "{ scale = [2.0, 1.0, 3.0] }, { rotate_x = -90.0 }, { translate = [0.0, 0.0, 2.0] }",
    ];
    let children: Vec<String> = faces
        .iter()
        .zip(shaders)
        .map(|(t, s)| format!("  {{ object = \"square\", shader = \"{s}\", transform = [{t}] }},"))
        .collect();
    format!(
        r#"
[render]
width = 32
height = 32
spp = {spp}
root = "world"
integrator = {{ class = "path" }}
[cameras.c]
class = "pinhole"
eye = [0.1, 0.2, 0.3]
look_at = [1.0, -0.5, 2.0]
fov_y = 100.0
{defs}
[objects.square]
class = "mesh"
file = "{square}"
[objects.world]
class = "bvh"
children = [
{children}
]
"#,
        square = root().join("scenes/meshes/floor.obj").display(),
        children = children.join("\n")
    )
}

/// Albedo 0: every pixel is exactly the emission of the face it sees, for
/// three shaders bound to different instances of one object.
#[test]
fn furnace_without_reflection_is_exactly_the_emission_per_instance() {
    let defs = r#"
[shaders.a]
class = "lambert"
albedo = [0.0, 0.0, 0.0]
emission = [1.0, 0.5, 0.25]
[shaders.b]
class = "lambert"
albedo = [0.0, 0.0, 0.0]
emission = [0.5, 2.0, 0.125]
[shaders.c]
class = "lambert"
albedo = [0.0, 0.0, 0.0]
emission = [3.0, 0.0, 1.0]
"#;
    let (run, img) = render_scene(&furnace(["a", "a", "b", "b", "c", "c"], defs, 4), &[]);
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    let allowed = [[1.0, 0.5, 0.25], [0.5, 2.0, 0.125], [3.0, 0.0, 1.0]];
    let mut seen = [0; 3];
    for y in 0..32 {
        for x in 0..32 {
            let p = img.px(x, y);
            // 4 samples may straddle two faces only where faces meet; the
            // camera sees only whole faces otherwise.
            match allowed.iter().position(|a| *a == p) {
                Some(i) => seen[i] += 1,
                None => {
                    // A mix of faces: each channel between the extremes.
                    for c in 0..3 {
                        let lo = allowed.iter().map(|a| a[c]).fold(f32::MAX, f32::min);
                        let hi = allowed.iter().map(|a| a[c]).fold(f32::MIN, f32::max);
                        assert!((lo..=hi).contains(&p[c]), "pixel ({x},{y}) {p:?}");
                    }
                }
            }
        }
    }
    assert!(seen.iter().all(|&n| n > 20), "faces seen: {seen:?}");
}

/// Albedo ρ = 0.5 and emission Le everywhere: every pixel's expectation is
/// Le / (1 − ρ). The 1024 pixels are independent estimates of it, so
/// their spread gives the tolerance of their mean (5 standard errors).
#[test]
fn white_furnace_converges_to_le_over_one_minus_albedo() {
    let defs = r#"
[shaders.wall]
class = "lambert"
albedo = [0.5, 0.5, 0.5]
emission = [1.0, 0.5, 2.0]
"#;
    let (run, img) = render_scene(&furnace(["wall"; 6], defs, 64), &["--stats"]);
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    let le = [1.0, 0.5, 2.0];
    let n = (img.width * img.height) as f64;
    for (c, le) in le.iter().enumerate() {
        let v: Vec<f64> = img
            .data
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&x| x as f64)
            .collect();
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let expected = le / (1.0 - 0.5);
        let tol = 5.0 * (var / n).sqrt();
        assert!(
            (mean - expected).abs() < tol,
            "channel {c}: mean {mean} vs {expected} (tolerance {tol}, pixel σ {})",
            var.sqrt()
        );
        // The spread itself is what a working estimator gives: not zero
        // (the test would prove nothing), and a few percent at 64 spp.
        assert!(var.sqrt() > 1e-4 * expected && var.sqrt() < 0.2 * expected);
    }
    // Every light sample went through a transformed instance's surface.
    assert!(run.stats()["light_samples"].as_u64().unwrap() > 100_000);
}

/// Two parallel mirrors (phong, diffuse kd and mirror r) with a point
/// light between them, seen along their common normal through a 1×1
/// image: each of the depth + 1 hits adds the same direct light D, each
/// seen through one more mirror, so L = D (1 − r^(depth+1)) / (1 − r).
#[test]
fn mirror_corridor_matches_the_geometric_series() {
    let (kd, r, i, depth) = (0.3f64, 0.5f64, 10.0f64, 32u32);
    let scene = format!(
        r#"
[render]
width = 1
height = 1
root = "world"
integrator = {{ class = "whitted", max_depth = {depth} }}
[cameras.c]
class = "pinhole"
eye = [0.0, 0.0, 2.0]
look_at = [1.0, 0.0, 2.0]
fov_y = 1.0
[lights.l]
class = "point"
position = [0.0, 1.0, 2.0]
intensity = [{i}, {i}, {i}]
[shaders.m]
class = "phong"
diffuse = [{kd}, {kd}, {kd}]
mirror = [{r}, {r}, {r}]
[objects.plane]
class = "mesh"
file = "{floor}"
[objects.world]
class = "list"
children = [
  {{ object = "plane", shader = "m", transform = [{{ scale = 10.0 }}, {{ rotate_z = 90.0 }}, {{ translate = [1.0, 0.0, 0.0] }}] }},
  {{ object = "plane", shader = "m", transform = [{{ scale = 10.0 }}, {{ rotate_z = 90.0 }}, {{ translate = [-1.0, 0.0, 0.0] }}] }},
]
"#,
        floor = root().join("scenes/meshes/floor.obj").display()
    );
    // The hits lie 1.4 away from the squares' diagonals: points near an
    // edge are moved into their triangle by twice their error bound (rule
    // 6), a few 1e-4 on a 1000-wide mirror, which would show here.
    let (run, img) = render_scene(&scene, &[]);
    assert!(run.ok, "{}", run.stderr);
    let px = img.unwrap().px(0, 0);
    // The light is at distance √2 from each hit, 45° off the normal.
    let d2 = 2.0f64;
    let direct = kd / std::f64::consts::PI * i / d2 * (1.0 / d2.sqrt());
    let expected = direct * (1.0 - r.powi(depth as i32 + 1)) / (1.0 - r);
    for c in px {
        assert!(
            (c as f64 - expected).abs() < 1e-5 * expected,
            "{c} vs {expected}"
        );
    }
}

/// `scenes/cornell.toml` against Mitsuba 3's 4096-spp reference: at 16 spp
/// its error must be what an unbiased estimator gives (Mitsuba's own at 16
/// spp, 0.0361, with 10 % to spare), and its mean colour must match the
/// reference's within the noise of a mean over 65,536 pixels; with
/// independent and with stratified pixel positions.
#[test]
fn cornell_box_converges_to_mitsuba() {
    let Some(reference) = shared("anchors/mitsuba/ref_cornell.exr") else {
        return;
    };
    for sampler in ["independent", "stratified"] {
        cornell_against(&reference, sampler);
    }
}

fn cornell_against(reference: &std::path::Path, sampler: &str) {
    let dir = tempfile::tempdir().unwrap();
    let set = format!("render.sampler={sampler}");
    let (run, img) = render_file(
        &root().join("scenes/cornell.toml"),
        dir.path(),
        &["--set", "render.spp=16", "--set", &set],
    );
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    let r = Image::read(reference);
    assert_eq!((img.width, img.height), (r.width, r.height));
    let n = img.data.len() as f64;
    let mse = img
        .data
        .iter()
        .zip(&r.data)
        .map(|(a, b)| (*a as f64 - *b as f64).powi(2))
        .sum::<f64>()
        / n;
    let rmse = mse.sqrt();
    assert!(
        rmse < 1.1 * 0.03608,
        "RMSE {rmse} against Mitsuba's reference"
    );
    let pixels = (img.width * img.height) as f64;
    for c in 0..3 {
        let mean = |d: &[f32]| d.iter().skip(c).step_by(3).map(|&x| x as f64).sum::<f64>() / pixels;
        let (a, b) = (mean(&img.data), mean(&r.data));
        // Pixel errors have RMS `rmse`: their mean's noise is rmse/256.
        let tol = 5.0 * rmse / pixels.sqrt();
        assert!(
            (a - b).abs() < tol,
            "channel {c}: mean {a} vs {b} (± {tol})"
        );
    }
}

/// The brief's I1: a convex Lambertian sphere of albedo ρ under a constant
/// environment L reflects exactly ρL (it cannot see itself), and with
/// ρ = 1 it disappears. Pixels wholly inside the silhouette are
/// independent estimates of ρL: their mean must lie within 5 standard
/// errors; rays that miss see exactly L.
#[test]
fn convex_lambertian_under_a_constant_environment_reflects_albedo_times_l() {
    for albedo in [0.5f64, 1.0] {
        let scene = format!(
            r#"
[render]
width = 32
height = 32
spp = 32
filter = "box"
root = "world"
integrator = {{ class = "path" }}
[cameras.c]
class = "pinhole"
eye = [0.0, 0.0, 4.0]
fov_y = 40.0
[lights.sky]
class = "constant"
radiance = [1.0, 1.0, 1.0]
[shaders.s]
class = "lambert"
albedo = [{albedo}, {albedo}, {albedo}]
[objects.ball]
class = "sphere"
[objects.world]
class = "list"
children = [{{ object = "ball", shader = "s" }}]
"#
        );
        let (run, img) = render_scene(&scene, &[]);
        assert!(run.ok, "{}", run.stderr);
        let img = img.unwrap();
        let t = 20f64.to_radians().tan();
        let (mut inside, mut outside) = (Vec::new(), 0);
        for y in 0..32 {
            for x in 0..32 {
                // The pixel's corners' rays: all within 0.9 of the centre
                // line, or all beyond 1.1 (the sphere's radius is 1).
                let dist = |fx: f64, fy: f64| {
                    let (sx, sy) = ((2.0 * fx / 32.0 - 1.0) * t, (1.0 - 2.0 * fy / 32.0) * t);
                    4.0 * (sx * sx + sy * sy).sqrt() / (1.0 + sx * sx + sy * sy).sqrt()
                };
                let (x, y) = (x as f64, y as f64);
                let d = [
                    dist(x, y),
                    dist(x + 1.0, y),
                    dist(x, y + 1.0),
                    dist(x + 1.0, y + 1.0),
                ];
                let p = img.px(x as u32, y as u32);
                if d.iter().all(|&d| d < 0.9) {
                    inside.push(p[0] as f64);
                } else if d.iter().all(|&d| d > 1.1) {
                    assert_eq!(p, [1.0; 3], "background pixel ({x},{y})");
                    outside += 1;
                }
            }
        }
        let n = inside.len() as f64;
        let mean = inside.iter().sum::<f64>() / n;
        let var = inside.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let tol = 5.0 * (var / n).sqrt() + 1e-6;
        assert!(n > 100.0 && outside > 100, "{n} {outside}");
        assert!(
            (mean - albedo).abs() < tol,
            "albedo {albedo}: mean {mean} (± {tol})"
        );
    }
}

/// `--profile` times the scene services without changing the image: on
/// the Cornell box (a bvh over 32 triangles, an area light, Lambert walls)
/// every part of the render is seen and the shares of the threads' time
/// add up to at most 1; the parts timed are where a path spends its time
/// (traversal is the largest of the services); the image is the plain
/// render's bit for bit.
#[test]
fn profile_shares_add_up_and_leave_the_image_alone() {
    let cornell = root().join("scenes/cornell.toml");
    let dir = tempfile::tempdir().unwrap();
    let args = [
        "--spp",
        "4",
        "--set",
        "render.width=64",
        "--set",
        "render.height=64",
    ];
    let (plain, plain_img) = render_file(&cornell, dir.path(), &args);
    assert!(plain.ok, "{}", plain.stderr);
    let with: Vec<&str> = args.iter().copied().chain(["--profile"]).collect();
    let (run, img) = render_file(&cornell, dir.path(), &with);
    assert!(run.ok, "{}", run.stderr);
    assert!(
        plain_img.unwrap().data == img.unwrap().data,
        "the profile changed the image"
    );
    let p = &run.stats()["profile"];
    let share = |k: &str| {
        p["shares"][k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {p}"))
    };
    let parts = [
        "traversal",
        "surface",
        "lights",
        "integrator_and_shaders",
        "render_loop",
    ];
    let sum: f64 = parts.iter().map(|k| share(k)).sum();
    assert!(
        sum <= 1.0 + 1e-6 && sum > 0.5,
        "shares add up to {sum}: {p}"
    );
    for k in parts {
        assert!(share(k) > 0.0, "{k}: {p}");
    }
    assert!(share("traversal") > share("surface"), "{p}");
    let b = &p["boundary"];
    // 64x64 at 4 spp: every camera sample's li at least, and its rays.
    assert!(b["crossings"].as_u64().unwrap() > 3 * 64 * 64 * 4, "{p}");
    let per = b["seconds_per_crossing"].as_f64().unwrap();
    assert!(per > 0.0 && per < 1e-6, "{p}");
}
