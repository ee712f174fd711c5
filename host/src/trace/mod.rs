//! `rtk trace`: cast rays against a scene's root (or a mesh under any
//! aggregate) and report throughput, build time, memory and checksums — the
//! interface benchmarks, tests and other tools use.

pub(crate) mod rays;

use anyhow::{bail, Context, Result};
use rays::{HitRec, RayRec};
use rtk_kernel::abi::{Hit, Ray, Stats, TraceCtx};
use rtk_kernel::sdk::batch;
use rtk_shell::plugins::Module;
use rtk_shell::{Parallel, PluginPath, Registry, World};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// The arguments of `rtk trace`.
#[derive(clap::Args)]
pub struct TraceArgs {
    /// A scene (.toml), or a mesh (.ply, .obj) traced under `--aggregate`.
    pub input: PathBuf,
    /// Rays to trace: a ray file (docs/trace.md).
    #[arg(long, value_name = "FILE", conflicts_with = "rayset")]
    pub rays: Option<PathBuf>,
    /// Rays to trace: a set of the Embree anchor's RAYS.md, generated over the root's box.
    #[arg(long, value_enum)]
    pub rayset: Option<RaySet>,
    /// Any-hit queries (shadow rays) instead of nearest hits.
    #[arg(long)]
    pub occluded: bool,
    /// Trace through the root's ray-stream entries, 64 consecutive rays per
    /// batch (rtk-abi 3.1), instead of one ray at a time: the hits are the
    /// same bit for bit (`rtk conform` checks every plugin's).
    #[arg(long)]
    pub stream: bool,
    /// The aggregate class: over the mesh, or in place of the scene root's class.
    #[arg(long, value_name = "NAME")]
    pub aggregate: Option<String>,
    /// Override a scene value (as `rtk render --set`), after `--aggregate`;
    /// a mesh's generated scene names its root `world`, e.g.
    /// --set objects.world.simd=avx2 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Tracing threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Write one hit record per ray to FILE (docs/trace.md).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the rays traced to FILE (a ray file).
    #[arg(long = "save-rays", value_name = "FILE")]
    pub save_rays: Option<PathBuf>,
    /// Timed passes over the rays, 1 to 1000 (the median is reported).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub iters: u32,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Extra folders to search for plugins first (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    pub plugin_path: Vec<PathBuf>,
}

/// The generated ray sets.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum RaySet {
    /// 1024x1024 pinhole rays through pixel centres.
    Primary,
    /// 2^20 rays from the padded box's surface, uniform inward directions.
    Incoherent,
}

/// Rays per task: as the Embree anchor splits its work.
const CHUNK: usize = 4096;
/// Most timed passes `--iters` may ask for: a benchmark's median needs a
/// handful, and a typo of a few more digits should not run for days.
const MAX_ITERS: u32 = 1000;

/// Run `rtk trace`.
pub fn run(a: TraceArgs, pool: &rayon::ThreadPool, parallel: &dyn Parallel) -> Result<()> {
    if a.iters == 0 {
        bail!("--iters must be at least 1 (the timed passes over the rays)");
    }
    if a.iters > MAX_ITERS {
        bail!("--iters must be at most {MAX_ITERS}, got {}", a.iters);
    }
    let rss0 = resident_bytes();
    let t_build = Instant::now();
    let world = load_world(&a, parallel)?;
    let load = t_build.elapsed().as_secs_f64();
    // The aggregates' build is their `prepare` (every class that builds over
    // primitives, the nested ones too); the rest of loading is reading files.
    let root_class = world.root.class_name();
    let build: f64 = world
        .plugins
        .iter()
        .filter(|p| matches!(p.module, Module::Object(m) if m.flattens_primitives()))
        .filter_map(|p| world.timings.prepare_by_class.get(&p.class))
        .map(|d| d.as_secs_f64())
        // From +0, not `sum`'s -0: a list builds nothing and reports 0.0 ms.
        .fold(0.0, |a, b| a + b);
    let memory = resident_bytes().saturating_sub(rss0);
    let (lo, hi) = world_box(&world, &a.input)?;
    let (set_name, rays) = match (&a.rays, a.rayset) {
        (Some(p), _) => (p.display().to_string(), rays::read_rays(p)?),
        (None, Some(set @ RaySet::Primary)) => ("primary".into(), generate(set, lo, hi)),
        (None, Some(set @ RaySet::Incoherent)) => ("incoherent".into(), generate(set, lo, hi)),
        (None, None) => {
            bail!("say which rays to trace: --rays FILE or --rayset primary|incoherent")
        }
    };
    if let Some(p) = &a.save_rays {
        rays::write_rays(p, &rays)?;
    }
    let (mut times, stats, hits) = time_passes(&a, &world, &rays, pool)?;
    let passes = times.clone();
    times.sort_by(f64::total_cmp);
    let secs = times[times.len() / 2];
    if let Some(p) = &a.out {
        std::fs::write(p, rays::hit_bytes(&hits))
            .with_context(|| format!("writing {}", p.display()))?;
    }
    let report = Report {
        input: a.input.display().to_string(),
        set: set_name,
        query: if a.occluded { "occluded" } else { "intersect" },
        path: if a.stream { "stream" } else { "single" },
        rays: rays.len(),
        rays_hash: format!("{:016x}", rays::rays_hash(&rays)),
        threads: pool.current_num_threads(),
        seconds: secs,
        passes,
        build_seconds: build,
        load_seconds: load,
        aggregate: root_class,
        memory_bytes: memory,
        hits: &hits,
        stats: &stats,
    };
    report.print(a.json);
    Ok(())
}

