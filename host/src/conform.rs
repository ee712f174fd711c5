//! `rtk conform PLUGIN_FILE`: the conformance suite rtk's own object and
//! aggregate plugins pass, run against any plugin library, built anywhere.
//! Randomized scenes of spheres and small meshes (and duplicated children,
//! for ties) are traced under the plugin and under `list`, the oracle, with
//! random and adversarial rays; then bounds, nesting, concurrency and
//! parameter refusal. One line per check; a non-zero exit on any failure.

use crate::stress::{box_mesh, header, uv_sphere, vec3f, Bench, Probe, Size};
use anyhow::{bail, Context, Result};
use rtk_kernel::abi::{Hit, Ray, TraceCtx};
use rtk_kernel::glam::{DVec3, Vec3};
use rtk_kernel::RngState;
use rtk_shell::World;
use std::path::PathBuf;

/// The arguments of `rtk conform`.
#[derive(clap::Args)]
pub struct ConformArgs {
    /// The plugin library (librtk_NAME.so, rtk_NAME.dll, librtk_NAME.dylib).
    pub plugin: PathBuf,
    /// Its class (default: from the file name).
    #[arg(long, value_name = "NAME")]
    pub class: Option<String>,
    /// Fewer scenes and rays (seconds).
    #[arg(long)]
    pub quick: bool,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
    /// Threads the scenes are built for and the concurrency check runs on (at least 2).
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub threads: usize,
    /// Extra folders to search for the other plugins (sphere, mesh, list,
    /// bvh...) after the plugin's own (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    pub plugin_path: Vec<PathBuf>,
}

/// One check's outcome.
pub(crate) struct Check {
    pub name: &'static str,
    pub pass: bool,
    pub detail: String,
}

fn class_of(a: &ConformArgs) -> Result<String> {
    if let Some(c) = &a.class {
        return Ok(c.clone());
    }
    let stem = a
        .plugin
        .file_name()
        .and_then(|f| f.to_str())
        .context("the plugin's file name")?;
    let stem = stem
        .strip_prefix(std::env::consts::DLL_PREFIX)
        .unwrap_or(stem)
        .strip_suffix(std::env::consts::DLL_SUFFIX)
        .unwrap_or(stem);
    match stem.strip_prefix("rtk_") {
        Some(c) if rtk_shell::plugins::is_identifier(c) => Ok(c.to_string()),
        _ => bail!(
            "{}: cannot tell the class from the file name; say --class NAME",
            a.plugin.display()
        ),
    }
}

/// A random scene: its object definitions and the root's children (TOML
/// instance expressions), spheres and small meshes, some listed twice.
struct SceneDefs {
    defs: String,
    children: Vec<String>,
}

fn random_scene(b: &Bench, rng: &mut RngState, k: usize, n: usize) -> Result<SceneDefs> {
    let mut defs = String::new();
    let mut children = Vec::new();
    for i in 0..n {
        let c = DVec3::new(
            rng.next_f64() * 8.0 - 4.0,
            rng.next_f64() * 8.0 - 4.0,
            rng.next_f64() * 8.0 - 4.0,
        );
        let r = 0.2 + rng.next_f64() * 1.2;
        let name = format!("o{i}");
        match rng.next_u32() % 3 {
            0 => {
                defs += &format!(
                    "[objects.{name}]\nclass = \"sphere\"\ncenter = {}\nradius = {}\n",
                    vec3f(c.as_vec3()),
                    r as f32
                )
            }
            1 => {
                let m = uv_sphere(c, 4, 6, |_| r);
                let p = b.write_obj(&format!("s{k}_{i}.obj"), &m)?;
                defs += &mesh_def(&name, &p.display().to_string());
            }
            _ => {
                let m = box_mesh(c, DVec3::splat(r * 0.7));
                let p = b.write_obj(&format!("s{k}_{i}.obj"), &m)?;
                defs += &mesh_def(&name, &p.display().to_string());
            }
        }
        children.push(format!("\"{name}\""));
        // Ties: the same object again, later (the earlier must win).
        if rng.next_u32() & 3 == 0 {
            children.push(format!("\"{name}\""));
        }
    }
    Ok(SceneDefs { defs, children })
}

