//! `rtk conform` for object plugins: primitives, aggregates, and classes
//! with a fixed number of children (`motion`, `transform`: one; `csg`: two).
//!
//! Randomized scenes of spheres and small meshes (and duplicated children,
//! for ties) are traced under the plugin and under an oracle — `list`, or
//! the class `--oracle` names, over the same children — with random and
//! adversarial rays; then bounds, nesting, concurrency and parameter
//! refusal. A plugin with a fixed number of children gets children made of
//! disjoint closed objects (what `csg` needs), one `list` of them per child;
//! it has no oracle unless one is named, and is then checked for what holds
//! of any object: occlusion agrees with the nearest hit, the nearest hit is
//! the nearest (nothing is found before it), hits lie in the bounds, nesting
//! either way changes nothing, threads agree.

use crate::conform::{
    brief, note, readme_examples, scene_using, unknown_key, Check, Cx, Kind, Params, Suite, Usage,
};
use crate::stress::{box_mesh, header, uv_sphere, vec3f, Bench, Probe};
use anyhow::{bail, Result};
use rtk_kernel::abi::{geom_mask, Hit, Ray, TraceCtx, SLAB_NORMALS};
use rtk_kernel::glam::{DVec3, Vec3};
use rtk_kernel::RngState;
use rtk_shell::World;

/// How many children the plugin takes.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Shape {
    /// None.
    Primitive,
    /// Any number.
    Aggregate,
    /// Exactly this many.
    Fixed(usize),
}

impl Shape {
    pub fn is_aggregate(self) -> bool {
        self == Shape::Aggregate
    }
    /// Children a scene gives the plugin to be valid.
    pub fn count(self) -> usize {
        match self {
            Shape::Primitive => 0,
            Shape::Aggregate => 1,
            Shape::Fixed(n) => n,
        }
    }
}

/// A random scene: its object definitions and the root's children (TOML
/// instance expressions), spheres and small meshes, some listed twice.
/// With `disjoint`, every object lies in its own cell of a grid, so no two
/// overlap (each is closed, with outward normals).
struct SceneDefs {
    defs: String,
    children: Vec<String>,
}

fn random_scene(
    b: &Bench,
    rng: &mut RngState,
    k: usize,
    n: usize,
    disjoint: bool,
) -> Result<SceneDefs> {
    let mut defs = String::new();
    let mut children = Vec::new();
    // Disjoint: cells of 2.5 on a 4x4x4 grid, centres jittered by 0.1, reach
    // at most 1.09 (the box mesh's half-diagonal at r = 0.9) < 1.25.
    let mut cells: Vec<usize> = (0..64).collect();
    for i in 0..n {
        let (c, r) = if disjoint {
            let j = (rng.next_u32() as usize) % cells.len();
            let cell = cells.swap_remove(j);
            let mut at = |q: usize| (q as f64 - 1.5) * 2.5 + (rng.next_f64() - 0.5) * 0.2;
            let c = DVec3::new(at(cell % 4), at(cell / 4 % 4), at(cell / 16));
            (c, 0.3 + rng.next_f64() * 0.6)
        } else {
            let c = DVec3::new(
                rng.next_f64() * 8.0 - 4.0,
                rng.next_f64() * 8.0 - 4.0,
                rng.next_f64() * 8.0 - 4.0,
            );
            (c, 0.2 + rng.next_f64() * 1.2)
        };
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
        crate::conform::toml_str(file)
    )
}

/// An object definition of `class` with `params` over `children`.
pub(crate) fn def(name: &str, class: &str, params: &Params, children: &[String]) -> String {
    let mut s = format!("[objects.{name}]\nclass = \"{class}\"\n{}", params.lines());
    if !children.is_empty() {
        s += &format!("children = [{}]\n", children.join(", "));
    }
    s
}

