//! Long renders (issue 11): checkpoint and resume give exactly the image of
//! one uninterrupted run; a checkpoint of another scene or other settings
//! is refused; Ctrl-C (SIGINT) writes a valid partial image and exits 130.

use rtk_tests::*;
use std::path::{Path, PathBuf};

fn cornell() -> PathBuf {
    root().join("scenes/cornell.toml")
}

/// 32x32 at 8 spp: small, noisy (path traced), quick.
const SIZE: [&str; 6] = [
    "--set",
    "render.width=32",
    "--set",
    "render.height=32",
    "--set",
    "render.spp=8",
];

fn render(dir: &Path, out: &str, extra: &[&str]) -> Run {
    let scene = cornell();
    let out = dir.join(out);
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    if !extra.contains(&"--threads") {
        args.extend_from_slice(&["--threads", "2"]);
    }
    args.extend_from_slice(&SIZE);
    args.extend_from_slice(extra);
    Run::from(rtk(&args).output().expect("run rtk"))
}

#[test]
fn checkpoint_then_resume_is_bit_identical_to_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck.rtkfilm");
    let ck = ck.to_str().unwrap();
    let run = render(dir.path(), "single.exr", &[]);
    assert!(run.ok, "{}", run.stderr);
    // One pass of 1 sample, then stop (time limit 0): the checkpoint holds 1 spp.
    let run = render(
        dir.path(),
        "a.exr",
        &[
            "--checkpoint",
            ck,
            "--checkpoint-every",
            "0",
            "--time-limit",
            "0",
        ],
    );
    assert!(run.ok, "{}", run.stderr);
    assert!(
        run.stderr.contains("1 of 8 samples per pixel"),
        "{}",
        run.stderr
    );
    // Resume it for another pass (and one thread this time), then to the end.
    let run = render(
        dir.path(),
        "b.exr",
        &[
            "--resume",
            ck,
            "--checkpoint",
            ck,
            "--time-limit",
            "0",
            "--threads",
            "1",
        ],
    );
    assert!(run.ok, "{}", run.stderr);
    assert!(
        run.stderr.contains("2 of 8 samples per pixel"),
        "{}",
        run.stderr
    );
    let run = render(dir.path(), "resumed.exr", &["--resume", ck]);
    assert!(run.ok, "{}", run.stderr);
    let single = Image::read(&dir.path().join("single.exr"));
    let resumed = Image::read(&dir.path().join("resumed.exr"));
    assert!(single.data.iter().any(|v| *v > 0.0));
    let bits = |i: &Image| i.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&single), bits(&resumed), "resumed image differs");
    // Partial renders are not the final image (the test would be void otherwise).
    let partial = Image::read(&dir.path().join("b.exr"));
    assert_ne!(bits(&single), bits(&partial));
}

#[test]
fn resume_refuses_a_checkpoint_of_another_scene_or_settings() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck.rtkfilm");
    let ck = ck.to_str().unwrap();
    let run = render(
        dir.path(),
        "a.exr",
        &["--checkpoint", ck, "--time-limit", "0"],
    );
    assert!(run.ok, "{}", run.stderr);
    // Another scene: an object changed by --set.
    let run = render(
        dir.path(),
        "b.exr",
        &["--resume", ck, "--set", "render.background=[1,0,0]"],
    );
    assert!(!run.ok);
    assert!(
        run.stderr.contains("was rendered from another scene"),
        "{}",
        run.stderr
    );
    assert!(!dir.path().join("b.exr").exists());
    // Other settings: spp.
    let run = render(dir.path(), "b.exr", &["--resume", ck, "--spp", "16"]);
    assert!(!run.ok);
    assert!(
        run.stderr
            .contains("other settings: spp 8 (this render: 16)"),
        "{}",
        run.stderr
    );
    // Another crop.
    let run = render(
        dir.path(),
        "b.exr",
        &["--resume", ck, "--crop", "0,0,16,16"],
    );
    assert!(!run.ok);
    assert!(
        run.stderr.contains("--crop must be the same"),
        "{}",
        run.stderr
    );
    // Not a film file at all.
    let scene = cornell();
    let run = render(dir.path(), "b.exr", &["--resume", scene.to_str().unwrap()]);
    assert!(!run.ok);
    assert!(
        run.stderr.contains("is not an rtk film file"),
        "{}",
        run.stderr
    );
}

