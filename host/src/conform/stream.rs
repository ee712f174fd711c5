//! `stream-parity`: a plugin's ray-stream entries (rtk-abi 3.1) give its
//! single-ray answers, bit for bit — objects' `intersect_batch`,
//! `occluded_batch` and `local_geom_batch` against `intersect`, `occluded`
//! and `local_geom`; lights' `sample_li_batch` against `sample_li`;
//! integrators' `li_batch` against `li` with each ray's random stream.
//!
//! Why every lane and every bit: the render loop and the aggregates call
//! the stream entries where they called the single-ray ones, and images
//! must not change. A batch path one ulp off on one lane of full batches
//! changes some pixel somewhere; only an exact comparison of every lane
//! finds it, and only batches of every shape exercise it.
//!
//! So the queries go in batches of 1, 7 and 64 (one lane, a ragged batch,
//! a full one), with active masks of every lane, random lanes, few lanes
//! and all lanes but one, objects from levels 0 and 2 (an object answers
//! at any depth of a hit stack). Inactive lanes' outputs are filled with a
//! sentinel first and must keep it; returned masks must name exactly the
//! active lanes that hit (are occluded, got a sample). The report names the
//! first lane that differs and what differed.
//!
//! Which plugins have stream entries: every plugin built against rtk-abi
//! 3.1 or later offers them — the SDK's defaults loop over the single-ray
//! entries unless the class overrides them, and the record does not tell
//! the two apart — so the check runs on all of them (cheaply, for the
//! defaults). A plugin built before 3.1 has none; the host then loops over
//! its single-ray entries itself, and the check is skipped, saying so.

use super::light::Query;
use super::Check;
use crate::render::tracer::Tracer;
use anyhow::{bail, Result};
use rtk_handles::Light;
use rtk_kernel::abi::{
    geom_mask, Color, Float3, Hit, LightSample, LocalGeom, Ray, TraceCtx, HIT_STACK_DEPTH,
};
use rtk_kernel::sdk::{batch, LiveObject};
use rtk_kernel::RngState;
use rtk_shell::World;

/// The check's name.
pub(crate) const NAME: &str = "stream-parity";

/// Batch sizes, in turn: one lane, a ragged batch, a full one.
const SIZES: [usize; 3] = [1, 7, 64];

/// Why the check is skipped for a plugin without stream entries.
const WITHOUT: &str = "the plugin has no stream entries (built before rtk-abi 3.1): \
                       the defaults loop over its single-ray entries, which the other checks cover";

/// One batch of a run: where its queries start, how many, which are asked.
#[derive(Clone, Copy)]
struct Batch {
    k: usize,
    first: usize,
    n: usize,
    active: u64,
    level: u32,
    /// The local-geometry fields asked for.
    geom: u32,
}

impl Batch {
    /// Where a lane is, for a report.
    fn at(&self, lane: usize) -> String {
        format!(
            "batch {} ({} queries from #{}, active {:#x}, level {}), lane {lane}",
            self.k, self.n, self.first, self.active, self.level
        )
    }
    fn asks(&self, lane: usize) -> bool {
        lane < self.n && (self.active >> lane) & 1 == 1
    }
    /// An output per lane: `fresh` for the lanes asked, `sentinel` (which
    /// must survive the call) for the others.
    fn outputs<T>(&self, fresh: impl Fn() -> T, sentinel: impl Fn() -> T) -> Vec<T> {
        (0..self.n)
            .map(|i| if self.asks(i) { fresh() } else { sentinel() })
            .collect()
    }
}

/// 64 random bits.
fn bits64(rng: &mut RngState) -> u64 {
    (rng.next_u32() as u64) << 32 | rng.next_u32() as u64
}

/// The batches over `len` queries: sizes 1, 7, 64 in turn, masks of every
/// lane, random lanes, few lanes and all but one in turn (4 and 3 are
/// coprime, so every size meets every kind of mask), and every other dozen
/// batches from level 2 when `levels`.
fn batches(rng: &mut RngState, len: usize, levels: bool) -> Vec<Batch> {
    let mut out = Vec::new();
    let (mut first, mut k) = (0, 0);
    while first < len {
        let n = SIZES[k % SIZES.len()].min(len - first);
        let all = batch::all(n);
        let active = match k % 4 {
            0 => all,
            1 => bits64(rng) & all,
            2 => bits64(rng) & bits64(rng) & all,
            _ => all & !(1u64 << (rng.next_u32() as usize % n)),
        };
        let level = if levels && (k / 12) % 2 == 1 { 2 } else { 0 };
        let geom = if k % 2 == 0 {
            geom_mask::ALL
        } else {
            rng.next_u32() & geom_mask::ALL
        };
        out.push(Batch {
            k,
            first,
            n,
            active,
            level,
            geom,
        });
        first += n;
        k += 1;
    }
    out
}

