//! Closed forms for mirror reflection and refraction, attribute blocks, PNG encoding.

use rtk_tests::*;

fn sphere_scene(shader: &str, extra: &str) -> String {
    format!(
        r#"
[render]
width = 48
height = 48
root = "world"
background = [0.2, 0.4, 0.6]
integrator = {{ class = "whitted", max_depth = 64 }}
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
{extra}
"#
    )
}

const BG: [f32; 3] = [0.2, 0.4, 0.6];

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
            // distance of the ray from the centre, eye at distance 4
            let d = 4.0 * (sx * sx + sy * sy).sqrt() / (1.0 + sx * sx + sy * sy).sqrt();
            if d < 0.9 {
                v.push((x, y));
            }
        }
    }
    v
}

#[test]
fn mirror_sphere_reflects_the_background_times_kr() {
    // A convex mirror cannot see itself: every reflected ray escapes.
    let (run, img) = render_scene(
        &sphere_scene(
            "class = \"phong\"\ndiffuse = [0.0, 0.0, 0.0]\nmirror = [0.5, 0.25, 1.0]",
            "",
        ),
        &["--stats"],
    );
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    let px = interior_pixels();
    assert!(px.len() > 300);
    for (x, y) in px {
        let p = img.px(x, y);
        for (c, e) in p.iter().zip([0.5 * BG[0], 0.25 * BG[1], BG[2]]) {
            assert!((c - e).abs() < 1e-6, "({x},{y}): {p:?}");
        }
    }
    let s = run.stats();
    assert!(s["rays"]["reflection"].as_u64().unwrap() > 300);
    assert_eq!(s["rays"]["shadow"], 0, "no lights, no shadow rays");
}

#[test]
fn clear_glass_sphere_conserves_the_background() {
    // Fresnel splits each ray into reflected and refracted parts that sum to
    // one; with no absorption and a uniform background, every pixel sees it.
    let (run, img) = render_scene(
        &sphere_scene("class = \"phong\"\ndiffuse = [0.0, 0.0, 0.0]\ntransmission = [1.0, 1.0, 1.0]\nior = 1.5", ""),
        &["--stats"],
    );
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    for (x, y) in interior_pixels() {
        let p = img.px(x, y);
        for (c, e) in p.iter().zip(BG) {
            assert!((c - e).abs() < 1e-4 * e, "({x},{y}): {p:?}");
        }
    }
    let s = run.stats();
    assert!(
        s["rays"]["refraction"].as_u64().unwrap() > 600,
        "rays enter and leave"
    );
    // Reaching depth 64 would lose energy; some paths do bounce inside many times.
    assert!(
        s["rays"]["reflection"].as_u64().unwrap() > s["rays"]["refraction"].as_u64().unwrap() / 2
    );
}

#[test]
fn attribute_blocks_override_the_shader_per_instance() {
    let scene = sphere_scene("class = \"flat\"\ncolor = [0.5, 0.5, 0.5]", "")
        .replace(
            "children = [{ object = \"ball\", shader = \"s\" }]",
            "children = [{ object = \"ball\", shader = \"s\", transform = [{ translate = [-1.2, 0.0, 0.0] }] },\n\
             { object = \"ball\", shader = \"s\", attributes = { color = [0.0, 1.0, 0.25] }, transform = [{ translate = [1.2, 0.0, 0.0] }] }]",
        )
        .replace("eye = [0.0, 0.0, 4.0]", "eye = [0.0, 0.0, 8.0]");
    let (run, img) = render_scene(&scene, &["--stats"]);
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    // Left sphere: the shader's colour; right sphere: the attributes'.
    assert_eq!(img.px(14, 24), [0.5, 0.5, 0.5]);
    assert_eq!(img.px(33, 24), [0.0, 1.0, 0.25]);
    assert_eq!(run.stats()["shaders_created"], 2);

    // The same through PNG: sRGB encoding of 0.5 is 188, of 0.25 is 137.
    let dir = tempfile::tempdir().unwrap();
    let sp = dir.path().join("s.toml");
    std::fs::write(&sp, &scene).unwrap();
    let out = dir.path().join("o.png");
    let r = rtk(&[
        "render",
        sp.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ])
    .output()
    .unwrap();
    assert!(r.status.success());
    let png = image::open(&out).unwrap().into_rgb8();
    assert_eq!(png.get_pixel(14, 24).0, [188, 188, 188]);
    assert_eq!(png.get_pixel(33, 24).0, [0, 255, 137]);
}

