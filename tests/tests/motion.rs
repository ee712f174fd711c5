//! The `motion` class: poses exactly at their keyframes, and motion blur
//! whose image is the time average of the poses.

use rtk_tests::*;

fn scene(world: &str, shutter: [f32; 2], spp: u32) -> String {
    format!(
        r#"
[render]
width = 48
height = 32
spp = {spp}
filter = "box"
sampler = "stratified"
shutter = [{}, {}]
root = "world"
background = [0.0, 0.0, 0.0]
integrator = {{ class = "whitted" }}
[cameras.c]
class = "pinhole"
eye = [0.0, 0.0, 6.0]
fov_y = 40.0
[shaders.white]
class = "flat"
color = [1.0, 1.0, 1.0]
[objects.ball]
class = "sphere"
radius = 0.5
{world}
"#,
        shutter[0], shutter[1]
    )
}

const MOVING: &str = r#"
[objects.moving]
class = "motion"
children = ["ball"]
keyframes = [
  { time = 0.0, translate = [-1.0, 0.0, 0.0] },
  { time = 1.0, translate = [1.0, 0.5, 0.0], rotate = { axis = [0.0, 0.0, 1.0], angle = 90.0 } },
]
[objects.world]
class = "list"
children = [{ object = "moving", shader = "white" }]
"#;

fn still(at: [f32; 3], turn: f32) -> String {
    format!(
        r#"
[objects.world]
class = "list"
children = [{{ object = "ball", shader = "white", transform = [{{ rotate_z = {turn} }}, {{ translate = [{}, {}, {}] }}] }}]
"#,
        at[0], at[1], at[2]
    )
}

fn mean(img: &Image) -> f64 {
    img.data.iter().map(|&v| v as f64).sum::<f64>() / img.data.len() as f64
}

/// A shutter closed at a keyframe's time shows the child exactly at that
/// keyframe's pose: the same image, bit for bit, as a still instance.
#[test]
fn poses_are_exactly_the_keyframes() {
    for (t, at, turn) in [(0.0, [-1.0, 0.0, 0.0], 0.0), (1.0, [1.0, 0.5, 0.0], 90.0)] {
        let (run, moving) = render_scene(&scene(MOVING, [t, t], 4), &[]);
        assert!(run.ok, "{}", run.stderr);
        let (run, fixed) = render_scene(&scene(&still(at, turn), [0.0, 1.0], 4), &[]);
        assert!(run.ok, "{}", run.stderr);
        let (m, f) = (moving.unwrap(), fixed.unwrap());
        let differ = m.data.iter().zip(&f.data).filter(|(a, b)| a != b).count();
        // A rotation by 90° rounds differently in a quaternion and in the
        // transform steps: allow silhouette pixels to differ there only.
        let allowed = if turn == 0.0 { 0 } else { 3 * 24 };
        assert!(differ <= allowed, "t = {t}: {differ} channel values differ");
        assert!(mean(&m) > 0.02, "the ball is in view");
    }
}

/// Motion blur: the blurred image's mean equals the mean over the poses
/// (32 stills at the midpoints of 32 equal time steps, each rendered with
/// a closed shutter) within 5 standard errors of the two estimates, and the
/// swept region holds partial coverage.
#[test]
fn blur_is_the_time_average_of_the_poses() {
    let (run, blurred) = render_scene(&scene(MOVING, [0.0, 1.0], 256), &[]);
    assert!(run.ok, "{}", run.stderr);
    let blurred = blurred.unwrap();
    let n = 32;
    let mut avg = 0.0;
    for k in 0..n {
        let t = (k as f32 + 0.5) / n as f32;
        let (run, img) = render_scene(&scene(MOVING, [t, t], 16), &[]);
        assert!(run.ok, "{}", run.stderr);
        avg += mean(&img.unwrap()) / n as f64;
    }
    let m = mean(&blurred);
    // Each sample is covered or not (white on black): both means are means
    // of Bernoulli values, over 48·32·256 samples and 32·48·32·16.
    let p = avg.clamp(1e-3, 1.0);
    let samples = (48.0 * 32.0 * 256.0, 32.0 * 48.0 * 32.0 * 16.0);
    let sigma = (p * (1.0 - p) * (1.0 / samples.0 + 1.0 / samples.1)).sqrt();
    assert!(
        (m - avg).abs() < 5.0 * sigma,
        "blurred mean {m} vs time average {avg} (σ {sigma})"
    );
    let partial = blurred
        .data
        .iter()
        .filter(|&&v| v > 0.05 && v < 0.95)
        .count();
    assert!(partial > 200, "only {partial} partially covered values");
}