/// One stream entry's tally: lanes compared, lanes that differ (and the first).
struct Entry {
    name: &'static str,
    lanes: u64,
    bad: (u64, String),
}

impl Entry {
    fn new(name: &'static str) -> Entry {
        Entry {
            name,
            lanes: 0,
            bad: (0, String::new()),
        }
    }
    /// Count a lane, and its difference if any.
    fn lane(&mut self, diff: Option<String>) {
        self.lanes += 1;
        if let Some(d) = diff {
            super::note(&mut self.bad, || d);
        }
    }
}

/// The check from the entries' tallies over `batches` batches; `absent`
/// lists the stream entries the plugin lacks.
fn verdict(entries: &[Entry], batches: usize, masked: bool, absent: &[&str]) -> Check {
    let mut failed = entries.iter().filter(|e| e.bad.0 > 0);
    if let Some(e) = failed.next() {
        let mut d = format!(
            "{}: {} of {} lanes differ from the single-ray answers; first: {}",
            e.name, e.bad.0, e.lanes, e.bad.1
        );
        for o in failed {
            d += &format!("; {}: {} of {} lanes differ", o.name, o.bad.0, o.lanes);
        }
        return Check::new(NAME, false, d);
    }
    let names: Vec<&str> = entries.iter().map(|e| e.name).collect();
    let lanes: u64 = entries.iter().map(|e| e.lanes).sum();
    let mut d =
        format!(
        "{}: {batches} batches of 1, 7 and 64, {lanes} lanes: the single-ray answers bit for bit{}",
        names.join(", "),
        if masked { ", inactive lanes untouched" } else { "" }
    );
    if !absent.is_empty() {
        d += &format!(
            " ({} absent: the host loops over the single-ray entry)",
            absent.join(", ")
        );
    }
    Check::pass(NAME, d)
}

/// A plugin failure recorded in the context, as an error.
fn failed(ctx: &TraceCtx) -> Result<()> {
    if let Some((c, m)) = ctx.failure() {
        bail!("plugin `{c}` {m}");
    }
    Ok(())
}

/// An f32 as its value and its bits.
fn f(x: f32) -> String {
    format!("{x:?} ({:#010x})", x.to_bits())
}

// ---------------------------------------------------------------- objects

/// What inactive lanes' hit records hold, and must still hold after.
fn hit_sentinel() -> Hit {
    Hit {
        t: f32::from_bits(0x7fc0_5eed),
        depth: 0x5eed,
        uv: [f32::from_bits(0x7fc0_0001), f32::from_bits(0x7fc0_0002)],
        stack: [0x5eed_5eed; HIT_STACK_DEPTH],
    }
}

/// Whether a record is the sentinel still, bit for bit.
fn untouched(h: &Hit) -> bool {
    let s = hit_sentinel();
    h.t.to_bits() == s.t.to_bits()
        && h.depth == s.depth
        && h.uv.map(f32::to_bits) == s.uv.map(f32::to_bits)
        && h.stack == s.stack
}

/// How the batch's hit record differs from the single ray's: `t`, the
/// depth, the path down to the leaf, the leaf's two words.
fn hit_diff(got: &Hit, want: &Hit) -> Option<String> {
    if got.t.to_bits() != want.t.to_bits() {
        return Some(format!("t {}, intersect's {}", f(got.t), f(want.t)));
    }
    if got.depth != want.depth {
        return Some(format!("depth {}, intersect's {}", got.depth, want.depth));
    }
    let d = (want.depth as usize).min(HIT_STACK_DEPTH);
    if let Some(l) = (0..d).find(|&l| got.stack[l] != want.stack[l]) {
        return Some(format!(
            "stack[{l}] {}, intersect's {}",
            got.stack[l], want.stack[l]
        ));
    }
    (0..2).find_map(|j| {
        (got.uv[j].to_bits() != want.uv[j].to_bits())
            .then(|| format!("uv[{j}] {}, intersect's {}", f(got.uv[j]), f(want.uv[j])))
    })
}