#[test]
fn attribute_errors_point_into_the_attribute_block() {
    let scene = sphere_scene("class = \"flat\"", "").replace(
        "{ object = \"ball\", shader = \"s\" }",
        "{ object = \"ball\", shader = \"s\", attributes = { colour = [1, 0, 0] } }",
    );
    let (run, _) = render_scene(&scene, &[]);
    assert!(!run.ok);
    assert!(
        run.stderr.contains("key `colour`")
            && run.stderr.contains("(attributes)")
            && run.stderr.contains("scene.toml:18:"),
        "{}",
        run.stderr
    );
}

#[test]
fn transform_class_used_directly_with_steps() {
    let scene = sphere_scene("class = \"flat\"", "[objects.moved]\nclass = \"transform\"\nsteps = [{ scale = 0.25 }, { translate = [1.0, 0.0, 0.0] }]\nchildren = [\"ball\"]\n")
        .replace("{ object = \"ball\", shader = \"s\" }", "{ object = \"moved\", shader = \"s\" }");
    let (run, img) = render_scene(&scene, &[]);
    assert!(run.ok, "{}", run.stderr);
    let img = img.unwrap();
    assert_eq!(img.px(24, 24), BG, "the centre shows the background now");
    // x = 1 at distance 4 with fov 40: pixel 24 + 24 * (1/4)/tan(20°) ≈ 40.5
    assert_eq!(img.px(40, 24), [1.0, 1.0, 1.0]);
}

/// Two facing mirrors: no ray ever escapes, so every camera ray spawns
/// exactly `max_depth + 1` reflection rays (the last returns black at once),
/// and the image is black. Depth 1024 must not overflow any stack.
#[test]
fn facing_mirrors_stop_exactly_at_the_depth_limit() {
    for depth in [40u64, 1024] {
        let scene = format!(
            r#"
[render]
width = 16
height = 16
root = "world"
background = [1.0, 1.0, 1.0]
integrator = {{ class = "whitted", max_depth = {depth} }}
[cameras.c]
class = "pinhole"
eye = [0.0, 0.0, 0.0]
look_at = [1.0, 0.0, 0.0]
fov_y = 10.0
[shaders.m]
class = "phong"
diffuse = [0.0, 0.0, 0.0]
mirror = [0.99, 0.99, 0.99]
[objects.plane]
class = "mesh"
file = "{floor}"
[objects.world]
class = "list"
children = [
  {{ object = "plane", shader = "m", transform = [{{ scale = 1000.0 }}, {{ rotate_z = 90.0 }}, {{ translate = [1.0, 0.0, 0.0] }}] }},
  {{ object = "plane", shader = "m", transform = [{{ scale = 1000.0 }}, {{ rotate_z = 90.0 }}, {{ translate = [-1.0, 0.0, 0.0] }}] }},
]
"#,
            floor = root().join("scenes/meshes/floor.obj").display()
        );
        let (run, img) = render_scene(&scene, &["--stats"]);
        assert!(run.ok, "{}", run.stderr);
        assert_eq!(run.stats()["rays"]["reflection"], 256 * (depth + 1));
        assert!(img.unwrap().data.iter().all(|&v| v == 0.0));
    }
}

