//! The render loop: tiles over the host's rayon pool, a random stream per
//! (seed, pixel, sample), an f64 film. The image does not depend on the
//! thread count or on the order tiles finish.
//!
//! The film ([`Accum`]) holds, per pixel, the f64 sum of its samples and
//! how many there are. A render runs in *passes*: each pass brings every
//! pixel's count up to the next multiple of the pass size (or to `spp`),
//! adding each new sample to the pixel's running sum in sample-index order.
//! Since sample `s` of pixel `p` draws only from `(seed, p, s)`, the sum —
//! and the final pixel, sum × (1 / spp) — is the same f64 however the work
//! was split into passes, runs (checkpoint and resume), crops or threads.

use crate::render::tracer::Tracer;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rtk_kernel::abi::*;
use rtk_kernel::sdk::batch;
use rtk_shell::desc::render::Filter;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

mod chunked;

/// Edge of a square tile, in pixels.
pub const TILE: u32 = 16;

/// A finished render.
pub struct Film {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Linear RGB per pixel, row-major from the top, averaged over samples.
    pub pixels: Vec<[f64; 3]>,
    /// Counters summed over threads.
    pub stats: Stats,
}

/// Bytes of film per pixel: linear RGB in f64.
const FILM_BYTES_PER_PIXEL: u64 = std::mem::size_of::<[f64; 3]>() as u64;

/// Bytes of an [`Accum`] per pixel: the f64 sums, their squares and the
/// sample count.
const ACCUM_BYTES_PER_PIXEL: u64 = 2 * FILM_BYTES_PER_PIXEL + 4;

/// A vector of `n` copies of `v`, allocated fallibly.
fn try_filled<T: Clone>(n: usize, v: T) -> Option<Vec<T>> {
    let mut out = Vec::new();
    out.try_reserve_exact(n).ok()?;
    out.resize(n, v);
    Some(out)
}

impl Film {
    /// A black film of `width` x `height`, allocated before the scene is
    /// built and fallibly: an image too large for memory fails with a
    /// message, where an infallible allocation would abort the process.
    pub fn new(width: u32, height: u32) -> Result<Film, String> {
        let n = width as usize * height as usize;
        let pixels = try_filled(n, [0.0; 3]).ok_or_else(|| {
            format!(
                "the film of {width}x{height} pixels needs {} MiB ({FILM_BYTES_PER_PIXEL} bytes a pixel), which could not be allocated: render a smaller image",
                (n as u64 * FILM_BYTES_PER_PIXEL) >> 20
            )
        })?;
        Ok(Film {
            width,
            height,
            pixels,
            stats: Stats::default(),
        })
    }
}

/// A pixel rectangle `[x0, x1) x [y0, y1)` of the full image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rect {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// One past the right column.
    pub x1: u32,
    /// One past the bottom row.
    pub y1: u32,
}

impl Rect {
    /// The whole image.
    pub fn full(width: u32, height: u32) -> Rect {
        Rect {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
    /// Width.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }
    /// Height.
    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }
    /// Pixels.
    pub fn len(&self) -> usize {
        self.width() as usize * self.height() as usize
    }
}

impl std::fmt::Display for Rect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// A film being rendered: per pixel of `rect` (a rectangle of the full
/// image, all of it unless cropped), the f64 sum of its samples' radiance,
/// the sum of their squares and their number. What checkpoints and crop
/// files hold. The squares cost 24 bytes a pixel and three multiply-adds a
/// sample; they give every render its per-pixel variance (`--variance`),
/// which the statistical tests of `rtk diff` need and which cannot be
/// recovered afterwards.
pub struct Accum {
    /// Width of the full image (what the camera sees).
    pub full_width: u32,
    /// Height of the full image.
    pub full_height: u32,
    /// The pixels held.
    pub rect: Rect,
    /// Per pixel of `rect`, row-major: the sum of its samples.
    pub sums: Vec<[f64; 3]>,
    /// Per pixel of `rect`: the sum of its samples' squares, per channel.
    pub squares: Vec<[f64; 3]>,
    /// Per pixel of `rect`: how many samples the sum holds.
    pub counts: Vec<u32>,
    /// Counters summed over threads (of this run only).
    pub stats: Stats,
}

impl Accum {
    /// An empty film for `rect` of a `full_width` x `full_height` image,
    /// allocated fallibly.
    pub fn new(full_width: u32, full_height: u32, rect: Rect) -> Result<Accum, String> {
        let n = rect.len();
        let fail = || {
            format!(
                "the film of {}x{} pixels needs {} MiB ({ACCUM_BYTES_PER_PIXEL} bytes a pixel), which could not be allocated: render a smaller image",
                rect.width(),
                rect.height(),
                (n as u64 * ACCUM_BYTES_PER_PIXEL) >> 20
            )
        };
        let sums = try_filled(n, [0.0; 3]).ok_or_else(fail)?;
        let squares = try_filled(n, [0.0; 3]).ok_or_else(fail)?;
        let counts = try_filled(n, 0u32).ok_or_else(fail)?;
        Ok(Accum {
            full_width,
            full_height,
            rect,
            sums,
            squares,
            counts,
            stats: Stats::default(),
        })
    }

