//! `rtk converge`: run time against error. The scene is loaded once and
//! rendered at each sample count with several seeds; each render is timed
//! (the render only) and measured against a reference image or a closed-form
//! one ([`crate::converge::analytic`]). Writes `converge.csv`, `converge.json` (the
//! fit and the comparison) and `converge.png` (log-log RMSE against seconds).

pub(crate) mod analytic;
mod plot;

use crate::render::render_loop::{self, Film};
use crate::render::tracer;
use crate::shared::images::{self, Image};
use crate::shared::{output, scene};
use analytic::Analytic;
use anyhow::{bail, Context, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Largest `--seeds`: seeds are `spp_index * SEED_STRIDE + k`, k in 1..=N.
const SEED_STRIDE: u64 = 1000;

/// The arguments of `rtk converge`.
#[derive(clap::Args)]
#[command(group(
    clap::ArgGroup::new("reference_image")
        .required(true)
        .args(["reference", "analytic"])
))]
pub struct ConvergeArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Reference image: .exr, .pfm, .npy (float32 H x W x 3) or .png (sRGB).
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Closed-form reference: `furnace:le=R[,G,B],albedo=A` (Le / (1 - A)) or
    /// `constant:R,G,B`.
    #[arg(long, value_name = "SPEC")]
    pub analytic: Option<String>,
    /// Sample counts, comma-separated.
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        default_value = "1,4,16,64,256"
    )]
    pub spp: Vec<u32>,
    /// Renders per sample count, each with its own seed.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub seeds: u32,
    /// Rendering threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Override a scene value, as for `rtk render` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Output folder (created if needed): converge.csv, converge.png, converge.json.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Another renderer's time-vs-error CSV (columns spp, wall_seconds or
    /// wall_seconds_min, rmse): overlaid, and the equal-error time ratio reported.
    #[arg(long, value_name = "CSV")]
    pub compare: Option<PathBuf>,
    /// The other curve's sample count (the nearest present) for the equal-error ratio.
    #[arg(long = "compare-spp", value_name = "N", default_value_t = 64)]
    pub compare_spp: u32,
    /// Extra folders to search for plugins first (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    pub plugin_path: Vec<PathBuf>,
    /// Distrust the scene, as for `rtk render --safe`.
    #[arg(long)]
    pub safe: bool,
    /// No progress on stderr.
    #[arg(short, long)]
    pub quiet: bool,
}

/// One render.
#[derive(Debug, Clone)]
struct Row {
    spp: u32,
    seed: u64,
    seconds: f64,
    rmse: f64,
    relmse: f64,
}

/// A curve point: the median over the seeds at one sample count, and the spread.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Samples per pixel.
    pub spp: u32,
    /// Median wall seconds.
    pub seconds: f64,
    /// Median RMSE.
    pub rmse: f64,
    /// Smallest and largest wall seconds.
    pub seconds_range: (f64, f64),
    /// Smallest and largest RMSE.
    pub rmse_range: (f64, f64),
}

/// A time-vs-error curve: per-spp medians, by increasing spp.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend name.
    pub label: String,
    /// The points.
    pub points: Vec<Point>,
}

/// The median of a non-empty list.
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Per-spp medians and ranges of (spp, seconds, rmse) samples.
pub fn curve(label: &str, samples: &[(u32, f64, f64)]) -> Curve {
    let mut spps: Vec<u32> = samples.iter().map(|s| s.0).collect();
    spps.sort_unstable();
    spps.dedup();
    let points = spps
        .into_iter()
        .map(|spp| {
            let mut t: Vec<f64> = samples.iter().filter(|s| s.0 == spp).map(|s| s.1).collect();
            let mut e: Vec<f64> = samples.iter().filter(|s| s.0 == spp).map(|s| s.2).collect();
            let (tm, em) = (median(&mut t), median(&mut e));
            Point {
                spp,
                seconds: tm,
                rmse: em,
                seconds_range: (t[0], t[t.len() - 1]),
                rmse_range: (e[0], e[e.len() - 1]),
            }
        })
        .collect();
    Curve {
        label: label.to_string(),
        points,
    }
}

/// Points usable on log axes: finite and positive.
fn loggable(p: &Point) -> bool {
    p.seconds.is_finite() && p.seconds > 0.0 && p.rmse.is_finite() && p.rmse > 0.0
}

