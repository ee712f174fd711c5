//! `rtk conform` for light plugins: the light of a small scene, created
//! with `--params`, sampled from random points of the box [-4, 4]³ with
//! random samples and times, as integrators sample it.
//!
//! Every light:
//! - `finite`: each sample's direction is finite and unit, its distance
//!   positive (infinite allowed), its radiance finite and ≥ 0, its density
//!   finite and > 0; `le` finite and ≥ 0; some point receives light;
//! - `deterministic`: the same query gives the same sample, bit for bit;
//! - `concurrent-queries`: from every thread at once, one thread's answers;
//! - `stream-parity`: `sample_li_batch` gives `sample_li`'s samples (stream.rs).
//!
//! A light without `le` is a delta light to the host (a point or a single
//! direction: no ray can find it, and `path` weighs it by next-event
//! estimation alone):
//! - `delta-light`: its density is 1, `pdf_li` (if offered) says 0, and
//!   the sample does not depend on the random numbers;
//! - `points-on-light`: from every point (at one time) the samples point
//!   at one position (p + wi · dist), or along one direction when the
//!   distance is infinite.
//!
//! An environment light (`le` offered):
//! - `at-infinity`: every sample's distance is infinite;
//! - `li-matches-le`: a sample's radiance is `le` of its direction;
//! - `pdf-matches-sample`: `pdf_li` of a sampled direction is the density
//!   the sample reported;
//! - `pdf-integrates`: ∫ pdf_li dω over the sphere is 1 (uniform-sphere
//!   Monte Carlo, within 5 standard errors): a density MIS can use.

use crate::conform::{note, scene_using, unknown_key, Check, Cx, Kind, Suite};
use anyhow::{anyhow, Result};
use rtk_handles::Light;
use rtk_kernel::abi::{Color, Float3, LightSample, TraceCtx};
use rtk_kernel::glam::Vec3;
use rtk_kernel::sdk::shading::uniform_sphere;
use rtk_kernel::RngState;

/// One query: the point, the random numbers, the time.
#[derive(Clone, Copy)]
pub(crate) struct Query {
    pub p: Vec3,
    pub u: [f32; 2],
    pub time: f32,
}

fn sample(l: &Light, ctx: &mut TraceCtx, q: &Query) -> Result<Option<LightSample>> {
    let s = l.sample_li(ctx, q.p, q.u, q.time);
    if let Some((c, m)) = ctx.failure() {
        return Err(anyhow!("plugin `{c}` {m}"));
    }
    Ok(s)
}

fn bits(s: &Option<LightSample>) -> Option<[u32; 8]> {
    s.map(|s| {
        [
            s.wi.x.to_bits(),
            s.wi.y.to_bits(),
            s.wi.z.to_bits(),
            s.dist.to_bits(),
            s.li.r.to_bits(),
            s.li.g.to_bits(),
            s.li.b.to_bits(),
            s.pdf.to_bits(),
        ]
    })
}

fn color_ok(c: Color) -> bool {
    c.is_finite() && c.r >= 0.0 && c.g >= 0.0 && c.b >= 0.0
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1e-6)
}

fn random_point(rng: &mut RngState) -> Vec3 {
    Vec3::new(
        rng.next_f32() * 8.0 - 4.0,
        rng.next_f32() * 8.0 - 4.0,
        rng.next_f32() * 8.0 - 4.0,
    )
}