/// `--iters` timed passes over `rays`: each pass's seconds, the counters
/// of the last, and the hit records (one per ray, written in place by
/// every pass, as the Embree anchor writes its arrays: the timing is the
/// tracing's alone).
fn time_passes(
    a: &TraceArgs,
    world: &World,
    rays: &[RayRec],
    pool: &rayon::ThreadPool,
) -> Result<(Vec<f64>, Stats, Vec<HitRec>)> {
    let mut times = Vec::new();
    let mut stats = Stats::default();
    // Query ids must never repeat on a thread, across passes too (mailboxes
    // are keyed by them): each thread's counter lives for the whole run.
    let next_query: Vec<AtomicU64> = (0..pool.current_num_threads())
        .map(|_| AtomicU64::new(0))
        .collect();
    let mut hits = vec![HitRec::MISS; rays.len()];
    let q = Query {
        occluded: a.occluded,
        stream: a.stream,
    };
    for _ in 0..a.iters {
        let t = Instant::now();
        stats = trace_all(world, rays, q, pool, &next_query, &mut hits)?;
        times.push(t.elapsed().as_secs_f64());
    }
    Ok((times, stats, hits))
}

/// The world to trace: the scene, or a generated one over the mesh.
fn load_world(a: &TraceArgs, parallel: &dyn Parallel) -> Result<World> {
    let (file, sets) = trace_input(&a.input, a.aggregate.as_deref())?;
    if let Some(s) = a
        .set
        .iter()
        .find(|s| s.split('=').next().map(str::trim) == Some("render.origin"))
    {
        bail!("--set {s}: rtk trace traces in world coordinates (ray files and ray sets are); render.origin cannot be set");
    }
    let sets = sets.into_iter().chain(a.set.iter().cloned()).collect();
    build_world(file, sets, &a.plugin_path, parallel)
}

/// The scene `rtk trace` reads from `input`: a scene file, with its root's
/// class replaced by `aggregate` if given, or a generated scene over a mesh
/// file (.ply, .obj) under `aggregate` (`bvh` by default); and the `--set`s
/// the replacement needs.
pub(crate) fn trace_input(
    input: &Path,
    aggregate: Option<&str>,
) -> Result<(rtk_shell::SceneFile, Vec<String>)> {
    let ext = input
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    Ok(match ext.as_deref() {
        Some("ply") | Some("obj") => (mesh_scene(input, aggregate)?, vec![]),
        _ => {
            let mut file = rtk_shell::SceneFile::read(input)?;
            let sets = match aggregate {
                Some(class) => {
                    let root = root_object(&file)?;
                    let dropped = keep_class_neutral_keys(&mut file, &root, class);
                    if !dropped.is_empty() {
                        eprintln!(
                            "note: --aggregate {class}: the root `{root}`'s own parameters ({}) are not {class}'s; dropped",
                            dropped.join(", ")
                        );
                    }
                    vec![format!("objects.{root}.class={class}")]
                }
                None => vec![],
            };
            (file, sets)
        }
    })
}

