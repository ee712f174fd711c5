//! `rtk`: render TOML scenes with plugin object classes, shaders, integrators,
//! cameras and lights.

mod bench_aggregate;
mod conform;
mod converge;
mod new;
mod render;
mod shared;
mod stress;
mod trace;

use render::{film_file as checkpoint, render_loop, tracer};
use shared::{images, output};

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use rtk_kernel::abi::{geom_mask, ray_kind, Stats};
use rtk_shell::{Parallel, PluginPath, Registry};
use std::path::{Path, PathBuf};
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
    Render(RenderArgs),
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
    /// RMSE and relMSE of image A against reference B (.exr, .pfm, .npy, .png).
    Diff {
        /// The image.
        a: PathBuf,
        /// The reference.
        b: PathBuf,
    },
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

#[derive(clap::Args)]
struct RenderArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Output image: .png (8-bit sRGB) or .exr (linear float). Default:
    /// `[render] output`, else the scene's name with .png, in the current folder.
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Frame N (from 0) of an animation of `--frames` frames: the scene's
    /// time [0, 1] (the `motion` class's keyframes) is split into equal
    /// frames and this render's shutter is frame N's share of it (with
    /// `--shutter-fraction` of the frame open, from its start).
    #[arg(long, value_name = "N", requires = "frames")]
    frame: Option<u32>,
    /// Number of frames in the animation (with --frame).
    #[arg(long, value_name = "F", requires = "frame")]
    frames: Option<u32>,
    /// Part of each frame's time the shutter is open (default 0.5, a film
    /// camera's 180° shutter).
    #[arg(long = "shutter-fraction", value_name = "F", requires = "frame")]
    shutter_fraction: Option<f64>,
    /// Samples per pixel (same as --set render.spp=N).
    #[arg(long, value_name = "N")]
    spp: Option<u32>,
    /// Rendering threads (default: all cores). The image is identical for any count.
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Override a scene value, e.g. --set render.width=256 --set objects.ball.radius=2 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// Print statistics (timings, rays by kind, plugins, objects) as JSON on stdout.
    #[arg(long)]
    stats: bool,
    /// Extra folders to search for plugins first (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    plugin_path: Vec<PathBuf>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Distrust the scene: its output and its file parameters (keys named
    /// `file` or ending in `_file`) must lie inside its folder or the working
    /// directory, and its output may not be an absolute path.
    #[arg(long)]
    safe: bool,
    /// Render only the pixels [x0, x1) x [y0, y1) of the full image (the
    /// camera still sees the full image); the output is the crop's size.
    /// With `-o PART.rtkfilm`, crops are stitched by `rtk merge`.
    #[arg(long, value_name = "X0,Y0,X1,Y1")]
    crop: Option<String>,
    /// Save the film (f64 sums, per-pixel sample counts, the scene's hash and
    /// settings) to FILE atomically between sample passes, every
    /// --checkpoint-every seconds, and when the render stops.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints (default 60; 0: after every pass).
    #[arg(
        long = "checkpoint-every",
        value_name = "SECS",
        requires = "checkpoint"
    )]
    checkpoint_every: Option<f64>,
    /// Continue the render saved in FILE (a checkpoint of the same scene,
    /// settings and crop): the image is bit-identical to an uninterrupted run.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Render in passes of one sample per pixel and stop after the pass
    /// during which SECS seconds of rendering have passed (or at spp).
    #[arg(long = "time-limit", value_name = "SECS")]
    time_limit: Option<f64>,
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

fn main() {
    restore_sigpipe();
    let start = Instant::now();
    let cli = Cli::parse();
    let res = match cli.command {
        Command::Render(a) => cmd_render(a, start),
        Command::Trace(a) => cmd_trace(a),
        Command::Stress(a) => pool(a.threads).and_then(|(pool, _)| stress::run(a, &pool)),
        Command::Converge(a) => {
            pool(a.threads).and_then(|(pool, threads)| converge::run(a, &pool, threads))
        }
        Command::Diff { a, b } => cmd_diff(&a, &b),
        Command::Plugins {
            plugin_path,
            short,
            check,
        } => {
            if check {
                cmd_plugins_check(&plugin_path)
            } else {
                cmd_plugins(&plugin_path, short)
            }
        }
        Command::Merge { out, parts } => checkpoint::merge(&out, &parts),
        Command::New(a) => new::run(a),
        Command::Conform(a) => {
            pool(Some(a.threads.max(2))).and_then(|(pool, _)| conform::run(a, &pool))
        }
        Command::BenchAggregate(a) => {
            pool(a.threads).and_then(|(pool, _)| bench_aggregate::run(a, &pool, &Pool(&pool)))
        }
    };
    if let Err(e) = res {
        eprintln!("error: {}", printable(&format!("{e:#}")));
        std::process::exit(1);
    }
}

