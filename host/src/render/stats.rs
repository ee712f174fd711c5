//! `rtk render --stats`: one JSON record of what the render did (rays by
//! kind, plugin calls, the plugins mapped) and how long each step took, so
//! that scripts and benchmarks read numbers instead of parsing messages.

use super::render_loop::Film;
use super::RenderArgs;
use anyhow::Result;
use rtk_kernel::abi::{geom_mask, ray_kind, Stats};
use std::path::Path;
use std::time::{Duration, Instant};

/// Print the `--stats` record on stdout, with the fewest and most samples
/// per pixel (`samples`) and `--profile`'s record.
#[allow(clippy::too_many_arguments)]
pub(super) fn print(
    a: &RenderArgs,
    out: &Path,
    world: &rtk_shell::World,
    film: &Film,
    threads: usize,
    times: &StepTimes,
    (min, max): (u32, u32),
    profile: Option<serde_json::Value>,
) -> Result<()> {
    let mut json = stats_json(a, out, world, film, threads, times);
    json["samples_per_pixel"] = serde_json::json!([min, max]);
    if let Some(p) = profile {
        json["profile"] = p;
    }
    // A closed pipe (`| head`) is not an error worth a panic.
    use std::io::Write;
    let _ = writeln!(
        std::io::stdout(),
        "{}",
        serde_json::to_string_pretty(&json)?
    );
    Ok(())
}

/// How long the host's own steps took.
pub(super) struct StepTimes {
    pub parse: Duration,
    pub render: Duration,
    pub write: Duration,
    /// When the process started.
    pub start: Instant,
}

/// The `--stats` record.
fn stats_json(
    a: &RenderArgs,
    out: &Path,
    world: &rtk_shell::World,
    film: &Film,
    threads: usize,
    t: &StepTimes,
) -> serde_json::Value {
    let s = &film.stats;
    serde_json::json!({
        "scene": a.scene.display().to_string(),
        "output": out.display().to_string(),
        "width": film.width,
        "height": film.height,
        "spp": world.desc.render.spp,
        "threads": threads,
        "seconds": {
            "parse": t.parse.as_secs_f64(),
            "load_plugins": world.timings.load_plugins.as_secs_f64(),
            "create": world.timings.create.as_secs_f64(),
            "prepare": world.timings.prepare.as_secs_f64(),
            "render": t.render.as_secs_f64(),
            "write": t.write.as_secs_f64(),
            "total": t.start.elapsed().as_secs_f64(),
        },
        "plugins_loaded": world.plugins.iter().map(|p| p.class.clone()).collect::<Vec<_>>(),
        "plugins_mapped": mapped_plugins(),
        "objects_created": world.objects_created,
        "shaders_created": world.shaders.len(),
        "lights": world.lights.len(),
        "files_read": world.files_read,
        "rays": rays_json(s),
        // Every ray traced (camera, scattered, shadow) over the render's
        // wall-clock seconds: counted per thread, no clock read per ray.
        "rays_per_second": s.rays.iter().sum::<u64>() as f64 / t.render.as_secs_f64().max(1e-9),
        "paths_per_second": s.rays[ray_kind::CAMERA as usize] as f64 / t.render.as_secs_f64().max(1e-9),
        "local_geom": {
            "calls": s.local_geom_calls,
            "position": s.local_geom_fields[bit(geom_mask::POSITION)],
            "geometric_normal": s.local_geom_fields[bit(geom_mask::GEOMETRIC_NORMAL)],
            "shading_normal": s.local_geom_fields[bit(geom_mask::SHADING_NORMAL)],
            "tangents": s.local_geom_fields[bit(geom_mask::TANGENTS)],
            "uv": s.local_geom_fields[bit(geom_mask::UV)],
        },
        "node_tests": s.node_tests,
        "prim_tests": s.prim_tests,
        "shader_calls": s.shader_calls,
        "light_samples": s.light_samples,
        "nonfinite_samples": s.nonfinite_samples,
    })
}

fn bit(mask: u32) -> usize {
    mask.trailing_zeros() as usize
}

fn rays_json(s: &Stats) -> serde_json::Value {
    serde_json::json!({
        "camera": s.rays[ray_kind::CAMERA as usize],
        "reflection": s.rays[ray_kind::REFLECTION as usize],
        "refraction": s.rays[ray_kind::REFRACTION as usize],
        "shadow": s.rays[ray_kind::SHADOW as usize],
        "scatter": s.rays[ray_kind::SCATTER as usize],
    })
}

/// The rtk plugin libraries actually mapped into this process, read from
/// the OS (Linux), not from the loader's own bookkeeping.
fn mapped_plugins() -> Vec<String> {
    let Ok(maps) = std::fs::read_to_string("/proc/self/maps") else {
        return vec![];
    };
    let prefix = format!("{}rtk_", std::env::consts::DLL_PREFIX);
    let mut out: Vec<String> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| {
            Path::new(p)
                .file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| {
                    n.starts_with(&prefix) && n.ends_with(std::env::consts::DLL_SUFFIX)
                })
        })
        .map(str::to_string)
        .collect();
    out.sort();
    out.dedup();
    out
}