/// Build the world of `file` with `sets` applied, in world coordinates.
pub(crate) fn build_world(
    file: rtk_shell::SceneFile,
    sets: Vec<String>,
    plugin_path: &[PathBuf],
    parallel: &dyn Parallel,
) -> Result<World> {
    let mut registry = Registry::new(PluginPath::standard(plugin_path));
    let mut file = file;
    let mut sets = sets;
    // Ray files and the generated sets are in world coordinates: no
    // camera-relative shift (docs/scene-format.md, `origin`).
    sets.push("render.origin=\"world\"".to_string());
    file.apply_overrides(&sets)?;
    let desc = rtk_shell::Desc::from_file(&file)?;
    Ok(rtk_shell::build(&file, desc, &mut registry, parallel)?)
}

/// The generated ray set over the box [lo, hi].
pub(crate) fn generate(set: RaySet, lo: [f64; 3], hi: [f64; 3]) -> Vec<RayRec> {
    match set {
        RaySet::Primary => rays::primary(lo, hi),
        RaySet::Incoherent => rays::incoherent(lo, hi),
    }
}

/// The world's box as f64 corners; an error if it is empty.
pub(crate) fn world_box(world: &World, what: &Path) -> Result<([f64; 3], [f64; 3])> {
    let b = world.bounds;
    if b.is_empty() {
        bail!(
            "{}: the scene is empty (its root has no bounds)",
            what.display()
        );
    }
    Ok((
        b.min.to_array().map(|x| x as f64),
        b.max.to_array().map(|x| x as f64),
    ))
}

/// A scene holding the mesh (tested by brute force: `accel = "none"`)
/// under one aggregate, `bvh` by default.
pub(crate) fn mesh_scene(mesh: &Path, aggregate: Option<&str>) -> Result<rtk_shell::SceneFile> {
    let abs = std::path::absolute(mesh).with_context(|| format!("{}", mesh.display()))?;
    let agg = aggregate.unwrap_or(rtk_kernel::classes::DEFAULT_ACCEL);
    let file = toml_string(&abs.to_string_lossy());
    let text = format!(
        "[render]\nroot = \"world\"\nintegrator = \"normals\"\n[cameras.none]\nclass = \"pinhole\"\n\
         [objects.mesh]\nclass = \"mesh\"\nfile = {file}\naccel = \"none\"\n\
         [objects.world]\nclass = {}\nchildren = [\"mesh\"]\n",
        toml_string(agg)
    );
    Ok(rtk_shell::SceneFile::parse(
        &abs.with_extension("trace.toml"),
        text,
    )?)
}

fn toml_string(s: &str) -> String {
    toml_quote(s)
}

