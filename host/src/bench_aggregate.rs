//! `rtk bench-aggregate NAME --against bvh,grid`: an aggregate against
//! others, side by side in one run: build time, memory and Mrays/s for the
//! primary, incoherent and occluded ray sets of `rtk trace`, interleaved
//! (A, B, A, B, ...; best of N) so that a busy machine slows all alike.

use crate::trace::rays::{HitRec, RayRec};
use crate::trace::{self, RaySet};
use anyhow::{bail, Result};
use rtk_shell::{Parallel, World};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicU64;
use std::time::Instant;

/// The arguments of `rtk bench-aggregate`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// The aggregate class to measure.
    pub name: String,
    /// The aggregates to compare it with (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "bvh",
        value_name = "A,B,..."
    )]
    pub against: Vec<String>,
    /// A mesh (.ply, .obj) to build over (repeatable; default: scenes/meshes/bunny.ply).
    #[arg(long = "mesh", value_name = "FILE")]
    pub meshes: Vec<PathBuf>,
    /// Tracing threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Timed passes per aggregate and ray set, interleaved; the best is kept.
    #[arg(long, default_value_t = 3, value_name = "N")]
    pub repeats: u32,
    /// Trace at most N rays of each set (evenly spaced through it; default: all 2^20).
    #[arg(long = "rays", value_name = "N")]
    pub max_rays: Option<usize>,
    /// Trace through the aggregates' ray-stream entries, 64 rays per batch
    /// (as `rtk trace --stream`), instead of one ray at a time.
    #[arg(long)]
    pub stream: bool,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
    /// Extra folders to search for plugins first (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    pub plugin_path: Vec<PathBuf>,
}

/// The ray sets: (name, generated set, any-hit query).
const SETS: [(&str, RaySet, bool); 3] = [
    ("primary", RaySet::Primary, false),
    ("incoherent", RaySet::Incoherent, false),
    ("occluded", RaySet::Incoherent, true),
];

struct Built {
    class: String,
    world: World,
    build_s: f64,
    memory: usize,
}

/// One row: an aggregate on a mesh and ray set.
struct Row {
    mesh: String,
    set: &'static str,
    class: String,
    build_s: f64,
    memory: usize,
    rays: usize,
    best_s: f64,
    hits: usize,
}

impl Row {
    fn mrays(&self) -> f64 {
        self.rays as f64 / self.best_s / 1e6
    }
}

fn default_mesh() -> PathBuf {
    let host = Path::new(env!("CARGO_MANIFEST_DIR"));
    host.parent()
        .unwrap_or(host)
        .join("scenes/meshes/bunny.ply")
}

/// Every `len / n`-th ray, at most `n`.
fn thin(rays: Vec<RayRec>, n: Option<usize>) -> Vec<RayRec> {
    match n {
        Some(n) if n > 0 && n < rays.len() => {
            let step = rays.len() as f64 / n as f64;
            (0..n).map(|i| rays[(i as f64 * step) as usize]).collect()
        }
        _ => rays,
    }
}

/// Run `rtk bench-aggregate`.
pub fn run(a: BenchArgs, pool: &rayon::ThreadPool, parallel: &dyn Parallel) -> Result<()> {
    if a.max_rays == Some(0) {
        bail!("--rays must be at least 1 (leave it out to trace all 2^20 rays of each set)");
    }
    let classes = classes_of(&a)?;
    let meshes = if a.meshes.is_empty() {
        vec![default_mesh()]
    } else {
        a.meshes.clone()
    };
    let next_query: Vec<AtomicU64> = (0..pool.current_num_threads())
        .map(|_| AtomicU64::new(0))
        .collect();
    let mut rows = Vec::new();
    for mesh in &meshes {
        if !mesh.is_file() {
            bail!("{}: no such mesh file (--mesh FILE)", mesh.display());
        }
        let built = build_all(&a, mesh, &classes, parallel)?;
        let (lo, hi) = trace::world_box(&built[0].world, mesh)?;
        let mesh_name = mesh.file_name().map_or_else(
            || mesh.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        );
        for (set_name, set, occluded) in SETS {
            let rays = thin(trace::generate(set, lo, hi), a.max_rays);
            let (best, hits) = time_interleaved(&a, &built, &rays, occluded, pool, &next_query)?;
            for (i, b) in built.iter().enumerate() {
                rows.push(Row {
                    mesh: mesh_name.clone(),
                    set: set_name,
                    class: b.class.clone(),
                    build_s: b.build_s,
                    memory: b.memory,
                    rays: rays.len(),
                    best_s: best[i],
                    hits: hits[i],
                });
            }
        }
    }
    print(&a, &rows, pool.current_num_threads());
    Ok(())
}

/// NAME, then each `--against` class once, every one a class name.
fn classes_of(a: &BenchArgs) -> Result<Vec<String>> {
    let mut classes = vec![a.name.clone()];
    for c in &a.against {
        let c = c.trim();
        if !c.is_empty() && !classes.iter().any(|x| x == c) {
            classes.push(c.to_string());
        }
    }
    for c in &classes {
        if !rtk_shell::plugins::is_identifier(c) {
            bail!("`{}` is not a class name", rtk_shell::error::shown(c, 80));
        }
    }
    Ok(classes)
}