/// The checks for light plugin `cx.class`.
pub(crate) fn checks(cx: &mut Cx, suite: &mut Suite) -> Result<()> {
    suite.at("create");
    // An area light is made by the shell for an emitting instance, never
    // named in a scene: the suite's scene has one, a ball that emits.
    let area = cx.class == rtk_kernel::classes::AREA_LIGHT;
    let scene = if area {
        emitter_scene()
    } else {
        scene_using(Kind::Light, &cx.class, &cx.params, 0)
    };
    let w = cx.bench.scene(&scene)?;
    let light = w
        .lights
        .first()
        .ok_or_else(|| anyhow!("the scene has no light"))?;
    let env = light.is_environment();
    let mut ctx = TraceCtx::new(0, 1, 0);
    let n = cx.n(4000, 40000);
    let queries: Vec<Query> = (0..n)
        .map(|_| Query {
            p: random_point(&mut cx.rng),
            u: [cx.rng.next_f32(), cx.rng.next_f32()],
            time: cx.rng.next_f32(),
        })
        .collect();

    suite.at("finite");
    let mut t = Tallies::default();
    let mut results = Vec::with_capacity(n);
    for q in &queries {
        results.push(sample_checked(light, &mut ctx, q, env, &mut t)?);
    }
    if let Some((c, m)) = ctx.failure() {
        return Err(anyhow!("plugin `{c}` {m}"));
    }
    let nq = n as u64;
    if t.lit == 0 {
        suite.push(Check::new(
            "finite",
            false,
            format!("no sample from {n} points: the light lights nothing"),
        ));
    } else {
        suite.push(Check::held("finite", &t.bad, nq, "queries"));
    }
    kind_checks(cx, suite, (&w, light), &mut ctx, (&t, &queries), area)?;

    suite.at("deterministic");
    suite.push(deterministic(light, &mut ctx, &queries, &results)?);
    suite.at("concurrent-queries");
    suite.push(concurrent_queries(light, &queries, &results, cx.threads));
    if suite.wants(super::stream::NAME) {
        suite.at(super::stream::NAME);
        // Its own masks' stream: the other checks' draws stay as they were.
        let c = super::stream::light(light, &queries, &mut RngState::seeded(0x57EA))?;
        suite.push(c);
    }
    drop(w);

    suite.at("unknown-key-refused");
    let c = unknown_key(cx, 0);
    suite.push(c);
    super::panics::run(cx, suite, 0)?;
    Ok(())
}

/// The checks of the light's kind: an environment light's, an area
/// light's (on the emitting ball of `w`), or a delta light's; the other
/// kinds' checks reported as skipped.
fn kind_checks(
    cx: &mut Cx,
    suite: &mut Suite,
    (w, light): (&rtk_shell::World, &Light),
    ctx: &mut TraceCtx,
    (t, queries): (&Tallies, &[Query]),
    area: bool,
) -> Result<()> {
    if light.is_environment() {
        environment_checks(cx, suite, light, ctx, t);
    } else if area {
        suite.at("pdf-matches-hit");
        suite.push(pdf_matches_hit(
            w,
            light,
            ctx,
            &queries[..queries.len().min(2000)],
        )?);
        let why = "an area light (its instance's surface), not a delta or an environment light";
        for c in [
            "delta-light",
            "points-on-light",
            "at-infinity",
            "li-matches-le",
            "pdf-matches-sample",
            "pdf-integrates",
        ] {
            suite.push(Check::skip(c, why));
        }
    } else {
        suite.push(Check::held("delta-light", &t.delta, t.lit, "samples"));
        suite.at("points-on-light");
        suite.push(points_on_light(
            light,
            ctx,
            &queries[..queries.len().min(1000)],
        )?);
        let why = "a delta light (no `le`): rays cannot find it";
        for c in [
            "at-infinity",
            "li-matches-le",
            "pdf-matches-sample",
            "pdf-integrates",
        ] {
            suite.push(Check::skip(c, why));
        }
    }
    Ok(())
}

/// The scene of an area light: a ball of radius 1 at the origin whose
/// shader emits, so the shell makes the light and binds it.
fn emitter_scene() -> String {
    format!(
        "{}[shaders.lamp]\nclass = \"lambert\"\nalbedo = [0.0, 0.0, 0.0]\n\
         emission = [4.0, 3.0, 2.0]\n[objects.ball]\nclass = \"sphere\"\n\
         [objects.world]\nclass = \"list\"\nchildren = [{{ object = \"ball\", shader = \"lamp\" }}]\n",
        crate::stress::header("world")
    )
}

