//! `rtk stress`: the numerical-stability catalogue of docs/numerics.md, run
//! through the real plugins and the real render path, one line per
//! measurement: the case, its setup, the metric, the value, the target and
//! whether it passed.
//!
//! Why a command and not only tests: the evidence that the renderer is robust
//! should be something a user can run on their own machine, on their own
//! build of the plugins, and read. The tests run `--quick` and assert that
//! every line passes; the full run (minutes) is an ignored test.
//!
//! Each case is a function from a [`Bench`] (the plugin registry, a scratch
//! folder, the size) to its lines, named after what it checks; its
//! catalogue id (`A3`) is the [`Case`]'s `id`, which `--case` and every line
//! use. Cases build small scenes as TOML text and trace them through
//! `World::root`, or render them, exactly as `rtk render` does; the f64
//! reference is the kernel's own routines instantiated for f64 on the same
//! f32 inputs (`rtk_kernel::geom`, generic over `Real`).

mod aggregates;
mod bench;
mod hygiene;
mod integrators;
mod mirrors;
mod quadrics;
mod spawn;
mod transforms;
mod triangles;

pub(crate) use bench::{box_mesh, header, unit_vector as bench_unit, uv_sphere, vec3f, Probe};
pub use bench::{Bench, Line, Size};

use anyhow::{bail, Result};
use std::path::PathBuf;
use std::time::Instant;

/// The arguments of `rtk stress`.
#[derive(clap::Args)]
pub struct StressArgs {
    /// Small sizes (seconds): what the default test run uses.
    #[arg(long)]
    pub quick: bool,
    /// Only the cases whose id starts with one of these (`S5`, `T`, `A3`).
    #[arg(long, value_name = "ID")]
    pub case: Vec<String>,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
    /// List the cases and exit.
    #[arg(long)]
    pub list: bool,
    /// Threads for the cases that render (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Extra folders to search for plugins first (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    pub plugin_path: Vec<PathBuf>,
}

/// One case of the catalogue.
pub struct Case {
    /// The catalogue's id (docs/numerics.md §2).
    pub id: &'static str,
    /// What it stresses.
    pub title: &'static str,
    /// Runs it.
    pub run: fn(&mut Bench) -> Result<Vec<Line>>,
}

/// Every case, in the catalogue's order. Cases whose object classes do not
/// exist yet (patches) are absent, not stubbed: docs/numerics.md lists them.
pub const CASES: &[Case] = &[
    triangles::T1,
    triangles::T2,
    triangles::T3,
    triangles::T4,
    aggregates::A1,
    aggregates::A2,
    aggregates::A3,
    aggregates::A4,
    aggregates::A5,
    quadrics::Q1,
    quadrics::Q2,
    quadrics::Q3,
    spawn::S1,
    spawn::S2,
    spawn::S3,
    spawn::S4,
    mirrors::S5,
    transforms::X1,
    transforms::X2,
    transforms::X3,
    hygiene::V1,
    hygiene::V2,
    hygiene::V3,
    integrators::I1,
    integrators::I2,
    integrators::I3,
];

/// Run `rtk stress`.
pub fn run(a: StressArgs, pool: &rayon::ThreadPool) -> Result<()> {
    let chosen: Vec<&Case> = CASES
        .iter()
        .filter(|c| a.case.is_empty() || a.case.iter().any(|p| c.id.starts_with(p.as_str())))
        .collect();
    if chosen.is_empty() {
        let ids: Vec<&str> = CASES.iter().map(|c| c.id).collect();
        bail!(
            "no case matches {:?}; the cases are {}",
            a.case,
            ids.join(", ")
        );
    }
    if a.list {
        for c in &chosen {
            println!("{:<4} {}", c.id, c.title);
        }
        return Ok(());
    }
    let size = if a.quick { Size::Quick } else { Size::Full };
    let mut bench = Bench::new(size, &a.plugin_path, pool)?;
    let mut lines = Vec::new();
    let mut failed = 0;
    if !a.json {
        println!(
            "{:<4} {:<44} {:<28} {:>12} {:>10}  result",
            "case", "setup", "metric", "value", "target"
        );
    }
    for c in chosen {
        let t = Instant::now();
        let got = (c.run)(&mut bench).map_err(|e| e.context(format!("case {}", c.id)))?;
        let secs = t.elapsed().as_secs_f64();
        for l in got {
            if !l.pass() {
                failed += 1;
            }
            if !a.json {
                println!("{}", l.row(c.id));
            }
            lines.push(serde_json::json!({
                "case": c.id, "title": c.title, "setup": l.setup, "metric": l.metric,
                "value": l.value, "target": l.target.to_string(), "pass": l.pass(),
                "seconds": secs,
            }));
        }
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&lines)?);
    } else {
        println!(
            "{} measurements, {} failed ({} size)",
            lines.len(),
            failed,
            if a.quick { "quick" } else { "full" }
        );
    }
    if failed > 0 {
        bail!("{failed} stress measurements missed their target");
    }
    Ok(())
}
