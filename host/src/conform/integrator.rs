//! `rtk conform` for integrator plugins: small scenes rendered through the
//! host's tracer (the services `rtk render` gives integrators), one camera
//! ray per estimate, each with its own random stream (seed, ray), as the
//! render loop draws them. Rays start 4 units from the origin, aimed within
//! 1.6 of it: some hit the sphere of radius 1 there, some miss.
//!
//! - `finite`: every estimate is finite and ≥ 0, in each scene (a furnace,
//!   a dark one, and one with a point light, a mirror, glass and a floor);
//! - `furnace`: a Lambert sphere of albedo ρ = 0.5 under a constant
//!   environment of radiance L (and nothing else): a convex object sees
//!   only the environment, so a ray that hits it carries exactly ρ·L and a
//!   ray that misses exactly L. The means of estimate / expectation, per
//!   channel, over hitting and missing rays, must be 1 within 5 standard
//!   errors + 1%: no energy created or lost;
//! - `black-without-light`: with no light and a black background every
//!   estimate is 0;
//! - `deterministic`: the same ray with the same random stream gives the
//!   same estimate, bit for bit (in another order: no hidden state);
//! - `concurrent-queries`: estimates from every thread at once are one
//!   thread's;
//! - `stream-parity`: `li_batch` gives `li`'s estimates, each ray with its
//!   own random stream, and leaves each stream where `li` does (stream.rs).
//!
//! `furnace` and `black-without-light` assume the integrator estimates
//! radiance (`normals` does not: `--skip` them).

use crate::conform::{note, unknown_key, Check, Cx, Suite};
use crate::render::tracer::Tracer;
use anyhow::{anyhow, Result};
use rtk_kernel::abi::{Color, Hit, Ray, TraceCtx};
use rtk_kernel::RngState;
use rtk_shell::World;

/// Radiance of the furnace's environment (not grey: channels are told apart).
const L: [f32; 3] = [0.6, 0.8, 1.0];
/// Albedo of its sphere.
const RHO: f32 = 0.5;
/// The seed of the random streams.
const SEED: u64 = 7;

fn scene(cx: &Cx, body: &str) -> String {
    let inline = cx.params.inline();
    format!(
        "[render]\nroot = \"world\"\nwidth = 8\nheight = 8\nintegrator = {{ class = {}{}{inline} }}\n\
         [cameras.c]\nclass = \"pinhole\"\n{body}",
        crate::conform::toml_str(&cx.class),
        if inline.is_empty() { "" } else { ", " }
    )
}

fn furnace(cx: &Cx) -> String {
    scene(
        cx,
        &format!(
            "[lights.sky]\nclass = \"constant\"\nradiance = {L:?}\n\
             [shaders.grey]\nclass = \"lambert\"\nalbedo = [{RHO:?}, {RHO:?}, {RHO:?}]\n\
             [objects.ball]\nclass = \"sphere\"\nradius = 1.0\n\
             [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", shader = \"grey\" }}]\n"
        ),
    )
}

fn dark(cx: &Cx) -> String {
    scene(
        cx,
        &format!(
            "[shaders.grey]\nclass = \"lambert\"\nalbedo = [{RHO:?}, {RHO:?}, {RHO:?}]\n\
             [objects.ball]\nclass = \"sphere\"\nradius = 1.0\n\
             [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", shader = \"grey\" }}]\n"
        ),
    )
}

fn mixed(cx: &Cx) -> String {
    scene(
        cx,
        "[lights.key]\nclass = \"point\"\nposition = [2.0, 4.0, 3.0]\nintensity = [20.0, 20.0, 20.0]\n\
         [shaders.grey]\nclass = \"lambert\"\n\
         [shaders.mirror]\nclass = \"conductor\"\n\
         [shaders.glass]\nclass = \"dielectric\"\n\
         [objects.ball]\nclass = \"sphere\"\nradius = 0.6\n\
         [objects.floor]\nclass = \"disk\"\ncenter = [0.0, -1.0, 0.0]\nradius = 3.0\n\
         [objects.world]\nclass = \"list\"\nchildren = [\n\
           { object = \"ball\", shader = \"mirror\", transform = [{ translate = [-0.7, 0.0, 0.0] }] },\n\
           { object = \"ball\", shader = \"glass\", transform = [{ translate = [0.7, 0.0, 0.0] }] },\n\
           { object = \"floor\", shader = \"grey\" },\n]\n",
    )
}