/// An area light's sample is a point of its surface that the ray towards
/// it finds first (from outside the ball), at the sample's distance, the
/// hit naming this light; and the light's `pdf_hit` of that hit is the
/// sample's density (the two meet in multiple importance sampling).
fn pdf_matches_hit(
    w: &rtk_shell::World,
    light: &Light,
    ctx: &mut TraceCtx,
    queries: &[Query],
) -> Result<Check> {
    let mut bad = (0u64, String::new());
    let (mut count, mut grazing) = (0u64, 0u64);
    for q in queries.iter().filter(|q| q.p.length() > 1.01) {
        let Some(s) = sample(light, ctx, q)? else {
            continue;
        };
        let ray = rtk_kernel::abi::Ray {
            t_max: s.dist * 1.001,
            time: q.time,
            ..rtk_kernel::abi::Ray::new(q.p, s.wi.v())
        };
        let mut hit = rtk_kernel::abi::Hit::new();
        if !w.root.intersect(ctx, &ray, &mut hit) {
            note(&mut bad, || {
                format!(
                    "from {:?}: the ray towards the sample hits nothing",
                    q.p.to_array()
                )
            });
            continue;
        }
        let mut g = rtk_kernel::abi::LocalGeom::EMPTY;
        w.root
            .local_geom(ctx, &ray, &hit, rtk_kernel::abi::geom_mask::ALL, &mut g);
        w.root_inst.bind(&mut g);
        let pdf = light.pdf_hit(ctx, q.p, &ray, &g).unwrap_or(0.0);
        // Near grazing the density (dist² / cos) is ill-conditioned: a
        // normal that differs in the last bits changes it by percents.
        if g.ng.v().normalize_or_zero().dot(s.wi.v()).abs() < GRAZING {
            grazing += 1;
            continue;
        }
        count += 1;
        if !close(hit.t, s.dist) || !close(pdf, s.pdf) {
            note(&mut bad, || {
                format!(
                    "from {:?}: sample at distance {} with density {}; the ray finds t {} and pdf_hit {}",
                    q.p.to_array(),
                    s.dist,
                    s.pdf,
                    hit.t,
                    pdf
                )
            });
        }
    }
    if let Some((c, m)) = ctx.failure() {
        return Err(anyhow!("plugin `{c}` {m}"));
    }
    let mut c = Check::held("pdf-matches-hit", &bad, count, "samples");
    c.detail += &format!(" ({grazing} grazing samples, |cos| < {GRAZING}, not compared)");
    Ok(c)
}

/// Below this |cos| between the light's normal and the direction a
/// sample's density is not compared.
const GRAZING: f32 = 0.05;

/// Failures (count, first) of the per-sample properties, and how many
/// queries received light.
#[derive(Default)]
struct Tallies {
    lit: u64,
    /// Not finite, not unit, or not positive.
    bad: (u64, String),
    /// A delta light's sample with a density, or one that depends on `u`.
    delta: (u64, String),
    /// An environment light's sample at a finite distance.
    inf: (u64, String),
    /// An environment light's radiance other than its `le`.
    le_bad: (u64, String),
    /// An environment light's density other than its `pdf_li`.
    pdf_bad: (u64, String),
}

/// Sample the light for `q` and tally what is wrong with the sample (and,
/// for an environment light, with `le` in a direction drawn from `q.u`).
fn sample_checked(
    light: &Light,
    ctx: &mut TraceCtx,
    q: &Query,
    env: bool,
    t: &mut Tallies,
) -> Result<Option<LightSample>> {
    let s = sample(light, ctx, q)?;
    if let Some(s) = &s {
        t.lit += 1;
        let wi = s.wi.v();
        if !(wi.is_finite()
            && (wi.length() - 1.0).abs() <= 1e-4
            && s.dist > 0.0
            && color_ok(s.li)
            && s.pdf.is_finite()
            && s.pdf > 0.0)
        {
            note(&mut t.bad, || format!("from {:?}: {s:?}", q.p.to_array()));
        }
        let pdf_li = light.pdf_li(ctx, q.p, s.wi).unwrap_or(0.0);
        if env {
            check_environment_sample(light, ctx, q, s, pdf_li, t);
        } else {
            check_delta_sample(light, ctx, q, s, pdf_li, t)?;
        }
    }
    if env {
        let d: Float3 = uniform_sphere(q.u).into();
        let le = light.le(ctx, d).unwrap_or(Color::BLACK);
        if !color_ok(le) {
            note(&mut t.bad, || {
                format!("le towards {:?} = {le:?}", d.to_array())
            });
        }
    }
    Ok(s)
}

