//! `rtk render`: a scene through the render loop into an image or a film
//! file. Everything the render path owns lives here: the loop and its f64
//! film ([`render_loop`]), the film file of checkpoints and crops
//! ([`film_file`]), the services the host gives integrators and shaders
//! ([`tracer`]) and the `--stats` record ([`stats`]).

pub(crate) mod film_file;
mod profile;
pub(crate) mod render_loop;
mod stats;
pub(crate) mod tracer;

use crate::shared::{output, scene, threads};
use anyhow::{anyhow, bail, Result};
use film_file::Header;
use render_loop::{Accum, Control, End, Film, Rect};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};
use tracer::Tracer;

/// The arguments of `rtk render`.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// The scene file: rtk's TOML, or Mitsuba XML (.xml) or pbrt-v4
    /// (.pbrt), translated as `rtk import` does.
    scene: PathBuf,
    #[command(flatten)]
    import: crate::import::ImportOptions,
    /// Output image: .png (8-bit sRGB) or .exr (linear float). Default:
    /// `[render] output`, else the scene's name with .png, in the current folder.
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    /// Also write the variance of one sample, per pixel and channel, to
    /// FILE (.exr): Mitsuba's convention for its reference `_var` images,
    /// what `rtk diff --ztest` and `--welch` read.
    #[arg(long, value_name = "FILE.exr")]
    variance: Option<PathBuf>,
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
    /// With the statistics, where the time went: traversal, surface records,
    /// light sampling, integrator and shaders, the render loop, and an
    /// estimate of the plugin boundary's share (docs/design.md). Costs a
    /// little time: the services read a cycle counter per call.
    #[arg(long)]
    profile: bool,
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

/// Set by the Ctrl-C (SIGINT) handler; the render loop polls it.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Exit status of a render stopped by Ctrl-C (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: i32 = 130;

/// Run `rtk render`; `start` is when the process started (the total time
/// `--stats` and the closing line report).
pub fn run(a: RenderArgs, start: Instant) -> Result<()> {
    let (pool, threads) = threads::pool(a.threads)?;
    let sets = scene_sets(&a)?;
    let time_limit = seconds("--time-limit", a.time_limit)?;
    let every =
        seconds("--checkpoint-every", a.checkpoint_every)?.unwrap_or(Duration::from_secs(60));

    let t_parse = Instant::now();
    let (file, desc) = scene::read_any_scene(&a.scene, &sets, a.safe, &a.import)?;
    let parse_time = t_parse.elapsed();

    let out = output_path(&a, desc.render.output.as_deref());
    output::check_writable(&out)?;
    if let Some(v) = &a.variance {
        check_variance_path(v, &out)?;
    }
    if let Some(c) = &a.checkpoint {
        output::check_can_create(c, "checkpoint")?;
    }
    let header = Header::new(&file.text.src, &sets, &desc.render);
    let mut accum = starting_film(&a, &header, desc.render.width, desc.render.height)?;

    let world = scene::build_world(&file, desc, &a.plugin_path, &pool)?;
    let passes = Passes {
        time_limit,
        checkpoint_every: every,
        profile: a
            .profile
            .then(|| profile::Profile::new(threads, &Tracer::new(&world).record())),
    };
    let (end, render_time) = render_in_passes(&a, &world, &pool, &header, &passes, &mut accum)?;
    let t_write = Instant::now();
    let (film, samples) = write_film(&a, &out, &header, accum)?;
    let times = stats::StepTimes {
        parse: parse_time,
        render: render_time,
        write: t_write.elapsed(),
        start,
    };

    if a.stats || a.profile {
        let profile = passes
            .profile
            .as_ref()
            .map(|p| p.json(render_time.as_secs_f64(), threads, film.stats.shader_calls));
        stats::print(&a, &out, &world, &film, threads, &times, samples, profile)?;
    }
    report_end(&a, end, &out, &film, world.desc.render.spp, samples, start);
    Ok(())
}

/// The `--set` overrides with those the flags imply (`--spp`, `--frame`).
fn scene_sets(a: &RenderArgs) -> Result<Vec<String>> {
    let mut sets = a.set.clone();
    if let Some(spp) = a.spp {
        sets.push(format!("render.spp={spp}"));
    }
    if let (Some(n), Some(f)) = (a.frame, a.frames) {
        sets.push(frame_shutter(n, f, a.shutter_fraction.unwrap_or(0.5))?);
    }
    Ok(sets)
}