/// The camera rays: from 4 units out, aimed within 1.6 of the origin.
fn rays(rng: &mut RngState, n: usize) -> Vec<Ray> {
    (0..n)
        .map(|_| {
            let o = crate::stress::bench_unit(rng).as_vec3() * 4.0;
            let target = crate::stress::bench_unit(rng).as_vec3() * (1.6 * rng.next_f32().cbrt());
            let mut r = Ray::new(o, (target - o).normalize());
            r.time = rng.next_f32();
            r
        })
        .collect()
}

/// The estimate for ray `i`, with its own random stream.
fn li(t: &Tracer, ctx: &mut TraceCtx, ray: &Ray, i: usize) -> Result<Color> {
    ctx.rng = RngState::for_sample(SEED, i as u64, 0);
    let c = t.camera_li(ctx, ray);
    if let Some((class, m)) = ctx.failure() {
        return Err(anyhow!("plugin `{class}` {m}"));
    }
    Ok(c)
}

fn ok(c: &Color) -> bool {
    c.is_finite() && c.r >= 0.0 && c.g >= 0.0 && c.b >= 0.0
}

fn bits(c: &Color) -> [u32; 3] {
    [c.r.to_bits(), c.g.to_bits(), c.b.to_bits()]
}

/// Estimates of `rays` in `w`, noting those not finite or negative.
fn estimates(w: &World, rays: &[Ray], bad: &mut (u64, String), what: &str) -> Result<Vec<Color>> {
    let t = Tracer::new(w);
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut out = Vec::with_capacity(rays.len());
    for (i, r) in rays.iter().enumerate() {
        let c = li(&t, &mut ctx, r, i)?;
        if !ok(&c) {
            note(bad, || {
                format!(
                    "{what}: ray o {:?} d {:?}: {c:?}",
                    r.origin.to_array(),
                    r.dir.to_array()
                )
            });
        }
        out.push(c);
    }
    Ok(out)
}

/// Mean and standard error.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, (var / n).sqrt())
}

/// The checks for integrator plugin `cx.class`.
pub(crate) fn checks(cx: &mut Cx, suite: &mut Suite) -> Result<()> {
    suite.at("create");
    let n = cx.n(4000, 40000);
    let rs = rays(&mut cx.rng, n);
    let w = cx.bench.scene(&furnace(cx))?;
    let mut bad = (0u64, String::new());
    suite.at("finite");
    let est = estimates(&w, &rs, &mut bad, "furnace")?;
    let dark_world = cx.bench.scene(&dark(cx))?;
    let dark_est = estimates(&dark_world, &rs[..n / 4], &mut bad, "dark scene")?;
    let mixed_world = cx.bench.scene(&mixed(cx))?;
    estimates(
        &mixed_world,
        &rs[..n / 2],
        &mut bad,
        "mirror, glass and a point light",
    )?;
    suite.push(Check::held(
        "finite",
        &bad,
        (n + n / 4 + n / 2) as u64,
        "estimates",
    ));

    if suite.wants("furnace") {
        suite.at("furnace");
        suite.push(furnace_check(&w, &rs, &est));
    }
    if suite.wants("black-without-light") {
        suite.at("black-without-light");
        suite.push(black_without_light(&dark_est));
    }

    suite.at("deterministic");
    {
        let t = Tracer::new(&w);
        suite.push(deterministic(&t, &rs, &est)?);
        suite.at("concurrent-queries");
        suite.push(concurrent_queries(&t, &rs, &est, cx.threads));
    }
    if suite.wants(super::stream::NAME) {
        suite.at(super::stream::NAME);
        // The mixed scene: shadow rays, mirror and glass paths, misses.
        let t = Tracer::new(&mixed_world);
        let c = super::stream::integrator(&t, &rs[..cx.n(1000, 10000).min(n)], SEED)?;
        suite.push(c);
    }
    drop((w, dark_world, mixed_world));

    suite.at("unknown-key-refused");
    let c = unknown_key(cx, 0);
    suite.push(c);
    super::panics::run(cx, suite, 0)?;
    Ok(())
}