    /// The fewest and the most samples any pixel has.
    pub fn sample_range(&self) -> (u32, u32) {
        let min = self.counts.iter().copied().min().unwrap_or(0);
        let max = self.counts.iter().copied().max().unwrap_or(0);
        (min, max)
    }

    /// The variance of one sample, per pixel and channel: the unbiased
    /// sample variance (sum of squares − sum²/n) / (n − 1), clamped at 0
    /// against rounding; 0 for pixels with fewer than two samples. This is
    /// the per-sample variance Mitsuba's reference `_var` images hold (its
    /// `moment` integrator's m₂ − m₁², which differs by n/(n−1)).
    pub fn variance(&self) -> Vec<[f64; 3]> {
        (self.sums.iter().zip(&self.squares).zip(&self.counts))
            .map(|((s, q), &c)| {
                if c < 2 {
                    return [0.0; 3];
                }
                let n = c as f64;
                std::array::from_fn(|k| ((q[k] - s[k] * s[k] / n) / (n - 1.0)).max(0.0))
            })
            .collect()
    }

    /// The image: each pixel its sum × (1 / count), black without samples.
    /// Converted in place (no second image-sized buffer).
    pub fn into_film(self) -> Film {
        let mut pixels = self.sums;
        for (p, &c) in pixels.iter_mut().zip(&self.counts) {
            if c == 0 {
                *p = [0.0; 3];
            } else {
                let inv = 1.0 / c as f64;
                *p = [p[0] * inv, p[1] * inv, p[2] * inv];
            }
        }
        Film {
            width: self.rect.width(),
            height: self.rect.height(),
            pixels,
            stats: self.stats,
        }
    }
}

/// How a render ([`render_passes`]) ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// Every pixel has all its samples.
    Complete,
    /// Stopped by the stop flag (Ctrl-C): pixels may have different counts.
    Interrupted,
    /// Stopped at the time limit, between passes: every pixel has the same count.
    TimeUp,
}

/// What steers a render besides the scene.
pub struct Control<'a> {
    /// Show a progress bar (after a second).
    pub progress: bool,
    /// Samples per pixel a pass adds (at least 1; more for an image of a
    /// tile or fewer per thread, so a pass has samples for every thread).
    pub pass_spp: u32,
    /// Set (by the Ctrl-C handler) to stop: polled before every sample.
    pub stop: Option<&'a AtomicBool>,
    /// Stop after the pass during which this instant passes.
    pub deadline: Option<Instant>,
    /// Called after every pass but the last (checkpoints).
    pub after_pass: &'a mut dyn FnMut(&Accum) -> Result<(), String>,
}

/// The first plugin failure of the render, and the flag that stops the other
/// threads. A failure is recorded in a thread's trace context by the plugin's
/// SDK shim; the render loop reads the context after every camera sample.
#[derive(Default)]
struct Failure {
    stop: AtomicBool,
    first: Mutex<Option<String>>,
}

impl Failure {
    /// Take the failure recorded in `ctx`, if any; true when the render must stop.
    fn check(&self, ctx: &TraceCtx) -> bool {
        if let Some((class, msg)) = ctx.failure() {
            self.stop.store(true, Ordering::Relaxed);
            if let Ok(mut first) = self.first.lock() {
                first.get_or_insert_with(|| format!("plugin `{class}` {msg}"));
            }
        }
        self.stop.load(Ordering::Relaxed)
    }
}