/// A scene rooted at `class` (with `params`) over `children`.
pub(crate) fn world(defs: &str, class: &str, params: &Params, children: &[String]) -> String {
    format!(
        "{}{defs}{}",
        header("world"),
        def("world", class, params, children)
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
            let leaf = |h: &Hit| h.stack[(h.depth as usize).saturating_sub(1)];
            a.t.to_bits() == b.t.to_bits() && a.stack[0] == b.stack[0] && leaf(a) == leaf(b)
        }
        _ => false,
    }
}

fn show(h: &Option<Hit>) -> String {
    match h {
        None => "miss".into(),
        Some(h) => {
            let path: Vec<String> = (0..h.depth as usize)
                .map(|l| format!("({})", h.stack[l]))
                .collect();
            format!("t {:?} {}", h.t, path.join(""))
        }
    }
}

pub(crate) fn ray_text(r: &Ray) -> String {
    format!(
        "o {:?} d {:?} time {:?}",
        r.origin.to_array(),
        r.dir.to_array(),
        r.time
    )
}

/// Tallies of one comparison (against the oracle, and of the plugin with itself).
#[derive(Default)]
struct Tally {
    nearest: (u64, String),
    ties: (u64, String),
    anyhit: (u64, String),
    bounds: (u64, String),
    volumes: (u64, String),
    interval: (u64, String),
    geom: (u64, String),
    /// Hits found again, a few ulps nearer, with `t_max` at them.
    rerounded: u64,
    rays: u64,
}

/// How much nearer a hit may be found again when the ray's `t_max` is set
/// to it, and still count as the same hit: this many f32 epsilons of the
/// scale (the larger of t, the plugin's extent and the ray's origin), the
/// rounding noise of a root computed from coordinates of that size.
const REROUND_EPSILONS: f32 = 32.0;

impl Tally {
    /// Disagreements with the oracle, of any kind (the nesting checks).
    fn merged(&self) -> (u64, String) {
        [&self.nearest, &self.ties, &self.anyhit]
            .iter()
            .fold((0, String::new()), |acc, s| {
                if acc.0 == 0 {
                    (s.0, s.1.clone())
                } else {
                    (acc.0 + s.0, acc.1)
                }
            })
    }
}

/// Trace `rays` under `test` and, if there is one, the oracle: nearest hits
/// and occlusion against the oracle's; and of the plugin alone, that
/// `occluded` agrees with `intersect`, that its hits lie inside its interval
/// and its bounds, and that nothing is found before its nearest hit (the
/// ray again with `t_max` at the hit).
fn compare(test: &World, oracle: Option<&World>, rays: &[Ray], t: &mut Tally) -> Result<()> {
    let mut pt = Probe::new(test);
    let mut po = oracle.map(Probe::new);
    let v = Volumes::of(test)?;
    for r in rays {
        t.rays += 1;
        let ht = pt.nearest(r)?;
        let ot = pt.occluded(r)?;
        if ot != ht.is_some() {
            note(&mut t.anyhit, || {
                format!(
                    "{}: occluded {ot}, but intersect {}",
                    ray_text(r),
                    show(&ht)
                )
            });
        }
        if let Some(h) = &ht {
            v.check_in_bounds(r, h, "the plugin's", t);
            v.check_in_volumes(test, r, h, t);
            check_geom(&mut pt, r, h, v.extent, t)?;
            check_nothing_before(&mut pt, r, h, v.extent, t)?;
        }
        if let Some(po) = po.as_mut() {
            let ho = po.nearest(r)?;
            if !same(&ht, &ho) {
                let tie =
                    matches!((&ht, &ho), (Some(a), Some(b)) if a.t.to_bits() == b.t.to_bits());
                let slot = if tie { &mut t.ties } else { &mut t.nearest };
                note(slot, || {
                    format!("{}: plugin {} oracle {}", ray_text(r), show(&ht), show(&ho))
                });
            }
            if let Some(h) = &ho {
                v.check_in_bounds(r, h, "the oracle's", t);
            }
            let oo = po.occluded(r)?;
            if ot != oo {
                note(&mut t.anyhit, || {
                    format!("{}: plugin occluded {ot}, oracle {oo}", ray_text(r))
                });
            }
        }
    }
    Ok(())
}