/// A non-negative, finite number of seconds from `flag`.
fn seconds(flag: &str, v: Option<f64>) -> Result<Option<Duration>> {
    match v {
        None => Ok(None),
        Some(s) if (0.0..1e9).contains(&s) => Ok(Some(Duration::from_secs_f64(s))),
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

/// The film the render starts from: the `--resume` checkpoint (which must
/// be of this scene, these settings and this crop), else an empty one of
/// the `--crop` rectangle (or the full `width` x `height` image).
fn starting_film(a: &RenderArgs, header: &Header, width: u32, height: u32) -> Result<Accum> {
    let rect = match &a.crop {
        Some(c) => film_file::parse_crop(c, width, height)?,
        None => Rect::full(width, height),
    };
    match &a.resume {
        Some(r) => {
            let (got, accum) = film_file::read(r)?;
            got.check_matches(header, r, &a.scene)?;
            if accum.rect != rect {
                bail!(
                    "{} holds the pixels {} of the image, this render asks for {rect} (--crop must be the same)",
                    r.display(),
                    accum.rect
                );
            }
            Ok(accum)
        }
        None => Accum::new(width, height, rect).map_err(|m| anyhow!("{}: {m}", a.scene.display())),
    }
}

/// When the passes stop early, how often they save a checkpoint, and what
/// they time.
struct Passes {
    /// `--time-limit`.
    time_limit: Option<Duration>,
    /// `--checkpoint-every` (60 s by default).
    checkpoint_every: Duration,
    /// `--profile`'s accumulators.
    profile: Option<profile::Profile>,
}

/// Render the world into `accum` pass by pass until it is complete, the
/// time limit passes or Ctrl-C stops it, saving `--checkpoint` between
/// passes; returns how it ended and the time spent rendering.
fn render_in_passes(
    a: &RenderArgs,
    world: &rtk_shell::World,
    pool: &rayon::ThreadPool,
    header: &Header,
    passes: &Passes,
    accum: &mut Accum,
) -> Result<(End, Duration)> {
    let spp = world.desc.render.spp;
    let tracer = match &passes.profile {
        Some(p) => Tracer::new(world).with_profile(p),
        None => Tracer::new(world),
    };
    install_interrupt_handler();
    let t_render = Instant::now();
    let watchdog = passes
        .time_limit
        .map(|limit| HangWatchdog::start(t_render + limit, limit));
    let mut last_checkpoint = Instant::now();
    let mut last_pass = Instant::now();
    let mut save = |acc: &Accum| -> Result<(), String> {
        if let Some(w) = &watchdog {
            w.passed(last_pass.elapsed());
            last_pass = Instant::now();
        }
        if let Some(c) = &a.checkpoint {
            if last_checkpoint.elapsed() >= passes.checkpoint_every {
                film_file::write(c, header, acc).map_err(|e| format!("{e:#}"))?;
                last_checkpoint = Instant::now();
            }
        }
        Ok(())
    };
    let mut ctl = Control {
        progress: !a.quiet,
        // --time-limit: one sample per pixel a pass, so the render stops
        // close to the limit; otherwise spp/16, at most 16, so Ctrl-C soon
        // leaves every pixel an estimate. The image is the same either way.
        pass_spp: if passes.time_limit.is_some() {
            1
        } else {
            spp.div_ceil(16).clamp(1, 16)
        },
        stop: Some(&INTERRUPTED),
        deadline: passes.time_limit.map(|d| t_render + d),
        after_pass: &mut save,
    };
    let end = render_loop::render_passes(&tracer, pool, &mut ctl, accum)
        .map_err(|m| anyhow!("rendering {} failed: {m}", a.scene.display()));
    if let Some(w) = &watchdog {
        w.finished();
    }
    Ok((end?, t_render.elapsed()))
}

/// Exit status of a render whose plugin call did not return after
/// `--time-limit` (GNU `timeout`'s).
const EXIT_HUNG: i32 = 124;

/// Shortest wait past `--time-limit` before a render is taken to be hung.
const HANG_GRACE: Duration = Duration::from_secs(10);

/// Under `--time-limit`, the render stops after the pass during which the
/// limit passes. A pass that does not end (a plugin call looping) would
/// hang the host for ever: this thread waits past the limit for the
/// longest of [`HANG_GRACE`], the limit itself and twice the longest pass
/// so far, then names the plugins the render threads are in and exits
/// with [`EXIT_HUNG`] (the last checkpoint stays; nothing else is written).
struct HangWatchdog {
    state: std::sync::Arc<(std::sync::Mutex<(bool, Duration)>, std::sync::Condvar)>,
}

impl HangWatchdog {
    fn start(deadline: Instant, limit: Duration) -> HangWatchdog {
        let state = std::sync::Arc::new((
            std::sync::Mutex::new((false, Duration::ZERO)),
            std::sync::Condvar::new(),
        ));
        let s = state.clone();
        std::thread::spawn(move || {
            let (lock, cv) = &*s;
            let Ok(mut g) = lock.lock() else { return };
            loop {
                if g.0 {
                    return;
                }
                let grace = HANG_GRACE.max(limit).max(2 * g.1);
                let now = Instant::now();
                if now >= deadline + grace {
                    break;
                }
                let Ok((next, _)) = cv.wait_timeout(g, deadline + grace - now) else {
                    return;
                };
                g = next;
            }
            eprintln!(
                "error: --time-limit {:.1} s: the render has not stopped {:.1} s after the limit; a plugin call does not return",
                limit.as_secs_f64(),
                (Instant::now() - deadline).as_secs_f64()
            );
            crate::shared::faults::report_stuck_threads();
            std::process::exit(EXIT_HUNG);
        });
        HangWatchdog { state }
    }

    /// A pass took `d`.
    fn passed(&self, d: Duration) {
        if let Ok(mut g) = self.state.0.lock() {
            g.1 = g.1.max(d);
        }
    }

    /// The render returned: the watchdog stands down.
    fn finished(&self) {
        if let Ok(mut g) = self.state.0.lock() {
            g.0 = true;
        }
        self.state.1.notify_all();
    }
}

/// Write the last checkpoint and the output (an image, or a film file for
/// `rtk merge`); returns the film and its fewest and most samples per pixel.
fn write_film(
    a: &RenderArgs,
    out: &Path,
    header: &Header,
    accum: Accum,
) -> Result<(Film, (u32, u32))> {
    if let Some(c) = &a.checkpoint {
        film_file::write(c, header, &accum)?;
    }
    let samples = accum.sample_range();
    if film_file::is_film_path(out) {
        film_file::write(out, header, &accum)?;
    }
    if let Some(v) = &a.variance {
        let r = accum.rect;
        let variance = Film {
            width: r.width(),
            height: r.height(),
            pixels: accum.variance(),
            stats: Default::default(),
        };
        output::write(&variance, v)?;
    }
    let film = accum.into_film();
    if !film_file::is_film_path(out) {
        output::write(&film, out)?;
    }
    Ok((film, samples))
}

/// `--variance FILE` must be an EXR (a variance is no colour for a PNG)
/// that can be written, and not the image itself.
fn check_variance_path(v: &Path, out: &Path) -> Result<()> {
    let exr = v
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !exr {
        bail!(
            "--variance {}: the variance is written as linear floats: name an .exr file",
            v.display()
        );
    }
    if v == out {
        bail!(
            "--variance {}: the same file as the image; name another",
            v.display()
        );
    }
    output::check_writable(v)
}

/// The closing line on stderr; a render stopped by Ctrl-C exits here with
/// [`EXIT_INTERRUPTED`], saying how to resume it.
fn report_end(
    a: &RenderArgs,
    end: End,
    out: &Path,
    film: &Film,
    spp: u32,
    (min, max): (u32, u32),
    start: Instant,
) {
    let counts = if min == max {
        format!("{min} of {spp} samples per pixel")
    } else {
        format!("{min} to {max} of {spp} samples per pixel")
    };
    match end {
        End::Interrupted => {
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
        End::TimeUp => eprintln!(
            "time limit: wrote {} ({}x{}, {counts})",
            out.display(),
            film.width,
            film.height
        ),
        End::Complete if !a.quiet => eprintln!(
            "wrote {} ({}x{}, {spp} spp) in {:.2} s",
            out.display(),
            film.width,
            film.height,
            start.elapsed().as_secs_f64()
        ),
        End::Complete => {}
    }
}