/// What every tile needs to know.
struct Job<'a, 'w> {
    tracer: &'a Tracer<'w>,
    /// Full image size (the camera's film).
    width: u32,
    height: u32,
    /// The pixels rendered.
    rect: Rect,
    spp: u32,
    seed: u64,
    filter: Option<Filter>,
    stratified: bool,
    shutter: [f32; 2],
    tiles_x: u32,
    threads: u32,
    /// Per thread: the next query id (mailbox ids never repeat on a thread).
    next_query: Vec<AtomicU64>,
    failure: Failure,
    interrupt: Option<&'a AtomicBool>,
}

/// Where in the pixel sample `s` of `spp` looks, from the pixel's corner:
/// drawn from the pixel filter's own distribution (so every sample weighs
/// 1). Without a filter, one sample looks through the centre (a 1-spp image
/// is the exact pinhole image) and more spread uniformly (a box).
///
/// Stratified (`sampler = "stratified"`, spp = m²): sample s draws its two
/// uniform numbers in cell (s mod m, s div m) of an m×m grid instead of the
/// whole square. Each cell holds exactly one of the pixel's samples, so the
/// pixel's mean stays an unbiased estimate, and edges (a light's
/// silhouette) converge faster. Keyed on the sample index and the total
/// spp, never the pass, so passes, resumes and crops give the same image.
/// Other spp fall back to independent positions.
#[inline]
fn film_offset(
    filter: Option<Filter>,
    s: u32,
    spp: u32,
    stratified: bool,
    rng: &mut RngState,
) -> (f32, f32) {
    if filter.is_none() && spp == 1 {
        return (0.5, 0.5);
    }
    let (mut u1, mut u2) = (rng.next_f32(), rng.next_f32());
    if stratified {
        let m = (spp as f64).sqrt() as u32;
        if m * m == spp && m > 1 {
            let inv = 1.0 / m as f32;
            // Still below 1 after rounding, so the sample stays in its pixel.
            u1 = (((s % m) as f32 + u1) * inv).min(1.0 - f32::EPSILON / 2.0);
            u2 = (((s / m) as f32 + u2) * inv).min(1.0 - f32::EPSILON / 2.0);
        }
    }
    match filter {
        None | Some(Filter::Box) => (u1, u2),
        Some(Filter::Tent) => {
            let tent = |u: f32| {
                if u < 0.5 {
                    (2.0 * u).sqrt() - 1.0
                } else {
                    1.0 - (2.0 - 2.0 * u).sqrt()
                }
            };
            (0.5 + tent(u1), 0.5 + tent(u2))
        }
        Some(Filter::Gaussian) => {
            // Box–Muller, σ = 0.5 pixel, both coordinates redrawn (from
            // fresh numbers) while either falls beyond 3σ (0.5 % of draws):
            // a redraw is an exact truncated sample, so a stratified first
            // draw stays unbiased.
            for _ in 0..64 {
                let r = 0.5 * (-2.0 * (1.0 - u1).ln()).sqrt();
                let a = std::f32::consts::TAU * u2;
                let (x, y) = (r * a.cos(), r * a.sin());
                if x.abs() <= 1.5 && y.abs() <= 1.5 {
                    return (0.5 + x, 0.5 + y);
                }
                (u1, u2) = (rng.next_f32(), rng.next_f32());
            }
            (0.5, 0.5)
        }
        // Drawn per axis by `mitsuba_gaussian_offset`, which needs the
        // pixel's place in the image (`Job::camera_sample` calls it).
        Some(Filter::MitsubaGaussian) => (0.5, 0.5),
    }
}