/// What the plugin says holds all of it: its box, and the sphere and slabs
/// `inq_bounds` answers (or the kernel derives from the hull points or box
/// when the plugin offers none); hits may stray by `slack`.
struct Volumes {
    bmin: Vec3,
    bmax: Vec3,
    /// The box's largest side.
    extent: f32,
    slack: f32,
    sphere: rtk_kernel::abi::BoundSphere,
    slabs: rtk_kernel::abi::SlabBounds,
}

impl Volumes {
    fn of(test: &World) -> Result<Volumes> {
        let b = test.bounds;
        let (bmin, bmax) = (b.min.v(), b.max.v());
        let extent = (bmax - bmin).max_element();
        Ok(Volumes {
            bmin,
            bmax,
            extent,
            slack: extent.max(1.0) * 1e-4,
            sphere: test.root.bound_sphere(0.0, 1.0)?,
            slabs: test.root.slabs(0.0, 1.0)?,
        })
    }

    /// `whose` hit `h` lies in the plugin's box.
    fn check_in_bounds(&self, r: &Ray, h: &Hit, whose: &str, t: &mut Tally) {
        let (bmin, bmax, slack) = (self.bmin, self.bmax, self.slack);
        let p = r.origin.v() + r.dir.v() * h.t;
        let inside =
            (p.cmpge(bmin - Vec3::splat(slack)) & p.cmple(bmax + Vec3::splat(slack))).all();
        if !inside {
            note(&mut t.bounds, || {
                format!(
                    "{whose} hit point {:?} outside the plugin's bounds {:?}..{:?}",
                    p.to_array(),
                    bmin.to_array(),
                    bmax.to_array()
                )
            });
        }
    }

    /// The plugin's hit `h` lies in its sphere and slabs, with the box
    /// check's slack.
    fn check_in_volumes(&self, test: &World, r: &Ray, h: &Hit, t: &mut Tally) {
        let slack = self.slack;
        let p = (r.origin.v() + r.dir.v() * h.t).as_dvec3();
        let c = self.sphere.center.v().as_dvec3();
        let in_sphere = p.distance(c) <= self.sphere.radius as f64 + slack as f64;
        let in_slabs = SLAB_NORMALS.iter().enumerate().all(|(k, n)| {
            let n = Vec3::from(*n).as_dvec3();
            let (v, pad) = (n.dot(p), slack as f64 * n.abs().element_sum());
            self.slabs.lo[k] as f64 - pad <= v && v <= self.slabs.hi[k] as f64 + pad
        });
        if !(in_sphere && in_slabs) {
            note(&mut t.volumes, || {
                format!(
                    "{}: hit point {:?} outside the plugin's {} (inq_bounds{})",
                    ray_text(r),
                    p.to_array(),
                    if in_sphere { "slabs" } else { "sphere" },
                    if test.root.offers_volumes() {
                        ""
                    } else {
                        ", derived from its box"
                    }
                )
            });
        }
    }
}

/// The hit's local geometry: position, geometric and shading normal
/// filled, the position at the hit, the normals unit.
fn check_geom(pt: &mut Probe, r: &Ray, h: &Hit, extent: f32, t: &mut Tally) -> Result<()> {
    let g = pt.geom(r, h)?;
    let at = r.origin.v() + r.dir.v() * h.t;
    let scale = at.abs().max_element().max(extent).max(1.0);
    let need = geom_mask::POSITION | geom_mask::GEOMETRIC_NORMAL | geom_mask::SHADING_NORMAL;
    let unit = |n: Vec3| n.is_finite() && (n.length() - 1.0).abs() <= 1e-3;
    let off = (g.p.v() - at).abs().max_element();
    if g.filled & need != need || !(off <= 1e-4 * scale) || !unit(g.ng.v()) || !unit(g.ns.v()) {
        note(&mut t.geom, || {
            format!(
                "{}: hit at {:?} (t {:?}); local_geom filled {:#b}, p {:?}, ng {:?}, ns {:?}",
                ray_text(r),
                at.to_array(),
                h.t,
                g.filled,
                g.p.to_array(),
                g.ng.to_array(),
                g.ns.to_array()
            )
        });
    }
    Ok(())
}