/// An error message made safe for the terminal: control characters that
/// reached it from a scene or a file (escape sequences) escaped, and each
/// line cut to a readable length. The shell's own errors are escaped
/// already; this covers the host's (paths, output names).
fn printable(msg: &str) -> String {
    msg.split('\n')
        .map(|l| rtk_shell::error::shown(l, rtk_shell::error::MAX_SHOWN_MESSAGE))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The host's rayon pool as the shell's [`Parallel`].
pub(crate) struct Pool<'a>(pub(crate) &'a rayon::ThreadPool);

impl Parallel for Pool<'_> {
    fn max_threads(&self) -> u32 {
        self.0.current_num_threads() as u32
    }
    fn run(&self, n: u64, f: &(dyn Fn(u64) + Sync)) {
        use rayon::prelude::*;
        self.0.install(|| (0..n).into_par_iter().for_each(f));
    }
}

/// Most rendering threads: starting the pool and the plugins' per-thread
/// state grow faster than linearly with the count (4096 threads take seconds
/// to start, 100000 practically never finish).
const MAX_THREADS: usize = 1024;

/// The rendering pool: `threads` threads (default: all cores, at most
/// [`MAX_THREADS`]).
fn pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, |n| n.get().min(MAX_THREADS))
    });
    if threads == 0 {
        bail!("--threads must be at least 1");
    }
    if threads > MAX_THREADS {
        bail!("--threads must be at most {MAX_THREADS}, got {threads}");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("rtk-render-{i}"))
        // Whitted recursion goes through plugin frames at every bounce
        // (max_depth up to 1024): a roomy stack, committed only as used.
        .stack_size(64 << 20)
        .build()
        .context("starting the thread pool")?;
    Ok((pool, threads))
}

fn cmd_trace(a: trace::TraceArgs) -> Result<()> {
    let (pool, _) = pool(a.threads)?;
    trace::run(a, &pool, &Pool(&pool))
}

/// Set by the Ctrl-C (SIGINT) handler; the render loop polls it.
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Exit status of a render stopped by Ctrl-C (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: i32 = 130;

/// A non-negative, finite number of seconds from `flag`.
fn seconds(flag: &str, v: Option<f64>) -> Result<Option<std::time::Duration>> {
    match v {
        None => Ok(None),
        Some(s) if (0.0..1e9).contains(&s) => Ok(Some(std::time::Duration::from_secs_f64(s))),
        Some(s) => bail!("{flag} {s}: expected a number of seconds, at least 0"),
    }
}

/// Stop the render at the next sample on the first Ctrl-C; quit at once
/// (nothing written) on the second.
fn install_interrupt_handler() {
    use std::sync::atomic::Ordering;
    let res = ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(EXIT_INTERRUPTED);
        }
    });
    if let Err(e) = res {
        eprintln!("warning: Ctrl-C will not save the image: {e}");
    }
}

/// The `render.shutter` override for frame `n` of `frames`: its share of
/// the scene's time [0, 1], open for `fraction` of it from the frame's start.
fn frame_shutter(n: u32, frames: u32, fraction: f64) -> Result<String> {
    if frames == 0 || n >= frames {
        anyhow::bail!("--frame {n} --frames {frames}: the frame must be below the frame count");
    }
    if !(0.0..=1.0).contains(&fraction) {
        anyhow::bail!("--shutter-fraction {fraction}: must lie in [0, 1]");
    }
    let open = n as f64 / frames as f64;
    let close = open + fraction / frames as f64;
    Ok(format!("render.shutter=[{open:?}, {close:?}]"))
}

