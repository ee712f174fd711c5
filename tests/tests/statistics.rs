//! `rtk render --variance` and the statistical tests of `rtk diff`
//! (`--ztest`, `--welch`; issue 23, item 4): the variance an image reports
//! is the spread its pixels show across seeds, two renders of one scene
//! pass, and a 2 % brighter light fails.

use rtk_tests::*;
use std::path::Path;

/// Two lambert spheres under a sun whose irradiance is the scene parameter
/// `sun`; `path` with two segments is direct lighting, so the per-sample
/// variance is small (edges and the sphere's silhouette) and a small bias
/// shows.
const SCENE: &str = r#"
[params]
sun = [1.0, 1.0, 1.0]

[render]
width = 32
height = 24
spp = 64
filter = "box"
camera = "main"
root = "world"
integrator = { class = "path", max_depth = 2 }

[cameras.main]
class = "pinhole"
eye = [0.0, 1.0, 6.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0

[lights.sun]
class = "directional"
direction = [-0.3, -1.0, -0.4]
irradiance = "$sun"

[shaders.clay]
class = "lambert"
albedo = [0.8, 0.6, 0.4]

[objects.ball]
class = "sphere"
radius = 1.0

[objects.world]
class = "list"
children = [
  { object = "ball", shader = "clay" },
  { object = "ball", shader = "clay", transform = [{ scale = 100.0 }, { translate = [0.0, -101.0, 0.0] }] },
]
"#;

fn render(dir: &Path, name: &str, args: &[&str]) -> Run {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let out = dir.join(format!("{name}.exr"));
    let var = dir.join(format!("{name}_var.exr"));
    let mut all = vec![
        "render",
        scene.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--variance",
        var.to_str().unwrap(),
    ];
    all.extend_from_slice(args);
    let r = Run::from(rtk(&all).output().unwrap());
    assert!(r.ok, "{}", r.stderr);
    r
}

#[test]
fn the_variance_image_is_the_spread_of_pixels_across_seeds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    render(d, "deep", &["--spp", "1024", "--set", "render.seed=100"]);
    let var = Image::read(&d.join("deep_var.exr"));
    // K renders of n samples: each pixel's mean varies by var / n.
    let (k, n) = (12, 16.0);
    let means: Vec<Image> = (0..k)
        .map(|s| {
            let seed = format!("render.seed={s}");
            render(d, "m", &["--spp", "16", "--set", &seed]);
            Image::read(&d.join("m.exr"))
        })
        .collect();
    let (mut predicted, mut seen) = (0.0f64, 0.0f64);
    for i in 0..var.data.len() {
        let xs: Vec<f64> = means.iter().map(|m| m.data[i] as f64).collect();
        let mu = xs.iter().sum::<f64>() / k as f64;
        let s2 = xs.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (k - 1) as f64;
        predicted += var.data[i] as f64 / n;
        seen += s2;
    }
    // Summed over 2304 pixel-channels of 11 degrees of freedom each, the
    // ratio's standard deviation is a few per cent (more where the
    // variance concentrates in few pixels).
    let ratio = seen / predicted;
    assert!(predicted > 0.0);
    assert!(
        (ratio - 1.0).abs() < 0.15,
        "seen {seen}, predicted {predicted}: ratio {ratio}"
    );
}

#[test]
fn welch_passes_two_seeds_and_fails_a_two_percent_brighter_sun() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let p = |n: &str| d.join(n).to_str().unwrap().to_string();
    render(d, "a", &["--spp", "256", "--set", "render.seed=1"]);
    render(d, "b", &["--spp", "256", "--set", "render.seed=2"]);
    let welch = |b: &str| {
        Run::from(
            rtk(&[
                "diff",
                &p("a.exr"),
                &p(&format!("{b}.exr")),
                "--welch",
                &p("a_var.exr"),
                &p(&format!("{b}_var.exr")),
                "--spp-a",
                "256",
                "--spp-b",
                "256",
                "--pmap",
                &p("pmap.png"),
            ])
            .output()
            .unwrap(),
        )
    };
    let same = welch("b");
    assert!(same.ok, "{}\n{}", same.stdout, same.stderr);
    assert!(same.stdout.contains("\npass\n"), "{}", same.stdout);
    assert!(Image::read(&d.join("pmap.png")).width == 32);
    render(
        d,
        "bright",
        &[
            "--spp",
            "256",
            "--set",
            "render.seed=2",
            "--set",
            "params.sun=[1.02, 1.02, 1.02]",
        ],
    );
    let biased = welch("bright");
    assert!(!biased.ok, "{}", biased.stdout);
    assert!(biased.stdout.contains("\nFAIL\n"), "{}", biased.stdout);
    // The z-test of an image against itself as a reference cannot fail;
    // against the brighter render it does.
    let z = |b: &str| {
        Run::from(
            rtk(&[
                "diff",
                &p(b),
                &p("b.exr"),
                "--ztest",
                &p("b_var.exr"),
                "--spp",
                "256",
            ])
            .output()
            .unwrap(),
        )
    };
    assert!(z("b.exr").ok);
    assert!(!z("bright.exr").ok);
}

#[test]
fn variance_and_pmap_paths_are_checked_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let s = scene.to_str().unwrap();
    let x = dir.path().join("x.exr");
    let r = Run::from(
        rtk(&[
            "render",
            s,
            "-o",
            x.to_str().unwrap(),
            "--variance",
            "v.png",
        ])
        .output()
        .unwrap(),
    );
    assert!(!r.ok);
    assert!(
        r.stderr
            .contains("--variance v.png: the variance is written as linear floats"),
        "{}",
        r.stderr
    );
    assert!(!x.exists());
    let r = Run::from(
        rtk(&["render", s, "--set", "params.sunn=[1,1,1]"])
            .output()
            .unwrap(),
    );
    assert!(!r.ok);
    assert!(
        r.stderr
            .contains("the scene declares no parameter `sunn` in [params]"),
        "{}",
        r.stderr
    );
}