/// The least-squares slope of ln(rmse) against ln(seconds) over the curve's
/// points; `None` with fewer than two usable points or no spread in time.
pub fn loglog_slope(points: &[Point]) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| loggable(p))
        .map(|p| (p.seconds.ln(), p.rmse.ln()))
        .collect();
    if xy.len() < 2 {
        return None;
    }
    let n = xy.len() as f64;
    let (mx, my) = (
        xy.iter().map(|p| p.0).sum::<f64>() / n,
        xy.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx).filter(|s| s.is_finite())
}

/// The time at which a curve reaches `rmse`, by log-log linear interpolation
/// between its points in order of time (the first segment that brackets
/// it); outside the curve's range, extrapolated from the end segment on that
/// side. Returns (seconds, extrapolated).
pub fn time_at_rmse(points: &[Point], rmse: f64) -> Option<(f64, bool)> {
    if !(rmse > 0.0 && rmse.is_finite()) {
        return None;
    }
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| loggable(p))
        .map(|p| (p.seconds.ln(), p.rmse.ln()))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    if p.len() < 2 {
        return None;
    }
    let e = rmse.ln();
    let at = |a: (f64, f64), b: (f64, f64)| -> Option<f64> {
        if a.1 == b.1 {
            return None;
        }
        let t = a.0 + (e - a.1) * (b.0 - a.0) / (b.1 - a.1);
        Some(t.exp()).filter(|t| t.is_finite())
    };
    for w in p.windows(2) {
        let (lo, hi) = (w[0].1.min(w[1].1), w[0].1.max(w[1].1));
        if (lo..=hi).contains(&e) {
            if w[0].1 == w[1].1 {
                return Some((w[0].0.exp(), false));
            }
            return at(w[0], w[1]).map(|t| (t, false));
        }
    }
    // Outside the range: below the smallest error (more time than measured)
    // from the slowest segment, above the largest from the fastest.
    let min_e = p.iter().map(|q| q.1).fold(f64::INFINITY, f64::min);
    let n = p.len();
    let seg = if e < min_e {
        (p[n - 2], p[n - 1])
    } else {
        (p[0], p[1])
    };
    at(seg.0, seg.1).map(|t| (t, true))
}

/// The equal-error comparison against another curve.
#[derive(Debug, Clone)]
pub struct Ratio {
    /// The other curve's point used.
    pub other: Point,
    /// rtk's time at the other point's RMSE.
    pub rtk_seconds: f64,
    /// Whether that time was extrapolated beyond rtk's measured range.
    pub extrapolated: bool,
    /// rtk_seconds / other.seconds.
    pub ratio: f64,
}

/// Compare at the other curve's point nearest `spp` (the larger on a tie).
pub fn equal_error_ratio(rtk: &Curve, other: &Curve, spp: u32) -> Result<Ratio> {
    let o = other
        .points
        .iter()
        .filter(|p| loggable(p))
        .min_by_key(|p| (p.spp.abs_diff(spp), std::cmp::Reverse(p.spp)))
        .with_context(|| format!("{} has no point with positive time and RMSE", other.label))?;
    let Some((t, extrapolated)) = time_at_rmse(&rtk.points, o.rmse) else {
        bail!(
            "cannot place RMSE {} on rtk's curve: it needs two sample counts with positive, distinct RMSE",
            o.rmse
        );
    };
    Ok(Ratio {
        other: o.clone(),
        rtk_seconds: t,
        extrapolated,
        ratio: t / o.seconds,
    })
}

/// Read another renderer's CSV: columns by header name (`spp`; `wall_seconds`,
/// else `wall_seconds_min`; `rmse`), several rows per spp allowed (medians).
pub fn read_curve(path: &Path) -> Result<Curve> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--compare {}: cannot read it", path.display()))?;
    parse_curve(&text, path).with_context(|| format!("--compare {}", path.display()))
}

