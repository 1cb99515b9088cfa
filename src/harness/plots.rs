//! Report figures as PNG and SVG (plotters). Text uses the embedded DejaVu Sans
//! (`assets/fonts/DejaVuSans.ttf`, registered through plotters' `ab_glyph` feature), so no
//! system font is needed.

use super::stats::{loglog_slope, median, quantile};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::path::{Path, PathBuf};
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();
const FONT_NAME: &str = "sans-serif";
const SIZE: (u32, u32) = (900, 560);

/// Registers the embedded DejaVu Sans as plotters' `sans-serif` (idempotent). Anything else
/// that draws with plotters in this crate's build (e.g. criterion's HTML report in benches)
/// needs this, because the `ab_glyph` feature has no system-font fallback.
pub fn register() {
    REGISTER.call_once(|| {
        // The bytes are a valid TTF shipped with the crate; failure would leave text unrendered.
        let _ = register_font(FONT_NAME, FontStyle::Normal, FONT);
    });
}

type PlotResult = std::result::Result<(), String>;

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 10] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
    ];
    P[i % P.len()]
}

macro_rules! both {
    ($dir:expr, $name:expr, $out:expr, $f:expr) => {{
        register();
        // drawn in memory, written through the safe write of `formats::write_atomic`
        let png: PathBuf = $dir.join(format!("{}.png", $name));
        {
            let mut rgb = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
                $f(root)?;
            }
            let bytes = crate::plot::encode_png(&rgb, SIZE.0, SIZE.1).map_err(err)?;
            crate::formats::write_atomic(&png, &bytes).map_err(err)?;
        }
        let svg: PathBuf = $dir.join(format!("{}.svg", $name));
        {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, SIZE).into_drawing_area();
                $f(root)?;
            }
            crate::formats::write_atomic(&svg, text.as_bytes()).map_err(err)?;
        }
        $out.push(png);
        $out.push(svg);
    }};
}

/// Named groups of values (one per solver).
pub type Groups = Vec<(String, Vec<f64>)>;

fn draw_box<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    ylabel: &str,
    groups: &Groups,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let all: Vec<f64> = groups
        .iter()
        .flat_map(|g| g.1.iter().copied())
        .filter(|v| v.is_finite())
        .collect();
    let (mut lo, mut hi) = (quantile(&all, 0.0), quantile(&all, 1.0));
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(1e-9);
    let names: Vec<String> = groups.iter().map(|g| g.0.clone()).collect();
    let k = groups.len().max(1) as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT_NAME, 22))
        .margin(12)
        .x_label_area_size(60)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5f64..k - 0.5, (lo - pad)..(hi + pad))
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(groups.len().max(1) + 1)
        .x_label_formatter(&|x| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < names.len() {
                names[i as usize].clone()
            } else {
                String::new()
            }
        })
        .y_desc(ylabel)
        .label_style((FONT_NAME, 13))
        .draw()
        .map_err(err)?;
    for (i, (_, v)) in groups.iter().enumerate() {
        let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            continue;
        }
        let x = i as f64;
        let (q1, q2, q3) = (quantile(&v, 0.25), median(&v), quantile(&v, 0.75));
        let iqr = q3 - q1;
        let wl = v
            .iter()
            .copied()
            .filter(|&a| a >= q1 - 1.5 * iqr)
            .fold(f64::INFINITY, f64::min);
        let wh = v
            .iter()
            .copied()
            .filter(|&a| a <= q3 + 1.5 * iqr)
            .fold(f64::NEG_INFINITY, f64::max);
        let c = color(i);
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(x - 0.3, q1), (x + 0.3, q3)],
                c.mix(0.3).filled(),
            )))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(x - 0.3, q1), (x + 0.3, q3)],
                c.stroke_width(2),
            )))
            .map_err(err)?;
        for seg in [
            vec![(x - 0.3, q2), (x + 0.3, q2)],
            vec![(x, q3), (x, wh)],
            vec![(x, q1), (x, wl)],
            vec![(x - 0.15, wh), (x + 0.15, wh)],
            vec![(x - 0.15, wl), (x + 0.15, wl)],
        ] {
            chart
                .draw_series(LineSeries::new(seg, c.stroke_width(2)))
                .map_err(err)?;
        }
        chart
            .draw_series(
                v.iter()
                    .filter(|&&a| a < wl || a > wh)
                    .map(|&a| Circle::new((x, a), 3, c.filled())),
            )
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Box plot of one value per solver (e.g. path reduction, lifts). Returns the files written.
pub fn box_plot(
    dir: &Path,
    name: &str,
    title: &str,
    ylabel: &str,
    groups: &Groups,
) -> std::result::Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    both!(dir, name, out, |r| draw_box(r, title, ylabel, groups));
    Ok(out)
}