/// A TOML basic string holding `s`.
fn toml_quote(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Swapping the class of `objects.<object>` for `class`: the definition's
/// parameters belong to its old class (a `bvh`'s `width` means nothing to a
/// `list`), so only `class` and `children` are kept when the class
/// changes. Returns the keys dropped.
fn keep_class_neutral_keys(
    file: &mut rtk_shell::SceneFile,
    object: &str,
    class: &str,
) -> Vec<String> {
    use rtk_shell::tree::Val;
    let Val::Table(sections) = &mut file.root.value else {
        return Vec::new();
    };
    let Some((_, _, objects)) = sections.iter_mut().find(|(k, _, _)| k == "objects") else {
        return Vec::new();
    };
    let Val::Table(objects) = &mut objects.value else {
        return Vec::new();
    };
    let Some((_, _, def)) = objects.iter_mut().find(|(k, _, _)| k == object) else {
        return Vec::new();
    };
    let Val::Table(keys) = &mut def.value else {
        return Vec::new();
    };
    let same = keys
        .iter()
        .any(|(k, _, v)| k == "class" && matches!(&v.value, Val::Str(c) if c == class));
    if same {
        return Vec::new();
    }
    let mut dropped = Vec::new();
    keys.retain(|(k, _, _)| {
        let keep = k == "class" || k == "children";
        if !keep {
            dropped.push(k.clone());
        }
        keep
    });
    dropped
}

/// The object name the scene's `[render] root` instances.
fn root_object(file: &rtk_shell::SceneFile) -> Result<String> {
    let root = file
        .root
        .get("render")
        .and_then(|r| r.get("root"))
        .context("--aggregate needs a scene with [render] root")?;
    match &root.value {
        rtk_shell::tree::Val::Str(s) => Ok(s.clone()),
        _ => match root.get("object").map(|o| &o.value) {
            Some(rtk_shell::tree::Val::Str(s)) => Ok(s.clone()),
            _ => bail!("--aggregate: [render] root names no object"),
        },
    }
}

/// What each ray asks, and through which entries.
#[derive(Clone, Copy)]
pub(crate) struct Query {
    /// Any hit instead of the nearest.
    pub occluded: bool,
    /// Through the stream entries, in batches of [`batch::MAX`] rays.
    pub stream: bool,
}

/// Trace every ray on the pool, in chunks, each ray's hit into its place
/// in `out` (as long as `rays`); the counters of the pass.
pub(crate) fn trace_all(
    world: &World,
    rays: &[RayRec],
    q: Query,
    pool: &rayon::ThreadPool,
    next_query: &[AtomicU64],
    out: &mut [HitRec],
) -> Result<Stats> {
    use rayon::prelude::*;
    assert_eq!(rays.len(), out.len(), "one hit record per ray");
    let threads = pool.current_num_threads() as u32;
    let chunks: Vec<(Stats, Option<String>)> = pool.install(|| {
        rays.par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .map(|(chunk, out)| {
                let ti = rayon::current_thread_index().unwrap_or(0);
                let counter = &next_query[ti];
                let mut ctx = TraceCtx::new(ti as u32, threads, counter.load(Ordering::Relaxed));
                if q.stream {
                    for (rs, os) in chunk.chunks(batch::MAX).zip(out.chunks_mut(batch::MAX)) {
                        trace_batch(world, &mut ctx, rs, q.occluded, os);
                    }
                } else {
                    // One hit record per chunk, reset per ray.
                    let mut hit = Hit::new();
                    for (r, o) in chunk.iter().zip(out) {
                        *o = trace_one(world, &mut ctx, &mut hit, r, q.occluded);
                    }
                }
                counter.store(ctx.query_counter(), Ordering::Relaxed);
                let failure = ctx.failure().map(|(c, m)| format!("plugin `{c}` {m}"));
                (ctx.stats, failure)
            })
            .collect()
    });
    let mut stats = Stats::default();
    for (s, failure) in chunks {
        if let Some(f) = failure {
            bail!("tracing failed: {f}");
        }
        stats.merge(&s);
    }
    Ok(stats)
}

/// A ray file's ray as the kernel's, at time 0.
#[inline]
pub(crate) fn to_ray(r: &RayRec) -> Ray {
    Ray {
        origin: r.o.into(),
        dir: r.d.into(),
        t_min: r.t_min,
        t_max: r.t_max,
        time: 0.0,
        generation: 0,
    }
}

/// The record of an occluded ray (`prim` 1 says blocked).
const BLOCKED: HitRec = HitRec {
    t: 0.0,
    prim: 1,
    ..HitRec::MISS
};

/// The record of a nearest hit: its `t`, the leaf's primitive, its uv.
#[inline]
fn hit_rec(hit: &Hit) -> HitRec {
    HitRec {
        t: hit.t,
        prim: hit.at(hit.depth.saturating_sub(1)),
        u: hit.uv[0],
        v: hit.uv[1],
    }
}

#[inline]
fn trace_one(
    world: &World,
    ctx: &mut TraceCtx,
    hit: &mut Hit,
    r: &RayRec,
    occluded: bool,
) -> HitRec {
    let ray = to_ray(r);
    if occluded {
        return if world.root.occluded(ctx, &ray) {
            BLOCKED
        } else {
            HitRec::MISS
        };
    }
    hit.reset();
    if !world.root.intersect(ctx, &ray, hit) {
        return HitRec::MISS;
    }
    hit_rec(hit)
}

/// Up to [`batch::MAX`] rays through the root's stream entries, every lane
/// active, each lane's record into `out`.
#[inline]
fn trace_batch(
    world: &World,
    ctx: &mut TraceCtx,
    rs: &[RayRec],
    occluded: bool,
    out: &mut [HitRec],
) {
    // `rs` is never empty (a chunk of a chunk): its first ray fills the rest.
    let mut rays = [to_ray(&rs[0]); batch::MAX];
    for (d, r) in rays.iter_mut().zip(rs) {
        *d = to_ray(r);
    }
    let n = rs.len();
    let active = batch::all(n);
    if occluded {
        let m = world.root.occluded_stream(ctx, &rays[..n], active);
        for (i, o) in out.iter_mut().enumerate() {
            *o = if (m >> i) & 1 == 1 {
                BLOCKED
            } else {
                HitRec::MISS
            };
        }
        return;
    }
    let mut hits = [Hit::new(); batch::MAX];
    let m = world
        .root
        .intersect_stream(ctx, &rays[..n], &mut hits[..n], active);
    for (i, o) in out.iter_mut().enumerate() {
        *o = if (m >> i) & 1 == 1 {
            hit_rec(&hits[i])
        } else {
            HitRec::MISS
        };
    }
}

/// Resident memory of the process, from /proc (0 where unavailable).
pub(crate) fn resident_bytes() -> usize {
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<usize>().ok())
        .map_or(0, |pages| pages * 4096)
}