/// Mitsuba's Gaussian pixel filter along one axis, for the pixel at
/// `pixel` of an image `size` pixels long: an offset from the pixel's
/// corner drawn with density ∝ max(0, exp(−x²/2σ²) − exp(−r²/2σ²)),
/// σ = 0.5, r = 2, around the centre, and never outside [0, size) (the
/// part of the footprint inside the image, renormalised, as Mitsuba's film
/// weighs a border pixel). By rejection from a normal draw: exact.
#[inline]
fn mitsuba_gaussian_offset(pixel: u32, size: u32, rng: &mut RngState) -> f32 {
    const SIGMA: f32 = 0.5;
    const RADIUS: f32 = 2.0;
    let floor = (-RADIUS * RADIUS / (2.0 * SIGMA * SIGMA)).exp();
    for _ in 0..256 {
        let (u1, u2, u3) = (rng.next_f32(), rng.next_f32(), rng.next_f32());
        let x = SIGMA * (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f32::consts::TAU * u2).cos();
        let at = pixel as f32 + 0.5 + x;
        if x.abs() > RADIUS || !(at >= 0.0 && at < size as f32) {
            continue;
        }
        // Accept with (g(x) − g(r)) / g(x).
        let g = (-x * x / (2.0 * SIGMA * SIGMA)).exp();
        if u3 * g < g - floor {
            return 0.5 + x;
        }
    }
    0.5
}

/// Render the world's image on the pool's threads into `film` (of the
/// world's image size, from [`Film::new`]), in one pass.
pub fn render(
    tracer: &Tracer,
    pool: &rayon::ThreadPool,
    progress: bool,
    film: Film,
) -> Result<Film, String> {
    let r = &tracer.world().desc.render;
    let rect = Rect::full(film.width, film.height);
    let counts = try_filled(rect.len(), 0u32)
        .ok_or_else(|| "the film's sample counts could not be allocated".to_string())?;
    let squares = try_filled(rect.len(), [0.0; 3])
        .ok_or_else(|| "the film's sums of squares could not be allocated".to_string())?;
    let mut accum = Accum {
        full_width: film.width,
        full_height: film.height,
        rect,
        sums: film.pixels,
        squares,
        counts,
        stats: film.stats,
    };
    let mut ctl = Control {
        progress,
        pass_spp: r.spp.max(1),
        stop: None,
        deadline: None,
        after_pass: &mut |_| Ok(()),
    };
    render_passes(tracer, pool, &mut ctl, &mut accum)?;
    Ok(accum.into_film())
}

/// Render the world into `accum` (of the world's image size; any
/// rectangle of it; possibly holding samples already, from a checkpoint)
/// in passes, until every pixel has the scene's `spp` samples, the stop
/// flag is set, or the deadline passes.
pub fn render_passes(
    tracer: &Tracer,
    pool: &rayon::ThreadPool,
    ctl: &mut Control,
    accum: &mut Accum,
) -> Result<End, String> {
    let r = &tracer.world().desc.render;
    if (accum.full_width, accum.full_height) != (r.width, r.height) {
        return Err(format!(
            "the film is of a {}x{} image, the scene's is {}x{}",
            accum.full_width, accum.full_height, r.width, r.height
        ));
    }
    let rect = accum.rect;
    let job = Job::new(tracer, rect, pool.current_num_threads(), ctl.stop);
    let n_tiles = job.tiles_x * rect.height().div_ceil(TILE);
    let todo: u64 = accum
        .counts
        .iter()
        .map(|&c| r.spp.saturating_sub(c) as u64)
        .sum();
    let progress = Progress::new(todo, ctl.progress);
    let pass = if (n_tiles as usize) <= pool.current_num_threads() {
        // A tile or fewer per thread: a pass of a few samples would cost
        // more in starting it than in sampling, and leave threads idle.
        (ctl.pass_spp.max(1)).max(chunked::MIN_PASS.div_ceil(rect.len()) as u32)
    } else {
        ctl.pass_spp.max(1)
    };
    let end = loop {
        let (min, _) = accum.sample_range();
        if min >= r.spp {
            break End::Complete;
        }
        let target = (min / pass)
            .saturating_add(1)
            .saturating_mul(pass)
            .min(r.spp);
        job.pass(pool, accum, n_tiles, target, &progress);
        if let Some(msg) = job.failure.first.lock().ok().and_then(|f| f.clone()) {
            progress.bar.finish_and_clear();
            return Err(msg);
        }
        if job.stopped() {
            break End::Interrupted;
        }
        if target >= r.spp {
            break End::Complete;
        }
        if ctl.deadline.is_some_and(|d| Instant::now() >= d) {
            break End::TimeUp;
        }
        if let Err(e) = (ctl.after_pass)(accum) {
            progress.bar.finish_and_clear();
            return Err(e);
        }
    };
    progress.bar.finish_and_clear();
    Ok(end)
}

