//! `panics-reported`: a panic in each entry of the plugin is caught at the
//! boundary and reported with the plugin's name and the entry, and the
//! process carries on. The suite cannot make an arbitrary plugin panic, so
//! the plugin names the way: `--panic-param KEY`, a parameter whose value
//! is the entry to panic in (`panic_in` in rtk's test fixtures). Each entry
//! of the plugin's kind is then provoked in turn — the cold ones (`create`,
//! `add_child`, `prepare`, `bounds`, a shader's `lobes`) by building a scene
//! that uses the plugin, the hot ones (queries, sampling, `generate_ray`,
//! `li`) by calling them on the built scene — and each error must read
//! ``plugin `CLASS` panicked in ENTRY``: from the shell for cold calls,
//! from the record the SDK leaves in the trace context for hot ones.

use crate::conform::{brief, scene_using, Check, Cx, Kind, Suite};
use anyhow::Result;
use rtk_kernel::abi::{geom_mask, lobe, CameraSample, Float3, LocalGeom, Ray, TraceCtx};
use rtk_kernel::glam::Vec3;
use rtk_shell::World;

/// The entries of each kind that a plugin implements.
fn entries(kind: Kind) -> &'static [&'static str] {
    match kind {
        Kind::Object => &[
            "create",
            "add_child",
            "prepare",
            "bounds",
            "intersect",
            "occluded",
            "local_geom",
        ],
        Kind::Shader => &["create", "lobes", "eval", "sample", "pdf", "emitted"],
        Kind::Light => &["create", "sample_li", "le", "pdf_li"],
        Kind::Camera => &["create", "generate_ray"],
        Kind::Integrator => &["create", "li"],
    }
}

enum Outcome {
    /// Caught and reported with the plugin's name and the entry.
    Reported,
    /// The plugin did not panic there (it may not offer the entry, or its
    /// parameter may not reach it): why.
    NotProvoked(String),
    /// Reported without the plugin's name or the entry: the message.
    Misreported(String),
}

fn judge(class: &str, entry: &str, msg: &str) -> Outcome {
    if !msg.contains("panicked") {
        return Outcome::NotProvoked(format!("refused: {}", brief(msg)));
    }
    if msg.contains(&format!("`{class}`")) && msg.contains(&format!("panicked in {entry}")) {
        Outcome::Reported
    } else {
        Outcome::Misreported(brief(msg))
    }
}

/// A hot failure recorded in `ctx`, as the render loop reports it.
fn failure(ctx: &TraceCtx) -> Option<String> {
    ctx.failure().map(|(c, m)| format!("plugin `{c}` {m}"))
}