/// The nearest hit `h` lies in the ray's interval, and the ray again with
/// `t_max` at it finds nothing (but the same primitive rounded nearer).
fn check_nothing_before(
    pt: &mut Probe,
    r: &Ray,
    h: &Hit,
    extent: f32,
    t: &mut Tally,
) -> Result<()> {
    if !(h.t > r.t_min && h.t < r.t_max && h.t.is_finite()) {
        note(&mut t.interval, || {
            format!(
                "{}: a hit at t {:?}, outside the ray's interval",
                ray_text(r),
                h.t
            )
        });
    }
    let short = Ray { t_max: h.t, ..*r };
    let before = pt.nearest(&short)?;
    let occ = pt.occluded(&short)?;
    // The same primitive, a few ulps nearer: its root was rounded
    // otherwise for the narrower interval (a search bracketed by
    // t_max), not a nearer surface missed. (The root's child may
    // differ: a duplicate child then answers first.)
    let leaf = |h: &Hit| h.stack[(h.depth as usize).saturating_sub(1)];
    let scale = h.t.max(extent).max(r.origin.v().abs().max_element());
    let rerounded = before.as_ref().is_some_and(|b| {
        leaf(b) == leaf(h) && h.t - b.t <= REROUND_EPSILONS * f32::EPSILON * scale
    });
    if rerounded {
        t.rerounded += 1;
    } else if before.is_some() || occ {
        let ht = Some(*h);
        note(&mut t.interval, || {
            format!(
                "{}: nearest hit {}, but with t_max = that t: {} (occluded {occ})",
                ray_text(r),
                show(&ht),
                show(&before)
            )
        });
    }
    Ok(())
}

/// Trace `rays` from `threads` threads at once (each its own context),
/// twice over, against the single-thread answers: (differing, answers).
fn concurrent(w: &World, rays: &[Ray], threads: usize) -> Result<(u64, u64)> {
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
    Ok((bad.into_inner(), rays.len() as u64 * 2 * threads as u64))
}

fn interval_check(t: &Tally) -> Check {
    let mut c = Check::tally("interval-respected", &t.interval, t.rays, "rays");
    if t.rerounded > 0 {
        c.detail += &format!(
            " ({} found their hit again nearer by rounding noise (under {REROUND_EPSILONS} ε of the scale) with t_max at it: the root depends on t_max)",
            t.rerounded
        );
    }
    c
}

fn concurrency_check(bad: u64, of: u64, threads: usize) -> Check {
    Check::new(
        "concurrent-queries",
        bad == 0,
        format!("{threads} threads: {bad} of {of} answers differ from one thread's"),
    )
}

/// `--children N|any`.
pub(crate) fn parse_children(c: &str) -> Result<Shape> {
    Ok(match c {
        "any" => Shape::Aggregate,
        "0" => Shape::Primitive,
        n => match n.parse::<usize>() {
            Ok(n) if (1..=16).contains(&n) => Shape::Fixed(n),
            _ => bail!("--children {n}: expected `any` or a number from 0 to 16"),
        },
    })
}

/// Whether the plugin, created with `params`, builds with `n` sphere children.
fn builds(cx: &mut Cx, params: &Params, n: usize) -> Option<String> {
    let scene = scene_using(Kind::Object, &cx.class, params, n);
    cx.bench.build_error(&scene)
}

