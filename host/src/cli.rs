//! The command line: clap's arguments and the dispatch to each command's
//! module, which does the work.

use crate::shared::printable;
use crate::shared::threads::{pool, Pool};
use crate::{
    bench_aggregate, conform, converge, diff, import, merge, new, plugins, render, stress, trace,
};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "rtk",
    version,
    about = "A ray tracer built on Kirk and Arvo's ray tracing kernel: every object class, shader, integrator, camera and light is a plugin."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to PNG (sRGB) or EXR (linear).
    Render(render::RenderArgs),
    /// Cast rays (a ray file, or the Embree anchor's sets) against a scene or
    /// a mesh under any aggregate: throughput, build time, memory, checksums.
    Trace(trace::TraceArgs),
    /// Run the numerical-stability catalogue (docs/numerics.md) through the
    /// real plugins: one line per case, metric, value, target, pass or fail.
    Stress(stress::StressArgs),
    /// Render a scene at several sample counts and seeds, timing each
    /// render and measuring its error against a reference: a CSV, a log-log
    /// plot of RMSE against seconds, the fitted slope, and the equal-error
    /// time ratio against another renderer's curve (--compare).
    Converge(converge::ConvergeArgs),
    /// RMSE and relMSE of image A against reference B (.exr, .pfm, .npy,
    /// .png); with --ztest or --welch, a statistical test of equal means
    /// (exit status 1 when it fails).
    Diff(diff::DiffArgs),
    /// List every plugin on the plugin path with its kind and parameters.
    Plugins {
        /// Extra folders to search first (repeatable).
        #[arg(long = "plugin-path", value_name = "DIR")]
        plugin_path: Vec<PathBuf>,
        /// Print only class, kind and file, not each plugin's documentation.
        #[arg(long)]
        short: bool,
        /// Load every plugin library on the path (shadowed ones too) and print
        /// one line per library: `ok` (class, kind, version) or `broken` with
        /// the loader's reason. Exits non-zero if any is broken.
        #[arg(long)]
        check: bool,
    },
    /// Translate a Mitsuba XML scene to rtk's TOML (docs/import.md),
    /// refusing with file, line and column what has no exact equivalent.
    Import(import::ImportArgs),
    /// Stitch crop films (`rtk render --crop ... -o PART.rtkfilm`) into the
    /// full image, bit for bit what a single render gives.
    Merge {
        /// The full image: .png, .exr, or .rtkfilm.
        out: PathBuf,
        /// The crop films (.rtkfilm), complete, of one scene and settings,
        /// together covering the image without overlap.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
    },
    /// Write a ready-to-build plugin crate of any kind (Cargo.toml against
    /// this rtk's kernel, the smallest correct implementation, its README.md
    /// and a scene using it).
    New(new::NewArgs),
    /// Time an aggregate against others on meshes, side by side in one run:
    /// build time, memory, Mrays/s (primary, incoherent, occluded), ratios.
    BenchAggregate(bench_aggregate::BenchArgs),
    /// Run the conformance suite of a plugin library of any kind (object,
    /// aggregate, shader, camera, light, integrator): one line per check,
    /// pass, FAIL or skip (with why); exits non-zero on any failure.
    Conform(conform::ConformArgs),
}

/// Die quietly on a closed pipe (`rtk diff A B | head -1`), as command-line
/// tools do: Rust ignores SIGPIPE, which turns every later `println!` into
/// a panic.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to its default at start-up,
    // before any thread exists, is async-signal-safe and races nothing.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The `rtk` binary: parse the command line, run the command, exit 1 with
/// the error on failure.
pub fn main() {
    restore_sigpipe();
    crate::shared::faults::install();
    let start = Instant::now();
    if let Err(e) = dispatch(Cli::parse(), start, false) {
        eprintln!("error: {}", printable(&format!("{e:#}")));
        std::process::exit(1);
    }
}

/// Run one command line (`["converge", "scene.toml", ...]`, without the
/// program name) in this process, returning its error: how an embedding
/// host reaches the commands it has no API of its own for.
pub fn run_args(args: &[String]) -> anyhow::Result<()> {
    let argv = std::iter::once("rtk".to_string()).chain(args.iter().cloned());
    let cli = Cli::try_parse_from(argv).map_err(|e| anyhow::anyhow!("{}", e.render()))?;
    dispatch(cli, Instant::now(), true)
}

/// Run the parsed command; `embedded`: inside another program (no child
/// processes of the running executable, which is not `rtk`).
fn dispatch(cli: Cli, start: Instant, embedded: bool) -> anyhow::Result<()> {
    match cli.command {
        Command::Render(a) => render::run(a, start),
        Command::Trace(a) => {
            pool(a.threads).and_then(|(pool, _)| trace::run(a, &pool, &Pool(&pool)))
        }
        Command::Stress(a) => pool(a.threads).and_then(|(pool, _)| stress::run(a, &pool)),
        Command::Converge(a) => {
            pool(a.threads).and_then(|(pool, threads)| converge::run(a, &pool, threads))
        }
        Command::Diff(a) => diff::run(&a),
        Command::Plugins {
            plugin_path,
            short,
            check,
        } => {
            if check {
                plugins::check(&plugin_path)
            } else {
                plugins::list(&plugin_path, short)
            }
        }
        Command::Import(a) => import::run(&a),
        Command::Merge { out, parts } => merge::run(&out, &parts),
        Command::New(a) => new::run(a),
        Command::Conform(a) if !a.in_process && !embedded => conform::run_in_child(),
        Command::Conform(a) => {
            pool(Some(a.threads.max(2))).and_then(|(pool, _)| conform::run(a, &pool))
        }
        Command::BenchAggregate(a) => {
            pool(a.threads).and_then(|(pool, _)| bench_aggregate::run(a, &pool, &Pool(&pool)))
        }
    }
}
