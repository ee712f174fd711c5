//! `rtk conform` for camera plugins: the camera of a 16x12 scene, created
//! with `--params`, asked for rays over the film (a grid of positions, the
//! corners included, with random lens and time samples) as the render loop
//! asks:
//!
//! - `finite`: origins, directions and weights finite, weights ≥ 0, the
//!   ray's interval not empty;
//! - `unit-directions`: directions of unit length (the kernel's contract
//!   for root rays);
//! - `time-in-shutter`: the ray carries the sample's time, which the render
//!   loop draws within the shutter (a camera does not move it);
//! - `pixel-centres`: every pixel centre of the image maps to a ray of
//!   positive weight, and no two to the same ray;
//! - `not-mirrored`: film x runs to the right and y downwards as seen
//!   along the view: (right × down) · forward > 0, from the points one
//!   unit along the rays of the film's middle row and column;
//! - `deterministic`: the same sample gives the same ray, bit for bit;
//! - `concurrent-queries`: rays asked from every thread at once are those
//!   of one thread.

use crate::conform::{note, scene_using, unknown_key, Check, Cx, Kind, Suite};
use anyhow::{anyhow, Result};
use rtk_handles::Camera;
use rtk_kernel::abi::{CameraRay, CameraSample, Ray, TraceCtx};
use rtk_kernel::glam::Vec3;

/// The camera's answer as (ray, weight): weight 0 (and a placeholder ray)
/// when the sample sees nothing.
fn ray_and_weight(r: Option<CameraRay>) -> (Ray, f32) {
    r.map_or((Ray::new(Vec3::ZERO, Vec3::Z), 0.0), |c| (c.ray, c.weight))
}

fn ray_of(cam: &Camera, ctx: &mut TraceCtx, s: &CameraSample) -> Result<(Ray, f32)> {
    let r = ray_and_weight(cam.generate_ray(ctx, s));
    if let Some((c, m)) = ctx.failure() {
        return Err(anyhow!("plugin `{c}` {m}"));
    }
    Ok(r)
}

fn bits(r: &Ray, w: f32) -> [u32; 10] {
    [
        r.origin.x.to_bits(),
        r.origin.y.to_bits(),
        r.origin.z.to_bits(),
        r.dir.x.to_bits(),
        r.dir.y.to_bits(),
        r.dir.z.to_bits(),
        r.t_min.to_bits(),
        r.t_max.to_bits(),
        r.time.to_bits(),
        w.to_bits(),
    ]
}

/// The checks for camera plugin `cx.class`.
pub(crate) fn checks(cx: &mut Cx, suite: &mut Suite) -> Result<()> {
    suite.at("create");
    let scene = scene_using(Kind::Camera, &cx.class, &cx.params, 0);
    let w = cx.bench.scene(&scene)?;
    let (width, height) = (w.desc.render.width, w.desc.render.height);
    let cam = &w.camera;
    let mut ctx = TraceCtx::new(0, 1, 0);

    // Samples: a grid over the film, corners included, random lens and time.
    let g = cx.n(24, 96);
    let mut samples = Vec::with_capacity((g + 1) * (g + 1));
    for j in 0..=g {
        for i in 0..=g {
            samples.push(CameraSample {
                film: [i as f32 / g as f32, j as f32 / g as f32],
                lens: [cx.rng.next_f32(), cx.rng.next_f32()],
                time: cx.rng.next_f32(),
            });
        }
    }
    suite.at("finite");
    let rays = finite_rays(cam, &mut ctx, &samples, suite)?;
    suite.at("pixel-centres");
    suite.push(pixel_centres(cam, &mut ctx, width, height)?);
    suite.at("not-mirrored");
    suite.push(not_mirrored(cam, &mut ctx)?);
    suite.at("deterministic");
    suite.push(deterministic(cam, &mut ctx, &samples, &rays)?);
    suite.at("concurrent-queries");
    suite.push(concurrent_queries(cam, &samples, &rays, cx.threads));
    drop(w);

    suite.at("unknown-key-refused");
    let c = unknown_key(cx, 0);
    suite.push(c);
    super::panics::run(cx, suite, 0)?;
    Ok(())
}

/// `finite`, `unit-directions` and `time-in-shutter` over the rays of
/// `samples`; returns the rays with their weights.
fn finite_rays(
    cam: &Camera,
    ctx: &mut TraceCtx,
    samples: &[CameraSample],
    suite: &mut Suite,
) -> Result<Vec<(Ray, f32)>> {
    let (mut nonfinite, mut unit, mut time) = Default::default();
    let mut rays = Vec::with_capacity(samples.len());
    for s in samples {
        let (r, wt) = ray_of(cam, ctx, s)?;
        let what = || format!("film {:?} lens {:?} time {:?}", s.film, s.lens, s.time);
        if !(r.origin.is_finite()
            && r.dir.is_finite()
            && wt.is_finite()
            && wt >= 0.0
            && r.t_min >= 0.0
            && r.t_min < r.t_max)
        {
            note(&mut nonfinite, || {
                format!("{}: ray {r:?}, weight {wt}", what())
            });
        }
        let len = r.dir.v().length();
        if !((len - 1.0).abs() <= 1e-5) {
            note(&mut unit, || format!("{}: |d| = {len}", what()));
        }
        if r.time.to_bits() != s.time.to_bits() {
            note(&mut time, || {
                format!("{}: the ray's time is {:?}", what(), r.time)
            });
        }
        rays.push((r, wt));
    }
    let n = samples.len() as u64;
    suite.push(Check::held("finite", &nonfinite, n, "rays"));
    suite.push(Check::held("unit-directions", &unit, n, "rays"));
    suite.push(Check::held("time-in-shutter", &time, n, "rays"));
    Ok(rays)
}