fn mesh_def(name: &str, file: &str) -> String {
    format!(
        "[objects.{name}]\nclass = \"mesh\"\nfile = {}\naccel = \"none\"\n",
        toml_str(file)
    )
}

fn toml_str(s: &str) -> String {
    format!("{s:?}")
}

fn world(defs: &str, class: &str, children: &[String]) -> String {
    format!(
        "{}{defs}[objects.world]\nclass = \"{class}\"\nchildren = [{}]\n",
        header("world"),
        children.join(", ")
    )
}

/// Random rays through the box, and adversarial ones: aimed at sphere and
/// mesh centres, axis-aligned (zero direction components), starting inside,
/// grazing the box faces, with random times in the shutter interval.
fn rays(rng: &mut RngState, n: usize, w: &World) -> Vec<Ray> {
    let (lo, hi) = (w.bounds.min.v().as_dvec3(), w.bounds.max.v().as_dvec3());
    let ext = hi - lo;
    let pick = |rng: &mut RngState, pad: f64| {
        lo - ext * pad
            + DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * ext * (1.0 + 2.0 * pad)
    };
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let o = pick(rng, 0.3);
        let d = match i % 5 {
            // Towards a point inside the box.
            0 | 1 => (pick(rng, 0.0) - o).normalize_or(DVec3::X),
            // Axis-aligned: two zero components.
            2 => {
                let mut d = DVec3::ZERO;
                d[(rng.next_u32() % 3) as usize] = if rng.next_u32() & 1 == 0 { 1.0 } else { -1.0 };
                d
            }
            // One zero component.
            3 => {
                let mut d = crate::stress::bench_unit(rng);
                d[(rng.next_u32() % 3) as usize] = 0.0;
                d.normalize_or(DVec3::Y)
            }
            _ => crate::stress::bench_unit(rng),
        };
        let mut r = Ray::new(o.as_vec3(), d.as_vec3().normalize_or(Vec3::X));
        r.time = rng.next_f32();
        out.push(r);
    }
    out
}

/// The same hit: the same t, the same child of the root, the same
/// primitive at the leaf. Not the whole path: the levels between depend on
/// how each side holds a primitive set (flattened into an aggregate that
/// builds over primitives, or wrapped in its own `accel` under one that
/// does not), which is not the plugin's to choose.
fn same(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            let leaf = |h: &Hit| h.stack[(h.depth as usize).saturating_sub(1)].prim;
            a.t.to_bits() == b.t.to_bits()
                && a.stack[0].index == b.stack[0].index
                && leaf(a) == leaf(b)
        }
        _ => false,
    }
}

fn show(h: &Option<Hit>) -> String {
    match h {
        None => "miss".into(),
        Some(h) => {
            let path: Vec<String> = (0..h.depth as usize)
                .map(|l| format!("({},{})", h.stack[l].index, h.stack[l].prim))
                .collect();
            format!("t {:?} {}", h.t, path.join(""))
        }
    }
}

fn ray_text(r: &Ray) -> String {
    format!(
        "o {:?} d {:?} time {:?}",
        r.origin.to_array(),
        r.dir.to_array(),
        r.time
    )
}

/// Tallies of one comparison against the oracle.
#[derive(Default)]
struct Tally {
    nearest: (u64, String),
    ties: (u64, String),
    anyhit: (u64, String),
    bounds: (u64, String),
    rays: u64,
}

fn note(slot: &mut (u64, String), msg: impl FnOnce() -> String) {
    if slot.0 == 0 {
        slot.1 = msg();
    }
    slot.0 += 1;
}