/// An environment light's sample lies at infinity and agrees with `le`
/// and `pdf_li` in its direction.
fn check_environment_sample(
    light: &Light,
    ctx: &mut TraceCtx,
    q: &Query,
    s: &LightSample,
    pdf_li: f32,
    t: &mut Tallies,
) {
    let wi = s.wi.v();
    if s.dist != f32::INFINITY {
        note(&mut t.inf, || {
            format!("from {:?}: distance {}", q.p.to_array(), s.dist)
        });
    }
    let le = light.le(ctx, s.wi).unwrap_or(Color::BLACK);
    if !(close(le.r, s.li.r) && close(le.g, s.li.g) && close(le.b, s.li.b)) {
        note(&mut t.le_bad, || {
            format!(
                "towards {:?}: sample's li {:?}, le {le:?}",
                wi.to_array(),
                s.li
            )
        });
    }
    if !close(pdf_li, s.pdf) {
        note(&mut t.pdf_bad, || {
            format!(
                "towards {:?}: pdf_li {pdf_li}, sample's pdf {}",
                wi.to_array(),
                s.pdf
            )
        });
    }
}

/// A delta light's sample has density 1, `pdf_li` 0, and does not depend
/// on the random numbers (another `u` gives the same sample).
fn check_delta_sample(
    light: &Light,
    ctx: &mut TraceCtx,
    q: &Query,
    s: &LightSample,
    pdf_li: f32,
    t: &mut Tallies,
) -> Result<()> {
    let other = Query {
        u: [1.0 - q.u[1], 1.0 - q.u[0]],
        ..*q
    };
    let s2 = sample(light, ctx, &other)?;
    if s.pdf != 1.0 || pdf_li != 0.0 || bits(&s2) != bits(&Some(*s)) {
        note(&mut t.delta, || {
            format!(
                "from {:?}: pdf {}, pdf_li {pdf_li}, another u gives {}",
                q.p.to_array(),
                s.pdf,
                if bits(&s2) == bits(&Some(*s)) {
                    "the same sample"
                } else {
                    "another sample"
                }
            )
        });
    }
    Ok(())
}

/// The checks only an environment light has: its tallies, and
/// `pdf-integrates`; the delta-light checks are skipped.
fn environment_checks(
    cx: &mut Cx,
    suite: &mut Suite,
    light: &Light,
    ctx: &mut TraceCtx,
    t: &Tallies,
) {
    suite.push(Check::held("at-infinity", &t.inf, t.lit, "samples"));
    suite.push(Check::held("li-matches-le", &t.le_bad, t.lit, "samples"));
    suite.push(Check::held(
        "pdf-matches-sample",
        &t.pdf_bad,
        t.lit,
        "samples",
    ));
    suite.at("pdf-integrates");
    suite.push(pdf_integrates(cx, light, ctx));
    let why = "an environment light, not a delta light";
    suite.push(Check::skip("delta-light", why));
    suite.push(Check::skip("points-on-light", why));
}

/// `pdf-integrates`: ∫ pdf_li dω by uniform directions, 4π·E\[pdf\], is 1
/// from each of a few random points.
fn pdf_integrates(cx: &mut Cx, light: &Light, ctx: &mut TraceCtx) -> Check {
    let m = cx.n(20000, 200000);
    let mut worst = None;
    for k in 0..4 {
        let p: Float3 = random_point(&mut cx.rng).into();
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..m {
            let d: Float3 = uniform_sphere([cx.rng.next_f32(), cx.rng.next_f32()]).into();
            let v = light.pdf_li(ctx, p, d).unwrap_or(0.0) as f64 * 4.0 * std::f64::consts::PI;
            s1 += v;
            s2 += v * v;
        }
        let mean = s1 / m as f64;
        let se = ((s2 / m as f64 - mean * mean).max(0.0) / m as f64).sqrt();
        if (mean - 1.0).abs() > 5.0 * se + 0.02 && worst.is_none() {
            worst = Some(format!(
                "from {:?} (point {k}), ∫ pdf_li dω = {mean:.4} ± {se:.4}, not 1",
                p.to_array()
            ));
        }
    }
    match worst {
        None => Check::pass("pdf-integrates", "∫ pdf_li dω = 1 from every point tried"),
        Some(w) => Check::new("pdf-integrates", false, w),
    }
}