fn cmd_render(a: RenderArgs, start: Instant) -> Result<()> {
    let (pool, threads) = pool(a.threads)?;
    let mut sets = a.set.clone();
    if let Some(spp) = a.spp {
        sets.push(format!("render.spp={spp}"));
    }
    if let (Some(n), Some(f)) = (a.frame, a.frames) {
        sets.push(frame_shutter(n, f, a.shutter_fraction.unwrap_or(0.5))?);
    }
    let time_limit = seconds("--time-limit", a.time_limit)?;
    let every = seconds("--checkpoint-every", a.checkpoint_every)?
        .unwrap_or(std::time::Duration::from_secs(60));

    let t_parse = Instant::now();
    let (file, desc) = read_scene(&a.scene, &sets, a.safe)?;
    let parse_time = t_parse.elapsed();

    let out = output_path(&a, desc.render.output.as_deref());
    output::check_writable(&out)?;
    if let Some(c) = &a.checkpoint {
        output::check_can_create(c, "checkpoint")?;
    }
    let header = checkpoint::Header::new(&file.text.src, &sets, &desc.render);
    let (w, h) = (desc.render.width, desc.render.height);
    let rect = match &a.crop {
        Some(c) => checkpoint::parse_crop(c, w, h)?,
        None => render_loop::Rect::full(w, h),
    };
    let mut accum = match &a.resume {
        Some(r) => {
            let (got, accum) = checkpoint::read(r)?;
            got.check_matches(&header, r, &a.scene)?;
            if accum.rect != rect {
                bail!(
                    "{} holds the pixels {} of the image, this render asks for {rect} (--crop must be the same)",
                    r.display(),
                    accum.rect
                );
            }
            accum
        }
        None => render_loop::Accum::new(w, h, rect)
            .map_err(|m| anyhow::anyhow!("{}: {m}", a.scene.display()))?,
    };

    let world = build_world(&file, desc, &a.plugin_path, &pool)?;
    let spp = world.desc.render.spp;

    let tracer = tracer::Tracer::new(&world);
    install_interrupt_handler();
    let t_render = Instant::now();
    let mut last_checkpoint = Instant::now();
    let mut save = |acc: &render_loop::Accum| -> Result<(), String> {
        if let Some(c) = &a.checkpoint {
            if last_checkpoint.elapsed() >= every {
                checkpoint::write(c, &header, acc).map_err(|e| format!("{e:#}"))?;
                last_checkpoint = Instant::now();
            }
        }
        Ok(())
    };
    let mut ctl = render_loop::Control {
        progress: !a.quiet,
        // --time-limit: one sample per pixel a pass, so the render stops
        // close to the limit; otherwise spp/16, at most 16, so Ctrl-C soon
        // leaves every pixel an estimate. The image is the same either way.
        pass_spp: if time_limit.is_some() {
            1
        } else {
            spp.div_ceil(16).clamp(1, 16)
        },
        stop: Some(&INTERRUPTED),
        deadline: time_limit.map(|d| t_render + d),
        after_pass: &mut save,
    };
    let end = render_loop::render_passes(&tracer, &pool, &mut ctl, &mut accum)
        .map_err(|m| anyhow::anyhow!("rendering {} failed: {m}", a.scene.display()))?;
    let render_time = t_render.elapsed();
    let t_write = Instant::now();
    if let Some(c) = &a.checkpoint {
        checkpoint::write(c, &header, &accum)?;
    }
    let (min, max) = accum.sample_range();
    if checkpoint::is_film_path(&out) {
        checkpoint::write(&out, &header, &accum)?;
    }
    let film = accum.into_film();
    if !checkpoint::is_film_path(&out) {
        output::write(&film, &out)?;
    }
    let times = StepTimes {
        parse: parse_time,
        render: render_time,
        write: t_write.elapsed(),
        start,
    };

    if a.stats {
        let mut json = stats_json(&a, &out, &world, &film, threads, &times);
        json["samples_per_pixel"] = serde_json::json!([min, max]);
        // A closed pipe (`| head`) is not an error worth a panic.
        use std::io::Write;
        let _ = writeln!(
            std::io::stdout(),
            "{}",
            serde_json::to_string_pretty(&json)?
        );
    }
    let counts = if min == max {
        format!("{min} of {spp} samples per pixel")
    } else {
        format!("{min} to {max} of {spp} samples per pixel")
    };
    match end {
        render_loop::End::Interrupted => {
            eprintln!(
                "interrupted: wrote {} ({}x{}, {counts}){}",
                out.display(),
                film.width,
                film.height,
                a.checkpoint
                    .as_ref()
                    .map(|c| format!("; continue with --resume {}", c.display()))
                    .unwrap_or_default()
            );
            std::process::exit(EXIT_INTERRUPTED);
        }
        render_loop::End::TimeUp => eprintln!(
            "time limit: wrote {} ({}x{}, {counts})",
            out.display(),
            film.width,
            film.height
        ),
        render_loop::End::Complete if !a.quiet => eprintln!(
            "wrote {} ({}x{}, {spp} spp) in {:.2} s",
            out.display(),
            film.width,
            film.height,
            start.elapsed().as_secs_f64()
        ),
        render_loop::End::Complete => {}
    }
    Ok(())
}