fn parse_curve(text: &str, path: &Path) -> Result<Curve> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().context("the file is empty")?;
    let cols: Vec<String> = split_csv(header);
    let find = |name: &str| cols.iter().position(|c| c == name);
    let spp_i = find("spp").context("no `spp` column")?;
    let t_i = find("wall_seconds")
        .or_else(|| find("wall_seconds_min"))
        .context("no `wall_seconds` or `wall_seconds_min` column")?;
    let e_i = find("rmse").context("no `rmse` column")?;
    let mut samples = vec![];
    let mut names: Vec<String> = vec![];
    for (n, line) in lines {
        let f = split_csv(line);
        let get = |i: usize, what: &str| -> Result<&str> {
            f.get(i)
                .map(String::as_str)
                .with_context(|| format!("line {}: no `{what}` value", n + 1))
        };
        let num = |i: usize, what: &str| -> Result<f64> {
            let s = get(i, what)?;
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| format!("line {}: `{what}` is `{s}`, not a number", n + 1))
        };
        let spp = get(spp_i, "spp")?;
        let spp: u32 = spp
            .parse()
            .with_context(|| format!("line {}: `spp` is `{spp}`, not a count", n + 1))?;
        samples.push((spp, num(t_i, &cols[t_i])?, num(e_i, "rmse")?));
        let who: Vec<&str> = ["renderer", "variant"]
            .iter()
            .filter_map(|c| find(c).and_then(|i| f.get(i)).map(String::as_str))
            .filter(|s| !s.is_empty())
            .collect();
        if !who.is_empty() && names.is_empty() {
            names.push(who.join(" "));
        }
    }
    if samples.is_empty() {
        bail!("no rows");
    }
    let label = names.pop().unwrap_or_else(|| {
        path.file_stem()
            .map_or_else(|| "other".into(), |s| s.to_string_lossy().into_owned())
    });
    Ok(curve(&label, &samples))
}

/// One CSV line's fields (plain commas; surrounding quotes removed).
fn split_csv(line: &str) -> Vec<String> {
    line.split(',')
        .map(|f| f.trim().trim_matches('"').to_string())
        .collect()
}

/// Check the arguments that need no scene.
fn check_args(a: &ConvergeArgs) -> Result<Vec<u32>> {
    if a.spp.is_empty() {
        bail!("--spp: give at least one sample count");
    }
    let mut seen = vec![];
    for &s in &a.spp {
        if !(1..=1 << 24).contains(&s) {
            bail!("--spp: {s} is out of range (1 to 16777216)");
        }
        if seen.contains(&s) {
            bail!("--spp: {s} is given twice");
        }
        seen.push(s);
    }
    if a.seeds == 0 || a.seeds as u64 >= SEED_STRIDE {
        bail!(
            "--seeds must be between 1 and {}, got {}",
            SEED_STRIDE - 1,
            a.seeds
        );
    }
    Ok(seen)
}

/// Create the output folder and check that it takes files.
fn prepare_out(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("--out {}: cannot create the folder", dir.display()))?;
    if !dir.is_dir() {
        bail!("--out {}: is not a folder", dir.display());
    }
    output::check_writable(&dir.join("converge.png"))
}

/// Run `rtk converge`.
pub fn run(a: ConvergeArgs, pool: &rayon::ThreadPool, threads: usize) -> Result<()> {
    let spps = check_args(&a)?;
    let analytic = a.analytic.as_deref().map(Analytic::parse).transpose()?;
    let other = a.compare.as_deref().map(read_curve).transpose()?;

    let (file, desc) = scene::read_scene(&a.scene, &a.set, a.safe)?;
    let (w, h) = (desc.render.width, desc.render.height);
    let (reference, reference_name) = reference_image(&a, analytic.as_ref(), w, h)?;
    prepare_out(&a.out)?;

    let mut world = scene::build_world(&file, desc, &a.plugin_path, pool)?;
    let rows = render_all(&a, &mut world, &spps, &reference, pool)?;

    let samples: Vec<(u32, f64, f64)> = rows.iter().map(|r| (r.spp, r.seconds, r.rmse)).collect();
    let rtk = curve("rtk", &samples);
    let slope = loglog_slope(&rtk.points);
    let ratio = other
        .as_ref()
        .map(|o| equal_error_ratio(&rtk, o, a.compare_spp));

    let csv = a.out.join("converge.csv");
    let csv_text = csv_text(&rows, w, h, threads);
    output::write_atomically(&csv, |tmp| Ok(std::fs::write(tmp, &csv_text)?))?;

    let title = format!(
        "{}  {w}x{h}, {threads} threads, vs {}",
        a.scene
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        reference_name
    );
    let png = a.out.join("converge.png");
    let ratio_ok = ratio.as_ref().and_then(|r| r.as_ref().ok());
    let png_bytes = plot::converge_png(&title, &rtk, other.as_ref(), slope, ratio_ok)?;
    output::write_atomically(&png, |tmp| Ok(std::fs::write(tmp, &png_bytes)?))?;

    let json = a.out.join("converge.json");
    let summary = summary_json(
        &a,
        &reference_name,
        (w, h),
        threads,
        &rtk,
        slope,
        other.as_ref(),
        ratio.as_ref(),
    );
    let json_text = serde_json::to_string_pretty(&summary)? + "\n";
    output::write_atomically(&json, |tmp| Ok(std::fs::write(tmp, &json_text)?))?;

    print_report(&rtk, slope, other.as_ref(), ratio.as_ref());
    println!(
        "wrote {}, {}, {}",
        csv.display(),
        png.display(),
        json.display()
    );
    Ok(())
}