/// Names of [`geom_words`], in order; the first 26 are f32s.
const GEOM_FIELDS: [&str; 31] = [
    "p.x", "p.y", "p.z", "p_err.x", "p_err.y", "p_err.z", "ng.x", "ng.y", "ng.z", "ns.x", "ns.y",
    "ns.z", "dpdu.x", "dpdu.y", "dpdu.z", "dpdv.x", "dpdv.y", "dpdv.z", "dndu.x", "dndu.y",
    "dndu.z", "dndv.x", "dndv.y", "dndv.z", "uv[0]", "uv[1]", "shader", "light", "instance",
    "prim", "filled",
];

/// Every field of a local geometry as bits.
fn geom_words(g: &LocalGeom) -> [u32; 31] {
    let v = [g.p, g.p_err, g.ng, g.ns, g.dpdu, g.dpdv, g.dndu, g.dndv];
    let mut w = [0u32; 31];
    for (i, x) in v.iter().enumerate() {
        w[3 * i] = x.x.to_bits();
        w[3 * i + 1] = x.y.to_bits();
        w[3 * i + 2] = x.z.to_bits();
    }
    w[24] = g.uv[0].to_bits();
    w[25] = g.uv[1].to_bits();
    w[26..].copy_from_slice(&[g.shader, g.light, g.instance, g.prim, g.filled]);
    w
}

/// A word of [`geom_words`] as its value.
fn geom_value(i: usize, w: u32) -> String {
    if i < 26 {
        f(f32::from_bits(w))
    } else {
        format!("{w:#x}")
    }
}

/// The first field in which two local geometries differ.
fn geom_diff(got: &LocalGeom, want: &LocalGeom, single: &str) -> Option<String> {
    let (a, b) = (geom_words(got), geom_words(want));
    (0..a.len()).find(|&i| a[i] != b[i]).map(|i| {
        format!(
            "{} {}, {single}'s {}",
            GEOM_FIELDS[i],
            geom_value(i, a[i]),
            geom_value(i, b[i])
        )
    })
}

/// What inactive lanes' local geometry holds, and must still hold after.
fn geom_sentinel() -> LocalGeom {
    let x = f32::from_bits(0x7fc0_5eed);
    let v = Float3::new(x, x, x);
    LocalGeom {
        p: v,
        p_err: v,
        ng: v,
        ns: v,
        dpdu: v,
        dpdv: v,
        dndu: v,
        dndv: v,
        uv: [x, x],
        shader: 0x5eed,
        light: 0x5eed,
        instance: 0x5eed,
        prim: 0x5eed,
        filled: 0x5eed,
    }
}

/// The single-ray answers for every lane of a batch.
struct Singles {
    hits: Vec<Option<Hit>>,
    occluded: Vec<bool>,
}

fn singles(obj: &LiveObject, ctx: &mut TraceCtx, rays: &[Ray], level: u32) -> Result<Singles> {
    let mut s = Singles {
        hits: Vec::with_capacity(rays.len()),
        occluded: Vec::with_capacity(rays.len()),
    };
    for r in rays {
        let mut h = Hit::new();
        let found = obj.intersect(ctx, r, &mut h, level);
        s.hits.push(found.then_some(h));
        s.occluded.push(obj.occluded(ctx, r, level));
        failed(ctx)?;
    }
    Ok(s)
}

/// A mask's bits beyond the batch: a lane there would be out of bounds.
fn beyond(b: &Batch, mask: u64, what: &str) -> Option<String> {
    let extra = mask & !batch::all(b.n);
    (extra != 0).then(|| {
        let lane = extra.trailing_zeros() as usize;
        format!(
            "{}: the returned mask sets it, beyond the batch's {} {what}",
            b.at(lane),
            b.n
        )
    })
}

