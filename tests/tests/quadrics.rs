//! The disk, cylinder, cone, torus and polygon classes through the real
//! binary: a `normals` render checked pixel by pixel against analytic
//! expectations, and each class refusing bad parameters with the key named.

use rtk_tests::*;

const W: u32 = 96;
const H: u32 = 64;
const FOV_Y: f64 = 40.0;
const EYE_Z: f64 = 10.0;
const BG: [f32; 3] = [0.1, 0.2, 0.3];

/// Objects in the plane z = 0 (the camera at z = 10 looks down −z): top row
/// disk, torus, cylinder; bottom row cone, an L-shaped polygon with a hole,
/// a clockwise polygon.
const SCENE: &str = r#"
[render]
width = 96
height = 64
root = "world"
integrator = "normals"
background = [0.1, 0.2, 0.3]

[cameras.main]
class = "pinhole"
eye = [0.0, 0.0, 10.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0

[objects.plate]
class = "disk"
center = [-3.2, 1.6, 0.0]
normal = [0.2, 0.3, 1.0]
radius = 0.9

[objects.ring]
class = "torus"
center = [0.0, 1.6, 0.0]
axis = [0.0, 0.0, 1.0]
major_radius = 1.0
minor_radius = 0.35

[objects.pipe]
class = "cylinder"
base = [3.2, 0.8, 0.0]
axis = [0.0, 1.0, 0.0]
height = 1.6
radius = 1.0

[objects.spike]
class = "cone"
apex = [-3.2, -0.6, 0.0]
axis = [0.0, -1.8, 0.0]
radius = 0.9

[objects.ell]
class = "polygon"
points = [[-1.4, -2.6, 0.0], [1.4, -2.6, 0.0], [1.4, -1.8, 0.0], [-0.4, -1.8, 0.0],
          [-0.4, -0.6, 0.0], [-1.4, -0.6, 0.0]]
holes = [[[0.3, -2.4, 0.0], [0.9, -2.4, 0.0], [0.9, -2.0, 0.0], [0.3, -2.0, 0.0]]]

[objects.back]
class = "polygon"
points = [[2.6, -1.0, 0.0], [3.8, -1.0, 0.0], [3.8, -2.2, 0.0], [3.2, -2.6, 0.0], [2.6, -2.2, 0.0]]

[objects.world]
class = "list"
children = ["plate", "ring", "pipe", "spike", "ell", "back"]
"#;

/// The camera ray's unit direction through the centre of pixel (x, y), as
/// `pinhole` computes it (in f64).
fn ray_dir(x: u32, y: u32) -> [f64; 3] {
    let t = (FOV_Y.to_radians() * 0.5).tan();
    let aspect = W as f64 / H as f64;
    let fx = (x as f64 + 0.5) / W as f64;
    let fy = (y as f64 + 0.5) / H as f64;
    let d = [(2.0 * fx - 1.0) * t * aspect, (1.0 - 2.0 * fy) * t, -1.0];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    d.map(|c| c / l)
}

/// The pixel whose centre ray meets the plane z = 0 closest to (px, py).
fn pixel_at(px: f64, py: f64) -> (u32, u32) {
    let t = (FOV_Y.to_radians() * 0.5).tan();
    let aspect = W as f64 / H as f64;
    let fx = (px / (EYE_Z * t * aspect) + 1.0) * 0.5;
    let fy = (1.0 - py / (EYE_Z * t)) * 0.5;
    (
        (fx * W as f64).floor() as u32,
        (fy * H as f64).floor() as u32,
    )
}

fn false_colour(n: [f64; 3]) -> [f64; 3] {
    n.map(|c| 0.5 * (c + 1.0))
}

fn assert_close(got: [f32; 3], want: [f64; 3], tol: f64, what: &str) {
    for k in 0..3 {
        assert!(
            (got[k] as f64 - want[k]).abs() <= tol,
            "{what}: got {got:?}, expected {want:?} (±{tol})"
        );
    }
}

fn render() -> Image {
    let (run, img) = render_scene(SCENE, &[]);
    assert!(run.ok, "{}", run.stderr);
    img.expect("image")
}

#[test]
fn five_classes_render_their_analytic_normals() {
    let img = render();

    // Disk: its centre pixel shows the given normal's false colour.
    let n = [0.2f64, 0.3, 1.0];
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let (x, y) = pixel_at(-3.2, 1.6);
    assert_close(
        img.px(x, y),
        false_colour(n.map(|c| c / l)),
        1e-6,
        "disk centre",
    );

    // Torus: the hole shows the background; the tube's front faces the camera.
    let (x, y) = pixel_at(0.0, 1.6);
    assert_eq!(img.px(x, y), BG, "through the torus' hole");
    let (x, y) = pixel_at(1.0, 1.6);
    assert!(
        img.px(x, y)[2] > 0.97,
        "the tube's front: {:?}",
        img.px(x, y)
    );
    let (x, y) = pixel_at(-1.0, 1.6);
    assert!(
        img.px(x, y)[2] > 0.97,
        "the tube's front: {:?}",
        img.px(x, y)
    );
    // Just outside the tube and just inside the hole's rim: background.
    let (x, y) = pixel_at(1.6, 1.6);
    assert_eq!(img.px(x, y), BG, "beside the torus");
    let (x, y) = pixel_at(0.0, 1.6 + 0.45);
    assert_eq!(img.px(x, y), BG, "inside the hole");

    // Cylinder (axis +y through x = 3.2, z = 0, radius 1): the centre ray of
    // a pixel in the middle meets the near wall; the normal is radial.
    let wall = |x: u32, y: u32, far: bool| -> Option<[f64; 3]> {
        let d = ray_dir(x, y);
        let o = [0.0 - 3.2, 0.0, EYE_Z]; // relative to the axis
        let a = d[0] * d[0] + d[2] * d[2];
        let b = o[0] * d[0] + o[2] * d[2];
        let c = o[0] * o[0] + o[2] * o[2] - 1.0;
        let disc = b * b - a * c;
        if disc < 0.0 {
            return None;
        }
        let ts = [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a];
        let t = if far { ts[1] } else { ts[0] };
        let p = [o[0] + t * d[0], t * d[1], o[2] + t * d[2]];
        (0.8..=2.4).contains(&p[1]).then_some([p[0], 0.0, p[2]])
    };
    let (x, y) = pixel_at(3.0, 1.6);
    let n = wall(x, y, false).expect("the near wall");
    assert_close(img.px(x, y), false_colour(n), 2e-4, "cylinder front");
    // Seen from below through the open bottom: the far wall from inside, its
    // outward normal pointing away from the camera.
    let x = pixel_at(3.2, 0.0).0;
    let below = (0..H).find(|&y| {
        // The ray enters the circle below the bottom rim (so it passes under
        // the near wall) and leaves it well within the height range.
        let d = ray_dir(x, y);
        let (ox, oz) = (-3.2, EYE_Z);
        let a = d[0] * d[0] + d[2] * d[2];
        let b = ox * d[0] + oz * d[2];
        let c = ox * ox + oz * oz - 1.0;
        let disc = b * b - a * c;
        if disc < 0.0 {
            return false;
        }
        let (t0, t1) = ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a);
        t0 * d[1] < 0.8 - 0.02 && (0.8 + 0.02..2.4).contains(&(t1 * d[1]))
    });
    let y = below.expect("a pixel sees into the open bottom");
    let n = wall(x, y, true).unwrap();
    assert!(n[2] < -0.9);
    assert_close(
        img.px(x, y),
        false_colour(n),
        2e-4,
        "inside of the cylinder",
    );

    // Cone (apex (−3.2, −0.6), axis −y, height 1.8, base radius 0.9, so
    // k = 0.5): its normal leans towards the apex, n_y = k/√(1 + k²).
    let (x, y) = pixel_at(-3.2, -1.6);
    let d = ray_dir(x, y);
    let o = [3.2, 0.6, EYE_Z]; // relative to the apex, y measured downwards
    let dl = [d[0], -d[1], d[2]];
    let ol = [o[0], -o[1], o[2]];
    let k2 = 0.25;
    let a = dl[0] * dl[0] + dl[2] * dl[2] - k2 * dl[1] * dl[1];
    let b = ol[0] * dl[0] + ol[2] * dl[2] - k2 * ol[1] * dl[1];
    let c = ol[0] * ol[0] + ol[2] * ol[2] - k2 * ol[1] * ol[1];
    let disc = b * b - a * c;
    let t = [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a]
        .into_iter()
        .filter(|&t| t > 0.0 && (0.0..=1.8).contains(&(ol[1] + t * dl[1])))
        .fold(f64::INFINITY, f64::min);
    let p = [ol[0] + t * dl[0], ol[1] + t * dl[1], ol[2] + t * dl[2]];
    let rho = p[0].hypot(p[2]);
    let sec = (1.0f64 + k2).sqrt();
    let n = [p[0] / rho / sec, 0.5 / sec, p[2] / rho / sec];
    assert_close(img.px(x, y), false_colour(n), 2e-4, "cone front");

    // Polygon: the L's bars show +z (its points run counter-clockwise);
    // the notch and the hole show the background.
    for (px, py, what) in [
        (-0.9, -1.2, "vertical bar"),
        (1.15, -2.2, "bottom bar"),
        (-1.0, -2.2, "corner"),
    ] {
        let (x, y) = pixel_at(px, py);
        assert_close(img.px(x, y), [0.5, 0.5, 1.0], 1e-6, what);
    }
    let (x, y) = pixel_at(0.5, -1.2);
    assert_eq!(img.px(x, y), BG, "the L's notch");
    let (x, y) = pixel_at(0.6, -2.2);
    assert_eq!(img.px(x, y), BG, "the L's hole");
    // The clockwise polygon's normal is −z.
    let (x, y) = pixel_at(3.2, -1.7);
    assert_close(img.px(x, y), [0.5, 0.5, 0.0], 1e-6, "clockwise polygon");
}