#[test]
#[cfg(unix)]
fn sigint_writes_a_valid_partial_image_and_exits_130() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck.rtkfilm");
    let out = dir.path().join("partial.exr");
    let scene = cornell();
    // Far too many samples to finish: the render is stopped by SIGINT once
    // its first checkpoint (after the first pass) shows it is rendering.
    let mut child = rtk(&[
        "render",
        scene.to_str().unwrap(),
        "-q",
        "--threads",
        "2",
        "--set",
        "render.width=32",
        "--set",
        "render.height=32",
        "--spp",
        "16000000",
        "--checkpoint",
        ck.to_str().unwrap(),
        "--checkpoint-every",
        "0",
        "-o",
        out.to_str().unwrap(),
    ])
    .stderr(std::process::Stdio::piped())
    .spawn()
    .expect("spawn rtk");
    let mut waited = 0;
    while !ck.exists() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("rtk ended before its first checkpoint: {status}");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        waited += 1;
        assert!(waited < 20 * 600, "no checkpoint after ten minutes");
    }
    let status = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(status.success());
    let o = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted: wrote"), "{stderr}");
    assert!(stderr.contains("of 16000000 samples per pixel"), "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    let img = Image::read(&out);
    assert_eq!((img.width, img.height), (32, 32));
    assert!(img.data.iter().all(|v| v.is_finite()));
    // Every pixel has an estimate (the first pass finished): the fewest
    // samples a pixel has, as printed, is at least 1.
    let counts = stderr
        .split("(32x32, ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|n| n.parse::<u64>().ok())
        .unwrap_or_else(|| panic!("no sample count in: {stderr}"));
    assert!(counts >= 1, "{stderr}");
    assert!(img.data.iter().any(|v| *v > 0.0), "an all-black image");
    assert!(ck.exists());
}

/// A 3x2 image is one tile: on two threads its samples are split into
/// chunks both threads take (issue 22, item 5), and the image is the
/// one-thread image bit for bit, resumed from a one-thread checkpoint too.
#[test]
fn a_small_image_split_across_threads_equals_the_one_thread_image() {
    let dir = tempfile::tempdir().unwrap();
    let ck = dir.path().join("ck.rtkfilm");
    let ck = ck.to_str().unwrap();
    let small = [
        "--set",
        "render.width=3",
        "--set",
        "render.height=2",
        "--set",
        "render.spp=20000",
    ];
    fn with<'a>(small: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [small, extra].concat()
    }
    let run = render(dir.path(), "one.exr", &with(&small, &["--threads", "1"]));
    assert!(run.ok, "{}", run.stderr);
    let run = render(dir.path(), "two.exr", &with(&small, &["--threads", "2"]));
    assert!(run.ok, "{}", run.stderr);
    // A first pass on one thread, checkpointed, then the rest on two.
    let run = render(
        dir.path(),
        "part.exr",
        &with(
            &small,
            &[
                "--threads",
                "1",
                "--checkpoint",
                ck,
                "--checkpoint-every",
                "0",
                "--time-limit",
                "0",
            ],
        ),
    );
    assert!(run.ok, "{}", run.stderr);
    let run = render(dir.path(), "resumed.exr", &with(&small, &["--resume", ck]));
    assert!(run.ok, "{}", run.stderr);
    let bits = |f: &str| {
        let i = Image::read(&dir.path().join(f));
        i.data.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    };
    assert!(Image::read(&dir.path().join("one.exr"))
        .data
        .iter()
        .any(|v| *v > 0.0));
    assert_eq!(bits("one.exr"), bits("two.exr"), "two threads differ");
    assert_eq!(bits("one.exr"), bits("resumed.exr"), "resumed differs");
    assert_ne!(bits("one.exr"), bits("part.exr"));
}