/// Trace `rays` under `test` and the oracle `oracle`; `dups` tells whether
/// the scene lists a child twice (a disagreement on identity alone with equal
/// `t` is then a tie broken wrongly).
fn compare(test: &World, oracle: &World, rays: &[Ray], t: &mut Tally) -> Result<()> {
    let (mut pt, mut po) = (Probe::new(test), Probe::new(oracle));
    let b = test.bounds;
    let (bmin, bmax) = (b.min.v(), b.max.v());
    let slack = (bmax - bmin).max_element().max(1.0) * 1e-4;
    for r in rays {
        t.rays += 1;
        let (ht, ho) = (pt.nearest(r)?, po.nearest(r)?);
        if !same(&ht, &ho) {
            let tie = matches!((&ht, &ho), (Some(a), Some(b)) if a.t.to_bits() == b.t.to_bits());
            let slot = if tie { &mut t.ties } else { &mut t.nearest };
            note(slot, || {
                format!("{}: plugin {} list {}", ray_text(r), show(&ht), show(&ho))
            });
        }
        if let Some(h) = &ho {
            let p = r.origin.v() + r.dir.v() * h.t;
            let inside =
                (p.cmpge(bmin - Vec3::splat(slack)) & p.cmple(bmax + Vec3::splat(slack))).all();
            if !inside {
                note(&mut t.bounds, || {
                    format!(
                        "hit point {:?} outside the plugin's bounds {:?}..{:?}",
                        p.to_array(),
                        bmin.to_array(),
                        bmax.to_array()
                    )
                });
            }
        }
        let (ot, oo) = (pt.occluded(r)?, po.occluded(r)?);
        if ot != oo {
            note(&mut t.anyhit, || {
                format!("{}: plugin occluded {ot}, list {oo}", ray_text(r))
            });
        }
    }
    Ok(())
}

fn verdict(name: &'static str, slot: &(u64, String), rays: u64) -> Check {
    Check {
        name,
        pass: slot.0 == 0,
        detail: if slot.0 == 0 {
            format!("{rays} rays agree")
        } else {
            format!("{} of {rays} rays differ; first: {}", slot.0, slot.1)
        },
    }
}

/// Trace `rays` from `threads` threads at once (each its own context),
/// twice over, against the single-thread answers.
fn concurrent(w: &World, rays: &[Ray], threads: usize) -> Result<u64> {
    let mut p = Probe::new(w);
    let mut want = Vec::with_capacity(rays.len());
    for r in rays {
        want.push((p.nearest(r)?, p.occluded(r)?));
    }
    let bad = std::sync::atomic::AtomicU64::new(0);
    std::thread::scope(|s| {
        for ti in 0..threads {
            let (want, bad) = (&want, &bad);
            s.spawn(move || {
                let mut ctx = TraceCtx::new(ti as u32, threads as u32, 0);
                for _ in 0..2 {
                    for (k, r) in rays.iter().enumerate() {
                        let mut h = Hit::new();
                        let got = w.root.intersect(&mut ctx, r, &mut h).then_some(h);
                        let occ = w.root.occluded(&mut ctx, r);
                        if !same(&got, &want[k].0) || occ != want[k].1 || ctx.failure().is_some() {
                            bad.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        }
                    }
                }
            });
        }
    });
    Ok(bad.into_inner())
}