/// Whitted's work bound: a glass ball in the house of mirrors spawns two
/// rays at every glass hit; from `branch_depth` (8) on only the stronger is
/// followed, so a pixel's tree stays under 2^8 rays per generation, and the
/// full tree (`branch_depth = max_depth`) is larger.
#[test]
fn whitted_ray_trees_are_bounded() {
    let scene = root().join("scenes/mirrors.toml");
    let dir = tempfile::tempdir().unwrap();
    let count = |branch: u32| {
        let b = format!("render.integrator.branch_depth={branch}");
        let (run, _) = render_file(
            &scene,
            dir.path(),
            &[
                "--stats",
                "--set",
                "render.width=8",
                "--set",
                "render.height=8",
                "--set",
                "render.integrator.max_depth=24",
                "--set",
                "shaders.red.transmission=[1.0, 1.0, 1.0]",
                "--set",
                "shaders.red.diffuse=[0.0, 0.0, 0.0]",
                "--set",
                &b,
            ],
        );
        assert!(run.ok, "{}", run.stderr);
        let s = run.stats();
        s["rays"]["reflection"].as_u64().unwrap() + s["rays"]["refraction"].as_u64().unwrap()
    };
    let (bounded, full) = (count(8), count(24));
    assert!(bounded <= 64 * 256 * 25, "{bounded} rays");
    assert!(full > bounded, "{full} vs {bounded}");
}

/// The `transform` class used directly keeps rule 1's coordinate limit.
#[test]
fn transform_class_refuses_translations_beyond_the_limit() {
    let scene = sphere_scene("class = \"flat\"", "[objects.moved]\nclass = \"transform\"\nsteps = [{ translate = [2e12, 0.0, 0.0] }]\nchildren = [\"ball\"]\n")
        .replace("{ object = \"ball\", shader = \"s\" }", "{ object = \"moved\", shader = \"s\" }");
    let (run, img) = render_scene(&scene, &[]);
    assert!(!run.ok && img.is_none());
    assert!(
        run.stderr.contains("objects.moved")
            && run.stderr.contains("steps")
            && run.stderr.contains("1e12"),
        "{}",
        run.stderr
    );
}

