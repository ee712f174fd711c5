//! `rtk diff A B`: the error of an image against a reference, with the
//! metrics `rtk converge` plots (the Mitsuba anchor's), so that one number
//! compares renders from rtk and from other renderers; and, with
//! `--ztest` or `--welch`, a statistical test of "same mean"
//! ([`hypothesis`]) that says pass or fail where an error metric cannot.

pub mod hypothesis;

use crate::render::render_loop::Film;
use crate::shared::{images, output};
use anyhow::{bail, Result};
use hypothesis::{Outcome, Sampled};
use std::path::{Path, PathBuf};

/// The arguments of `rtk diff`.
#[derive(clap::Args)]
pub struct DiffArgs {
    /// The image.
    a: PathBuf,
    /// The reference (or, with --welch, the other image).
    b: PathBuf,
    /// Mitsuba's render test: B is a converged reference and B_VAR its
    /// per-sample variance (`rtk render --variance`, Mitsuba's `_var.exr`);
    /// A was rendered with --spp samples a pixel.
    #[arg(long, value_name = "B_VAR", requires = "spp", conflicts_with = "welch")]
    ztest: Option<PathBuf>,
    /// Samples per pixel of A (with --ztest).
    #[arg(long, value_name = "N")]
    spp: Option<u64>,
    /// Welch's t-test (two noisy renders): A_VAR and B_VAR are their
    /// per-sample variances, --spp-a and --spp-b their sample counts.
    #[arg(long, num_args = 2, value_names = ["A_VAR", "B_VAR"], requires_all = ["spp_a", "spp_b"])]
    welch: Option<Vec<PathBuf>>,
    /// Samples per pixel of A (with --welch).
    #[arg(long = "spp-a", value_name = "N")]
    spp_a: Option<u64>,
    /// Samples per pixel of B (with --welch).
    #[arg(long = "spp-b", value_name = "M")]
    spp_b: Option<u64>,
    /// Write the p-value map: .exr holds each pixel-channel's p (X, Y, Z
    /// as R, G, B); .png shows each pixel's smallest p as grey (white:
    /// p = 1) and failing pixels in red.
    #[arg(long, value_name = "FILE")]
    pmap: Option<PathBuf>,
}

/// Exit status of a statistical test that failed (the images differ).
pub const EXIT_TEST_FAILED: i32 = 1;

/// `rtk diff`: the metrics of A against B, then the test if one is asked.
pub fn run(a: &DiffArgs) -> Result<()> {
    let img = read_same_size(&a.a, None)?;
    let reference = read_same_size(&a.b, Some((&img, &a.a)))?;
    let m = images::metrics(&img.data, &reference.data);
    println!("rmse {}", m.rmse);
    println!("relmse {}", m.relmse);
    let outcome = if let Some(var) = &a.ztest {
        let spp = positive("--spp", a.spp)?;
        let var = read_same_size(var, Some((&img, &a.a)))?;
        let (x, r, v) = (xyz(&img), xyz(&reference), xyz(&var));
        Some(("z-test", hypothesis::z_test(&x, &r, &v, spp)))
    } else if let Some(vars) = &a.welch {
        let (na, nb) = (positive("--spp-a", a.spp_a)?, positive("--spp-b", a.spp_b)?);
        if na < 2 || nb < 2 {
            bail!("--welch: each image needs at least 2 samples a pixel for a variance");
        }
        let va = read_same_size(&vars[0], Some((&img, &a.a)))?;
        let vb = read_same_size(&vars[1], Some((&img, &a.a)))?;
        let (ma, mb, va, vb) = (xyz(&img), xyz(&reference), xyz(&va), xyz(&vb));
        let sa = Sampled {
            mean: &ma,
            var: &va,
            spp: na,
        };
        let sb = Sampled {
            mean: &mb,
            var: &vb,
            spp: nb,
        };
        Some(("Welch t-test", hypothesis::welch_test(&sa, &sb)))
    } else {
        if a.pmap.is_some() {
            bail!("--pmap needs a test: --ztest or --welch");
        }
        None
    };
    let Some((name, o)) = outcome else {
        return Ok(());
    };
    if let Some(p) = &a.pmap {
        output::check_writable(p)?;
        output::write(&p_value_map(&o, &img, p), p)?;
    }
    report(name, &o);
    if !o.passed() {
        std::process::exit(EXIT_TEST_FAILED);
    }
    Ok(())
}

/// `path` read, refused unless it has the size of `like` (when given).
fn read_same_size(path: &Path, like: Option<(&images::Image, &PathBuf)>) -> Result<images::Image> {
    let img = images::read(path)?;
    if let Some((l, name)) = like {
        images::check_same_size(
            (img.width, img.height),
            &path.display().to_string(),
            (l.width, l.height),
            &name.display().to_string(),
        )?;
    }
    Ok(img)
}

fn xyz(img: &images::Image) -> Vec<f64> {
    hypothesis::to_xyz(&img.data)
}

fn positive(flag: &str, v: Option<u64>) -> Result<u64> {
    match v {
        Some(n) if n > 0 => Ok(n),
        Some(_) => bail!("{flag}: the samples per pixel must be at least 1"),
        None => bail!("{flag} is needed"),
    }
}

/// The lines that say how the test went (stdout): the level, the failing
/// pixel-channels against those allowed, the smallest p, and the verdict.
fn report(name: &str, o: &Outcome) {
    let allowed = o.p.len() - (hypothesis::PASS_FRACTION * o.pixels as f64 * 3.0).ceil() as usize;
    println!("test {name}");
    println!("alpha {:.6e}", o.alpha);
    println!(
        "failing {} of {} pixel-channels (at most {allowed} may fail)",
        o.failing,
        o.p.len()
    );
    println!("min_p {:.6e}", o.min_p());
    println!("{}", if o.passed() { "pass" } else { "FAIL" });
}

/// The p-value map as a film: p per channel for an EXR, or for a PNG the
/// pixel's smallest p as grey with failing pixels red (the PNG writer
/// encodes to sRGB, so grey levels are given as linear values).
fn p_value_map(o: &Outcome, img: &images::Image, path: &Path) -> Film {
    let exr = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let pixels =
        o.p.chunks_exact(3)
            .map(|p| {
                if exr {
                    return [p[0], p[1], p[2]];
                }
                let min = p[0].min(p[1]).min(p[2]);
                if !(min > o.alpha) {
                    [1.0, 0.0, 0.0]
                } else {
                    let g = images::srgb_to_linear(min.clamp(0.0, 1.0));
                    [g, g, g]
                }
            })
            .collect();
    Film {
        width: img.width,
        height: img.height,
        pixels,
        stats: Default::default(),
    }
}