/// The number of children, from `--children` or by trying 0 to 3: `Err`
/// with the refusals when the plugin builds with none of them.
fn shape_with(cx: &mut Cx, params: &Params) -> Result<(Shape, String), String> {
    if let Some(shape) = cx.children {
        return match builds(cx, params, shape.count()) {
            None => Ok((shape, "as --children says".into())),
            Some(e) => Err(e),
        };
    }
    let errs: Vec<Option<String>> = (0..=3).map(|n| builds(cx, params, n)).collect();
    let ok = |n: usize| errs[n].is_none();
    let refusal = |n: usize| errs[n].as_deref().map(brief).unwrap_or_default();
    if ok(1) && ok(2) && ok(3) {
        Ok((
            Shape::Aggregate,
            "any number: checked as an aggregate".into(),
        ))
    } else if let Some(n) = (1..=3).find(|&n| ok(n)) {
        let other = if n == 1 { 2 } else { 1 };
        Ok((
            Shape::Fixed(n),
            format!("exactly {n} (with {other}: {})", refusal(other)),
        ))
    } else if ok(0) {
        Ok((Shape::Primitive, "none: checked as a primitive".to_string()))
    } else {
        Err(errs[0].clone().unwrap_or_default())
    }
}

/// The shape, trying the README's examples when the plugin refuses to be
/// made without parameters (and none were given). Sets `cx.params`.
fn shape(cx: &mut Cx, suite: &mut Suite) -> Result<Shape> {
    suite.at("children");
    let given = cx.args.params.is_some();
    let first = match shape_with(cx, &cx.params.clone()) {
        Ok((s, why)) => {
            suite.push(Check::pass("children", why));
            return Ok(s);
        }
        Err(e) => e,
    };
    if !given {
        for mut ex in readme_examples(&cx.doc, &cx.class) {
            if ex.resolve_files(std::path::Path::new("")).is_err() {
                continue;
            }
            if let Ok((s, why)) = shape_with(cx, &ex) {
                suite.push(Check::pass(
                    "params",
                    format!(
                        "none refused ({}); using the README's example: {}",
                        brief(&first),
                        ex.shown()
                    ),
                ));
                suite.push(Check::pass("children", why));
                cx.params = ex;
                return Ok(s);
            }
        }
        bail!("{first} (nor do the README's examples build; give --params)");
    }
    bail!("{first}")
}

/// The checks for object plugin `cx.class`; returns its shape.
pub(crate) fn checks(cx: &mut Cx, suite: &mut Suite) -> Result<Shape> {
    let shape = shape(cx, suite)?;
    let oracle_params = cx.oracle_params.clone();
    let oracle: Option<(String, Params)> = match (&cx.args.oracle, shape) {
        (Some(_), Shape::Primitive) => {
            return Err(Usage(format!(
                "--oracle: `{}` takes no children: a primitive is checked under bvh against list, with no oracle of its own",
                cx.class
            ))
            .into())
        }
        (Some(o), _) => Some((o.clone(), oracle_params)),
        (None, Shape::Aggregate) => Some(("list".into(), Params::default())),
        (None, _) => None,
    };
    let (scenes, nobj, nrays) = (cx.n(4, 20), cx.n(12, 30), cx.n(600, 5000));
    match shape {
        Shape::Aggregate | Shape::Fixed(_) => {
            with_children(cx, suite, shape, oracle.as_ref(), scenes, nobj, nrays)?
        }
        Shape::Primitive => primitive(cx, suite, scenes * nrays)?,
    }
    if suite.wants(super::stream::NAME) {
        suite.at(super::stream::NAME);
        let c = stream_parity(cx, shape)?;
        suite.push(c);
    }
    suite.at("interior-parity");
    let points = cx.n(2000, 20000);
    let c = super::interior::check(cx, shape, points)?;
    suite.push(c);
    suite.at("unknown-key-refused");
    let c = unknown_key(cx, shape.count());
    suite.push(c);
    super::panics::run(cx, suite, shape.count())?;
    Ok(shape)
}