/// `pixel-centres`: every pixel centre of the `width` x `height` image maps
/// to a ray of positive weight, no two to the same ray.
fn pixel_centres(cam: &Camera, ctx: &mut TraceCtx, width: u32, height: u32) -> Result<Check> {
    let mut seen = std::collections::HashMap::new();
    let mut centres = (0u64, String::new());
    for y in 0..height {
        for x in 0..width {
            let s = CameraSample {
                film: [
                    (x as f32 + 0.5) / width as f32,
                    (y as f32 + 0.5) / height as f32,
                ],
                lens: [0.5, 0.5],
                time: 0.5,
            };
            let (r, wt) = ray_of(cam, ctx, &s)?;
            if !(wt > 0.0) {
                note(&mut centres, || format!("pixel ({x}, {y}): weight {wt}"));
            }
            let mut key = bits(&r, 0.0);
            key[8] = 0;
            if let Some((px, py)) = seen.insert(key, (x, y)) {
                note(&mut centres, || {
                    format!("pixels ({px}, {py}) and ({x}, {y}) map to the same ray")
                });
            }
        }
    }
    let pixels = (width * height) as u64;
    Ok(Check::new(
        "pixel-centres",
        centres.0 == 0,
        if centres.0 == 0 {
            format!("{pixels} pixel centres ({width}x{height}): distinct rays of positive weight")
        } else {
            format!("{} of {pixels} pixels: {}", centres.0, centres.1)
        },
    ))
}

/// `not-mirrored`: film x runs right and y down, seen along the view.
fn not_mirrored(cam: &Camera, ctx: &mut TraceCtx) -> Result<Check> {
    let at = |ctx: &mut TraceCtx, fx: f32, fy: f32| -> Result<(Vec3, Vec3)> {
        let (r, _) = ray_of(
            cam,
            ctx,
            &CameraSample {
                film: [fx, fy],
                lens: [0.5, 0.5],
                time: 0.5,
            },
        )?;
        Ok((r.origin.v() + r.dir.v(), r.dir.v()))
    };
    let right = at(ctx, 0.75, 0.5)?.0 - at(ctx, 0.25, 0.5)?.0;
    let down = at(ctx, 0.5, 0.75)?.0 - at(ctx, 0.5, 0.25)?.0;
    let forward = at(ctx, 0.5, 0.5)?.1;
    let handed = right.cross(down).dot(forward);
    Ok(Check::new(
        "not-mirrored",
        handed > 0.0,
        if handed > 0.0 {
            "film x runs right and y down, seen along the view".to_string()
        } else {
            format!(
                "(right × down) · forward = {handed:e}: the image is mirrored (right {:?}, down {:?}, forward {:?})",
                right.to_array(),
                down.to_array(),
                forward.to_array()
            )
        },
    ))
}

/// `deterministic`: the samples again, in reverse order, give the same
/// rays bit for bit.
fn deterministic(
    cam: &Camera,
    ctx: &mut TraceCtx,
    samples: &[CameraSample],
    rays: &[(Ray, f32)],
) -> Result<Check> {
    let mut again = (0u64, String::new());
    for (s, (r, wt)) in samples.iter().zip(rays).rev() {
        let (r2, w2) = ray_of(cam, ctx, s)?;
        if bits(r, *wt) != bits(&r2, w2) {
            note(&mut again, || {
                format!("film {:?}: {r:?} then {r2:?}", s.film)
            });
        }
    }
    Ok(Check::held(
        "deterministic",
        &again,
        samples.len() as u64,
        "rays",
    ))
}

/// `concurrent-queries`: every thread at once, twice over the samples,
/// gets one thread's rays.
fn concurrent_queries(
    cam: &Camera,
    samples: &[CameraSample],
    rays: &[(Ray, f32)],
    threads: usize,
) -> Check {
    let bad = std::sync::atomic::AtomicU64::new(0);
    std::thread::scope(|sc| {
        for ti in 0..threads {
            let bad = &bad;
            sc.spawn(move || {
                let mut ctx = TraceCtx::new(ti as u32, threads as u32, 0);
                for _ in 0..2 {
                    for (s, (r, wt)) in samples.iter().zip(rays) {
                        let (r2, w2) = ray_and_weight(cam.generate_ray(&mut ctx, s));
                        if bits(r, *wt) != bits(&r2, w2) || ctx.failed() {
                            bad.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        }
                    }
                }
            });
        }
    });
    let of = samples.len() as u64 * 2 * threads as u64;
    let bad = bad.into_inner();
    Check::new(
        "concurrent-queries",
        bad == 0,
        format!("{threads} threads: {bad} of {of} rays differ from one thread's"),
    )
}
