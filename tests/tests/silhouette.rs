//! A sphere's silhouette covers exactly the analytically expected pixels,
//! through `list` and directly as the root; threads do not change the image.

use rtk_tests::*;

const W: u32 = 64;
const H: u32 = 48;
const FOV_Y: f64 = 40.0;
const EYE_Z: f64 = 5.0;

fn scene(root: &str) -> String {
    format!(
        r#"
[render]
width = {W}
height = {H}
root = "{root}"
integrator = "normals"

[cameras.main]
class = "pinhole"
eye = [0.0, 0.0, {EYE_Z}]
look_at = [0.0, 0.0, 0.0]
fov_y = {FOV_Y}

[objects.ball]
class = "sphere"
radius = 1.0

[objects.world]
class = "list"
children = ["ball"]
"#
    )
}

/// Distance from the sphere's centre to the camera ray through film point (fx, fy), in f64.
fn miss_distance(fx: f64, fy: f64) -> f64 {
    let t = (FOV_Y.to_radians() * 0.5).tan();
    let aspect = W as f64 / H as f64;
    let d = [(2.0 * fx - 1.0) * t * aspect, (1.0 - 2.0 * fy) * t, -1.0];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let d = d.map(|c| c / len);
    // |eye × d| with eye = (0, 0, EYE_Z)
    let c = [-EYE_Z * d[1], EYE_Z * d[0], 0.0];
    (c[0] * c[0] + c[1] * c[1]).sqrt()
}

fn check_silhouette(img: &Image) {
    let (mut inside, mut outside, mut ring) = (0, 0, 0);
    for y in 0..H {
        for x in 0..W {
            let centre = miss_distance((x as f64 + 0.5) / W as f64, (y as f64 + 0.5) / H as f64);
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(a, b)| miss_distance((x as f64 + a) / W as f64, (y as f64 + b) / H as f64));
            let hit = img.px(x, y).iter().any(|&c| c > 0.0);
            if corners.iter().all(|&d| d < 1.0) {
                assert!(
                    hit,
                    "pixel ({x},{y}) lies inside the silhouette but was missed"
                );
                inside += 1;
            } else if corners.iter().all(|&d| d > 1.0) {
                assert!(
                    !hit,
                    "pixel ({x},{y}) lies outside the silhouette but was hit"
                );
                outside += 1;
            } else {
                // The boundary ring: the pixel centre decides (rendered at 1 spp).
                assert_eq!(
                    hit,
                    centre < 1.0,
                    "ring pixel ({x},{y}) disagrees with its centre"
                );
                ring += 1;
            }
        }
    }
    assert!(
        inside > 100 && outside > 100 && ring > 10,
        "{inside} {outside} {ring}"
    );
}

#[test]
fn sphere_silhouette_through_list() {
    let (run, img) = render_scene(&scene("world"), &[]);
    assert!(run.ok, "{}", run.stderr);
    check_silhouette(&img.unwrap());
}

#[test]
fn sphere_silhouette_as_root() {
    let (run, img) = render_scene(&scene("ball"), &[]);
    assert!(run.ok, "{}", run.stderr);
    check_silhouette(&img.unwrap());
}

#[test]
fn normals_face_the_camera() {
    // At the image centre the sphere's normal is (0, 0, 1): colour (0.5, 0.5, 1).
    let (run, img) = render_scene(
        &scene("ball"),
        &["--set", "render.width=63", "--set", "render.height=63"],
    );
    assert!(run.ok, "{}", run.stderr);
    let p = img.unwrap().px(31, 31);
    for (c, e) in p.iter().zip([0.5, 0.5, 1.0]) {
        assert!((c - e).abs() < 1e-3, "{p:?}");
    }
}

#[test]
fn one_and_two_threads_give_identical_images() {
    let s = scene("world");
    let (a, ia) = render_scene(&s, &["--threads", "1", "--spp", "4"]);
    let (b, ib) = render_scene(&s, &["--threads", "2", "--spp", "4"]);
    assert!(a.ok && b.ok, "{} {}", a.stderr, b.stderr);
    let (ia, ib) = (ia.unwrap(), ib.unwrap());
    assert!(ia
        .data
        .iter()
        .zip(&ib.data)
        .all(|(x, y)| x.to_bits() == y.to_bits()));
    // And jittered samples really were taken (the edge is antialiased).
    assert!(ia.data.iter().any(|&v| v > 0.0 && v < 0.4));
}