/// The scratch files' index of the stream check's scene (the others are 0..scenes).
const STREAM_SCENE: usize = 1000;

/// `stream-parity` on a world whose root is the plugin itself (so its own
/// entries are asked, not an aggregate's over it): alone (a primitive) or
/// over a random scene's children, with the suite's random rays. It draws
/// from a stream of its own, so the checks after it see what they saw
/// before it existed.
fn stream_parity(cx: &mut Cx, shape: Shape) -> Result<Check> {
    let saved = std::mem::replace(&mut cx.rng, RngState::seeded(0x57EA));
    let nrays = cx.n(2000, 20000);
    let res = stream_world(cx, shape).and_then(|w| {
        let rs = rays(&mut cx.rng, nrays, &w);
        super::stream::object(&w, &cx.class, &rs, &mut cx.rng)
    });
    cx.rng = saved;
    res
}

/// The world of [`stream_parity`]. A primitive set at the root is wrapped
/// in its `accel` aggregate by the shell, whose entries would be asked
/// instead: it is built again with `accel = "none"`.
fn stream_world(cx: &mut Cx, shape: Shape) -> Result<World> {
    let scene = |params: &Params, cx: &mut Cx| -> Result<String> {
        Ok(match shape {
            Shape::Primitive => format!("{}{}", header("p"), def("p", &cx.class, params, &[])),
            _ => {
                let c = children(cx, shape, STREAM_SCENE, cx.n(12, 30))?;
                world(&c.defs, &cx.class, params, &c.kids)
            }
        })
    };
    let params = cx.params.clone();
    let text = scene(&params, cx)?;
    let w = cx.bench.scene(&text)?;
    if w.root.class_name() == cx.class || shape != Shape::Primitive {
        return Ok(w);
    }
    let bare = params.with("accel", toml::Value::String("none".into()));
    let text = scene(&bare, cx)?;
    cx.bench.scene(&text)
}

/// A primitive: under bvh as under list, its own consistency, bounds,
/// concurrency.
fn primitive(cx: &mut Cx, suite: &mut Suite, nrays: usize) -> Result<()> {
    suite.push(Check::skip(
        "nearest-hit",
        "a primitive has no oracle of its own: it is compared under bvh against list (nested-inside-bvh)",
    ));
    suite.at("nested-inside-bvh");
    let defs = def("p", &cx.class, &cx.params, &[]);
    let kids = ["\"p\"".to_string(), "\"p\"".to_string()];
    let none = Params::default();
    let oracle = cx.bench.scene(&world(&defs, "list", &none, &kids))?;
    let test = cx.bench.scene(&world(&defs, "bvh", &none, &kids))?;
    let rs = rays(&mut cx.rng, nrays, &oracle);
    let mut t = Tally::default();
    compare(&test, Some(&oracle), &rs, &mut t)?;
    suite.push(Check::tally(
        "nested-inside-bvh",
        &t.nearest,
        t.rays,
        "rays",
    ));
    suite.push(Check::tally("ties-lowest-index", &t.ties, t.rays, "rays"));
    suite.push(Check::tally("any-hit", &t.anyhit, t.rays, "rays"));
    suite.push(Check::tally(
        "bounds-contain-hits",
        &t.bounds,
        t.rays,
        "rays",
    ));
    suite.push(Check::tally(
        "volumes-contain-hits",
        &t.volumes,
        t.rays,
        "rays",
    ));
    suite.push(interval_check(&t));
    suite.push(Check::held("local-geom", &t.geom, t.rays, "rays"));
    suite.push(Check::skip(
        "bvh-nested-inside",
        "a primitive takes no children",
    ));
    suite.at("concurrent-queries");
    let (bad, of) = concurrent(&test, &rs, cx.threads)?;
    suite.push(concurrency_check(bad, of, cx.threads));
    Ok(())
}