/// What `rtk trace` prints.
struct Report<'a> {
    input: String,
    set: String,
    query: &'static str,
    /// Through which entries: `single` or `stream`.
    path: &'static str,
    rays: usize,
    rays_hash: String,
    threads: usize,
    seconds: f64,
    /// Every pass's time, in the order run (a structure built while
    /// tracing, `raycls`, is slower in the first).
    passes: Vec<f64>,
    build_seconds: f64,
    load_seconds: f64,
    aggregate: &'a str,
    memory_bytes: usize,
    hits: &'a [HitRec],
    stats: &'a Stats,
}

/// The walk a `bvh` (8-wide, `simd = "auto"`) runs on this CPU, as the
/// plugin decides it (the same kernel code): a timing says what it timed.
fn cpu_simd() -> &'static str {
    rtk_kernel::accel::Bvh::<8>::best_simd().name()
}

impl Report<'_> {
    fn print(&self, json: bool) {
        let n_hits = self.hits.iter().filter(|h| h.t.is_finite()).count();
        let sum_t: f64 = self
            .hits
            .iter()
            .filter(|h| h.t.is_finite())
            .map(|h| h.t as f64)
            .sum();
        let sum_prim: u64 = self
            .hits
            .iter()
            .filter(|h| h.t.is_finite())
            .map(|h| h.prim as u64)
            .sum();
        let mrays = self.rays as f64 / self.seconds / 1e6;
        let per_ray = |x: u64| x as f64 / self.rays.max(1) as f64;
        if json {
            let j = serde_json::json!({
                "input": self.input, "set": self.set, "query": self.query, "path": self.path,
                "rays": self.rays, "rays_hash": self.rays_hash, "threads": self.threads,
                "mrays_per_s": mrays, "trace_seconds": self.seconds,
                "pass_seconds": self.passes,
                "aggregate": self.aggregate, "build_seconds": self.build_seconds,
                "load_seconds": self.load_seconds, "memory_bytes": self.memory_bytes,
                "hits": n_hits, "sum_t": sum_t, "sum_prim": sum_prim,
                "node_tests_per_ray": per_ray(self.stats.node_tests),
                "prim_tests_per_ray": per_ray(self.stats.prim_tests),
                "cpu_simd": cpu_simd(),
            });
            println!("{j}");
        } else {
            println!(
                "{} {} {} ({}): {} rays (hash {}), {} threads, cpu simd {}\n  {:.2} Mrays/s ({:.3} s), {} build {:.1} ms (loading {:.1} ms), memory {:.1} MB\n  hits {}, sum_t {:.6}, sum_prim {}\n  {:.1} node tests and {:.1} primitive tests per ray",
                self.input, self.set, self.query, self.path, self.rays, self.rays_hash, self.threads, cpu_simd(),
                mrays, self.seconds, self.aggregate, self.build_seconds * 1e3, self.load_seconds * 1e3,
                self.memory_bytes as f64 / 1e6,
                n_hits, sum_t, sum_prim,
                per_ray(self.stats.node_tests), per_ray(self.stats.prim_tests)
            );
        }
    }
}