/// Read a scene file and apply `--set` overrides; with `safe`, check it
/// (`--safe`). Returns the file and its description.
pub(crate) fn read_scene(
    scene: &Path,
    sets: &[String],
    safe: bool,
) -> Result<(rtk_shell::SceneFile, rtk_shell::Desc)> {
    let mut file = rtk_shell::SceneFile::read(scene)?;
    file.apply_overrides(sets)?;
    let desc = rtk_shell::Desc::from_file(&file)?;
    if safe {
        rtk_shell::safe::check(&file, &desc)?;
    }
    Ok((file, desc))
}

/// A black film of the scene's image size (allocated fallibly).
pub(crate) fn new_film(desc: &rtk_shell::Desc, scene: &Path) -> Result<render_loop::Film> {
    render_loop::Film::new(desc.render.width, desc.render.height)
        .map_err(|m| anyhow::anyhow!("{}: {m}", scene.display()))
}

/// Load the plugins the scene needs (searching `plugin_path` first) and
/// build its world on the pool.
pub(crate) fn build_world(
    file: &rtk_shell::SceneFile,
    desc: rtk_shell::Desc,
    plugin_path: &[PathBuf],
    pool: &rayon::ThreadPool,
) -> Result<rtk_shell::World> {
    let mut registry = Registry::new(PluginPath::standard(plugin_path));
    Ok(rtk_shell::build(file, desc, &mut registry, &Pool(pool))?)
}

/// Render the world (its `[render]` settings: size, spp, seed) into `film`.
pub(crate) fn render_film(
    tracer: &tracer::Tracer,
    pool: &rayon::ThreadPool,
    progress: bool,
    film: render_loop::Film,
    scene: &Path,
) -> Result<render_loop::Film> {
    render_loop::render(tracer, pool, progress, film)
        .map_err(|m| anyhow::anyhow!("rendering {} failed: {m}", scene.display()))
}

/// `rtk diff A B`: the metrics of A against the reference B.
fn cmd_diff(a: &Path, b: &Path) -> Result<()> {
    let img = images::read(a)?;
    let reference = images::read(b)?;
    images::check_same_size(
        (img.width, img.height),
        &a.display().to_string(),
        (reference.width, reference.height),
        &b.display().to_string(),
    )?;
    let m = images::metrics(&img.data, &reference.data);
    println!("rmse {}", m.rmse);
    println!("relmse {}", m.relmse);
    Ok(())
}

/// `-o`, else `[render] output`, else the scene's name with `.png`.
fn output_path(a: &RenderArgs, scene_output: Option<&str>) -> PathBuf {
    match (&a.output, scene_output) {
        (Some(o), _) => o.clone(),
        (None, Some(o)) => PathBuf::from(o),
        (None, None) => PathBuf::from(format!(
            "{}.png",
            a.scene
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "render".into())
        )),
    }
}

/// How long the host's own steps took.
struct StepTimes {
    parse: std::time::Duration,
    render: std::time::Duration,
    write: std::time::Duration,
    start: Instant,
}

/// The `--stats` record.
fn stats_json(
    a: &RenderArgs,
    out: &Path,
    world: &rtk_shell::World,
    film: &render_loop::Film,
    threads: usize,
    t: &StepTimes,
) -> serde_json::Value {
    let s = &film.stats;
    serde_json::json!({
        "scene": a.scene.display().to_string(),
        "output": out.display().to_string(),
        "width": film.width,
        "height": film.height,
        "spp": world.desc.render.spp,
        "threads": threads,
        "seconds": {
            "parse": t.parse.as_secs_f64(),
            "load_plugins": world.timings.load_plugins.as_secs_f64(),
            "create": world.timings.create.as_secs_f64(),
            "prepare": world.timings.prepare.as_secs_f64(),
            "render": t.render.as_secs_f64(),
            "write": t.write.as_secs_f64(),
            "total": t.start.elapsed().as_secs_f64(),
        },
        "plugins_loaded": world.plugins.iter().map(|p| p.class.clone()).collect::<Vec<_>>(),
        "plugins_mapped": mapped_plugins(),
        "objects_created": world.objects_created,
        "shaders_created": world.shaders.len(),
        "lights": world.lights.len(),
        "files_read": world.files_read,
        "rays": rays_json(s),
        "local_geom": {
            "calls": s.local_geom_calls,
            "position": s.local_geom_fields[bit(geom_mask::POSITION)],
            "geometric_normal": s.local_geom_fields[bit(geom_mask::GEOMETRIC_NORMAL)],
            "shading_normal": s.local_geom_fields[bit(geom_mask::SHADING_NORMAL)],
            "tangents": s.local_geom_fields[bit(geom_mask::TANGENTS)],
            "uv": s.local_geom_fields[bit(geom_mask::UV)],
        },
        "node_tests": s.node_tests,
        "prim_tests": s.prim_tests,
        "shader_calls": s.shader_calls,
        "light_samples": s.light_samples,
        "nonfinite_samples": s.nonfinite_samples,
    })
}