/// `intersect_batch` against `intersect`, lane by lane.
fn intersect_lanes(
    obj: &LiveObject,
    ctx: &mut TraceCtx,
    b: &Batch,
    rays: &[Ray],
    s: &Singles,
    e: &mut Entry,
) -> Result<()> {
    let mut hits = b.outputs(Hit::new, hit_sentinel);
    let Some(got) = obj.intersect_batch(ctx, rays, &mut hits, b.active, b.level) else {
        return Ok(());
    };
    failed(ctx)?;
    if let Some(d) = beyond(b, got, "rays") {
        e.lane(Some(d));
    }
    for i in 0..b.n {
        let said = (got >> i) & 1 == 1;
        let diff = if !b.asks(i) {
            let written = !untouched(&hits[i]);
            (said || written).then(|| {
                format!(
                    "{}: inactive, but {}",
                    b.at(i),
                    if said {
                        "the returned mask says it hit"
                    } else {
                        "its hit record was written"
                    }
                )
            })
        } else {
            match (&s.hits[i], said) {
                (Some(w), true) => hit_diff(&hits[i], w),
                (None, false) => None,
                (Some(w), false) => {
                    Some(format!("the mask says miss, intersect hit at t {}", f(w.t)))
                }
                (None, true) => Some(format!(
                    "the mask says hit (t {}), intersect missed",
                    f(hits[i].t)
                )),
            }
            .map(|d| {
                format!(
                    "{}: {d}; ray {}",
                    b.at(i),
                    super::object::ray_text(&rays[i])
                )
            })
        };
        if b.asks(i) || diff.is_some() {
            e.lane(diff);
        }
    }
    Ok(())
}

/// `occluded_batch` against `occluded`, lane by lane.
fn occluded_lanes(
    obj: &LiveObject,
    ctx: &mut TraceCtx,
    b: &Batch,
    rays: &[Ray],
    s: &Singles,
    e: &mut Entry,
) -> Result<()> {
    let Some(got) = obj.occluded_batch(ctx, rays, b.active, b.level) else {
        return Ok(());
    };
    failed(ctx)?;
    if let Some(d) = beyond(b, got, "rays") {
        e.lane(Some(d));
    }
    for (i, ray) in rays.iter().enumerate().take(b.n) {
        let said = (got >> i) & 1 == 1;
        if !b.asks(i) {
            if said {
                e.lane(Some(format!(
                    "{}: inactive, but the returned mask says occluded",
                    b.at(i)
                )));
            }
            continue;
        }
        e.lane((said != s.occluded[i]).then(|| {
            format!(
                "{}: the mask says {}, occluded says {}; ray {}",
                b.at(i),
                said,
                s.occluded[i],
                super::object::ray_text(ray)
            )
        }));
    }
    Ok(())
}

/// `local_geom_batch` against `local_geom`, for the active lanes that hit
/// (their single-ray hit records given to both), fields per the batch's mask.
fn geom_lanes(
    obj: &LiveObject,
    ctx: &mut TraceCtx,
    b: &Batch,
    rays: &[Ray],
    s: &Singles,
    e: &mut Entry,
) -> Result<()> {
    let hits: Vec<Hit> = s.hits.iter().map(|h| h.unwrap_or_else(Hit::new)).collect();
    let active = (0..b.n)
        .filter(|&i| b.asks(i) && s.hits[i].is_some())
        .fold(0u64, |m, i| m | 1 << i);
    let mut want = vec![LocalGeom::EMPTY; b.n];
    for i in batch::lanes(active, b.n) {
        obj.local_geom(ctx, &rays[i], &hits[i], b.level, b.geom, &mut want[i]);
        failed(ctx)?;
    }
    let g = Batch { active, ..*b };
    let mut out = g.outputs(|| LocalGeom::EMPTY, geom_sentinel);
    if obj
        .local_geom_batch(ctx, rays, &hits, active, b.level, b.geom, &mut out)
        .is_none()
    {
        return Ok(());
    }
    failed(ctx)?;
    for i in 0..b.n {
        let diff = if (active >> i) & 1 == 1 {
            geom_diff(&out[i], &want[i], "local_geom")
        } else {
            geom_diff(&out[i], &geom_sentinel(), "the sentinel")
                .map(|d| format!("inactive, but written: {d}"))
        };
        if (active >> i) & 1 == 1 || diff.is_some() {
            e.lane(diff.map(|d| format!("{} (fields {:#b}): {d}", g.at(i), b.geom)));
        }
    }
    Ok(())
}

/// `stream-parity` for an object plugin of class `class`: `w`'s root is the
/// plugin, asked for `rays` in batches, against its own single-ray answers.
pub(crate) fn object(w: &World, class: &str, rays: &[Ray], rng: &mut RngState) -> Result<Check> {
    let mut c = object_at_root(w, rays, rng)?;
    let root = w.root.class_name();
    if root != class {
        c.detail += &format!(" (asked of `{root}`, the root the shell made over `{class}`)");
    }
    Ok(c)
}