/// The progress bar and when it starts to be drawn.
struct Progress {
    bar: ProgressBar,
    started: Instant,
    /// Drawn already (or never to be: hidden).
    drawn: AtomicBool,
}

impl Progress {
    /// A bar of `todo` samples, hidden unless `shown`.
    fn new(todo: u64, shown: bool) -> Progress {
        Progress {
            bar: progress_bar(todo, shown),
            started: Instant::now(),
            drawn: AtomicBool::new(!shown),
        }
    }

    /// Count `samples` more done; start drawing once a second has passed.
    fn add(&self, samples: u64) {
        self.bar.inc(samples);
        if !self.drawn.load(Ordering::Relaxed)
            && self.started.elapsed().as_secs_f32() > 1.0
            && !self.drawn.swap(true, Ordering::Relaxed)
        {
            self.bar
                .set_draw_target(ProgressDrawTarget::stderr_with_hz(4));
        }
    }
}

/// The progress bar: camera samples done, their rate and the time left.
/// Hidden with `-q` and when stderr is not a terminal (the caller decides
/// `shown`), and drawn only once the render has run for a second, so short
/// renders print nothing.
fn progress_bar(n: u64, shown: bool) -> ProgressBar {
    if !shown {
        return ProgressBar::hidden();
    }
    let b = ProgressBar::with_draw_target(Some(n), ProgressDrawTarget::hidden());
    b.set_style(
        ProgressStyle::with_template(
            "rendering [{bar:32}] {percent:>3}%  {human_per_sec} samples/s  {elapsed} elapsed, ETA {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    b
}

impl<'a, 'w> Job<'a, 'w> {
    /// Rendering `rect` of the world's image on `threads` threads, stopped
    /// early by `interrupt`.
    fn new(
        tracer: &'a Tracer<'w>,
        rect: Rect,
        threads: usize,
        interrupt: Option<&'a AtomicBool>,
    ) -> Self {
        let r = &tracer.world().desc.render;
        Job {
            tracer,
            width: r.width,
            height: r.height,
            rect,
            spp: r.spp,
            seed: r.seed,
            filter: r.filter,
            stratified: r.stratified,
            shutter: r.shutter,
            tiles_x: rect.width().div_ceil(TILE),
            threads: threads as u32,
            next_query: (0..threads).map(|_| AtomicU64::new(0)).collect(),
            failure: Failure::default(),
            interrupt,
        }
    }

    /// One pass: every tile's pixels brought up to `target` samples, on
    /// the pool's threads (tiles left undone once the job has stopped).
    fn pass(
        &self,
        pool: &rayon::ThreadPool,
        accum: &mut Accum,
        n_tiles: u32,
        target: u32,
        progress: &Progress,
    ) {
        let shared = Mutex::new(accum);
        if (n_tiles as usize) < pool.current_num_threads() {
            // Fewer tiles than threads: each tile's samples on every thread.
            for t in 0..n_tiles {
                if self.stopped() {
                    return;
                }
                progress.add(self.tile_chunked(pool, &shared, t, target));
            }
            return;
        }
        pool.install(|| {
            use rayon::prelude::*;
            (0..n_tiles).into_par_iter().for_each(|t| {
                if self.stopped() {
                    return;
                }
                progress.add(self.tile(&shared, t, target));
            })
        });
    }
}

impl Job<'_, '_> {
    /// Interrupted (Ctrl-C) or failed.
    fn stopped(&self) -> bool {
        self.failure.stop.load(Ordering::Relaxed)
            || self.interrupt.is_some_and(|s| s.load(Ordering::Relaxed))
    }

    /// The pixel rectangle of tile `t`, in full-image coordinates.
    fn tile_rect(&self, t: u32) -> Rect {
        let x0 = self.rect.x0 + (t % self.tiles_x) * TILE;
        let y0 = self.rect.y0 + (t / self.tiles_x) * TILE;
        Rect {
            x0,
            y0,
            x1: (x0 + TILE).min(self.rect.x1),
            y1: (y0 + TILE).min(self.rect.y1),
        }
    }

    /// Index in the film of full-image pixel (x, y).
    fn index(&self, x: u32, y: u32) -> usize {
        (y - self.rect.y0) as usize * self.rect.width() as usize + (x - self.rect.x0) as usize
    }

    /// Bring tile `t`'s pixels up to `target` samples on the calling pool
    /// thread: read their sums and counts, add the new samples, write them
    /// back. Returns the samples taken.
    fn tile(&self, film: &Mutex<&mut Accum>, t: u32, target: u32) -> u64 {
        let ti = rayon::current_thread_index().unwrap_or(0);
        let counter = &self.next_query[ti];
        let mut ctx = TraceCtx::new(ti as u32, self.threads, counter.load(Ordering::Relaxed));
        let tr = self.tile_rect(t);
        let mut px = self.read_tile(film, &tr);
        let work = up_to(&px, target);
        let taken = self.sample_tile(&mut ctx, &tr, &work, &mut *px);
        counter.store(ctx.query_counter(), Ordering::Relaxed);
        self.write_tile(film, &tr, px, &ctx.stats);
        taken
    }

    /// The running sums and counts of the tile's pixels, in the tile's order.
    fn read_tile(&self, film: &Mutex<&mut Accum>, tr: &Rect) -> Vec<TilePixel> {
        let mut px = Vec::with_capacity(tr.len());
        if let Ok(f) = film.lock() {
            for y in tr.y0..tr.y1 {
                for x in tr.x0..tr.x1 {
                    let i = self.index(x, y);
                    px.push(TilePixel {
                        sum: f.sums[i],
                        square: f.squares[i],
                        count: f.counts[i],
                    });
                }
            }
        }
        px
    }

    /// Store the tile's pixels back into the film, with the counters.
    fn write_tile(&self, film: &Mutex<&mut Accum>, tr: &Rect, px: Vec<TilePixel>, stats: &Stats) {
        let tw = tr.width() as usize;
        if let Ok(mut f) = film.lock() {
            for (i, p) in px.into_iter().enumerate() {
                let (x, y) = (tr.x0 + (i % tw) as u32, tr.y0 + (i / tw) as u32);
                let j = self.index(x, y);
                f.sums[j] = p.sum;
                f.squares[j] = p.square;
                f.counts[j] = p.count;
            }
            f.stats.merge(stats);
        }
    }

    /// Take the samples `work` asks for (per tile pixel `i`, samples
    /// `start..end`, in that order) and hand each to `sink`; returns the
    /// samples taken.
    ///
    /// The camera rays of up to [`batch::MAX`] pixel samples are traced
    /// together (the integrator's `li_batch`: ray streams), each with its
    /// own random stream, so a sample's value does not depend on the
    /// samples it is batched with; the sink gets each pixel's samples in
    /// sample order. Stops early (the samples traced so far counted) on a
    /// failure or an interrupt.
    fn sample_tile<S: Sink + ?Sized>(
        &self,
        ctx: &mut TraceCtx,
        tr: &Rect,
        work: &[(usize, u32, u32)],
        sink: &mut S,
    ) -> u64 {
        let mut b = CameraBatch::new();
        let mut taken = 0u64;
        let tw = tr.width() as usize;
        for &(i, start, end) in work {
            let (x, y) = (tr.x0 + (i % tw) as u32, tr.y0 + (i / tw) as u32);
            let pixel = y as u64 * self.width as u64 + x as u64;
            for s in start..end {
                if self.interrupt.is_some_and(|s| s.load(Ordering::Relaxed)) {
                    return taken + self.flush(ctx, &mut b, sink).unwrap_or(0);
                }
                if !self.camera_sample(ctx, (x, y, pixel), s, i, &mut b, sink) {
                    return taken;
                }
                if b.len == batch::MAX {
                    match self.flush(ctx, &mut b, sink) {
                        Some(n) => taken += n,
                        None => return taken,
                    }
                }
            }
        }
        taken + self.flush(ctx, &mut b, sink).unwrap_or(0)
    }

    /// Pixel sample `s` of tile pixel `i` (full-image `x`, `y`, index
    /// `pixel`): its camera ray joins the batch, or (no ray) the sink gets a
    /// black sample at once. False once the render must stop (the camera
    /// failed).
    fn camera_sample<S: Sink + ?Sized>(
        &self,
        ctx: &mut TraceCtx,
        (x, y, pixel): (u32, u32, u64),
        s: u32,
        i: usize,
        b: &mut CameraBatch,
        sink: &mut S,
    ) -> bool {
        ctx.rng = RngState::for_sample(self.seed, pixel, s as u64);
        let (jx, jy) = match self.filter {
            Some(Filter::MitsubaGaussian) => (
                mitsuba_gaussian_offset(x, self.width, &mut ctx.rng),
                mitsuba_gaussian_offset(y, self.height, &mut ctx.rng),
            ),
            f => film_offset(f, s, self.spp, self.stratified, &mut ctx.rng),
        };
        let sample = CameraSample {
            film: [
                (x as f32 + jx) / self.width as f32,
                (y as f32 + jy) / self.height as f32,
            ],
            lens: [ctx.rng.next_f32(), ctx.rng.next_f32()],
            time: self.shutter[0] + (self.shutter[1] - self.shutter[0]) * ctx.rng.next_f32(),
        };
        match self.tracer.world().camera.generate_ray(ctx, &sample) {
            Some(c) if !ctx.failed() => {
                b.push(c.ray, ctx.rng, i, c.weight);
                true
            }
            _ => {
                if self.failure.check(ctx) {
                    return false;
                }
                // No ray: a black sample (its place among the pixel's
                // samples does not matter: nothing is added to the sum).
                sink.sample(i, None, &mut ctx.stats);
                true
            }
        }
    }

    /// Trace the batch and hand each sample to the sink, in batch order
    /// (each pixel's samples are in sample order there); the samples
    /// taken, or `None` when a plugin failed.
    fn flush<S: Sink + ?Sized>(
        &self,
        ctx: &mut TraceCtx,
        b: &mut CameraBatch,
        sink: &mut S,
    ) -> Option<u64> {
        let n = b.len;
        if n == 0 {
            return Some(0);
        }
        self.tracer
            .camera_li_batch(ctx, &b.rays[..n], &mut b.rngs[..n], &mut b.out[..n]);
        b.len = 0;
        if self.failure.check(ctx) {
            return None;
        }
        for k in 0..n {
            let (i, w) = b.slots[k];
            sink.sample(i, Some(b.out[k].scale(w)), &mut ctx.stats);
        }
        Some(n as u64)
    }
}

/// The samples a pass asks of a tile's pixels `px`: per pixel, from its
/// count up to `target`.
fn up_to(px: &[TilePixel], target: u32) -> Vec<(usize, u32, u32)> {
    (px.iter().enumerate())
        .filter(|(_, p)| p.count < target)
        .map(|(i, p)| (i, p.count, target))
        .collect()
}

/// A pixel's running sums while its tile is rendered (a copy of its
/// [`Accum`] entries, taken and put back under the film's lock).
#[derive(Clone, Copy)]
struct TilePixel {
    sum: [f64; 3],
    square: [f64; 3],
    count: u32,
}

/// Where a tile's samples go: straight into its pixels' running sums, or
/// (a small image, [`chunked`]) into a buffer added to them in order later.
trait Sink {
    /// A sample of tile pixel `i`: its radiance, or `None` for a sample
    /// without a camera ray (black: counted, nothing added).
    fn sample(&mut self, i: usize, l: Option<Color>, stats: &mut Stats);
}

impl Sink for [TilePixel] {
    #[inline]
    fn sample(&mut self, i: usize, l: Option<Color>, stats: &mut Stats) {
        add_sample(&mut self[i], l, stats);
    }
}

/// Add a sample to a pixel's running sums and count: a non-finite one (a
/// plugin's NaN or infinity) counts as black and is reported.
#[inline]
fn add_sample(p: &mut TilePixel, l: Option<Color>, stats: &mut Stats) {
    if let Some(l) = l {
        if l.is_finite() {
            let v = [l.r as f64, l.g as f64, l.b as f64];
            for ((s, q), v) in p.sum.iter_mut().zip(&mut p.square).zip(v) {
                *s += v;
                *q += v * v;
            }
        } else {
            stats.nonfinite_samples += 1;
        }
    }
    p.count += 1;
}

/// Camera rays waiting to be traced together: each with its random stream
/// (after the camera's draws), the tile pixel it belongs to and its weight.
struct CameraBatch {
    rays: [Ray; batch::MAX],
    rngs: [RngState; batch::MAX],
    slots: [(usize, f32); batch::MAX],
    out: [Color; batch::MAX],
    len: usize,
}

impl CameraBatch {
    fn new() -> Self {
        CameraBatch {
            rays: [Ray::new(Default::default(), Default::default()); batch::MAX],
            rngs: [RngState::default(); batch::MAX],
            slots: [(0, 0.0); batch::MAX],
            out: [Color::BLACK; batch::MAX],
            len: 0,
        }
    }

    fn push(&mut self, ray: Ray, rng: RngState, pixel: usize, weight: f32) {
        self.rays[self.len] = ray;
        self.rngs[self.len] = rng;
        self.slots[self.len] = (pixel, weight);
        self.len += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stratified_samples_fill_one_cell_each() {
        let mut rng = RngState::seeded(5);
        for spp in [4u32, 16, 64] {
            let m = (spp as f64).sqrt() as u32;
            let mut seen = vec![0u32; spp as usize];
            for s in 0..spp {
                let (x, y) = film_offset(Some(Filter::Box), s, spp, true, &mut rng);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                let cell = (y * m as f32) as u32 * m + (x * m as f32) as u32;
                seen[cell as usize] += 1;
            }
            assert!(seen.iter().all(|&n| n == 1), "{spp}: {seen:?}");
        }
        // Not a square: independent, anywhere in the pixel.
        let (x, y) = film_offset(Some(Filter::Box), 3, 5, true, &mut rng);
        assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
    }

    #[test]
    fn mitsubas_gaussian_has_its_density_and_stays_inside_the_image() {
        // Density ∝ exp(−2x²) − exp(−8) on [−2, 2], x from the centre.
        let w = |x: f64| ((-2.0 * x * x).exp() - (-8.0f64).exp()).max(0.0);
        let mut rng = RngState::seeded(3);
        let n = 400_000;
        let bins = 16;
        let mut hist = vec![0u32; bins];
        for _ in 0..n {
            let x = mitsuba_gaussian_offset(10, 100, &mut rng) as f64 - 0.5;
            assert!(x.abs() <= 2.0);
            hist[(((x + 2.0) / 4.0 * bins as f64) as usize).min(bins - 1)] += 1;
        }
        // Expected bin shares by the midpoint rule on a fine grid.
        let share = |a: f64, b: f64| {
            (0..100)
                .map(|k| w(a + (b - a) * (k as f64 + 0.5) / 100.0))
                .sum::<f64>()
                * (b - a)
                / 100.0
        };
        let total = share(-2.0, 2.0);
        for (i, &h) in hist.iter().enumerate() {
            let (a, b) = (
                -2.0 + 4.0 * i as f64 / bins as f64,
                -2.0 + 4.0 * (i + 1) as f64 / bins as f64,
            );
            let p = share(a, b) / total;
            let sd = (p * (1.0 - p) / n as f64).sqrt();
            let got = h as f64 / n as f64;
            assert!(
                (got - p).abs() < 5.0 * sd + 1e-6,
                "bin {i}: {got} against {p}"
            );
        }
        // Pixel 0 of a 100-pixel row: never left of the image.
        for _ in 0..10_000 {
            assert!(mitsuba_gaussian_offset(0, 100, &mut rng) >= 0.0);
            assert!(mitsuba_gaussian_offset(99, 100, &mut rng) < 1.0 + 0.0);
        }
    }

    #[test]
    fn one_sample_without_a_filter_is_the_centre() {
        let mut rng = RngState::seeded(1);
        assert_eq!(film_offset(None, 0, 1, true, &mut rng), (0.5, 0.5));
        assert_ne!(
            film_offset(Some(Filter::Box), 0, 1, false, &mut rng),
            (0.5, 0.5)
        );
    }
}