/// Points (n, seconds) per solver.
pub type Scaling = Vec<(String, Vec<(f64, f64)>)>;

fn log_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = vals.filter(|x| *x > 0.0 && x.is_finite()).collect();
    if v.is_empty() {
        return (1e-3, 1.0);
    }
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi <= lo {
        (lo / 2.0, hi * 2.0)
    } else {
        (lo / 1.3, hi * 1.3)
    }
}

fn draw_scaling<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, data: &Scaling) -> PlotResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let (xl, xh) = log_range(data.iter().flat_map(|d| d.1.iter().map(|p| p.0)));
    let (yl, yh) = log_range(data.iter().flat_map(|d| d.1.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(&root)
        .caption("Runtime against instance size (log-log)", (FONT_NAME, 22))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d((xl..xh).log_scale(), (yl..yh).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("cells n")
        .x_labels(6)
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_desc("wall seconds per trial (mean)")
        .label_style((FONT_NAME, 13))
        .draw()
        .map_err(err)?;
    for (i, (name, pts)) in data.iter().enumerate() {
        let c = color(i);
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
            .collect();
        let label = match loglog_slope(&pts) {
            Some((b, a)) => {
                let (x0, x1) = log_range(pts.iter().map(|p| p.0));
                let f = |x: f64| 10f64.powf(a + b * x.log10());
                chart
                    .draw_series(LineSeries::new(
                        vec![(x0, f(x0)), (x1, f(x1))],
                        c.stroke_width(1),
                    ))
                    .map_err(err)?;
                format!("{name} (slope {b:.2})")
            }
            None => name.clone(),
        };
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, c.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT_NAME, 13))
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Runtime against size, log-log, with a fitted slope per solver.
pub fn scaling_plot(dir: &Path, data: &Scaling) -> std::result::Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    both!(dir, "runtime_vs_size", out, |r| draw_scaling(r, data));
    Ok(out)
}

/// Curves per solver: (x, median, lower band, upper band).
pub type Bands = Vec<(String, Vec<(f64, f64, f64, f64)>)>;

#[allow(clippy::too_many_arguments)]
fn draw_curves<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    data: &Bands,
    ylim: Option<(f64, f64)>,
    step: bool,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let (xl, xh) = log_range(data.iter().flat_map(|d| d.1.iter().map(|p| p.0)));
    let (yl, yh) = ylim.unwrap_or_else(|| {
        let v: Vec<f64> = data
            .iter()
            .flat_map(|d| d.1.iter().flat_map(|p| [p.2, p.3]))
            .filter(|x| x.is_finite())
            .collect();
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() && hi > lo {
            (lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
        } else if lo.is_finite() {
            (lo - 1.0, lo + 1.0)
        } else {
            (0.0, 1.0)
        }
    });
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FONT_NAME, 22))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((xl..xh).log_scale(), yl..yh)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_desc(ylabel)
        .label_style((FONT_NAME, 13))
        .draw()
        .map_err(err)?;
    for (i, (name, pts)) in data.iter().enumerate() {
        let c = color(i);
        let pts: Vec<_> = pts
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1.is_finite())
            .collect();
        if pts.is_empty() {
            continue;
        }
        let mut band: Vec<(f64, f64)> = pts.iter().map(|p| (p.0, p.3)).collect();
        band.extend(pts.iter().rev().map(|p| (p.0, p.2)));
        chart
            .draw_series(std::iter::once(Polygon::new(band, c.mix(0.15))))
            .map_err(err)?;
        let line: Vec<(f64, f64)> = if step {
            let mut l = Vec::new();
            for (k, p) in pts.iter().enumerate() {
                if k > 0 {
                    l.push((p.0, pts[k - 1].1));
                }
                l.push((p.0, p.1));
            }
            l
        } else {
            pts.iter().map(|p| (p.0, p.1)).collect()
        };
        chart
            .draw_series(LineSeries::new(line, c.stroke_width(2)))
            .map_err(err)?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT_NAME, 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}

/// A log-x line plot with a band per solver (convergence, performance profile, ECDF).
#[allow(clippy::too_many_arguments)]
pub fn curve_plot(
    dir: &Path,
    name: &str,
    title: &str,
    xlabel: &str,
    ylabel: &str,
    data: &Bands,
    ylim: Option<(f64, f64)>,
    step: bool,
) -> std::result::Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    both!(dir, name, out, |r| draw_curves(
        r, title, xlabel, ylabel, data, ylim, step
    ));
    Ok(out)
}