/// `furnace`: in the furnace `w`, the estimates `est` of the rays `rs`
/// that hit the sphere are ρ·L, those that miss it L, in the mean per
/// channel within 5 standard errors.
fn furnace_check(w: &World, rs: &[Ray], est: &[Color]) -> Check {
    let mut ctx = TraceCtx::new(0, 1, 0);
    let (mut hit_ratio, mut miss_ratio) = ([vec![], vec![], vec![]], [vec![], vec![], vec![]]);
    for (r, c) in rs.iter().zip(est) {
        let mut h = Hit::new();
        let hits = w.root.intersect(&mut ctx, r, &mut h);
        let (ratios, scale) = if hits {
            (&mut hit_ratio, RHO)
        } else {
            (&mut miss_ratio, 1.0)
        };
        for (k, v) in c.to_array().into_iter().enumerate() {
            ratios[k].push(v as f64 / (scale * L[k]) as f64);
        }
    }
    let mut worst: Option<String> = None;
    let mut shown = Vec::new();
    for (what, ratios, expect) in [("hit", &hit_ratio, RHO), ("missed", &miss_ratio, 1.0)] {
        if ratios[0].is_empty() {
            continue;
        }
        let mut means = Vec::new();
        for (k, ch) in ["r", "g", "b"].iter().enumerate() {
            let (m, se) = mean_se(&ratios[k]);
            means.push(format!("{m:.3}"));
            if (m - 1.0).abs() > 5.0 * se + 0.01 && worst.is_none() {
                worst = Some(format!(
                    "{} rays that {what} the sphere: mean {ch} = {:.4} ± {:.4} × the expected {:.3} ({expect}·L)",
                    ratios[k].len(),
                    m,
                    se,
                    expect * L[k]
                ));
            }
        }
        shown.push(format!(
            "{} rays that {what} it: {}",
            ratios[0].len(),
            means.join(", ")
        ));
    }
    match worst {
        None => Check::pass(
            "furnace",
            format!(
                "ρ = {RHO} sphere under L = {L:?}: estimate / expected = 1 within noise ({})",
                shown.join("; ")
            ),
        ),
        Some(w) => Check::new("furnace", false, w),
    }
}

/// `black-without-light`: with no light and a black background every
/// estimate is 0.
fn black_without_light(dark_est: &[Color]) -> Check {
    let lit = dark_est.iter().filter(|c| !c.is_black()).count();
    let first = dark_est.iter().find(|c| !c.is_black());
    Check::new(
        "black-without-light",
        lit == 0,
        match first {
            None => format!("{} estimates, all 0", dark_est.len()),
            Some(c) => format!(
                "{lit} of {} estimates are not 0 with no light and a black background; first: {c:?}",
                dark_est.len()
            ),
        },
    )
}

/// `deterministic`: each ray again (in reverse order), with its own
/// random stream, gives the same estimate bit for bit.
fn deterministic(t: &Tracer, rs: &[Ray], est: &[Color]) -> Result<Check> {
    let mut ctx = TraceCtx::new(0, 1, 0);
    let mut again = (0u64, String::new());
    for (i, (r, c)) in rs.iter().zip(est).enumerate().rev() {
        let c2 = li(t, &mut ctx, r, i)?;
        if bits(c) != bits(&c2) {
            note(&mut again, || format!("ray {i}: {c:?} then {c2:?}"));
        }
    }
    Ok(Check::held(
        "deterministic",
        &again,
        rs.len() as u64,
        "estimates",
    ))
}

/// `concurrent-queries`: every thread at once, twice over the first
/// thousand rays, gets one thread's estimates.
fn concurrent_queries(t: &Tracer, rs: &[Ray], est: &[Color], threads: usize) -> Check {
    let m = rs.len().min(1000);
    let differ = std::sync::atomic::AtomicU64::new(0);
    std::thread::scope(|sc| {
        for ti in 0..threads {
            let differ = &differ;
            sc.spawn(move || {
                let mut ctx = TraceCtx::new(ti as u32, threads as u32, 0);
                for _ in 0..2 {
                    for i in 0..m {
                        ctx.rng = RngState::for_sample(SEED, i as u64, 0);
                        let c = t.camera_li(&mut ctx, &rs[i]);
                        if bits(&c) != bits(&est[i]) || ctx.failed() {
                            differ.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        }
                    }
                }
            });
        }
    });
    let of = (m * 2 * threads) as u64;
    let differ = differ.into_inner();
    Check::new(
        "concurrent-queries",
        differ == 0,
        format!("{threads} threads: {differ} of {of} estimates differ from one thread's"),
    )
}