/// Fault injection (issue 25): checkpointed renders killed with SIGKILL at
/// 100 moments drawn from a seeded generator (across scenes, thread counts
/// and checkpoint intervals), each then resumed from its checkpoint (or
/// started again when killed before the first one) to completion: every
/// final image equals the uninterrupted render's bit for bit, and every
/// checkpoint a kill left loads. Prints a table (`--nocapture`;
/// `host/benches/kill_resume.sh` runs it).
#[test]
#[cfg(unix)]
#[ignore = "minutes: 100 killed and resumed renders (README: long tests)"]
fn killed_checkpointed_renders_resume_to_the_uninterrupted_image() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let setups: [(&str, &[&str]); 2] = [
        (
            "cornell",
            &[
                "--set",
                "render.width=48",
                "--set",
                "render.height=48",
                "--spp",
                "48",
            ],
        ),
        (
            "default",
            &[
                "--set",
                "render.width=96",
                "--set",
                "render.height=72",
                "--spp",
                "8",
            ],
        ),
    ];
    let mut rng = rtk_kernel::RngState::seeded(0x6b11);
    let mut rows = Vec::new();
    for (scene, size) in setups {
        let file = root().join(format!("scenes/{scene}.toml"));
        let args = |out: &Path, extra: &[&str]| -> Vec<String> {
            let mut a: Vec<String> = ["render", file.to_str().unwrap(), "-q", "-o"]
                .iter()
                .map(|s| s.to_string())
                .collect();
            a.push(out.to_str().unwrap().into());
            a.extend(size.iter().chain(extra).map(|s| s.to_string()));
            a
        };
        let reference = dir.path().join(format!("{scene}-ref.exr"));
        let t0 = Instant::now();
        let a = args(&reference, &["--threads", "2"]);
        let r = Run::from(
            rtk(&a.iter().map(String::as_str).collect::<Vec<_>>())
                .output()
                .unwrap(),
        );
        assert!(r.ok, "{}", r.stderr);
        let whole = t0.elapsed();
        let want = std::fs::read(&reference).unwrap();
        for threads in ["1", "2", "4"] {
            for every in ["0", "0.05"] {
                let (mut resumed, mut fresh, mut finished) = (0, 0, 0);
                for k in 0..(100 / 12 + 1) {
                    let ck = dir
                        .path()
                        .join(format!("{scene}-{threads}-{every}-{k}.rtkfilm"));
                    let out = dir
                        .path()
                        .join(format!("{scene}-{threads}-{every}-{k}.exr"));
                    let extra = [
                        "--threads",
                        threads,
                        "--checkpoint",
                        ck.to_str().unwrap(),
                        "--checkpoint-every",
                        every,
                    ];
                    let a = args(&out, &extra);
                    let mut child = rtk(&a.iter().map(String::as_str).collect::<Vec<_>>())
                        .stderr(std::process::Stdio::null())
                        .spawn()
                        .unwrap();
                    // A moment within the render: the reference's time on
                    // two threads, twice that on one (the machine has two
                    // cores, so four threads take as long as two).
                    let span = if threads == "1" { 1.8 } else { 0.9 };
                    let at = whole.mul_f64(span * rng.next_f64());
                    std::thread::sleep(at.max(Duration::from_millis(1)));
                    let _ = child.kill();
                    let status = child.wait().unwrap();
                    let mut extra = vec!["--threads", threads];
                    if status.success() {
                        finished += 1;
                    } else if ck.exists() {
                        resumed += 1;
                        extra.extend(["--resume", ck.to_str().unwrap()]);
                    } else {
                        fresh += 1;
                    }
                    let a = args(&out, &extra);
                    let r = Run::from(
                        rtk(&a.iter().map(String::as_str).collect::<Vec<_>>())
                            .output()
                            .unwrap(),
                    );
                    assert!(
                        r.ok,
                        "{scene} threads {threads} every {every} kill {k}: {}",
                        r.stderr
                    );
                    assert!(
                        std::fs::read(&out).unwrap() == want,
                        "{scene} threads {threads} every {every} kill {k}: the image differs"
                    );
                }
                rows.push(format!(
                    "| {scene} | {threads} | {every} | {} | {resumed} | {fresh} | {finished} | identical |",
                    resumed + fresh + finished
                ));
            }
        }
    }
    println!("| scene | threads | checkpoint every s | runs | resumed | killed before a checkpoint | finished first | final image |");
    println!("|---|---:|---:|---:|---:|---:|---:|---|");
    for r in rows {
        println!("{r}");
    }
}