fn bit(mask: u32) -> usize {
    mask.trailing_zeros() as usize
}

fn rays_json(s: &Stats) -> serde_json::Value {
    serde_json::json!({
        "camera": s.rays[ray_kind::CAMERA as usize],
        "reflection": s.rays[ray_kind::REFLECTION as usize],
        "refraction": s.rays[ray_kind::REFRACTION as usize],
        "shadow": s.rays[ray_kind::SHADOW as usize],
        "scatter": s.rays[ray_kind::SCATTER as usize],
    })
}

/// The rtk plugin libraries actually mapped into this process, read from
/// the OS (Linux), not from the loader's own bookkeeping.
fn mapped_plugins() -> Vec<String> {
    let Ok(maps) = std::fs::read_to_string("/proc/self/maps") else {
        return vec![];
    };
    let prefix = format!("{}rtk_", std::env::consts::DLL_PREFIX);
    let mut out: Vec<String> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| {
            Path::new(p)
                .file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| {
                    n.starts_with(&prefix) && n.ends_with(std::env::consts::DLL_SUFFIX)
                })
        })
        .map(str::to_string)
        .collect();
    out.sort();
    out.dedup();
    out
}

fn cmd_plugins(extra: &[PathBuf], short: bool) -> Result<()> {
    let path = PluginPath::standard(extra);
    println!("plugin path (first match wins):");
    for d in &path.dirs {
        println!("  {}", d.display());
    }
    let avail = path.available();
    if avail.is_empty() {
        println!("\nno plugins found");
        return Ok(());
    }
    for (class, file) in avail {
        match rtk_shell::plugins::load(&file, Some(&class)) {
            Ok(p) => {
                println!(
                    "\n{class}  [{}]  v{}  {}",
                    p.kind.name(),
                    p.version,
                    file.display()
                );
                if !short {
                    for l in p.doc.lines() {
                        println!("    {l}");
                    }
                }
            }
            Err(e) => println!("\n{class}  [refused]  {e}"),
        }
    }
    Ok(())
}

/// `rtk plugins --check`: load every plugin library on the path, one line each.
fn cmd_plugins_check(extra: &[PathBuf]) -> Result<()> {
    let path = PluginPath::standard(extra);
    let libs = path.libraries();
    let mut seen = std::collections::BTreeMap::<String, PathBuf>::new();
    let mut broken = 0;
    for (file, class) in &libs {
        let Some(class) = class else {
            broken += 1;
            println!(
                "broken  {}: the file name must be {} with a class name made of letters, digits and _",
                file.display(),
                rtk_shell::plugins::library_file_name("<class>")
            );
            continue;
        };
        let shadow = match seen.get(class) {
            Some(first) => format!("  (shadowed by {}: not used)", first.display()),
            None => {
                seen.insert(class.clone(), file.clone());
                String::new()
            }
        };
        match rtk_shell::plugins::load(file, Some(class)) {
            Ok(p) => println!(
                "ok      {class}  [{}]  v{}  {}{shadow}",
                p.kind.name(),
                p.version,
                file.display()
            ),
            Err(e) => {
                broken += 1;
                let reason = printable(&e.to_string()).replace('\n', " ");
                println!("broken  {class}  {}: {reason}{shadow}", file.display());
            }
        }
    }
    println!(
        "{} plugin libraries: {} ok, {broken} broken",
        libs.len(),
        libs.len() - broken
    );
    if broken > 0 {
        bail!(
            "{broken} of {} plugin libraries on the plugin path cannot be loaded",
            libs.len()
        );
    }
    Ok(())
}
