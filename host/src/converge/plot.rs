//! The `rtk converge` plot: log-log RMSE against render seconds, drawn with
//! `plotters` into an RGB buffer and encoded as PNG by `image`. Text uses a
//! font compiled into the binary (Ubuntu Light, from `epaint_default_fonts`):
//! no system font library is needed.

use crate::converge::{Curve, Point, Ratio};
use anyhow::{Context, Result};
use plotters::prelude::*;
use plotters::style::FontStyle;

const SIZE: (u32, u32) = (1024, 720);
const RTK: RGBColor = RGBColor(31, 119, 180);
const OTHER: RGBColor = RGBColor(214, 39, 40);
const GUIDE: RGBColor = RGBColor(110, 110, 110);

/// Register the compiled-in font as plotters' `sans-serif` (once).
fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        )
        .is_ok()
    });
    anyhow::ensure!(ok, "the plot's built-in font could not be loaded");
    Ok(())
}

/// Axis range over positive values, padded on a log scale.
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-3, 1.0);
    }
    let (lo, hi) = if hi / lo < 10.0 {
        let mid = (lo * hi).sqrt();
        (mid / 3.5, mid * 3.5)
    } else {
        (lo, hi)
    };
    (lo / 1.5, hi * 1.5)
}

fn usable(p: &Point) -> bool {
    p.seconds > 0.0 && p.rmse > 0.0 && p.seconds.is_finite() && p.rmse.is_finite()
}