/// The `projector` light against its closed form: on a white lambert plane
/// at unit distance along its axis, Mitsuba's normalisation (irradiance ·
/// π · scale / (z² cos θ)) makes the reflected radiance irradiance · scale
/// everywhere inside the projected frame (the cosines and distances cancel
/// at z = 1), and nothing outside it.
#[test]
fn a_projector_lights_a_plane_at_unit_distance_evenly() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("p.toml");
    std::fs::write(
        &scene,
        r#"
[render]
width = 16
height = 16
spp = 4
filter = "box"
camera = "c"
root = "floor"
integrator = { class = "path", max_depth = 2 }

[cameras.c]
class = "pinhole"
eye = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
fov_y = 60.0

[lights.slide]
class = "projector"
# +z of its frame along world -z (a rotation of 180° about y).
to_world = [-1.0, 0.0, 0.0, 0.0,  0.0, 1.0, 0.0, 0.0,  0.0, 0.0, -1.0, 0.0,  0.0, 0.0, 0.0, 1.0]
fov = 90.0
irradiance = [0.5, 0.25, 1.0]
scale = 0.8

[shaders.white]
class = "lambert"
albedo = [1.0, 1.0, 1.0]

[objects.floor]
class = "polygon"
points = [[-10.0, -10.0, -1.0], [10.0, -10.0, -1.0], [10.0, 10.0, -1.0], [-10.0, 10.0, -1.0]]

[objects.floor_lit]
class = "list"
children = [{ object = "floor", shader = "white" }]
"#,
    )
    .unwrap();
    let out = dir.path().join("p.exr");
    let r = Run::from(
        rtk(&[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
            "--set",
            "render.root=floor_lit",
        ])
        .output()
        .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
    let img = Image::read(&out);
    // The camera's 60° frame lies inside the projector's 90°: every pixel lit.
    for (i, px) in img.data.chunks(3).enumerate() {
        for (c, want) in px.iter().zip([0.4f32, 0.2, 0.8]) {
            assert!((c - want).abs() < 1e-4, "pixel {i}: {px:?}");
        }
    }
    // A 30° projector leaves the frame's corners dark.
    let r = Run::from(
        rtk(&[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
            "--set",
            "render.root=floor_lit",
            "--set",
            "lights.slide.fov=30.0",
        ])
        .output()
        .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
    let img = Image::read(&out);
    assert_eq!(img.data[0], 0.0, "a corner outside the projection");
    let centre = (8 * 16 + 8) * 3;
    assert!((img.data[centre] - 0.4).abs() < 1e-4);
}

/// The `envmap` light against its closed form: a lambert plane facing +y
/// under a map lit only above the horizon (rows 0 to 2 of 5, so the
/// bilinear blend never reaches below 90°) receives E = π·(mean of the
/// columns) — bilinear interpolation, periodic in φ, keeps the columns'
/// mean — and reflects albedo·mean. The columns differ 4 : 0 : 1 : 3, so
/// a luminance-sampling density out of step with `pdf_li` would bias the
/// MIS sum. Turned upside down by `to_world`, only the blend between
/// rows 2 (lit, now at the horizon) and 3 (dark, now 45° up) reaches the
/// plane: L = mean·(θ − π/4)/(π/4) for θ in [π/4, π/2], whose cosine-
/// weighted integral makes the plane albedo·2·mean·(¼ − 1/(2π)), here
/// (½ − 1/π) of the upright map's — the interpolation in θ checked too.
#[test]
fn an_envmap_lights_a_plane_as_the_mean_of_its_sky() {
    let dir = tempfile::tempdir().unwrap();
    let sky = dir.path().join("sky.exr");
    let cols = [4.0f32, 0.0, 1.0, 3.0];
    image::ImageBuffer::<image::Rgb<f32>, _>::from_fn(4, 5, |x, y| {
        let v = if y <= 2 { cols[x as usize] } else { 0.0 };
        image::Rgb([v, 0.5 * v, 0.25 * v])
    })
    .save(&sky)
    .unwrap();
    let scene = dir.path().join("e.toml");
    std::fs::write(
        &scene,
        r#"
[render]
width = 24
height = 16
spp = 64
filter = "box"
camera = "c"
root = "floor"
integrator = { class = "path", max_depth = 2 }

[cameras.c]
class = "pinhole"
eye = [0.0, 1.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov_y = 60.0

[lights.sky]
class = "envmap"
radiance = { image_file = "sky.exr" }

[shaders.grey]
class = "lambert"
albedo = [0.5, 0.5, 0.5]

[objects.plane]
class = "polygon"
points = [[-100.0, 0.0, -100.0], [-100.0, 0.0, 100.0], [100.0, 0.0, 100.0], [100.0, 0.0, -100.0]]

[objects.floor]
class = "list"
children = [{ object = "plane", shader = "grey" }]
"#,
    )
    .unwrap();
    let out = dir.path().join("e.exr");
    let render = |extra: &[&str]| {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let r = Run::from(rtk(&args).output().unwrap());
        assert!(r.ok, "{}", r.stderr);
        Image::read(&out)
    };
    let check = |img: &Image, scale: f64| {
        let n = (img.data.len() / 3) as f64;
        for (c, want) in [1.0f64, 0.5, 0.25].into_iter().enumerate() {
            let want = want * scale;
            let mean = img
                .data
                .iter()
                .skip(c)
                .step_by(3)
                .map(|&v| v as f64)
                .sum::<f64>()
                / n;
            assert!(
                (mean / want - 1.0).abs() < 0.015,
                "channel {c}: {mean}, want {want}"
            );
        }
    };
    check(&render(&[]), 1.0);
    let flipped = "lights.sky.to_world=[1.0, 0.0, 0.0, 0.0,  0.0, -1.0, 0.0, 0.0,  0.0, 0.0, -1.0, 0.0,  0.0, 0.0, 0.0, 1.0]";
    check(
        &render(&["--set", flipped]),
        0.5 - std::f64::consts::FRAC_1_PI,
    );
}
