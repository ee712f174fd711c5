//! rtk inside another program (the Python module, `host/python`): the same
//! scene loading, render loop and ray casting as the `rtk` binary, with the
//! results in memory instead of files.
//!
//! Why a module of its own rather than calls into the commands: a command
//! owns its process (it writes files, prints, installs a Ctrl-C handler,
//! exits), and an embedding host owns none of that. What both need is the
//! code below them, which this module calls without copying: the scene is
//! read and overridden as `rtk render --set` does ([`SceneSource::from_file`]),
//! rendered by the same render loop (so the
//! image is bit-identical to `rtk render`'s EXR), and rays are cast through
//! the root's `intersect` exactly as `rtk trace` casts them (so `t`, `prim`
//! and the barycentrics equal its hit file bit for bit).

use crate::render::render_loop::{self, Accum, Control, Rect};
use crate::render::tracer::Tracer;
use crate::shared::threads::{self, Pool};
pub use crate::trace::rays::RayRec;
use anyhow::{anyhow, bail, Context, Result};
use rtk_kernel::abi::{geom_mask, Hit, LocalGeom, Ray, TraceCtx};
use rtk_shell::file::AttachedArray;
use rtk_shell::{PluginPath, Registry, SceneFile, World};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

/// Rays per task, as `rtk trace` splits its work.
const CHUNK: usize = 4096;

/// Where plugins are searched: the caller's folders first, then
/// `RTK_PLUGIN_PATH`, then `bundled` (the folder an embedding host ships
/// its plugins in, such as the Python wheel's), then the `rtk` binary's
/// places (beside the running executable).
pub fn plugin_path(extra: &[PathBuf], bundled: Option<&Path>) -> PluginPath {
    let mut path = PluginPath::standard(extra);
    if let Some(b) = bundled {
        // After `extra` and the environment's folders, before the executable's.
        let env_dirs = std::env::var_os("RTK_PLUGIN_PATH")
            .map(|v| {
                std::env::split_paths(&v)
                    .filter(|p| !p.as_os_str().is_empty())
                    .count()
            })
            .unwrap_or(0);
        path.dirs.insert(extra.len() + env_dirs, b.to_path_buf());
    }
    path
}

/// Every plugin on `path`: (class, kind, version, file), or the reason it
/// is refused in place of the kind.
pub fn list_plugins(path: &PluginPath) -> Vec<(String, String, String, PathBuf)> {
    path.available()
        .into_iter()
        .map(
            |(class, file)| match rtk_shell::plugins::load(&file, Some(&class)) {
                Ok(p) => (
                    class,
                    p.kind.name().to_string(),
                    p.version.to_string(),
                    file,
                ),
                Err(e) => (class, "refused".into(), e.to_string(), file),
            },
        )
        .collect()
}

/// A scene's source before it is built: its file (from disk, text or a
/// dictionary converted to text by the host) and the arrays a host attaches
/// to its definitions.
pub struct SceneSource {
    file: SceneFile,
    sets: Vec<String>,
}

impl SceneSource {
    /// A scene file (TOML; or a mesh, .ply or .obj, under `accel`), as
    /// `rtk render` reads it; `accel` replaces a scene root's class as
    /// `rtk trace --aggregate` does.
    pub fn from_file(path: &Path, accel: Option<&str>) -> Result<SceneSource> {
        let (file, sets) = crate::trace::trace_input(path, accel)?;
        Ok(SceneSource { file, sets })
    }

    /// Scene text; relative file parameters resolve against `base_dir`,
    /// and messages name the scene `name`.
    pub fn from_text(text: String, base_dir: &Path, name: &str) -> Result<SceneSource> {
        let path = base_dir.join(name);
        let file = SceneFile::parse(&path, text)?;
        Ok(SceneSource { file, sets: vec![] })
    }

    /// Attach an array (`vertices`) to the definition at `def` (`objects.bunny`).
    pub fn attach(&mut self, def: &str, array: AttachedArray) {
        self.file
            .arrays
            .entry(def.to_string())
            .or_default()
            .push(array);
    }

    /// Apply `--set` overrides (`render.spp=16`).
    pub fn set(&mut self, sets: &[String]) {
        self.sets.extend(sets.iter().cloned());
    }
}