fn object_at_root(w: &World, rays: &[Ray], rng: &mut RngState) -> Result<Check> {
    let obj: &LiveObject = &w.root;
    let class = obj.raw_class();
    let present = [
        class.intersect_batch().is_some(),
        class.occluded_batch().is_some(),
        class.local_geom_batch().is_some(),
    ];
    let mut es = [
        Entry::new("intersect_batch"),
        Entry::new("occluded_batch"),
        Entry::new("local_geom_batch"),
    ];
    if present.iter().all(|p| !p) {
        return Ok(Check::skip(NAME, WITHOUT));
    }
    let bs = batches(rng, rays.len(), true);
    let mut ctx = TraceCtx::new(0, 1, 0);
    for b in &bs {
        let rs = &rays[b.first..b.first + b.n];
        let s = singles(obj, &mut ctx, rs, b.level)?;
        intersect_lanes(obj, &mut ctx, b, rs, &s, &mut es[0])?;
        occluded_lanes(obj, &mut ctx, b, rs, &s, &mut es[1])?;
        geom_lanes(obj, &mut ctx, b, rs, &s, &mut es[2])?;
    }
    Ok(split_verdict(es, present, bs.len()))
}

/// The verdict over the entries present, naming those absent.
fn split_verdict<const N: usize>(es: [Entry; N], present: [bool; N], batches: usize) -> Check {
    let absent: Vec<&str> = es
        .iter()
        .zip(present)
        .filter(|(_, p)| !p)
        .map(|(e, _)| e.name)
        .collect();
    let kept: Vec<Entry> = es
        .into_iter()
        .zip(present)
        .filter(|(_, p)| *p)
        .map(|(e, _)| e)
        .collect();
    verdict(&kept, batches, true, &absent)
}

// ---------------------------------------------------------------- lights

/// What inactive lanes' light samples hold, and must still hold after.
fn sample_sentinel() -> LightSample {
    let x = f32::from_bits(0x7fc0_5eed);
    LightSample {
        wi: Float3::new(x, x, x),
        dist: x,
        li: Color {
            r: x,
            g: x,
            b: x,
            w: x,
        },
        pdf: x,
    }
}

/// Names of [`sample_words`], in order.
const SAMPLE_FIELDS: [&str; 9] = [
    "wi.x", "wi.y", "wi.z", "dist", "li.r", "li.g", "li.b", "li.w", "pdf",
];

fn sample_words(s: &LightSample) -> [f32; 9] {
    [
        s.wi.x, s.wi.y, s.wi.z, s.dist, s.li.r, s.li.g, s.li.b, s.li.w, s.pdf,
    ]
}

/// The first field in which two light samples differ.
fn sample_diff(got: &LightSample, want: &LightSample, single: &str) -> Option<String> {
    let (a, b) = (sample_words(got), sample_words(want));
    (0..a.len())
        .find(|&i| a[i].to_bits() != b[i].to_bits())
        .map(|i| format!("{} {}, {single}'s {}", SAMPLE_FIELDS[i], f(a[i]), f(b[i])))
}

/// One light batch: `sample_li_batch` against `sample_li`, lane by lane.
fn light_lanes(
    l: &Light,
    ctx: &mut TraceCtx,
    b: &Batch,
    qs: &[Query],
    e: &mut Entry,
) -> Result<()> {
    let mut want = Vec::with_capacity(b.n);
    for q in qs {
        want.push(l.sample_li(ctx, q.p, q.u, q.time));
        failed(ctx)?;
    }
    let p: Vec<Float3> = qs.iter().map(|q| q.p.into()).collect();
    let u: Vec<[f32; 2]> = qs.iter().map(|q| q.u).collect();
    let time: Vec<f32> = qs.iter().map(|q| q.time).collect();
    let mut out = b.outputs(LightSample::default, sample_sentinel);
    let Some(got) = l.sample_li_batch(ctx, &p, &u, &time, b.active, &mut out) else {
        return Ok(());
    };
    failed(ctx)?;
    if let Some(d) = beyond(b, got, "points") {
        e.lane(Some(d));
    }
    for i in 0..b.n {
        let said = (got >> i) & 1 == 1;
        let diff = if !b.asks(i) {
            sample_diff(&out[i], &sample_sentinel(), "the sentinel")
                .map(|d| format!("inactive, but written: {d}"))
                .or_else(|| said.then(|| "inactive, but the mask says sampled".into()))
        } else {
            match (&want[i], said) {
                (Some(w), true) => sample_diff(&out[i], w, "sample_li"),
                (None, false) => None,
                (Some(_), false) => Some("the mask says no sample, sample_li gave one".into()),
                (None, true) => Some("the mask says sampled, sample_li gave none".into()),
            }
            .map(|d| {
                format!(
                    "{d}; from {:?}, u {:?}, time {:?}",
                    qs[i].p.to_array(),
                    qs[i].u,
                    qs[i].time
                )
            })
        };
        if b.asks(i) || diff.is_some() {
            e.lane(diff.map(|d| format!("{}: {d}", b.at(i))));
        }
    }
    Ok(())
}

