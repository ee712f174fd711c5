//! Shading against closed forms, and what a Whitted render skips.

use rtk_tests::*;
use std::f64::consts::PI;

const N: u32 = 64;
const FOV_Y: f64 = 40.0;
const EYE_Z: f64 = 5.0;
const ALBEDO: f64 = 0.5;
const E: f64 = 2.0;
const BLOCKER_R: f64 = 0.3;

/// A unit Lambert sphere lit by a directional light coming from (1, 0, 1), a
/// small blocker sphere 3 units towards the light casting a cylindrical
/// shadow of radius 0.3 on the side facing the camera.
fn scene() -> String {
    format!(
        r#"
[render]
width = {N}
height = {N}
root = "world"
integrator = "whitted"
[cameras.main]
class = "pinhole"
eye = [0.0, 0.0, {EYE_Z}]
look_at = [0.0, 0.0, 0.0]
fov_y = {FOV_Y}
[lights.sun]
class = "directional"
direction = [-1.0, 0.0, -1.0]
irradiance = [{E}, {E}, {E}]
[shaders.matte]
class = "lambert"
albedo = [{ALBEDO}, {ALBEDO}, {ALBEDO}]
[objects.ball]
class = "sphere"
[objects.blocker]
class = "sphere"
center = [2.1213203, 0.0, 2.1213203]
radius = {BLOCKER_R}
[objects.world]
class = "list"
children = [{{ object = "ball", shader = "matte" }}, {{ object = "blocker", shader = "matte" }}]
"#
    )
}

/// The unit-sphere hit point of the camera ray through pixel (x, y)'s centre, in f64.
fn hit_point(x: u32, y: u32) -> Option<[f64; 3]> {
    let t = (FOV_Y.to_radians() * 0.5).tan();
    let d = [
        (2.0 * (x as f64 + 0.5) / N as f64 - 1.0) * t,
        (1.0 - 2.0 * (y as f64 + 0.5) / N as f64) * t,
        -1.0,
    ];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let d = d.map(|c| c / l);
    let o = [0.0, 0.0, EYE_Z];
    let b = o[2] * d[2];
    let c = EYE_Z * EYE_Z - 1.0;
    let disc = b * b - c;
    // Stay clear of the silhouette.
    if disc < 0.05 {
        return None;
    }
    let t = -b - disc.sqrt();
    Some([o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]])
}

#[test]
fn lambert_sphere_matches_albedo_over_pi_times_e_cos_theta() {
    let (run, img) = render_scene(&scene(), &["--stats"]);
    assert!(run.ok, "{}", run.stderr);
    let _ = run;
    let img = img.unwrap();
    let (mut lit, mut shadowed, mut dark) = (0, 0, 0);
    for y in 0..N {
        for x in 0..N {
            let Some(p) = hit_point(x, y) else { continue };
            let px = img.px(x, y);
            let a = std::f64::consts::FRAC_1_SQRT_2;
            let cos = p[0] * a + p[2] * a; // n · (towards the light)
            let along = [cos * a, 0.0, cos * a];
            let r_cyl =
                ((p[0] - along[0]).powi(2) + p[1].powi(2) + (p[2] - along[2]).powi(2)).sqrt();
            if cos > 0.0 && (r_cyl - BLOCKER_R).abs() < 0.02 {
                continue; // the shadow's edge
            }
            let expected = if cos > 0.0 && r_cyl < BLOCKER_R {
                shadowed += 1;
                0.0
            } else {
                if cos > 0.0 {
                    lit += 1;
                } else {
                    dark += 1;
                }
                ALBEDO / PI * E * cos.max(0.0)
            };
            for c in px {
                if expected == 0.0 {
                    assert_eq!(c, 0.0, "pixel ({x},{y}) at {p:?} must be exactly black");
                } else {
                    assert!(
                        (c as f64 - expected).abs() <= 1e-4 * expected + 1e-6,
                        "pixel ({x},{y}): {c} vs {expected}"
                    );
                }
            }
        }
    }
    assert!(
        lit > 300 && shadowed > 30 && dark > 30,
        "{lit} {shadowed} {dark}"
    );
}