/// Replace `from` by `to` in the scene and check the error names `needles`.
fn refused(from: &str, to: &str, needles: &[&str]) {
    assert!(SCENE.contains(from), "{from}");
    let (run, img) = render_scene(&SCENE.replacen(from, to, 1), &[]);
    assert!(!run.ok, "expected a refusal for {to:?}");
    assert!(img.is_none());
    for n in needles {
        assert!(run.stderr.contains(n), "missing {n:?} in: {}", run.stderr);
    }
}

#[test]
fn each_class_refuses_bad_parameters_naming_the_key() {
    refused(
        "radius = 0.9\n\n[objects.ring]",
        "radius = -1.0\n\n[objects.ring]",
        &["objects.plate", "key `radius`", "positive"],
    );
    refused(
        "radius = 0.9\n\n[objects.ring]",
        "radius = 0.9\ninner_radius = 0.9\n\n[objects.ring]",
        &["objects.plate", "key `inner_radius`"],
    );
    refused(
        "minor_radius = 0.35",
        "minor_radius = 1.5",
        &["objects.ring", "key `minor_radius`", "ring torus"],
    );
    refused(
        "major_radius = 1.0",
        "major_radius = nan",
        &["objects.ring", "key `major_radius`"],
    );
    refused(
        "height = 1.6\nradius = 1.0",
        "height = 1.6\nradius = -1.0",
        &["objects.pipe", "key `radius`", "positive"],
    );
    refused(
        "axis = [0.0, 1.0, 0.0]",
        "axis = [0.0, 0.0, 0.0]",
        &["objects.pipe", "key `axis`"],
    );
    refused(
        "axis = [0.0, -1.8, 0.0]",
        "axis = [0.0, -1.8, 0.0]\nheight = 0.0",
        &["objects.spike", "key `height`"],
    );
    refused(
        "radius = 0.9\n\n[objects.ell]",
        "radius = -1.0\n\n[objects.ell]",
        &["objects.spike", "key `radius`"],
    );
    // A point off the plane of the others (z = 0.5): named by its index.
    refused(
        "[-0.4, -0.6, 0.0]",
        "[-0.4, -0.6, 0.5]",
        &["objects.ell", "key `points[4]`", "coplanar"],
    );
    refused(
        "[0.9, -2.0, 0.0]",
        "[0.9, -2.0, 0.3]",
        &["objects.ell", "key `holes[0][2]`", "coplanar"],
    );
    refused(
        "points = [[2.6, -1.0, 0.0], [3.8, -1.0, 0.0], [3.8, -2.2, 0.0], [3.2, -2.6, 0.0], [2.6, -2.2, 0.0]]",
        "points = [[2.6, -1.0, 0.0], [3.8, -1.0, 0.0]]",
        &["objects.back", "key `points`", "at least 3"],
    );
    refused(
        "points = [[2.6, -1.0, 0.0], [3.8, -1.0, 0.0], [3.8, -2.2, 0.0], [3.2, -2.6, 0.0], [2.6, -2.2, 0.0]]",
        "points = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]",
        &["objects.back", "key `points`", "no area"],
    );
}