/// Bad keyframes are refused, naming the key.
#[test]
fn bad_keyframes_are_refused() {
    for (bad, key) in [
        ("keyframes = []", "keyframes"),
        (
            "keyframes = [{ time = 0.5 }, { time = 0.2 }]",
            "keyframes[1].time",
        ),
        (
            "keyframes = [{ time = 0.0, scale = 0.0 }]",
            "keyframes[0].scale",
        ),
    ] {
        let world = format!(
            "[objects.moving]\nclass = \"motion\"\nchildren = [\"ball\"]\n{bad}\n[objects.world]\nclass = \"list\"\nchildren = [\"moving\"]\n"
        );
        let (run, _) = render_scene(&scene(&world, [0.0, 1.0], 1), &[]);
        assert!(!run.ok, "{bad} accepted");
        assert!(run.stderr.contains(key), "{bad}: {}", run.stderr);
    }
}

/// A keyframe scale beyond what f32 intersection handles is refused, as an
/// instance transform's is (a scene once rendered a ball scaled by 1e30).
#[test]
fn keyframe_scales_beyond_1e12_are_refused() {
    for (bad, msg) in [
        (
            "{ time = 0.0 }, { time = 1.0, scale = 1e13 }",
            "key `keyframes[1].scale`: plugin `motion` refused its parameters: scales by 1.0e13, outside the 1e-12 to 1e12 rtk handles",
        ),
        (
            "{ time = 0.0, scale = 1e-13 }",
            "key `keyframes[0].scale`: plugin `motion` refused its parameters: scales by 1.0e-13, outside the 1e-12 to 1e12 rtk handles",
        ),
    ] {
        let world = format!(
            "[objects.moving]\nclass = \"motion\"\nchildren = [\"ball\"]\nkeyframes = [{bad}]\n[objects.world]\nclass = \"list\"\nchildren = [\"moving\"]\n"
        );
        let (run, img) = render_scene(&scene(&world, [0.0, 1.0], 1), &[]);
        assert!(!run.ok && img.is_none(), "{bad} accepted");
        assert!(
            run.stderr.contains("scene.toml:25:") && run.stderr.contains("objects.moving") && run.stderr.contains(msg),
            "{bad}: {}",
            run.stderr
        );
    }
}

/// `--frame N --frames F` renders frame N's share of the scene's time: with
/// a closed shutter (`--shutter-fraction 0`), exactly the pose at N / F.
#[test]
fn frames_split_the_scene_time() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.toml");
    for (n, t) in [(0u32, 0.0f32), (1, 0.5)] {
        std::fs::write(&path, scene(MOVING, [t, t], 4)).unwrap();
        let (run, at_t) = render_file(&path, dir.path(), &[]);
        assert!(run.ok, "{}", run.stderr);
        let (run, frame) = render_file(
            &path,
            dir.path(),
            &[
                "--frame",
                &n.to_string(),
                "--frames",
                "2",
                "--shutter-fraction",
                "0",
            ],
        );
        assert!(run.ok, "{}", run.stderr);
        assert_eq!(at_t.unwrap().data, frame.unwrap().data, "frame {n}");
    }
    let out = tempfile::tempdir().unwrap();
    let (run, _) = render_file(&path, out.path(), &["--frame", "2", "--frames", "2"]);
    assert!(
        !run.ok && run.stderr.contains("--frame 2"),
        "{}",
        run.stderr
    );
}

/// A pinhole camera with keyframes: a closed shutter at a keyframe's time
/// sees exactly what a still camera at that pose sees; `--frame` moves it.
#[test]
fn camera_keyframes_pose_exactly_and_animate() {
    let world = still([0.0, 0.0, 0.0], 0.0);
    let fixed = |eye: &str| {
        scene(&world, [0.0, 0.0], 4).replace("eye = [0.0, 0.0, 6.0]", &format!("eye = {eye}"))
    };
    let moving = |shutter: [f32; 2]| {
        scene(&world, shutter, 4).replace(
            "eye = [0.0, 0.0, 6.0]",
            "keyframes = [{ time = 0.0, eye = [0.0, 0.0, 6.0], look_at = [0.0, 0.0, 0.0] }, { time = 1.0, eye = [2.0, 0.0, 6.0], look_at = [0.0, 0.0, 0.0] }]",
        )
    };
    for (t, eye) in [(0.0f32, "[0.0, 0.0, 6.0]"), (1.0, "[2.0, 0.0, 6.0]")] {
        let (run, a) = render_scene(&moving([t, t]), &[]);
        assert!(run.ok, "{}", run.stderr);
        let (run, b) = render_scene(&fixed(eye), &[]);
        assert!(run.ok, "{}", run.stderr);
        assert_eq!(a.unwrap().data, b.unwrap().data, "t = {t}");
    }
    // Frames differ as the camera moves.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(&path, moving([0.0, 1.0])).unwrap();
    let (run, f0) = render_file(&path, dir.path(), &["--frame", "0", "--frames", "4"]);
    assert!(run.ok, "{}", run.stderr);
    let (run, f3) = render_file(&path, dir.path(), &["--frame", "3", "--frames", "4"]);
    assert!(run.ok, "{}", run.stderr);
    assert_ne!(f0.unwrap().data, f3.unwrap().data);
}