#[test]
fn bunny_scene_skips_what_it_does_not_need() {
    let scene = root().join("scenes/bunny.toml");
    let dir = tempfile::tempdir().unwrap();
    let (run, _) = render_file(
        &scene,
        dir.path(),
        &[
            "--stats",
            "--set",
            "render.width=128",
            "--set",
            "render.height=96",
            // An unused mesh definition whose file does not even exist.
            "--set",
            "objects.unused.class=mesh",
            "--set",
            "objects.unused.file=meshes/does-not-exist.ply",
        ],
    );
    assert!(run.ok, "{}", run.stderr);
    let s = run.stats();
    let files: Vec<&str> = s["files_read"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert_eq!(files.len(), 2, "{files:?}");
    assert!(
        files.iter().any(|f| f.ends_with("meshes/bunny.ply"))
            && files.iter().any(|f| f.ends_with("meshes/floor.obj"))
    );
    let rays = &s["rays"];
    let (camera, shadow) = (
        rays["camera"].as_u64().unwrap(),
        rays["shadow"].as_u64().unwrap(),
    );
    let traced =
        camera + rays["reflection"].as_u64().unwrap() + rays["refraction"].as_u64().unwrap();
    assert_eq!(camera, 128 * 96);
    // Two lights: many more shadow rays than traced rays...
    assert!(shadow > traced, "{shadow} {traced}");
    // ...yet at most one local-geometry request per traced ray: none for shadow rays.
    let lg = &s["local_geom"];
    assert!(lg["calls"].as_u64().unwrap() <= traced);
    assert!(lg["calls"].as_u64().unwrap() > 0);
    // Whitted asks for position and normals, never uv or tangents.
    assert_eq!(lg["uv"], 0);
    assert_eq!(lg["tangents"], 0);
    assert_eq!(lg["position"], lg["calls"]);
    // The list, the two meshes, and the `bvh` the shell builds over each
    // mesh (their `accel`: a `list` does not flatten primitive sets).
    assert_eq!(s["objects_created"], 6);
}

/// A closed octahedron as OBJ text, its vertices mapped by `f`.
fn octahedron(f: impl Fn([f64; 3]) -> [f64; 3]) -> String {
    let v = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    let faces = [
        [1, 3, 5],
        [3, 2, 5],
        [2, 4, 5],
        [4, 1, 5],
        [3, 1, 6],
        [2, 3, 6],
        [4, 2, 6],
        [1, 4, 6],
    ];
    let mut s = String::new();
    for p in v {
        let q = f(p);
        s += &format!("v {:.9} {:.9} {:.9}\n", q[0], q[1], q[2]);
    }
    for t in faces {
        s += &format!("f {} {} {}\n", t[0], t[1], t[2]);
    }
    s
}

/// (scale, rotate_y degrees, translate) of each instance.
const PLACES: [(f64, f64, [f64; 3]); 4] = [
    (0.5, 0.0, [-1.2, 0.3, 0.0]),
    (0.7, 30.0, [0.6, -0.4, 0.3]),
    (0.3, 75.0, [0.2, 0.9, -1.0]),
    (0.45, 200.0, [1.4, 0.8, -0.5]),
];

#[test]
fn instanced_mesh_matches_baked_copies() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("octa.obj"), octahedron(|p| p)).unwrap();
    let mut inst = Vec::new();
    let mut baked_defs = String::new();
    let mut baked = Vec::new();
    for (i, (s, ry, t)) in PLACES.iter().enumerate() {
        inst.push(format!(
            "{{ object = \"octa\", transform = [{{ scale = {s} }}, {{ rotate_y = {ry} }}, {{ translate = [{}, {}, {}] }}] }}",
            t[0], t[1], t[2]
        ));
        let (sn, cs) = ry.to_radians().sin_cos();
        let obj = octahedron(|p| {
            let q = [p[0] * s, p[1] * s, p[2] * s];
            [
                cs * q[0] + sn * q[2] + t[0],
                q[1] + t[1],
                -sn * q[0] + cs * q[2] + t[2],
            ]
        });
        std::fs::write(dir.path().join(format!("baked{i}.obj")), obj).unwrap();
        baked_defs += &format!("[objects.b{i}]\nclass = \"mesh\"\nfile = \"baked{i}.obj\"\n");
        baked.push(format!("\"b{i}\""));
    }
    let head = "[render]\nwidth = 96\nheight = 96\nroot = \"world\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\neye = [0.0, 0.5, 6.0]\n\
                [objects.octa]\nclass = \"mesh\"\nfile = \"octa.obj\"\n";
    let a = format!(
        "{head}[objects.world]\nclass = \"list\"\nchildren = [{}]\n",
        inst.join(", ")
    );
    let b = format!(
        "{head}{baked_defs}[objects.world]\nclass = \"list\"\nchildren = [{}]\n",
        baked.join(", ")
    );
    let pa = dir.path().join("a.toml");
    let pb = dir.path().join("b.toml");
    std::fs::write(&pa, a).unwrap();
    std::fs::write(&pb, b).unwrap();
    let (ra, ia) = render_file(&pa, dir.path(), &["--stats"]);
    assert!(ra.ok, "{}", ra.stderr);
    let ia = ia.unwrap();
    let (rb, ib) = render_file(&pb, dir.path(), &[]);
    assert!(rb.ok, "{}", rb.stderr);
    let ib = ib.unwrap();
    // One mesh, its one `bvh` (shared by every instance), four transforms,
    // one list: seven objects.
    assert_eq!(ra.stats()["objects_created"], 7);
    let mut differ = 0;
    let mut covered = 0;
    for (pa, pb) in ia.data.chunks(3).zip(ib.data.chunks(3)) {
        if pa.iter().any(|&v| v > 0.0) {
            covered += 1;
        }
        if pa.iter().zip(pb).any(|(x, y)| (x - y).abs() > 1e-3) {
            differ += 1;
        }
    }
    // Only silhouette pixels may flip (instance rays and baked vertices round differently).
    assert!(covered > 500, "{covered}");
    assert!(
        differ * 100 < covered,
        "{differ} of {covered} pixels differ"
    );
}

