//! The render loop: tiles over the host's rayon pool, a random stream per
//! (seed, pixel, sample), an f64 film. The image does not depend on the
//! thread count or on the order tiles finish.

use crate::tracer::Tracer;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rtk_kernel::abi::*;
use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Edge of a square tile, in pixels.
pub const TILE: u32 = 16;
/// Per-thread scratch memory handed to plugins.
pub const SCRATCH_BYTES: usize = 64 * 1024;

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

/// Per-thread state that outlives tiles: the query counter (mailbox ids must
/// never repeat on a thread) and the scratch memory.
struct PerThread {
    next_query: u64,
    scratch: Vec<u8>,
}

/// The first failure reported by a plugin, and the flag that stops the render.
#[derive(Default)]
pub struct Failure {
    stop: AtomicBool,
    first: Mutex<Option<String>>,
}

extern "C" fn report_failure(
    ctx: *mut c_void,
    class: *const u8,
    clen: usize,
    msg: *const u8,
    mlen: usize,
) {
    // SAFETY: `ctx` is the render's `Failure`, alive for the render; the
    // plugin passes valid byte ranges.
    let (f, class, msg) = unsafe {
        (
            &*(ctx as *const Failure),
            String::from_utf8_lossy(std::slice::from_raw_parts(class, clen)).into_owned(),
            String::from_utf8_lossy(std::slice::from_raw_parts(msg, mlen)).into_owned(),
        )
    };
    f.stop.store(true, Ordering::Relaxed);
    if let Ok(mut first) = f.first.lock() {
        first.get_or_insert_with(|| format!("plugin `{class}` {msg}"));
    }
}

/// Render the world's image with `threads` threads.
pub fn render(tracer: &Tracer, pool: &rayon::ThreadPool, progress: bool) -> Result<Film, String> {
    let world = tracer.world();
    let r = &world.desc.render;
    let (w, h, spp, seed) = (r.width, r.height, r.spp, r.seed);
    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let n_tiles = (tiles_x * tiles_y) as usize;
    let threads = pool.current_num_threads();
    let per_thread: Vec<Mutex<PerThread>> = (0..threads)
        .map(|_| {
            Mutex::new(PerThread {
                next_query: 0,
                scratch: vec![0; SCRATCH_BYTES],
            })
        })
        .collect();
    let failure = Failure::default();
    let bar = if progress {
        let b = ProgressBar::with_draw_target(Some(n_tiles as u64), ProgressDrawTarget::stderr());
        b.set_style(
            ProgressStyle::with_template(
                "{spinner} rendering [{bar:40}] {percent:>3}% tiles, {elapsed} elapsed, ETA {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        b
    } else {
        ProgressBar::hidden()
    };
    let camera = world.camera.module.generate_ray();
    let cam_this = world.camera.this as *const c_void;
    let cam = CamPtr(cam_this);

    let results: Vec<(u32, Vec<[f64; 3]>, Stats)> = pool.install(|| {
        use rayon::prelude::*;
        (0..n_tiles as u32)
            .into_par_iter()
            .map(|tile| {
                let ti = rayon::current_thread_index().unwrap_or(0);
                let mut slot = per_thread[ti].lock().unwrap_or_else(|e| e.into_inner());
                let PerThread {
                    next_query,
                    scratch,
                } = &mut *slot;
                let mut ctx = TraceCtx {
                    thread_index: ti as u32,
                    max_threads: threads as u32,
                    next_query: *next_query,
                    rng: RngState::default(),
                    scratch: scratch.as_mut_ptr(),
                    scratch_len: scratch.len(),
                    stats: Stats::default(),
                    failed: 0,
                    failure: FailureSink {
                        ctx: &failure as *const Failure as *mut c_void,
                        report: report_failure,
                    },
                };
                let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let mut px = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
                'rows: for y in y0..y1 {
                    for x in x0..x1 {
                        if failure.stop.load(Ordering::Relaxed) {
                            break 'rows;
                        }
                        let pixel = y as u64 * w as u64 + x as u64;
                        let mut sum = [0.0f64; 3];
                        for s in 0..spp {
                            ctx.rng = RngState::for_sample(seed, pixel, s as u64);
                            // One sample: the pixel centre; more: uniform jitter.
                            let (jx, jy) = if spp == 1 {
                                (0.5, 0.5)
                            } else {
                                (ctx.rng.next_f32(), ctx.rng.next_f32())
                            };
                            let sample = CameraSample {
                                film: [(x as f32 + jx) / w as f32, (y as f32 + jy) / h as f32],
                                lens: [ctx.rng.next_f32(), ctx.rng.next_f32()],
                                time: ctx.rng.next_f32(),
                            };
                            let mut ray = Ray::new(Default::default(), Default::default());
                            let weight = camera(cam.get(), &sample, &mut ray);
                            if !weight.is_finite() {
                                report_failure(
                                    ctx.failure.ctx,
                                    world.camera.class.as_ptr(),
                                    world.camera.class.len(),
                                    "panicked in generate_ray".as_ptr(),
                                    "panicked in generate_ray".len(),
                                );
                                break 'rows;
                            }
                            let l = tracer.camera_li(&mut ctx, &ray).scale(weight);
                            if l.is_finite() {
                                sum[0] += l.r as f64;
                                sum[1] += l.g as f64;
                                sum[2] += l.b as f64;
                            } else {
                                ctx.stats.nonfinite_samples += 1;
                            }
                        }
                        let inv = 1.0 / spp as f64;
                        px.push([sum[0] * inv, sum[1] * inv, sum[2] * inv]);
                    }
                }
                *next_query = ctx.next_query;
                bar.inc(1);
                (tile, px, ctx.stats)
            })
            .collect()
    });
    bar.finish_and_clear();
    if let Some(msg) = failure.first.lock().ok().and_then(|f| f.clone()) {
        return Err(msg);
    }
    let mut film = Film {
        width: w,
        height: h,
        pixels: vec![[0.0; 3]; (w * h) as usize],
        stats: Stats::default(),
    };
    for (tile, px, stats) in results {
        let (x0, y0) = ((tile % tiles_x) * TILE, (tile / tiles_x) * TILE);
        let x1 = (x0 + TILE).min(w);
        let tw = (x1 - x0) as usize;
        for (i, p) in px.into_iter().enumerate() {
            let (x, y) = (x0 as usize + i % tw, y0 as usize + i / tw);
            film.pixels[y * w as usize + x] = p;
        }
        film.stats.merge(&stats);
    }
    Ok(film)
}

struct CamPtr(*const c_void);
// SAFETY: the camera is immutable after creation and `Sync` by the SDK's contract.
unsafe impl Sync for CamPtr {}
impl CamPtr {
    fn get(&self) -> *const c_void {
        self.0
    }
}