/// The image errors are measured against (`--analytic`'s uniform one, or
/// `--reference`, which must be the render's size) and its name in the
/// outputs.
fn reference_image(
    a: &ConvergeArgs,
    analytic: Option<&Analytic>,
    w: u32,
    h: u32,
) -> Result<(Image, String)> {
    let reference = match (analytic, &a.reference) {
        (Some(an), _) => Image::uniform(w, h, an.radiance().map(|v| v as f32)),
        (None, Some(p)) => {
            let r = images::read(p)?;
            if (r.width, r.height) != (w, h) {
                bail!(
                    "the reference {} is {}x{} but {} renders {w}x{h}: match them with --set render.width={} --set render.height={}",
                    p.display(),
                    r.width,
                    r.height,
                    a.scene.display(),
                    r.width,
                    r.height
                );
            }
            r
        }
        (None, None) => bail!("give --reference FILE or --analytic SPEC"),
    };
    let reference_name = match (&a.analytic, &a.reference) {
        (Some(s), _) => format!("analytic {s}"),
        (None, Some(p)) => p.display().to_string(),
        _ => String::new(),
    };
    Ok((reference, reference_name))
}

/// Render the world at each sample count with `--seeds` seeds, timing each
/// render (the render only) and measuring it against `reference`.
fn render_all(
    a: &ConvergeArgs,
    world: &mut rtk_shell::World,
    spps: &[u32],
    reference: &Image,
    pool: &rayon::ThreadPool,
) -> Result<Vec<Row>> {
    let total = spps.len() * a.seeds as usize;
    let mut rows = Vec::with_capacity(total);
    for (i, &spp) in spps.iter().enumerate() {
        for k in 1..=a.seeds as u64 {
            let seed = i as u64 * SEED_STRIDE + k;
            world.desc.render.spp = spp;
            world.desc.render.seed = seed;
            let film = new_film(&world.desc, &a.scene)?;
            let tracer = tracer::Tracer::new(world);
            let t = Instant::now();
            let film = render_film(&tracer, pool, !a.quiet, film, &a.scene)?;
            let seconds = t.elapsed().as_secs_f64();
            let m = images::metrics(film.pixels.as_flattened(), &reference.data);
            let row = Row {
                spp,
                seed,
                seconds,
                rmse: m.rmse,
                relmse: m.relmse,
            };
            if !a.quiet {
                eprintln!(
                    "converge: [{}/{total}] spp {spp} seed {seed}: {seconds:.3} s, rmse {:.6}, relmse {:.6}",
                    rows.len() + 1,
                    row.rmse,
                    row.relmse
                );
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

/// A black film of the scene's image size (allocated fallibly).
fn new_film(desc: &rtk_shell::Desc, scene: &Path) -> Result<Film> {
    Film::new(desc.render.width, desc.render.height)
        .map_err(|m| anyhow::anyhow!("{}: {m}", scene.display()))
}

/// Render the world (its `[render]` settings: size, spp, seed) into `film`.
fn render_film(
    tracer: &tracer::Tracer,
    pool: &rayon::ThreadPool,
    progress: bool,
    film: Film,
    scene: &Path,
) -> Result<Film> {
    render_loop::render(tracer, pool, progress, film)
        .map_err(|m| anyhow::anyhow!("rendering {} failed: {m}", scene.display()))
}

/// The CSV: the required columns first, then extras.
fn csv_text(rows: &[Row], w: u32, h: u32, threads: usize) -> String {
    let mut s =
        String::from("spp,seed,wall_seconds,rmse,relmse,width,height,threads,samples_per_second\n");
    for r in rows {
        let sps = w as f64 * h as f64 * r.spp as f64 / r.seconds;
        let _ = writeln!(
            s,
            "{},{},{:.6},{},{},{w},{h},{threads},{:.1}",
            r.spp, r.seed, r.seconds, r.rmse, r.relmse, sps
        );
    }
    s
}

fn points_json(c: &Curve) -> serde_json::Value {
    c.points
        .iter()
        .map(|p| {
            serde_json::json!({
                "spp": p.spp,
                "median_seconds": p.seconds,
                "median_rmse": p.rmse,
                "min_seconds": p.seconds_range.0,
                "max_seconds": p.seconds_range.1,
                "min_rmse": p.rmse_range.0,
                "max_rmse": p.rmse_range.1,
            })
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
fn summary_json(
    a: &ConvergeArgs,
    reference: &str,
    (w, h): (u32, u32),
    threads: usize,
    rtk: &Curve,
    slope: Option<f64>,
    other: Option<&Curve>,
    ratio: Option<&Result<Ratio>>,
) -> serde_json::Value {
    let compare = other.map(|o| {
        let r = match ratio {
            Some(Ok(r)) => serde_json::json!({
                "other_spp": r.other.spp,
                "other_seconds": r.other.seconds,
                "rmse": r.other.rmse,
                "rtk_seconds": r.rtk_seconds,
                "extrapolated": r.extrapolated,
                "ratio": r.ratio,
            }),
            Some(Err(e)) => serde_json::json!({ "error": format!("{e:#}") }),
            None => serde_json::Value::Null,
        };
        serde_json::json!({
            "file": a.compare.as_ref().map(|p| p.display().to_string()),
            "label": o.label,
            "points": points_json(o),
            "equal_error": r,
        })
    });
    serde_json::json!({
        "scene": a.scene.display().to_string(),
        "reference": reference,
        "width": w,
        "height": h,
        "threads": threads,
        "seeds": a.seeds,
        "sets": a.set,
        "slope": slope,
        "slope_fit": "least squares of ln(median rmse) on ln(median wall seconds) over the sample counts",
        "points": points_json(rtk),
        "compare": compare,
    })
}

fn print_report(
    rtk: &Curve,
    slope: Option<f64>,
    other: Option<&Curve>,
    ratio: Option<&Result<Ratio>>,
) {
    println!("  spp   median s   median rmse   rmse min..max");
    for p in &rtk.points {
        println!(
            "{:>5}  {:>9.4}   {:>11.6}   {:.6}..{:.6}",
            p.spp, p.seconds, p.rmse, p.rmse_range.0, p.rmse_range.1
        );
    }
    match slope {
        Some(s) => {
            println!("slope {s:.4} (log rmse against log seconds, per-spp medians; ideal -0.5)")
        }
        None => println!("slope n/a (needs two sample counts with positive time and rmse)"),
    }
    if let (Some(o), Some(r)) = (other, ratio) {
        match r {
            Ok(r) => println!(
                "equal-error time ratio {:.4}: rtk {:.4} s{} vs {} {:.4} s at rmse {:.6} ({} spp)",
                r.ratio,
                r.rtk_seconds,
                if r.extrapolated {
                    " (extrapolated from the end segment of rtk's curve)"
                } else {
                    ""
                },
                o.label,
                r.other.seconds,
                r.other.rmse,
                r.other.spp
            ),
            Err(e) => println!("equal-error time ratio n/a: {e:#}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(spp: u32, t: f64, e: f64) -> Point {
        Point {
            spp,
            seconds: t,
            rmse: e,
            seconds_range: (t, t),
            rmse_range: (e, e),
        }
    }

    #[test]
    fn medians_and_ranges() {
        let c = curve(
            "x",
            &[
                (4, 2.0, 0.3),
                (1, 1.0, 0.5),
                (4, 1.0, 0.1),
                (4, 3.0, 0.2),
                (1, 3.0, 0.7),
            ],
        );
        assert_eq!(c.points.len(), 2);
        assert_eq!(
            c.points[0],
            Point {
                spp: 1,
                seconds: 2.0,
                rmse: 0.6,
                seconds_range: (1.0, 3.0),
                rmse_range: (0.5, 0.7),
            }
        );
        assert_eq!((c.points[1].seconds, c.points[1].rmse), (2.0, 0.2));
    }

    #[test]
    fn slope_of_an_ideal_curve_is_minus_a_half() {
        let pts: Vec<Point> = [1u32, 4, 16, 64]
            .iter()
            .map(|&s| pt(s, 0.01 * s as f64, 0.2 / (s as f64).sqrt()))
            .collect();
        assert!((loglog_slope(&pts).unwrap() + 0.5).abs() < 1e-12);
        assert_eq!(loglog_slope(&pts[..1]), None);
        assert_eq!(loglog_slope(&[pt(1, 1.0, 0.0), pt(2, 2.0, 0.1)]), None);
    }

    #[test]
    fn time_at_rmse_interpolates_and_extrapolates() {
        let pts = [pt(1, 1.0, 0.4), pt(4, 4.0, 0.2), pt(16, 16.0, 0.1)];
        let (t, x) = time_at_rmse(&pts, 0.2).unwrap();
        assert!((t - 4.0).abs() < 1e-12 && !x);
        // Between 0.4 and 0.2 along slope -1/2: 0.4 * t^-1/2 = 0.3.
        let (t, x) = time_at_rmse(&pts, 0.3).unwrap();
        assert!((t - (0.4f64 / 0.3).powi(2)).abs() < 1e-12 && !x, "{t}");
        // Below the range: from the last segment.
        let (t, x) = time_at_rmse(&pts, 0.05).unwrap();
        assert!((t - 64.0).abs() < 1e-9 && x, "{t}");
        // Above: from the first.
        let (t, x) = time_at_rmse(&pts, 0.8).unwrap();
        assert!((t - 0.25).abs() < 1e-12 && x, "{t}");
        assert_eq!(time_at_rmse(&pts[..1], 0.3), None);
        assert_eq!(time_at_rmse(&pts, 0.0), None);
    }

    #[test]
    fn equal_error_ratio_at_the_nearest_spp() {
        let rtk = Curve {
            label: "rtk".into(),
            points: vec![pt(1, 1.0, 0.4), pt(4, 4.0, 0.2), pt(16, 16.0, 0.1)],
        };
        let other = Curve {
            label: "m".into(),
            points: vec![pt(16, 2.0, 0.2), pt(64, 8.0, 0.1), pt(256, 32.0, 0.05)],
        };
        let r = equal_error_ratio(&rtk, &other, 64).unwrap();
        assert_eq!(r.other.spp, 64);
        assert!((r.ratio - 2.0).abs() < 1e-12 && !r.extrapolated);
        let r = equal_error_ratio(&rtk, &other, 100).unwrap();
        assert_eq!(r.other.spp, 64);
        let r = equal_error_ratio(&rtk, &other, 1000).unwrap();
        assert_eq!(r.other.spp, 256);
        assert!(r.extrapolated);
        assert!((r.ratio - 2.0).abs() < 1e-9);
    }

    #[test]
    fn reads_the_mitsuba_csv_layout() {
        let text = "renderer,variant,spp,seed,wall_seconds_min,wall_seconds_median,rmse\n\
                    mitsuba-3.9.1,scalar_rgb,1,1,0.0553,0.0564,0.164685\n\
                    mitsuba-3.9.1,scalar_rgb,64,4,3.3628,3.4158,0.0184898\n";
        let c = parse_curve(text, Path::new("m.csv")).unwrap();
        assert_eq!(c.label, "mitsuba-3.9.1 scalar_rgb");
        assert_eq!(c.points.len(), 2);
        assert_eq!((c.points[1].spp, c.points[1].seconds), (64, 3.3628));
        // rtk's own CSV: wall_seconds, several seeds per spp.
        let text = "spp,seed,wall_seconds,rmse,relmse\n1,1,0.5,0.2,0\n1,2,0.7,0.4,0\n";
        let c = parse_curve(text, Path::new("dir/rtk.csv")).unwrap();
        assert_eq!(c.label, "rtk");
        assert_eq!(c.points[0].seconds, 0.6);
        assert!((c.points[0].rmse - 0.3).abs() < 1e-15);
        let e = parse_curve("spp,rmse\n1,2\n", Path::new("x.csv")).unwrap_err();
        assert!(e.to_string().contains("wall_seconds"), "{e}");
        let e = parse_curve("spp,wall_seconds,rmse\n1,x,2\n", Path::new("x.csv")).unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
    }

    #[test]
    fn csv_header_and_rows() {
        let rows = [Row {
            spp: 4,
            seed: 1001,
            seconds: 0.25,
            rmse: 0.5,
            relmse: 0.125,
        }];
        let s = csv_text(&rows, 2, 2, 1);
        let mut l = s.lines();
        assert!(l
            .next()
            .unwrap()
            .starts_with("spp,seed,wall_seconds,rmse,relmse,"));
        assert_eq!(l.next().unwrap(), "4,1001,0.250000,0.5,0.125,2,2,1,64.0");
    }
}