/// `points-on-light`: a delta light's samples at one time, from every
/// point of `queries`, all lead to one position (or one direction, for a
/// light at infinity).
fn points_on_light(light: &Light, ctx: &mut TraceCtx, queries: &[Query]) -> Result<Check> {
    let mut at = None::<(Vec3, bool)>;
    let mut off = (0u64, String::new());
    let mut count = 0;
    for q in queries {
        let q = Query { time: 0.5, ..*q };
        let Some(s) = sample(light, ctx, &q)? else {
            continue;
        };
        count += 1;
        let (here, far) = if s.dist.is_finite() {
            (q.p + s.wi.v() * s.dist, false)
        } else {
            (s.wi.v(), true)
        };
        match at {
            None => at = Some((here, far)),
            Some((first, first_far)) => {
                let tol = 1e-4 * (1.0 + q.p.length() + if far { 0.0 } else { s.dist });
                if far != first_far || (here - first).abs().max_element() > tol {
                    note(&mut off, || {
                        format!(
                            "from {:?}: {} {:?}, from the first point {:?}",
                            q.p.to_array(),
                            if far { "direction" } else { "position" },
                            here.to_array(),
                            first.to_array()
                        )
                    });
                }
            }
        }
    }
    Ok(match (&at, off.0) {
        (Some((p, far)), 0) => Check::pass(
            "points-on-light",
            format!(
                "{count} samples at time 0.5: all {} {:?}",
                if *far {
                    "along the direction"
                } else {
                    "at the position"
                },
                p.to_array()
            ),
        ),
        _ => Check::held("points-on-light", &off, count, "samples"),
    })
}

/// `deterministic`: the same queries again, in reverse order, give the
/// same samples bit for bit.
fn deterministic(
    light: &Light,
    ctx: &mut TraceCtx,
    queries: &[Query],
    results: &[Option<LightSample>],
) -> Result<Check> {
    let mut again = (0u64, String::new());
    for (q, s) in queries.iter().zip(results).rev() {
        let s2 = sample(light, ctx, q)?;
        if bits(s) != bits(&s2) {
            note(&mut again, || {
                format!("from {:?}: {s:?} then {s2:?}", q.p.to_array())
            });
        }
    }
    Ok(Check::held(
        "deterministic",
        &again,
        queries.len() as u64,
        "queries",
    ))
}

/// `concurrent-queries`: every thread at once, twice over the queries,
/// gets one thread's answers.
fn concurrent_queries(
    light: &Light,
    queries: &[Query],
    results: &[Option<LightSample>],
    threads: usize,
) -> Check {
    let differ = std::sync::atomic::AtomicU64::new(0);
    std::thread::scope(|sc| {
        for ti in 0..threads {
            let differ = &differ;
            sc.spawn(move || {
                let mut ctx = TraceCtx::new(ti as u32, threads as u32, 0);
                for _ in 0..2 {
                    for (q, s) in queries.iter().zip(results) {
                        let s2 = light.sample_li(&mut ctx, q.p, q.u, q.time);
                        if bits(s) != bits(&s2) || ctx.failed() {
                            differ.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        }
                    }
                }
            });
        }
    });
    let of = queries.len() as u64 * 2 * threads as u64;
    let differ = differ.into_inner();
    Check::new(
        "concurrent-queries",
        differ == 0,
        format!("{threads} threads: {differ} of {of} samples differ from one thread's"),
    )
}