/// Short numbers for log axes: three significant digits, no trailing zeros.
fn tick(v: &f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e4).contains(&a) {
        return format!("{v:.0e}");
    }
    let digits = (2 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The plot as PNG bytes: rtk's per-spp medians with the min..max spread
/// over seeds (every render as a faint dot), a slope -1/2 guide through the
/// first median, and optionally another renderer's curve.
pub fn converge_png(
    title: &str,
    rtk: &Curve,
    other: Option<&Curve>,
    slope: Option<f64>,
    ratio: Option<&Ratio>,
) -> Result<Vec<u8>> {
    register_font()?;
    let (w, h) = SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw(&mut buf, title, rtk, other, slope, ratio)
        .map_err(|e| anyhow::anyhow!("drawing the plot: {e}"))?;
    let img = image::RgbImage::from_raw(w, h, buf).context("plot size")?;
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png)
        .context("encoding the plot")?;
    Ok(png.into_inner())
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// The log-log chart the curves are drawn on.
type Chart<'a, 'b> = ChartContext<'a, BitMapBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

fn draw(
    buf: &mut [u8],
    title: &str,
    rtk: &Curve,
    other: Option<&Curve>,
    slope: Option<f64>,
    ratio: Option<&Ratio>,
) -> DrawResult {
    let root = BitMapBackend::with_buffer(buf, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let curves: Vec<&Curve> = std::iter::once(rtk).chain(other).collect();
    let all = || {
        curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(|p| usable(p))
    };
    let (x0, x1) = log_range(all().flat_map(|p| [p.seconds_range.0, p.seconds_range.1]));
    let (y0, y1) = log_range(all().flat_map(|p| [p.rmse_range.0, p.rmse_range.1]));

    let (top, body) = root.split_vertically(40);
    top.draw(&Text::new(
        title.to_string(),
        (20, 12),
        ("sans-serif", 18).into_font().color(&BLACK),
    ))?;
    let mut chart = ChartBuilder::on(&body)
        .caption(caption(slope, ratio), ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(55)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("render wall time (seconds, log)")
        .y_desc("RMSE against the reference (log)")
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;

    draw_guide(&mut chart, rtk, (x0, x1), (y0, y1))?;
    for (c, colour) in curves.iter().zip([RTK, OTHER]) {
        draw_curve(&mut chart, c, colour)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// The chart's caption: the fitted slope and, against another renderer,
/// the equal-error time ratio.
fn caption(slope: Option<f64>, ratio: Option<&Ratio>) -> String {
    let slope_s = slope.map_or("n/a".into(), |s| format!("{s:.3}"));
    let mut caption = format!("RMSE against render time: fitted slope {slope_s}");
    if let Some(r) = ratio {
        caption += &format!(
            ", equal-error time ratio {}{}",
            tick(&r.ratio),
            if r.extrapolated {
                " (extrapolated)"
            } else {
                ""
            }
        );
    }
    caption
}

/// The -1/2 guide through rtk's first usable median, within the chart's
/// ranges: where a Monte Carlo renderer's curve should run parallel.
fn draw_guide(
    chart: &mut Chart,
    rtk: &Curve,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> DrawResult {
    if let Some(p) = rtk.points.iter().find(|p| usable(p)) {
        let n = 64;
        let guide: Vec<(f64, f64)> = (0..=n)
            .map(|i| x0 * (x1 / x0).powf(i as f64 / n as f64))
            .map(|x| (x, p.rmse * (x / p.seconds).powf(-0.5)))
            .filter(|&(_, y)| y >= y0 && y <= y1)
            .collect();
        chart
            .draw_series(DashedLineSeries::new(guide, 8, 6, GUIDE.stroke_width(2)))?
            .label("slope -1/2")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], GUIDE.stroke_width(2)));
    }
    Ok(())
}

/// One renderer's curve: its medians joined, each with its spread over
/// seeds as bars and labelled with its spp.
fn draw_curve(chart: &mut Chart, c: &Curve, colour: RGBColor) -> DrawResult {
    let pts: Vec<&Point> = c.points.iter().filter(|p| usable(p)).collect();
    let style = colour.stroke_width(2);
    // The spread over seeds: RMSE min..max (vertical) and time min..max
    // (horizontal) through each median.
    for p in &pts {
        let cap = |a: (f64, f64), b: (f64, f64)| PathElement::new(vec![a, b], style);
        chart.draw_series([
            cap((p.seconds, p.rmse_range.0), (p.seconds, p.rmse_range.1)),
            cap((p.seconds_range.0, p.rmse), (p.seconds_range.1, p.rmse)),
        ])?;
    }
    chart
        .draw_series(LineSeries::new(
            pts.iter().map(|p| (p.seconds, p.rmse)),
            style,
        ))?
        .label(format!("{} (median over seeds; bars: min..max)", c.label))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
    chart.draw_series(
        pts.iter()
            .map(|p| Circle::new((p.seconds, p.rmse), 5, colour.filled())),
    )?;
    chart.draw_series(pts.iter().map(|p| {
        EmptyElement::at((p.seconds, p.rmse))
            + Text::new(
                format!("{} spp", p.spp),
                (8, 4),
                ("sans-serif", 14).into_font().color(&colour),
            )
    }))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(spp: u32, t: f64, e: f64) -> Point {
        Point {
            spp,
            seconds: t,
            rmse: e,
            seconds_range: (t * 0.9, t * 1.1),
            rmse_range: (e * 0.8, e * 1.2),
        }
    }

    #[test]
    fn draws_a_png_with_and_without_data() {
        let rtk = Curve {
            label: "rtk".into(),
            points: vec![pt(1, 0.01, 0.3), pt(4, 0.04, 0.15), pt(16, 0.16, 0.08)],
        };
        let other = Curve {
            label: "mitsuba".into(),
            points: vec![pt(1, 0.05, 0.16), pt(64, 3.4, 0.018)],
        };
        let png = converge_png("t", &rtk, Some(&other), Some(-0.5), None).unwrap();
        let img = image::load_from_memory(&png).unwrap();
        assert_eq!((img.width(), img.height()), SIZE);
        // Something other than white was drawn, in rtk's colour among others.
        let rgb = img.to_rgb8();
        assert!(rgb.pixels().any(|p| p.0 == [RTK.0, RTK.1, RTK.2]));
        // No usable point (zero error): still a valid image.
        let zero = Curve {
            label: "rtk".into(),
            points: vec![pt(1, 0.01, 0.0)],
        };
        let png = converge_png("t", &zero, None, None, None).unwrap();
        assert!(image::load_from_memory(&png).is_ok());
    }

    #[test]
    fn tick_labels() {
        assert_eq!(tick(&0.01), "0.01");
        assert_eq!(tick(&0.0185), "0.0185");
        assert_eq!(tick(&0.5), "0.5");
        assert_eq!(tick(&2.0), "2");
        assert_eq!(tick(&300.0), "300");
        assert_eq!(tick(&1e-5), "1e-5");
    }
}
