//! Start-up cost of `rtk render` on a tiny scene (64x64, 1 spp): the whole
//! process, timed by criterion, and the per-step breakdown from `--stats`.
//!
//! Run: `cargo build --release --workspace && cargo bench -p rtk-host --bench startup`

use criterion::{criterion_group, criterion_main, Criterion};
use std::path::PathBuf;
use std::process::Command;

const SCENE: &str = r#"
[render]
width = 64
height = 64
spp = 1
root = "world"
integrator = "normals"
[cameras.main]
class = "pinhole"
[objects.ball]
class = "sphere"
[objects.world]
class = "list"
children = ["ball"]
"#;

fn scene_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("rtk-bench-startup-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    std::fs::write(d.join("tiny.toml"), SCENE).expect("scene");
    d
}

fn run(dir: &std::path::Path, stats: bool) -> std::process::Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_rtk"));
    c.arg("render")
        .arg(dir.join("tiny.toml"))
        .arg("-o")
        .arg(dir.join("tiny.png"))
        .arg("-q")
        .arg("--threads")
        .arg("1");
    if stats {
        c.arg("--stats");
    }
    let out = c.output().expect("run rtk");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn bench(c: &mut Criterion) {
    let dir = scene_dir();
    // The breakdown, median of 30 runs, printed once.
    let mut rows: Vec<serde_json::Value> = (0..30)
        .map(|_| serde_json::from_slice(&run(&dir, true).stdout).expect("stats"))
        .map(|v: serde_json::Value| v["seconds"].clone())
        .collect();
    println!(
        "\nmedian of 30 runs, milliseconds (64x64, 1 spp, normals, sphere in list, 1 thread):"
    );
    for k in [
        "parse",
        "load_plugins",
        "create",
        "prepare",
        "render",
        "write",
        "total",
    ] {
        rows.sort_by(|a, b| {
            a[k].as_f64()
                .unwrap_or(0.0)
                .total_cmp(&b[k].as_f64().unwrap_or(0.0))
        });
        println!(
            "  {k:>13}: {:8.3}",
            rows[15][k].as_f64().unwrap_or(0.0) * 1e3
        );
    }
    c.bench_function("rtk render tiny scene (process wall time)", |b| {
        b.iter(|| run(&dir, false))
    });
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = bench
}
criterion_main!(benches);