/// `stream-parity` for a light: `sample_li_batch` over `queries` in
/// batches, against `sample_li`.
pub(crate) fn light(l: &Light, queries: &[Query], rng: &mut RngState) -> Result<Check> {
    if l.raw_class().sample_li_batch().is_none() {
        return Ok(Check::skip(NAME, WITHOUT));
    }
    let mut e = Entry::new("sample_li_batch");
    let bs = batches(rng, queries.len(), false);
    let mut ctx = TraceCtx::new(0, 1, 0);
    for b in &bs {
        light_lanes(l, &mut ctx, b, &queries[b.first..b.first + b.n], &mut e)?;
    }
    Ok(verdict(&[e], bs.len(), true, &[]))
}

// ---------------------------------------------------------------- integrators

/// One integrator batch: `li_batch` against `li`, each ray `i` with the
/// stream `(seed, first + i)`: the same colour, and the stream left where
/// `li` leaves it.
fn li_lanes(
    t: &Tracer,
    ctx: &mut TraceCtx,
    b: &Batch,
    rays: &[Ray],
    seed: u64,
    e: &mut Entry,
) -> Result<()> {
    let stream = |i: usize| RngState::for_sample(seed, (b.first + i) as u64, 0);
    let mut want = Vec::with_capacity(b.n);
    for (i, r) in rays.iter().enumerate() {
        ctx.rng = stream(i);
        let c = t.camera_li(ctx, r);
        failed(ctx)?;
        want.push((c, ctx.rng));
    }
    let mut rngs: Vec<RngState> = (0..b.n).map(stream).collect();
    let x = f32::from_bits(0x7fc0_5eed);
    let mut out = vec![
        Color {
            r: x,
            g: x,
            b: x,
            w: x
        };
        b.n
    ];
    t.camera_li_batch(ctx, rays, &mut rngs, &mut out);
    failed(ctx)?;
    for i in 0..b.n {
        let (c, rng) = &want[i];
        let four = |c: &Color| [c.r, c.g, c.b, c.w];
        let (got, exp) = (four(&out[i]), four(c));
        let diff = (0..4)
            .find(|&j| got[j].to_bits() != exp[j].to_bits())
            .map(|j| format!("colour[{j}] {}, li's {}", f(got[j]), f(exp[j])))
            .or_else(|| {
                (rngs[i] != *rng).then(|| {
                    format!(
                        "the random stream is left at {:#x}, li leaves it at {:#x}",
                        rngs[i].state, rng.state
                    )
                })
            });
        e.lane(diff.map(|d| {
            format!(
                "{}: {d}; ray o {:?} d {:?}",
                b.at(i),
                rays[i].origin.to_array(),
                rays[i].dir.to_array()
            )
        }));
    }
    Ok(())
}

/// `stream-parity` for an integrator: `li_batch` over `rays` in batches
/// (every ray of a batch is asked: the entry has no mask), against `li`.
pub(crate) fn integrator(t: &Tracer, rays: &[Ray], seed: u64) -> Result<Check> {
    if t.world().integrator.raw_class().li_batch().is_none() {
        return Ok(Check::skip(NAME, WITHOUT));
    }
    let mut e = Entry::new("li_batch");
    let bs: Vec<Batch> = batches(&mut RngState::seeded(seed), rays.len(), false)
        .into_iter()
        .map(|b| Batch {
            active: batch::all(b.n),
            ..b
        })
        .collect();
    let mut ctx = TraceCtx::new(0, 1, 0);
    for b in &bs {
        li_lanes(t, &mut ctx, b, &rays[b.first..b.first + b.n], seed, &mut e)?;
    }
    Ok(verdict(&[e], bs.len(), false, &[]))
}