/// Run `rtk conform`.
pub fn run(a: ConformArgs, pool: &rayon::ThreadPool) -> Result<()> {
    let class = class_of(&a)?;
    let plugin = rtk_shell::plugins::load(&a.plugin, Some(&class))
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.plugin.display()))?;
    if let rtk_shell::plugins::Module::Shader(m) = plugin.module {
        let n = if a.quick { 4000 } else { 40000 };
        let checks = crate::conform_shader::checks(m, &class, n)?;
        return report(&a, &class, "shader", checks);
    }
    if plugin.kind.name() != "object" {
        bail!(
            "{}: `{class}` is a {} plugin; rtk conform checks object, aggregate and shader plugins",
            a.plugin.display(),
            plugin.kind.name()
        );
    }
    drop(plugin);
    // A plugin folder holding just this library, searched first.
    let folder = tempfile::Builder::new().prefix("rtk-conform").tempdir()?;
    let lib = folder
        .path()
        .join(rtk_shell::plugins::library_file_name(&class));
    std::fs::copy(&a.plugin, &lib)
        .with_context(|| format!("copying {} to {}", a.plugin.display(), lib.display()))?;
    let size = if a.quick { Size::Quick } else { Size::Full };
    let mut extra = vec![folder.path().to_path_buf()];
    extra.extend(a.plugin_path.iter().cloned());
    let mut b = Bench::new(size, &extra, pool)?;
    let (scenes, nobj, nrays) = if a.quick {
        (4, 12, 600)
    } else {
        (20, 30, 5000)
    };
    // Queries may come from as many threads as the scenes were built for.
    let threads = pool.current_num_threads().max(1);
    let mut checks = Vec::new();
    let mut rng = RngState::seeded(0xC0F0);

    // Is it an aggregate? It must accept a child.
    let probe = world(
        "[objects.a]\nclass = \"sphere\"\n",
        &class,
        &["\"a\"".to_string()],
    );
    let aggregate = b.build_error(&probe).is_none();
    if !aggregate {
        checks.push(Check {
            name: "aggregate",
            pass: true,
            detail: format!("`{class}` takes no children: checked as a primitive"),
        });
    }

    if aggregate {
        let mut t = Tally::default();
        let mut nest_in = Tally::default();
        let mut nest_out = Tally::default();
        let mut conc_bad = 0;
        let mut conc_rays = 0;
        for k in 0..scenes {
            let s = random_scene(&b, &mut rng, k, nobj)?;
            let oracle = b.scene(&world(&s.defs, "list", &s.children))?;
            let test = b.scene(&world(&s.defs, &class, &s.children))?;
            let rs = rays(&mut rng, nrays, &oracle);
            compare(&test, &oracle, &rs, &mut t)?;
            // Nesting: the plugin inside bvh, and bvh inside the plugin.
            let defs_in = format!(
                "{}[objects.inner]\nclass = \"{class}\"\nchildren = [{}]\n",
                s.defs,
                s.children.join(", ")
            );
            let w_in = b.scene(&world(&defs_in, "bvh", &["\"inner\"".into()]))?;
            let o_in = b.scene(&world(
                &defs_in.replace(
                    &format!("class = \"{class}\"\nchildren"),
                    "class = \"list\"\nchildren",
                ),
                "list",
                &["\"inner\"".into()],
            ))?;
            compare(&w_in, &o_in, &rs, &mut nest_in)?;
            let defs_out = format!(
                "{}[objects.inner]\nclass = \"bvh\"\nchildren = [{}]\n",
                s.defs,
                s.children.join(", ")
            );
            let w_out = b.scene(&world(
                &defs_out,
                &class,
                &["\"inner\"".into(), s.children[0].clone()],
            ))?;
            let o_out = b.scene(&world(
                &defs_out,
                "list",
                &["\"inner\"".into(), s.children[0].clone()],
            ))?;
            compare(&w_out, &o_out, &rs, &mut nest_out)?;
            if k == 0 {
                conc_bad += concurrent(&test, &rs, threads)?;
                conc_rays += rs.len() as u64 * 2 * threads as u64;
            }
        }
        checks.push(verdict("nearest-hit", &t.nearest, t.rays));
        checks.push(verdict("ties-lowest-index", &t.ties, t.rays));
        checks.push(verdict("any-hit", &t.anyhit, t.rays));
        checks.push(verdict("bounds-contain-hits", &t.bounds, t.rays));
        let merge = |x: &Tally| {
            let s = [&x.nearest, &x.ties, &x.anyhit]
                .iter()
                .fold((0, String::new()), |acc, s| {
                    if acc.0 == 0 {
                        (s.0, s.1.clone())
                    } else {
                        (acc.0 + s.0, acc.1)
                    }
                });
            (s, x.rays)
        };
        let (s, n) = merge(&nest_in);
        checks.push(verdict("nested-inside-bvh", &s, n));
        let (s, n) = merge(&nest_out);
        checks.push(verdict("bvh-nested-inside", &s, n));
        checks.push(Check {
            name: "concurrent-queries",
            pass: conc_bad == 0,
            detail: format!(
                "{} threads: {conc_bad} of {conc_rays} answers differ from one thread's",
                threads
            ),
        });
    } else {
        // A primitive: under bvh as under list, bounds, concurrency.
        let defs = format!("[objects.p]\nclass = \"{class}\"\n");
        let kids = ["\"p\"".to_string(), "\"p\"".to_string()];
        let oracle = b.scene(&world(&defs, "list", &kids))?;
        let test = b.scene(&world(&defs, "bvh", &kids))?;
        let rs = rays(&mut rng, nrays * scenes, &oracle);
        let mut t = Tally::default();
        compare(&test, &oracle, &rs, &mut t)?;
        checks.push(verdict("nested-inside-bvh", &t.nearest, t.rays));
        checks.push(verdict("ties-lowest-index", &t.ties, t.rays));
        checks.push(verdict("any-hit", &t.anyhit, t.rays));
        checks.push(verdict("bounds-contain-hits", &t.bounds, t.rays));
        let bad = concurrent(&test, &rs, threads)?;
        checks.push(Check {
            name: "concurrent-queries",
            pass: bad == 0,
            detail: format!(
                "{} threads: {bad} answers differ from one thread's",
                threads
            ),
        });
    }

    // Parameters: an unknown key is refused, naming it.
    let key = "conform_unknown_key";
    let bad = if aggregate {
        world(
            &format!("[objects.a]\nclass = \"sphere\"\n[objects.x]\nclass = \"{class}\"\n{key} = 1\nchildren = [\"a\"]\n"),
            "list",
            &["\"x\"".into()],
        )
    } else {
        world(
            &format!("[objects.x]\nclass = \"{class}\"\n{key} = 1\n"),
            "list",
            &["\"x\"".into()],
        )
    };
    let err = b.build_error(&bad);
    checks.push(Check {
        name: "unknown-key-refused",
        pass: err.as_deref().is_some_and(|e| e.contains(key)),
        detail: match err {
            None => format!("`{key} = 1` was accepted"),
            Some(e) if e.contains(key) => "refused, naming the key".into(),
            Some(e) => format!("refused without naming the key: {}", e.replace('\n', " ")),
        },
    });

    let kind = if aggregate { "aggregate" } else { "object" };
    report(&a, &class, kind, checks)
}

/// Print the checks (lines or JSON); an error when any failed.
fn report(a: &ConformArgs, class: &str, kind: &str, checks: Vec<Check>) -> Result<()> {
    let failed = checks.iter().filter(|c| !c.pass).count();
    if a.json {
        let list: Vec<_> = checks
            .iter()
            .map(|c| serde_json::json!({"check": c.name, "pass": c.pass, "detail": c.detail}))
            .collect();
        println!(
            "{}",
            serde_json::json!({"plugin": a.plugin.display().to_string(), "class": class,
                "kind": kind, "aggregate": kind == "aggregate", "checks": list, "failed": failed})
        );
    } else {
        for c in &checks {
            println!(
                "{}  {:<22} {}",
                if c.pass { "pass" } else { "FAIL" },
                c.name,
                c.detail
            );
        }
        println!(
            "{class} ({}): {} checks, {failed} failed",
            a.plugin.display(),
            checks.len()
        );
    }
    if failed > 0 {
        bail!("`{class}` fails {failed} conformance check(s)");
    }
    Ok(())
}