/// The mesh under each class, with its build time and the memory it took.
fn build_all(
    a: &BenchArgs,
    mesh: &Path,
    classes: &[String],
    parallel: &dyn Parallel,
) -> Result<Vec<Built>> {
    // Warm up: map the mesh, camera and integrator libraries and read the
    // mesh once, so that the first aggregate's memory and build time do
    // not pay for them.
    drop(trace::build_world(
        trace::mesh_scene(mesh, Some("list"))?,
        vec![],
        &a.plugin_path,
        parallel,
    )?);
    let mut built = Vec::new();
    for class in classes {
        let rss0 = trace::resident_bytes();
        let t = Instant::now();
        let file = trace::mesh_scene(mesh, Some(class))?;
        let world = trace::build_world(file, vec![], &a.plugin_path, parallel)?;
        let total = t.elapsed().as_secs_f64();
        // The build is the aggregate's `prepare`; without a record of it, all loading.
        let build_s = world
            .timings
            .prepare_by_class
            .get(class)
            .map_or(total, |d| d.as_secs_f64());
        let memory = trace::resident_bytes().saturating_sub(rss0);
        if world.root.class_name() != class {
            bail!(
                "the root of the benchmark scene is `{}`, not `{class}`",
                world.root.class_name()
            );
        }
        built.push(Built {
            class: class.clone(),
            world,
            build_s,
            memory,
        });
    }
    Ok(built)
}

/// Each aggregate's best time over `--repeats` passes of `rays`, the
/// aggregates taking turns (A, B, A, B, ...) so that a busy machine slows
/// all alike, and the hits of its last pass.
fn time_interleaved(
    a: &BenchArgs,
    built: &[Built],
    rays: &[RayRec],
    occluded: bool,
    pool: &rayon::ThreadPool,
    next_query: &[AtomicU64],
) -> Result<(Vec<f64>, Vec<usize>)> {
    let mut best = vec![f64::INFINITY; built.len()];
    let mut hits = vec![0usize; built.len()];
    let mut out = vec![HitRec::MISS; rays.len()];
    for _ in 0..a.repeats.max(1) {
        for (i, b) in built.iter().enumerate() {
            let t = Instant::now();
            let q = trace::Query {
                occluded,
                stream: a.stream,
            };
            trace::trace_all(&b.world, rays, q, pool, next_query, &mut out)?;
            best[i] = best[i].min(t.elapsed().as_secs_f64());
            hits[i] = out.iter().filter(|h| h.t.is_finite()).count();
        }
    }
    Ok((best, hits))
}

/// NAME's row for the same mesh and set as `r`.
fn ours<'r>(a: &BenchArgs, rows: &'r [Row], r: &Row) -> Option<&'r Row> {
    rows.iter()
        .find(|o| o.mesh == r.mesh && o.set == r.set && o.class == a.name)
}

/// Print the rows: a table, or JSON with `--json`.
fn print(a: &BenchArgs, rows: &[Row], threads: usize) {
    if a.json {
        print_json(a, rows, threads);
    } else {
        print_table(a, rows, threads);
    }
}

/// `--json`: one object holding every row and its ratios to NAME's.
fn print_json(a: &BenchArgs, rows: &[Row], threads: usize) {
    let list: Vec<_> = rows
        .iter()
        .map(|r| {
            let o = ours(a, rows, r);
            serde_json::json!({
                "mesh": r.mesh, "set": r.set, "aggregate": r.class,
                "build_seconds": r.build_s, "memory_bytes": r.memory,
                "rays": r.rays, "trace_seconds": r.best_s, "mrays_per_s": r.mrays(),
                "hits": r.hits,
                "ratio_mrays": o.map(|o| o.mrays() / r.mrays()),
                "ratio_build": o.map(|o| o.build_s / r.build_s),
                "ratio_memory": o.map(|o| o.memory as f64 / r.memory.max(1) as f64),
            })
        })
        .collect();
    println!(
        "{}",
        serde_json::json!({
            "aggregate": a.name, "threads": threads, "repeats": a.repeats.max(1),
            "path": if a.stream { "stream" } else { "single" },
            "rows": list,
        })
    );
}

/// The table: a line per mesh, set and aggregate, with its ratios to NAME's.
fn print_table(a: &BenchArgs, rows: &[Row], threads: usize) {
    println!(
        "{} against {}: best of {} interleaved passes, {threads} threads, {} rays; ratios are {} / the row's aggregate (Mrays/s > 1: {} is faster; build, memory < 1: {} is cheaper)",
        a.name,
        a.against.join(","),
        a.repeats.max(1),
        if a.stream { "streamed" } else { "single" },
        a.name,
        a.name,
        a.name
    );
    println!(
        "{:<14} {:<10} {:<10} {:>9} {:>9} {:>9} {:>8} {:>8} {:>7} {:>7} {:>7}",
        "mesh",
        "set",
        "aggregate",
        "build ms",
        "memory MB",
        "Mrays/s",
        "rays",
        "hits",
        "x rays",
        "x build",
        "x mem"
    );
    for r in rows {
        let (rr, rb, rm) = match ours(a, rows, r) {
            Some(o) if r.class != a.name => (
                format!("{:.2}", o.mrays() / r.mrays()),
                format!("{:.2}", o.build_s / r.build_s),
                format!("{:.2}", o.memory as f64 / r.memory.max(1) as f64),
            ),
            _ => ("-".into(), "-".into(), "-".into()),
        };
        let mismatch = match ours(a, rows, r) {
            Some(o) if o.hits != r.hits => "  (hits differ!)",
            _ => "",
        };
        println!(
            "{:<14} {:<10} {:<10} {:>9.1} {:>9.1} {:>9.2} {:>8} {:>8} {:>7} {:>7} {:>7}{mismatch}",
            r.mesh,
            r.set,
            r.class,
            r.build_s * 1e3,
            r.memory as f64 / 1e6,
            r.mrays(),
            r.rays,
            r.hits,
            rr,
            rb,
            rm
        );
    }
}