#[test]
fn ply_ascii_binary_and_obj_read_the_same_mesh() {
    let dir = tempfile::tempdir().unwrap();
    // The floor quad as ASCII PLY, with the OBJ's vertices and triangles.
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
               element face 2\nproperty list uchar int vertex_indices\nend_header\n\
               -0.5 0 -0.5\n0.5 0 -0.5\n0.5 0 0.5\n-0.5 0 0.5\n3 0 3 2\n3 0 2 1\n";
    std::fs::write(dir.path().join("quad.ply"), ply).unwrap();
    std::fs::copy(
        root().join("scenes/meshes/floor.obj"),
        dir.path().join("quad.obj"),
    )
    .unwrap();
    let scene = |file: &str| {
        format!(
            "[render]\nwidth = 48\nheight = 48\nroot = \"q\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\neye = [0.3, 1.5, 1.0]\n\
             [objects.q]\nclass = \"mesh\"\nfile = \"{file}\"\n"
        )
    };
    let render = |file: &str| {
        let p = dir.path().join(format!("{file}.toml"));
        std::fs::write(&p, scene(file)).unwrap();
        let (r, i) = render_file(&p, dir.path(), &[]);
        assert!(r.ok, "{}", r.stderr);
        i.unwrap()
    };
    let a = render("quad.ply");
    let b = render("quad.obj");
    assert_eq!(a, b);
    assert!(a.data.iter().any(|&v| v > 0.0));
    // The shared binary PLY and OBJ of the bunny hold bit-identical floats.
    if let Some(obj) = shared("data/meshes/bunny.obj") {
        std::fs::copy(obj, dir.path().join("bunny.obj")).unwrap();
        std::fs::copy(
            root().join("scenes/meshes/bunny.ply"),
            dir.path().join("bunny.ply"),
        )
        .unwrap();
        let s = |f: &str| {
            scene(f).replace(
                "eye = [0.3, 1.5, 1.0]",
                "eye = [0.0, 5.0, 25.0]\nlook_at = [0.0, 4.0, 0.0]",
            )
        };
        let r = |f: &str| {
            let p = dir.path().join(format!("{f}.toml"));
            std::fs::write(&p, s(f)).unwrap();
            render_file(&p, dir.path(), &[]).1.unwrap()
        };
        assert_eq!(r("bunny.ply"), r("bunny.obj"));
    }
}

#[test]
fn bad_mesh_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("bad.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
    )
    .unwrap();
    let scene = "[render]\nwidth = 8\nheight = 8\nroot = \"m\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n\
                 [objects.m]\nclass = \"mesh\"\nfile = \"FILE\"\n";
    for (file, needle) in [
        ("bad.obj", "bad.obj: line 4: vertex index 7 is out of range"),
        ("missing.ply", "cannot read"),
        ("x.stl", "use .ply or .obj"),
    ] {
        let p = dir.path().join("s.toml");
        std::fs::write(&p, scene.replace("FILE", file)).unwrap();
        let (r, _) = render_file(&p, dir.path(), &[]);
        assert!(!r.ok);
        assert!(
            r.stderr.contains(needle)
                && r.stderr.contains("objects.m")
                && r.stderr.contains("key `file`"),
            "{}",
            r.stderr
        );
        assert!(r.stderr.contains("s.toml:10:8"), "{}", r.stderr);
    }
}