/// An aggregate (any number of children) or a class with `n` children.
fn with_children(
    cx: &mut Cx,
    suite: &mut Suite,
    shape: Shape,
    oracle: Option<&(String, Params)>,
    scenes: usize,
    nobj: usize,
    nrays: usize,
) -> Result<()> {
    let class = cx.class.clone();
    let params = cx.params.clone();
    let mut all = ChildTallies::default();
    suite.at("nearest-hit");
    for k in 0..scenes {
        let c = children(cx, shape, k, nobj)?;
        let test = cx.bench.scene(&world(&c.defs, &class, &params, &c.kids))?;
        let oracle_world = match oracle {
            Some((o, op)) => Some(cx.bench.scene(&world(&c.defs, o, op, &c.kids))?),
            None => None,
        };
        let rs = rays(&mut cx.rng, nrays, oracle_world.as_ref().unwrap_or(&test));
        compare(&test, oracle_world.as_ref(), &rs, &mut all.t)?;
        let scene = SceneUnderTest { c, test, rs };
        compare_nested(cx, suite, shape, oracle, &scene, &mut all)?;
        // Every scene: a race shows only when threads happen to
        // interleave, which a loaded machine makes rarer.
        suite.at("concurrent-queries");
        let (bad, of) = concurrent(&scene.test, &scene.rs, cx.threads)?;
        all.conc_bad += bad;
        all.conc_of += of;
        suite.at("nearest-hit");
    }
    push_children_checks(suite, shape, oracle, &all, cx.threads);
    Ok(())
}

/// The tallies over every scene of [`with_children`].
#[derive(Default)]
struct ChildTallies {
    /// The plugin at the root.
    t: Tally,
    /// The plugin inside a bvh.
    nest_in: Tally,
    /// Bvhs inside the plugin.
    nest_out: Tally,
    conc_bad: u64,
    conc_of: u64,
}

/// The definitions of a random scene and the children the plugin gets:
/// `kids` (lists, or the scene's objects) and `bvh_kids` (the same under
/// bvhs).
struct Children {
    defs: String,
    kids: Vec<String>,
    bvh_kids: Vec<String>,
}

/// A random scene's children for `shape`: for a fixed number `n`, each
/// child a list (and a bvh) of disjoint closed objects; for an aggregate,
/// the scene's objects, and for the bvh nesting a bvh of them beside the
/// first.
fn children(cx: &mut Cx, shape: Shape, k: usize, nobj: usize) -> Result<Children> {
    let none = Params::default();
    Ok(match shape {
        Shape::Fixed(n) => {
            // Each child a list of disjoint closed objects; the same as bvhs.
            let s = random_scene(&cx.bench, &mut cx.rng, k, nobj.max(n), true)?;
            let mut defs = s.defs;
            let (mut kids, mut bvh_kids) = (Vec::new(), Vec::new());
            for g in 0..n {
                let members: Vec<String> = s.children.iter().skip(g).step_by(n).cloned().collect();
                defs += &def(&format!("g{g}"), "list", &none, &members);
                defs += &def(&format!("h{g}"), "bvh", &none, &members);
                kids.push(format!("\"g{g}\""));
                bvh_kids.push(format!("\"h{g}\""));
            }
            Children {
                defs,
                kids,
                bvh_kids,
            }
        }
        _ => {
            let s = random_scene(&cx.bench, &mut cx.rng, k, nobj, false)?;
            let defs = s.defs + &def("inner_bvh", "bvh", &none, &s.children);
            let bvh_kids = vec!["\"inner_bvh\"".to_string(), s.children[0].clone()];
            Children {
                defs,
                kids: s.children,
                bvh_kids,
            }
        }
    })
}

/// One scene with the plugin at its root and the rays traced through it.
struct SceneUnderTest {
    c: Children,
    test: World,
    rs: Vec<Ray>,
}

