//! The `fractal` and `bicubic` classes through the real binary: the
//! landscape through a bvh against every triangle tested (`accel = "none"`),
//! the teapot rendered with no hole, and both refusing bad parameters with
//! the key named.

use rtk_tests::*;

fn landscape(accel: &str, levels: u32) -> String {
    format!(
        r#"
[render]
width = 96
height = 64
root = "world"
integrator = "normals"
background = [0.1, 0.2, 0.3]

[cameras.main]
class = "pinhole"
eye = [0.0, 6.0, 12.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 50.0

[objects.land]
class = "fractal"
seed = 3
size = [12.0, 12.0]
levels = {levels}
height = 3.0
roughness = 0.6
center = [0.0, -1.0, 0.0]
accel = "{accel}"

[objects.world]
class = "list"
children = ["land"]
"#
    )
}

#[test]
fn fractal_through_a_bvh_matches_brute_force() {
    let (run_b, bvh) = render_scene(&landscape("bvh", 5), &[]);
    assert!(run_b.ok, "{}", run_b.stderr);
    let (run_n, none) = render_scene(&landscape("none", 5), &[]);
    assert!(run_n.ok, "{}", run_n.stderr);
    let (bvh, none) = (bvh.expect("image"), none.expect("image"));
    let differ = (0..bvh.height)
        .flat_map(|y| (0..bvh.width).map(move |x| (x, y)))
        .filter(|&(x, y)| bvh.px(x, y) != none.px(x, y))
        .count();
    assert_eq!(differ, 0, "pixels differing between bvh and brute force");
    // The landscape fills a good part of the view (about a quarter), and is
    // the same on a re-run.
    let bg = (0..bvh.height)
        .flat_map(|y| (0..bvh.width).map(move |x| (x, y)))
        .filter(|&(x, y)| bvh.px(x, y) == [0.1, 0.2, 0.3])
        .count();
    assert!(
        bg < (bvh.width * bvh.height * 9 / 10) as usize,
        "{bg} background pixels"
    );
    let (_, again) = render_scene(&landscape("bvh", 5), &[]);
    assert_eq!(again.expect("image"), bvh, "deterministic for a seed");
}

#[test]
fn fractal_refuses_too_many_levels_naming_the_key() {
    let (run, _) = render_scene(&landscape("bvh", 13), &[]);
    assert!(!run.ok);
    assert!(run.stderr.contains("levels"), "{}", run.stderr);
}

fn teapot(file: &str) -> String {
    format!(
        r#"
[render]
width = 96
height = 72
root = "world"
integrator = "normals"
background = [0.1, 0.2, 0.3]

[cameras.main]
class = "pinhole"
eye = [0.0, 3.0, 9.0]
look_at = [0.0, 1.3, 0.0]
fov_y = 30.0

[objects.teapot]
class = "bicubic"
file = "{file}"

[objects.world]
class = "list"
children = [{{ object = "teapot", transform = [{{ rotate_x = -90.0 }}] }}]
"#
    )
}

#[test]
fn teapot_renders_without_holes_or_nans() {
    let file = root().join("scenes/meshes/teapot.bpt");
    let (run, img) = render_scene(&teapot(file.to_str().expect("utf8")), &[]);
    assert!(run.ok, "{}", run.stderr);
    let img = img.expect("image");
    assert!(img.data.iter().all(|x| x.is_finite()));
    // The body's middle, a column through the pot: no background pixel
    // between the body's top and bottom rows at the centre.
    let x = img.width / 2;
    let rows: Vec<u32> = (0..img.height)
        .filter(|&y| img.px(x, y) != [0.1, 0.2, 0.3])
        .collect();
    assert!(
        rows.len() > 30,
        "{} teapot pixels in the centre column",
        rows.len()
    );
    let (lo, hi) = (rows[0], *rows.last().expect("rows"));
    assert_eq!(
        rows.len() as u32,
        hi - lo + 1,
        "a hole in the centre column"
    );
}

#[test]
fn bicubic_refuses_a_missing_file_naming_the_key() {
    let (run, _) = render_scene(&teapot("no/such/teapot.bpt"), &[]);
    assert!(!run.ok);
    assert!(run.stderr.contains("file"), "{}", run.stderr);
}

const GROUP_HEAD: &str = r#"
[render]
width = 64
height = 48
root = "world"
background = [0.1, 0.1, 0.1]
integrator = { class = "whitted" }
[cameras.c]
class = "pinhole"
eye = [0.0, 1.0, 6.0]
look_at = [0.0, 0.5, 0.0]
[lights.l]
class = "directional"
direction = [-0.3, -1.0, -0.4]
[shaders.red]
class = "lambert"
albedo = [0.8, 0.2, 0.1]
[shaders.blue]
class = "lambert"
albedo = [0.1, 0.2, 0.8]
[objects.ball]
class = "sphere"
radius = 0.4
"#;

/// A macro group instanced twice (one rotated), a member binding its own
/// shader and one taking the instance's, inside a nested group: the same
/// image, bit for bit, and the same objects created, as the four spheres
/// written out with their transforms concatenated.
#[test]
fn groups_expand_into_their_parents() {
    let grouped = format!(
        r#"{GROUP_HEAD}
[objects.left]
class = "group"
children = [{{ object = "ball", transform = [{{ translate = [-0.5, 0.4, 0.0] }}] }}]
[objects.pair]
class = "group"
children = [
  "left",
  {{ object = "ball", shader = "blue", transform = [{{ translate = [0.5, 0.4, 0.0] }}] }},
]
[objects.world]
class = "bvh"
children = [
  {{ object = "pair", shader = "red", transform = [{{ translate = [-1.2, 0.0, 0.0] }}] }},
  {{ object = "pair", shader = "red", transform = [{{ rotate_y = 90.0 }}, {{ translate = [1.2, 0.0, 0.0] }}] }},
]
"#
    );
    let flat = format!(
        r#"{GROUP_HEAD}
[objects.world]
class = "bvh"
children = [
  {{ object = "ball", shader = "red", transform = [{{ translate = [-0.5, 0.4, 0.0] }}, {{ translate = [-1.2, 0.0, 0.0] }}] }},
  {{ object = "ball", shader = "blue", transform = [{{ translate = [0.5, 0.4, 0.0] }}, {{ translate = [-1.2, 0.0, 0.0] }}] }},
  {{ object = "ball", shader = "red", transform = [{{ translate = [-0.5, 0.4, 0.0] }}, {{ rotate_y = 90.0 }}, {{ translate = [1.2, 0.0, 0.0] }}] }},
  {{ object = "ball", shader = "blue", transform = [{{ translate = [0.5, 0.4, 0.0] }}, {{ rotate_y = 90.0 }}, {{ translate = [1.2, 0.0, 0.0] }}] }},
]
"#
    );
    let (run_g, img_g) = render_scene(&grouped, &["--stats"]);
    assert!(run_g.ok, "{}", run_g.stderr);
    let (run_f, img_f) = render_scene(&flat, &["--stats"]);
    assert!(run_f.ok, "{}", run_f.stderr);
    assert_eq!(img_g.unwrap().data, img_f.unwrap().data);
    assert_eq!(
        run_g.stats()["objects_created"],
        run_f.stats()["objects_created"]
    );
}

/// A group is not an object: it cannot be the root, and takes no parameters.
#[test]
fn groups_are_refused_where_they_cannot_be() {
    let group = "[objects.g]\nclass = \"group\"\nchildren = [\"ball\"]\n";
    let root = format!("{GROUP_HEAD}{group}").replace("root = \"world\"", "root = \"g\"");
    let (run, img) = render_scene(&root, &[]);
    assert!(!run.ok && img.is_none());
    assert!(run.stderr.contains("is a group"), "{}", run.stderr);
    let params = format!(
        "{GROUP_HEAD}[objects.g]\nclass = \"group\"\nradius = 2.0\nchildren = [\"ball\"]\n[objects.world]\nclass = \"list\"\nchildren = [\"g\"]\n"
    );
    let (run, _) = render_scene(&params, &[]);
    assert!(!run.ok);
    assert!(
        run.stderr.contains("objects.g")
            && run.stderr.contains("radius")
            && run.stderr.contains("only `children`"),
        "{}",
        run.stderr
    );
}