/// Call the hot entries of the built scene's plugin; the first failure.
fn hot(kind: Kind, w: &World) -> Option<String> {
    let mut ctx = TraceCtx::new(0, 1, 0);
    match kind {
        Kind::Object => {
            let mut p = crate::stress::Probe::new(w);
            let b = w.bounds;
            let c = (b.min.v() + b.max.v()) * 0.5;
            let r = (b.max.v() - b.min.v()).length().max(1.0);
            for i in 0..26 {
                let d = Vec3::new(
                    (i % 3) as f32 - 1.0,
                    (i / 3 % 3) as f32 - 1.0,
                    (i / 9) as f32 - 1.0 + 0.01,
                )
                .normalize();
                let ray = Ray::new(c - d * 2.0 * r, d);
                let h = match p.nearest(&ray) {
                    Err(e) => return Some(e.to_string()),
                    Ok(h) => h,
                };
                if let Err(e) = p.occluded(&ray) {
                    return Some(e.to_string());
                }
                if let Some(h) = h {
                    if let Err(e) = p.geom(&ray, &h) {
                        return Some(e.to_string());
                    }
                }
            }
            None
        }
        Kind::Shader => {
            let s = w.shaders.first()?;
            let mut g = LocalGeom::EMPTY;
            g.p = Vec3::ZERO.into();
            g.ng = Vec3::Z.into();
            g.ns = Vec3::Z.into();
            g.dpdu = Vec3::X.into();
            g.dpdv = Vec3::Y.into();
            g.filled = geom_mask::ALL;
            let wo: Float3 = Vec3::new(0.3, 0.0, 0.95).normalize().into();
            let wi: Float3 = Vec3::new(-0.2, 0.1, 0.97).normalize().into();
            s.eval(&mut ctx, &g, wo, wi);
            s.sample(&mut ctx, &g, wo, [0.3, 0.6], lobe::ALL);
            s.pdf(&mut ctx, &g, wo, wi, lobe::ALL);
            s.emitted(&mut ctx, &g, wo);
            failure(&ctx)
        }
        Kind::Light => {
            let l = w.lights.first()?;
            let p: Float3 = Vec3::new(0.3, 2.0, 1.1).into();
            let wi: Float3 = Vec3::new(0.0, 1.0, 0.0).into();
            l.sample_li(&mut ctx, p, [0.3, 0.6], 0.5);
            l.le(&mut ctx, wi);
            l.pdf_li(&mut ctx, p, wi);
            failure(&ctx)
        }
        Kind::Camera => {
            let s = CameraSample {
                film: [0.5, 0.5],
                lens: [0.5, 0.5],
                time: 0.5,
            };
            w.camera.generate_ray(&mut ctx, &s);
            failure(&ctx)
        }
        Kind::Integrator => {
            let t = crate::render::tracer::Tracer::new(w);
            let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
            t.camera_li(&mut ctx, &ray);
            failure(&ctx)
        }
    }
}

/// `panics-reported` with `--panic-param`, else its `skip` line.
pub(crate) fn run(cx: &mut Cx, suite: &mut Suite, children: usize) -> Result<()> {
    match cx.args.panic_param.clone() {
        Some(key) => {
            suite.at("panics-reported");
            let c = check(cx, &key, children)?;
            suite.push(c);
        }
        None => suite.push(Check::skip(
            "panics-reported",
            "no --panic-param: the suite cannot make the plugin panic; a panic in another check fails it, naming the plugin",
        )),
    }
    Ok(())
}

/// The check, with `key` naming the entry to panic in and the plugin given
/// `children` children (an object).
fn check(cx: &mut Cx, key: &str, children: usize) -> Result<Check> {
    let mut reported = Vec::new();
    let mut not = Vec::new();
    let mut bad = Vec::new();
    for &entry in entries(cx.kind) {
        let params = cx.params.with(key, toml::Value::String(entry.to_string()));
        // add_child is only reached with a child to add.
        let n = if entry == "add_child" {
            children.max(1)
        } else {
            children
        };
        let scene = scene_using(cx.kind, &cx.class, &params, n);
        let outcome = match cx.bench.scene(&scene) {
            Err(e) => judge(&cx.class, entry, &format!("{e:#}")),
            Ok(w) => match hot(cx.kind, &w) {
                Some(msg) => judge(&cx.class, entry, &msg),
                None => Outcome::NotProvoked("no panic".into()),
            },
        };
        match outcome {
            Outcome::Reported => reported.push(entry),
            Outcome::NotProvoked(why) => not.push(format!("{entry} ({why})")),
            Outcome::Misreported(m) => bad.push(format!("{entry}: {m}")),
        }
    }
    let pass = bad.is_empty() && !reported.is_empty();
    let mut detail = if !bad.is_empty() {
        format!(
            "not reported as ``plugin `{}` panicked in ENTRY``: {}",
            cx.class,
            bad.join("; ")
        )
    } else if reported.is_empty() {
        format!("`{key}` = ENTRY made the plugin panic in no entry")
    } else {
        format!(
            "caught and reported with the plugin's name: {}",
            reported.join(", ")
        )
    };
    if !not.is_empty() {
        detail += &format!("; not provoked: {}", not.join(", "));
    }
    Ok(Check::new("panics-reported", pass, detail))
}