/// Nesting: the plugin inside a bvh against it (or the oracle) inside a
/// list, and bvhs inside the plugin against the oracle over the same
/// children (or, for a class with fixed children, against itself over
/// lists).
fn compare_nested(
    cx: &mut Cx,
    suite: &mut Suite,
    shape: Shape,
    oracle: Option<&(String, Params)>,
    scene: &SceneUnderTest,
    all: &mut ChildTallies,
) -> Result<()> {
    let (c, rs) = (&scene.c, &scene.rs);
    let none = Params::default();
    suite.at("nested-inside-bvh");
    let inner = def("inner", &cx.class, &cx.params, &c.kids);
    let w_in = cx.bench.scene(&world(
        &format!("{}{inner}", c.defs),
        "bvh",
        &none,
        &["\"inner\"".into()],
    ))?;
    // Against the oracle in list where there is one, else the plugin in list.
    let inner_o = match oracle {
        Some((o, op)) => def("inner", o, op, &c.kids),
        None => inner.clone(),
    };
    let o_in = cx.bench.scene(&world(
        &format!("{}{inner_o}", c.defs),
        "list",
        &none,
        &["\"inner\"".into()],
    ))?;
    compare(&w_in, Some(&o_in), rs, &mut all.nest_in)?;
    suite.at("bvh-nested-inside");
    let w_out = cx
        .bench
        .scene(&world(&c.defs, &cx.class, &cx.params, &c.bvh_kids))?;
    match shape {
        Shape::Fixed(_) => compare(&w_out, Some(&scene.test), rs, &mut all.nest_out),
        _ => {
            let (o, op) = oracle.expect("an aggregate has an oracle");
            let o_out = cx.bench.scene(&world(&c.defs, o, op, &c.bvh_kids))?;
            compare(&w_out, Some(&o_out), rs, &mut all.nest_out)
        }
    }
}

/// The checks' lines from the tallies (`nearest-hit` and
/// `ties-lowest-index` skipped without an oracle).
fn push_children_checks(
    suite: &mut Suite,
    shape: Shape,
    oracle: Option<&(String, Params)>,
    all: &ChildTallies,
    threads: usize,
) {
    let t = &all.t;
    match oracle {
        Some((o, _)) => {
            let rays = format!("rays agree with `{o}`");
            let mut c = Check::tally("nearest-hit", &t.nearest, t.rays, "rays");
            if c.status == crate::conform::Status::Pass {
                c.detail = format!("{} {rays}", t.rays);
            }
            suite.push(c);
            suite.push(Check::tally("ties-lowest-index", &t.ties, t.rays, "rays"));
        }
        None => {
            let why = format!(
                "no oracle for a class of exactly {} {}: name one with --oracle CLASS [--oracle-params ...]",
                shape.count(),
                if shape.count() == 1 { "child" } else { "children" }
            );
            suite.push(Check::skip("nearest-hit", why.clone()));
            suite.push(Check::skip("ties-lowest-index", why));
        }
    }
    suite.push(Check::tally("any-hit", &t.anyhit, t.rays, "rays"));
    suite.push(Check::tally(
        "bounds-contain-hits",
        &t.bounds,
        t.rays,
        "rays",
    ));
    suite.push(Check::tally(
        "volumes-contain-hits",
        &t.volumes,
        t.rays,
        "rays",
    ));
    suite.push(interval_check(t));
    suite.push(Check::held("local-geom", &t.geom, t.rays, "rays"));
    suite.push(Check::tally(
        "nested-inside-bvh",
        &all.nest_in.merged(),
        all.nest_in.rays,
        "rays",
    ));
    suite.push(Check::tally(
        "bvh-nested-inside",
        &all.nest_out.merged(),
        all.nest_out.rays,
        "rays",
    ));
    suite.push(concurrency_check(all.conc_bad, all.conc_of, threads));
}
