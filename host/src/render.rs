//! The render loop: tiles over the host's rayon pool, a random stream per
//! (seed, pixel, sample), an f64 film. The image does not depend on the
//! thread count or on the order tiles finish.

use crate::tracer::Tracer;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rtk_kernel::abi::*;
use rtk_shell::desc::render::Filter;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

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

impl Film {
    /// A black film of `width` x `height`, allocated before the scene is
    /// built and fallibly: an image too large for memory fails with a
    /// message, where an infallible allocation would abort the process. The
    /// render writes each tile into it as the tile finishes, so no second
    /// image-sized buffer exists while rendering.
    pub fn new(width: u32, height: u32) -> Result<Film, String> {
        let n = width as usize * height as usize;
        let mut pixels = Vec::new();
        pixels.try_reserve_exact(n).map_err(|_| {
            format!(
                "the film of {width}x{height} pixels needs {} MiB ({FILM_BYTES_PER_PIXEL} bytes a pixel), which could not be allocated: render a smaller image",
                (n as u64 * FILM_BYTES_PER_PIXEL) >> 20
            )
        })?;
        pixels.resize(n, [0.0; 3]);
        Ok(Film {
            width,
            height,
            pixels,
            stats: Stats::default(),
        })
    }
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

/// One finished tile.
struct Tile {
    index: u32,
    pixels: Vec<[f64; 3]>,
    stats: Stats,
}

/// What every tile needs to know.
struct Job<'a, 'w> {
    tracer: &'a Tracer<'w>,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
    filter: Option<Filter>,
    tiles_x: u32,
    threads: u32,
    /// Per thread: the next query id (mailbox ids never repeat on a thread).
    next_query: Vec<AtomicU64>,
    failure: Failure,
}

/// Where in the pixel a sample looks, from the pixel's corner: drawn from
/// the pixel filter's own distribution (so every sample weighs 1). Without
/// a filter, one sample looks through the centre (a 1-spp image is the
/// exact pinhole image) and more spread uniformly (a box).
#[inline]
fn film_offset(filter: Option<Filter>, spp: u32, rng: &mut RngState) -> (f32, f32) {
    match filter {
        None if spp == 1 => (0.5, 0.5),
        None | Some(Filter::Box) => (rng.next_f32(), rng.next_f32()),
        Some(Filter::Tent) => {
            let tent = |u: f32| {
                if u < 0.5 {
                    (2.0 * u).sqrt() - 1.0
                } else {
                    1.0 - (2.0 - 2.0 * u).sqrt()
                }
            };
            (0.5 + tent(rng.next_f32()), 0.5 + tent(rng.next_f32()))
        }
        Some(Filter::Gaussian) => {
            // Box–Muller, σ = 0.5 pixel, both coordinates redrawn while
            // either falls beyond 3σ (0.5 % of draws).
            for _ in 0..64 {
                let (u1, u2) = (1.0 - rng.next_f32(), rng.next_f32());
                let r = 0.5 * (-2.0 * u1.ln()).sqrt();
                let a = std::f32::consts::TAU * u2;
                let (x, y) = (r * a.cos(), r * a.sin());
                if x.abs() <= 1.5 && y.abs() <= 1.5 {
                    return (0.5 + x, 0.5 + y);
                }
            }
            (0.5, 0.5)
        }
    }
}

/// Render the world's image on the pool's threads into `film` (of the
/// world's image size, from [`Film::new`]).
pub fn render(
    tracer: &Tracer,
    pool: &rayon::ThreadPool,
    progress: bool,
    film: Film,
) -> Result<Film, String> {
    let r = &tracer.world().desc.render;
    let threads = pool.current_num_threads();
    let job = Job {
        tracer,
        width: r.width,
        height: r.height,
        spp: r.spp,
        seed: r.seed,
        filter: r.filter,
        tiles_x: r.width.div_ceil(TILE),
        threads: threads as u32,
        next_query: (0..threads).map(|_| AtomicU64::new(0)).collect(),
        failure: Failure::default(),
    };
    let n_tiles = job.tiles_x * r.height.div_ceil(TILE);
    let total = r.width as u64 * r.height as u64 * r.spp as u64;
    let bar = progress_bar(total, progress);
    let (started, drawn) = (std::time::Instant::now(), AtomicBool::new(!progress));
    let film = Mutex::new(film);
    pool.install(|| {
        use rayon::prelude::*;
        (0..n_tiles).into_par_iter().for_each(|t| {
            let tile = job.tile(t);
            let samples = tile.pixels.len() as u64 * job.spp as u64;
            if let Ok(mut f) = film.lock() {
                job.place(&mut f, tile);
            }
            bar.inc(samples);
            if !drawn.load(Ordering::Relaxed)
                && started.elapsed().as_secs_f32() > 1.0
                && !drawn.swap(true, Ordering::Relaxed)
            {
                bar.set_draw_target(ProgressDrawTarget::stderr_with_hz(4));
            }
        })
    });
    bar.finish_and_clear();
    if let Some(msg) = job.failure.first.lock().ok().and_then(|f| f.clone()) {
        return Err(msg);
    }
    film.into_inner()
        .map_err(|_| "a render thread failed".to_string())
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

impl Job<'_, '_> {
    /// The pixel rectangle of tile `t`: (x0, y0, x1, y1).
    fn rect(&self, t: u32) -> (u32, u32, u32, u32) {
        let (x0, y0) = ((t % self.tiles_x) * TILE, (t / self.tiles_x) * TILE);
        (
            x0,
            y0,
            (x0 + TILE).min(self.width),
            (y0 + TILE).min(self.height),
        )
    }

    /// Render tile `t` on the calling pool thread.
    fn tile(&self, t: u32) -> Tile {
        let ti = rayon::current_thread_index().unwrap_or(0);
        let counter = &self.next_query[ti];
        let mut ctx = TraceCtx::new(ti as u32, self.threads, counter.load(Ordering::Relaxed));
        let (x0, y0, x1, y1) = self.rect(t);
        let mut pixels = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
        'rows: for y in y0..y1 {
            for x in x0..x1 {
                match self.pixel(&mut ctx, x, y) {
                    Some(p) => pixels.push(p),
                    None => break 'rows,
                }
            }
        }
        counter.store(ctx.query_counter(), Ordering::Relaxed);
        Tile {
            index: t,
            pixels,
            stats: ctx.stats,
        }
    }

    /// The average of the pixel's samples; `None` once the render must stop.
    fn pixel(&self, ctx: &mut TraceCtx, x: u32, y: u32) -> Option<[f64; 3]> {
        let world = self.tracer.world();
        let pixel = y as u64 * self.width as u64 + x as u64;
        let mut sum = [0.0f64; 3];
        for s in 0..self.spp {
            ctx.rng = RngState::for_sample(self.seed, pixel, s as u64);
            let (jx, jy) = film_offset(self.filter, self.spp, &mut ctx.rng);
            let sample = CameraSample {
                film: [
                    (x as f32 + jx) / self.width as f32,
                    (y as f32 + jy) / self.height as f32,
                ],
                lens: [ctx.rng.next_f32(), ctx.rng.next_f32()],
                time: ctx.rng.next_f32(),
            };
            let (ray, weight) = world.camera.generate_ray(ctx, &sample);
            let l = if ctx.failed() {
                Color::BLACK
            } else {
                self.tracer.camera_li(ctx, &ray).scale(weight)
            };
            if self.failure.check(ctx) {
                return None;
            }
            if l.is_finite() {
                sum[0] += l.r as f64;
                sum[1] += l.g as f64;
                sum[2] += l.b as f64;
            } else {
                ctx.stats.nonfinite_samples += 1;
            }
        }
        let inv = 1.0 / self.spp as f64;
        Some([sum[0] * inv, sum[1] * inv, sum[2] * inv])
    }

    /// Place a finished tile in the film and add its counters.
    fn place(&self, film: &mut Film, tile: Tile) {
        let w = self.width as usize;
        let (x0, y0, x1, _) = self.rect(tile.index);
        let tw = (x1 - x0) as usize;
        for (i, p) in tile.pixels.into_iter().enumerate() {
            let (x, y) = (x0 as usize + i % tw, y0 as usize + i / tw);
            film.pixels[y * w + x] = p;
        }
        film.stats.merge(&tile.stats);
    }
}