/// A built scene, with the thread pool it last ran on.
pub struct EmbeddedScene {
    source: SceneFile,
    sets: Vec<String>,
    path: PluginPath,
    world: World,
    /// The world in world coordinates, for ray casting, when the render's
    /// has a camera-relative origin (built at the first trace).
    trace_world: OnceLock<World>,
    pool: Mutex<Option<(usize, Arc<rayon::ThreadPool>)>>,
    next_query: Mutex<Vec<Arc<[AtomicU64]>>>,
}

/// What one [`EmbeddedScene::render`] is asked.
pub struct RenderRequest<'a> {
    /// Samples per pixel instead of the scene's.
    pub spp: Option<u32>,
    /// Seed instead of the scene's.
    pub seed: Option<u64>,
    /// Threads (default all cores).
    pub threads: Option<usize>,
    /// Set to stop at the next sample (Ctrl-C in the embedding host).
    pub stop: &'a AtomicBool,
    /// Samples per pixel finished so far (for a progress bar).
    pub done: &'a AtomicU64,
}

/// A rendered image: linear radiance, row-major, RGB.
pub struct RenderedImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` values.
    pub rgb: Vec<f32>,
    /// Whether the stop flag ended it before every sample was taken.
    pub interrupted: bool,
}

impl EmbeddedScene {
    /// Build `source` with its overrides, loading plugins from `path`.
    pub fn build(source: SceneSource, path: PluginPath) -> Result<EmbeddedScene> {
        let SceneSource { file, sets } = source;
        let world = build_world(&file, &sets, &path)?;
        Ok(EmbeddedScene {
            source: file,
            sets,
            path,
            world,
            trace_world: OnceLock::new(),
            pool: Mutex::new(None),
            next_query: Mutex::new(Vec::new()),
        })
    }

    /// The world rendered.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Each instance's path by the id `trace` reports as its `object`.
    pub fn instances(&self) -> &[String] {
        &self.world.instances
    }

    /// The pool of `threads` threads (all cores by default), kept between calls.
    fn pool(&self, threads: Option<usize>) -> Result<Arc<rayon::ThreadPool>> {
        let want =
            threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let mut slot = self
            .pool
            .lock()
            .map_err(|_| anyhow!("the thread pool lock is poisoned"))?;
        if let Some((n, p)) = slot.as_ref() {
            if *n == want {
                return Ok(p.clone());
            }
        }
        let (p, _) = threads::pool(Some(want))?;
        let p = Arc::new(p);
        *slot = Some((want, p.clone()));
        Ok(p)
    }

    /// Render the image as `rtk render` with these `spp`/`seed` overrides
    /// would (its EXR's values, bit for bit), stopping early if `stop` is set.
    pub fn render(&mut self, req: &RenderRequest) -> Result<RenderedImage> {
        let (spp, seed) = self.settings(req.spp, req.seed)?;
        let pool = self.pool(req.threads)?;
        let r = &mut self.world.desc.render;
        let saved = (r.spp, r.seed);
        (r.spp, r.seed) = (spp, seed);
        let result = render_world(&self.world, &pool, req);
        let r = &mut self.world.desc.render;
        (r.spp, r.seed) = saved;
        result
    }

    /// The render settings with `spp` and `seed` applied, checked as the
    /// scene format checks them (the overrides go through `--set`).
    fn settings(&self, spp: Option<u32>, seed: Option<u64>) -> Result<(u32, u64)> {
        let r = &self.world.desc.render;
        if spp.is_none() && seed.is_none() {
            return Ok((r.spp, r.seed));
        }
        let mut file = self.source.clone();
        let mut sets = self.sets.clone();
        sets.extend(spp.map(|n| format!("render.spp={n}")));
        sets.extend(seed.map(|s| format!("render.seed={s}")));
        file.apply_overrides(&sets)?;
        let desc = rtk_shell::Desc::from_file(&file)?;
        Ok((desc.render.spp, desc.render.seed))
    }

    /// The world rays are cast in: world coordinates, as `rtk trace`'s.
    fn trace_world(&self) -> Result<&World> {
        if self.world.desc.render.origin == [0.0; 3] {
            return Ok(&self.world);
        }
        if let Some(w) = self.trace_world.get() {
            return Ok(w);
        }
        let mut sets = self.sets.clone();
        sets.push("render.origin=\"world\"".into());
        let w = build_world(&self.source, &sets, &self.path)?;
        Ok(self.trace_world.get_or_init(|| w))
    }

    /// Cast every ray of `rays` (`ray(i)` for i in 0..n) into `out`, on
    /// `threads` threads, as `rtk trace` casts them.
    ///
    /// A ray `rtk trace` would refuse in a ray file ([`RayRec::is_valid`])
    /// is an error naming the first such ray; it is checked as it is cast,
    /// not in a pass of its own (which would cost a tenth of the time).
    pub fn trace<F: Fn(usize) -> RayRec + Sync>(
        &self,
        n: usize,
        ray: &F,
        occluded: bool,
        threads: Option<usize>,
        out: HitArrays,
    ) -> Result<()> {
        out.check_len(n)?;
        let world = self.trace_world()?;
        let pool = self.pool(threads)?;
        let counters = self.counters(pool.current_num_threads())?;
        let job = TraceJob {
            world,
            ray,
            occluded,
            threads: pool.current_num_threads() as u32,
            counters: &counters,
            failure: Mutex::new(None),
            first_invalid: AtomicUsize::new(usize::MAX),
        };
        pool.install(|| job.run(0, out));
        let failure = job.failure.lock().ok().and_then(|mut f| f.take());
        if let Some(f) = failure {
            bail!("tracing failed: {f}");
        }
        match job.first_invalid.load(Ordering::Relaxed) {
            usize::MAX => Ok(()),
            i => {
                let r = ray(i);
                bail!(
                    "ray {i} (origin {:?}, direction {:?}, t_min {}, t_max {}) has a non-finite origin or direction, or t_min < 0 or t_max < t_min",
                    r.o, r.d, r.t_min, r.t_max
                )
            }
        }
    }

    /// Per-thread query counters, kept for the scene's life: query ids must
    /// never repeat on a thread (aggregates' mailboxes are keyed by them).
    fn counters(&self, threads: usize) -> Result<Arc<[AtomicU64]>> {
        let mut all = self
            .next_query
            .lock()
            .map_err(|_| anyhow!("the query counters' lock is poisoned"))?;
        if let Some(c) = all.iter().find(|c| c.len() == threads) {
            return Ok(c.clone());
        }
        // A fresh set starts past every id the others handed out.
        let start = all
            .iter()
            .flat_map(|c| c.iter().map(|a| a.load(Ordering::Relaxed)))
            .max()
            .unwrap_or(0);
        let c: Arc<[AtomicU64]> = (0..threads).map(|_| AtomicU64::new(start)).collect();
        all.push(c.clone());
        Ok(c)
    }
}

/// Build `file` with `sets` applied, loading plugins from `path`.
fn build_world(file: &SceneFile, sets: &[String], path: &PluginPath) -> Result<World> {
    let mut file = file.clone();
    file.apply_overrides(sets)?;
    let desc = rtk_shell::Desc::from_file(&file)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let (pool, _) = threads::pool(Some(threads))?;
    let mut registry = Registry::new(path.clone());
    Ok(rtk_shell::build(&file, desc, &mut registry, &Pool(&pool))?)
}

/// Render `world` (with its spp and seed as set) on `pool`.
fn render_world(
    world: &World,
    pool: &rayon::ThreadPool,
    req: &RenderRequest,
) -> Result<RenderedImage> {
    let r = &world.desc.render;
    let spp = r.spp;
    let mut accum =
        Accum::new(r.width, r.height, Rect::full(r.width, r.height)).map_err(|m| anyhow!("{m}"))?;
    let tracer = Tracer::new(world);
    let mut after = |a: &Accum| -> Result<(), String> {
        req.done.store(a.sample_range().0 as u64, Ordering::Relaxed);
        Ok(())
    };
    let mut ctl = Control {
        progress: false,
        // As `rtk render` passes: the image does not depend on it.
        pass_spp: spp.div_ceil(16).clamp(1, 16),
        stop: Some(req.stop),
        deadline: None,
        after_pass: &mut after,
    };
    let end = render_loop::render_passes(&tracer, pool, &mut ctl, &mut accum)
        .map_err(|m| anyhow!("rendering failed: {m}"))?;
    req.done.store(spp as u64, Ordering::Relaxed);
    let film = accum.into_film();
    let rgb = film
        .pixels
        .iter()
        .flat_map(|p| p.map(|v| v as f32))
        .collect();
    Ok(RenderedImage {
        width: film.width,
        height: film.height,
        rgb,
        interrupted: end == render_loop::End::Interrupted,
    })
}

/// Where [`EmbeddedScene::trace`] writes, one entry per ray. The surface
/// fields (`object`, `normal`, `uv`) are empty when not asked for: they
/// cost a `local_geom` call per hit, which `rtk trace` does not make.
pub struct HitArrays<'a> {
    /// Distance along the ray; +inf on a miss (0 when blocked, for occluded).
    pub t: &'a mut [f32],
    /// Primitive id within the object hit; -1 on a miss (1 blocked, occluded).
    pub prim: &'a mut [i64],
    /// The leaf's two words (barycentrics b1, b2 of triangles).
    pub bary: &'a mut [[f32; 2]],
    /// Whether the ray hit (or, occluded, was blocked).
    pub hit: &'a mut [bool],
    /// The innermost named instance hit (`instances()` index); -1 none.
    pub object: &'a mut [i64],
    /// Unit geometric normal at the hit.
    pub normal: &'a mut [[f32; 3]],
    /// Surface parameterisation at the hit.
    pub uv: &'a mut [[f32; 2]],
}

/// `s` cut at `mid`, an empty slice giving two empty halves.
fn cut<T>(s: &mut [T], mid: usize) -> (&mut [T], &mut [T]) {
    if s.is_empty() {
        (&mut [], &mut [])
    } else {
        s.split_at_mut(mid)
    }
}

impl<'a> HitArrays<'a> {
    fn len(&self) -> usize {
        self.t.len()
    }

    fn surface(&self) -> bool {
        !self.object.is_empty()
    }

    fn check_len(&self, n: usize) -> Result<()> {
        let base = [
            self.t.len(),
            self.prim.len(),
            self.bary.len(),
            self.hit.len(),
        ];
        let surf = [self.object.len(), self.normal.len(), self.uv.len()];
        if base.iter().any(|&l| l != n) || surf.iter().any(|&l| l != n && l != 0) {
            bail!("the output arrays must hold one entry per ray ({n})");
        }
        if surf.iter().any(|&l| l != surf[0]) {
            bail!("the surface outputs (object, normal, uv) come together or not at all");
        }
        Ok(())
    }

    fn split(self, mid: usize) -> (HitArrays<'a>, HitArrays<'a>) {
        let (t0, t1) = self.t.split_at_mut(mid);
        let (p0, p1) = self.prim.split_at_mut(mid);
        let (b0, b1) = self.bary.split_at_mut(mid);
        let (h0, h1) = self.hit.split_at_mut(mid);
        let (o0, o1) = cut(self.object, mid);
        let (n0, n1) = cut(self.normal, mid);
        let (u0, u1) = cut(self.uv, mid);
        (
            HitArrays {
                t: t0,
                prim: p0,
                bary: b0,
                hit: h0,
                object: o0,
                normal: n0,
                uv: u0,
            },
            HitArrays {
                t: t1,
                prim: p1,
                bary: b1,
                hit: h1,
                object: o1,
                normal: n1,
                uv: u1,
            },
        )
    }
}

/// One [`EmbeddedScene::trace`] call, split recursively over the pool.
struct TraceJob<'a, F> {
    world: &'a World,
    ray: &'a F,
    occluded: bool,
    threads: u32,
    counters: &'a [AtomicU64],
    failure: Mutex<Option<String>>,
    /// The lowest index of a ray that is not [`RayRec::is_valid`].
    first_invalid: AtomicUsize,
}

impl<F: Fn(usize) -> RayRec + Sync> TraceJob<'_, F> {
    /// Rays `first..first + out.len()` into `out`: halves in parallel down
    /// to chunks of [`CHUNK`].
    fn run(&self, first: usize, out: HitArrays) {
        let n = out.len();
        if n > CHUNK {
            let mid = (n / 2).div_ceil(CHUNK) * CHUNK;
            let (a, b) = out.split(mid);
            rayon::join(|| self.run(first, a), || self.run(first + mid, b));
            return;
        }
        let ti = rayon::current_thread_index().unwrap_or(0);
        let counter = &self.counters[ti];
        let mut ctx = TraceCtx::new(ti as u32, self.threads, counter.load(Ordering::Relaxed));
        self.chunk(&mut ctx, first, out);
        counter.store(ctx.query_counter(), Ordering::Relaxed);
        if let Some((c, m)) = ctx.failure() {
            if let Ok(mut f) = self.failure.lock() {
                f.get_or_insert_with(|| format!("plugin `{c}` {m}"));
            }
        }
    }

    fn chunk(&self, ctx: &mut TraceCtx, first: usize, out: HitArrays) {
        let surface = out.surface();
        let mut hit = Hit::new();
        for i in 0..out.len() {
            let r = (self.ray)(first + i);
            if !r.is_valid() {
                self.first_invalid.fetch_min(first + i, Ordering::Relaxed);
                continue;
            }
            let ray = crate::trace::to_ray(&r);
            if self.occluded {
                let blocked = self.world.root.occluded(ctx, &ray);
                out.t[i] = if blocked { 0.0 } else { f32::INFINITY };
                out.prim[i] = if blocked { 1 } else { -1 };
                out.bary[i] = [0.0; 2];
                out.hit[i] = blocked;
                continue;
            }
            hit.reset();
            let found = self.world.root.intersect(ctx, &ray, &mut hit);
            out.hit[i] = found;
            out.t[i] = if found { hit.t } else { f32::INFINITY };
            out.prim[i] = if found {
                hit.at(hit.depth.saturating_sub(1)) as i64
            } else {
                -1
            };
            out.bary[i] = if found { hit.uv } else { [0.0; 2] };
            if surface {
                self.surface(
                    ctx,
                    &ray,
                    &hit,
                    found,
                    i,
                    &mut *out.object,
                    &mut *out.normal,
                    &mut *out.uv,
                );
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn surface(
        &self,
        ctx: &mut TraceCtx,
        ray: &Ray,
        hit: &Hit,
        found: bool,
        i: usize,
        object: &mut [i64],
        normal: &mut [[f32; 3]],
        uv: &mut [[f32; 2]],
    ) {
        if !found {
            object[i] = -1;
            normal[i] = [0.0; 3];
            uv[i] = [0.0; 2];
            return;
        }
        let mut g = LocalGeom::EMPTY;
        let mask = geom_mask::GEOMETRIC_NORMAL | geom_mask::UV;
        self.world.root.local_geom(ctx, ray, hit, mask, &mut g);
        self.world.root_inst.bind(&mut g);
        object[i] = if g.instance == rtk_kernel::NONE_ID {
            -1
        } else {
            g.instance as i64
        };
        normal[i] = g.ng.v().to_array();
        uv[i] = g.uv;
    }
}

/// Run an `rtk` command line in this process (`["converge", "scene.toml",
/// ...]`), as the binary would, returning its error instead of exiting.
pub fn run_command(args: &[String]) -> Result<()> {
    crate::cli::run_args(args).context("rtk")
}

/// Write linear RGB (`width * height * 3` values, row-major) to `path` as
/// `rtk render` writes its output: PNG (sRGB, 8-bit) or EXR (linear float),
/// atomically (nothing is left at `path` if writing fails).
pub fn write_image(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    if width == 0 || height == 0 {
        bail!("{}: the image is empty ({width}x{height})", path.display());
    }
    if rgb.len() as u64 != width as u64 * height as u64 * 3 {
        bail!(
            "{}: the image must hold width x height x 3 values",
            path.display()
        );
    }
    crate::shared::output::check_writable(path)?;
    let mut film = render_loop::Film::new(width, height).map_err(|m| anyhow!("{m}"))?;
    for (p, c) in film.pixels.iter_mut().zip(rgb.chunks_exact(3)) {
        *p = [c[0] as f64, c[1] as f64, c[2] as f64];
    }
    crate::shared::output::write(&film, path)
}

/// An image file (.exr, .pfm, .npy, .png) as `rtk diff` reads it:
/// (width, height, linear RGB values).
pub fn read_image(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    let img = crate::shared::images::read(path)?;
    Ok((img.width, img.height, img.data))
}

/// `rtk diff`'s metrics of `img` against `reference` (same length):
/// (RMSE, relMSE).
pub fn image_error(img: &[f32], reference: &[f32]) -> Result<(f64, f64)> {
    if img.len() != reference.len() {
        bail!(
            "the images differ in size ({} and {} values)",
            img.len(),
            reference.len()
        );
    }
    let m = crate::shared::images::metrics(img, reference);
    Ok((m.rmse, m.relmse))
}
