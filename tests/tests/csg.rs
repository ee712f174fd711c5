//! The `csg` class against closed forms: volumes by ray parity, and the
//! tie rule (A − A is empty, A ∪ A and A ∩ A are A).

use rtk_tests::*;

const SPHERES: &str = r#"
[objects.ball]
class = "sphere"
radius = 1.0
"#;

fn csg(op: &str, b_shift: f64) -> String {
    format!(
        r#"
[objects.node]
class = "csg"
op = "{op}"
children = ["ball", {{ object = "ball", transform = [{{ translate = [{b_shift}, 0.0, 0.0] }}] }}]
"#
    )
}

fn render_flat(objects: &str, root: &str) -> Image {
    let scene = format!(
        r#"
[render]
width = 40
height = 40
root = {{ object = "{root}", shader = "white" }}
background = [0.0, 0.0, 0.0]
integrator = {{ class = "whitted" }}
[cameras.c]
class = "pinhole"
eye = [0.3, 0.4, 5.0]
fov_y = 40.0
[shaders.white]
class = "flat"
color = [1.0, 1.0, 1.0]
{SPHERES}
{objects}
"#
    );
    let (run, img) = render_scene(&scene, &[]);
    assert!(run.ok, "{}", run.stderr);
    img.unwrap()
}

/// Coincident surfaces cross together: A − A shows nothing, A ∪ A and
/// A ∩ A show exactly A.
#[test]
fn a_minus_a_is_empty_and_a_with_a_is_a() {
    let plain = render_flat("", "ball");
    assert!(plain.data.contains(&1.0));
    let empty = render_flat(&csg("difference", 0.0), "node");
    assert!(empty.data.iter().all(|&v| v == 0.0), "A − A is not empty");
    for op in ["union", "intersection"] {
        let img = render_flat(&csg(op, 0.0), "node");
        assert_eq!(img.data, plain.data, "A {op} A differs from A");
    }
}

/// Volume of a CSG solid by ray parity: rays along z through a 400×400
/// grid, each walked through its crossings (the ray again from its last
/// hit), the lengths inside summed; against the closed forms for two unit
/// spheres 0.8 apart: their lens π(4R + d)(2R − d)²/12, A − B the sphere
/// less the lens, A ∪ B two spheres less the lens. The grid's error on a
/// smooth boundary is well under 1 %.
#[test]
fn volumes_by_ray_parity_match_the_closed_forms() {
    let d = 0.8f64;
    let lens = std::f64::consts::PI * (4.0 + d) * (2.0 - d).powi(2) / 12.0;
    let ball = 4.0 / 3.0 * std::f64::consts::PI;
    for (op, expected) in [
        ("intersection", lens),
        ("difference", ball - lens),
        ("union", 2.0 * ball - lens),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene.toml");
        std::fs::write(
            &scene,
            format!(
                "[render]\nroot = \"node\"\n[cameras.c]\nclass = \"pinhole\"\n{SPHERES}{}",
                csg(op, d)
            ),
        )
        .unwrap();
        let n = 400usize;
        let (lo, hi) = (-1.5f64, 2.3f64);
        let cell = (hi - lo) / n as f64;
        let mut t_from = vec![0.0f32; n * n];
        let mut inside = vec![0.0f64; n * n];
        let mut crossings = vec![0u32; n * n];
        for _ in 0..6 {
            let mut rays = Vec::with_capacity(n * n * 32);
            for (i, &t0) in t_from.iter().enumerate() {
                let (x, y) = (
                    lo + (i % n) as f64 * cell + cell / 2.0,
                    -1.9 + (i / n) as f64 * (3.8 / n as f64) + 1.9 / n as f64,
                );
                for v in [x as f32, y as f32, -5.0, 0.0, 0.0, 1.0, t0, f32::INFINITY] {
                    rays.extend_from_slice(&v.to_le_bytes());
                }
            }
            let (rf, hf) = (dir.path().join("rays.bin"), dir.path().join("hits.bin"));
            std::fs::write(&rf, rays).unwrap();
            let out = rtk(&[
                "trace",
                scene.to_str().unwrap(),
                "--rays",
                rf.to_str().unwrap(),
                "--out",
                hf.to_str().unwrap(),
            ])
            .output()
            .unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let hits = std::fs::read(&hf).unwrap();
            for (i, t0) in t_from.iter_mut().enumerate() {
                let t = f32::from_le_bytes(hits[16 * i..16 * i + 4].try_into().unwrap());
                if t.is_finite() {
                    if crossings[i] % 2 == 1 {
                        inside[i] += (t - *t0) as f64;
                    }
                    crossings[i] += 1;
                    *t0 = t;
                } else {
                    *t0 = f32::INFINITY;
                }
            }
            for t in t_from.iter_mut() {
                if !t.is_finite() {
                    *t = 1e30;
                }
            }
        }
        assert!(
            crossings.iter().all(|c| c % 2 == 0),
            "{op}: a ray left the solid inside"
        );
        let volume: f64 = inside.iter().sum::<f64>() * cell * (3.8 / n as f64);
        let err = (volume - expected).abs() / expected;
        assert!(
            err < 0.01,
            "{op}: volume {volume} vs {expected} ({err:.4} relative)"
        );
    }
}