/// Resident memory of a live process, from /proc (bytes).
#[cfg(target_os = "linux")]
fn resident_bytes(pid: u32) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let kb = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    kb.split_whitespace()
        .nth(1)?
        .parse::<u64>()
        .ok()
        .map(|k| k * 1024)
}

/// Issue 25 item 8, the soak run: a render of 4,000 passes (one sample per
/// pixel each, as `--time-limit` makes them), a checkpoint after every
/// pass, 16 threads on however few cores: resident memory stays flat once
/// the first checkpoint is written, every pixel ends with exactly its
/// samples, and the image equals one plain 2-thread render bit for bit.
/// (80x64 is 20 tiles, more than the threads, so a pass is one sample per
/// pixel; a smaller image takes the small-image path's larger passes.)
#[test]
#[cfg(target_os = "linux")]
#[ignore = "minutes: 4,000 checkpointed passes on 16 threads (README: long tests)"]
fn soak_thousands_of_checkpointed_passes_keep_memory_flat_and_counts_exact() {
    use std::time::Duration;
    let dir = tempfile::tempdir().unwrap();
    let scene = cornell();
    let (out, ck) = (dir.path().join("soak.exr"), dir.path().join("soak.rtkfilm"));
    let size = [
        "--set",
        "render.width=80",
        "--set",
        "render.height=64",
        "--spp",
        "4000",
    ];
    let mut args = vec!["render", scene.to_str().unwrap(), "-q", "--stats", "-o"];
    args.push(out.to_str().unwrap());
    args.extend_from_slice(&size);
    args.extend_from_slice(&["--threads", "16", "--time-limit", "1000000"]);
    args.extend_from_slice(&[
        "--checkpoint",
        ck.to_str().unwrap(),
        "--checkpoint-every",
        "0",
    ]);
    let mut child = rtk(&args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id();
    // (after the first checkpoint?, resident bytes), every 20 ms.
    let mut samples = Vec::new();
    while child.try_wait().unwrap().is_none() {
        if let Some(rss) = resident_bytes(pid) {
            samples.push((ck.exists(), rss));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let run = Run::from(child.wait_with_output().unwrap());
    assert!(run.ok, "{}", run.stderr);
    assert_eq!(
        run.stats()["samples_per_pixel"],
        serde_json::json!([4000, 4000])
    );
    let steady: Vec<u64> = samples.iter().filter(|s| s.0).map(|s| s.1).collect();
    assert!(
        steady.len() > 50,
        "too few samples of the run's memory: {}",
        steady.len()
    );
    let (first, max) = (steady[0], *steady.iter().max().unwrap());
    let mib = |b: u64| b as f64 / 1048576.0;
    println!(
        "soak: {} memory samples after the first checkpoint (MiB): first {:.2}, at a quarter {:.2}, half {:.2}, three quarters {:.2}, last {:.2}, most {:.2}",
        steady.len(),
        mib(first),
        mib(steady[steady.len() / 4]),
        mib(steady[steady.len() / 2]),
        mib(steady[steady.len() * 3 / 4]),
        mib(*steady.last().unwrap()),
        mib(max)
    );
    // Flat: no growth with the passes beyond the allocator's page-level noise.
    assert!(
        max <= first + (4 << 20),
        "resident memory grew from {first} to {max} bytes"
    );
    let plain = dir.path().join("plain.exr");
    let mut args = vec!["render", scene.to_str().unwrap(), "-q", "-o"];
    args.push(plain.to_str().unwrap());
    args.extend_from_slice(&size);
    args.extend_from_slice(&["--threads", "2"]);
    let r = Run::from(rtk(&args).output().unwrap());
    assert!(r.ok, "{}", r.stderr);
    assert!(
        std::fs::read(&out).unwrap() == std::fs::read(&plain).unwrap(),
        "the soak image differs from one plain render"
    );
}
