//! Report figures as PNG and SVG (plotters), drawn for print: every series has its own colour,
//! line style and marker (the same solver looks the same in every figure), legends sit beside the
//! plot instead of over it, log axes carry clean decade ticks (`10⁻⁴`, `0.01`, `1`, `10⁵`), and
//! quartile bands are drawn only where each sits in a panel of its own (facets).
//!
//! Text uses the embedded DejaVu Sans ([`super::FONT`], registered by [`super::register_font`]),
//! so no system font is needed; in the SVG files text stays text
//! (`font-family="DejaVu Sans, sans-serif"`), so it can be searched, edited and re-typeset; the
//! PDF of each figure ([`svg_to_pdf`]) is the SVG with its text set in that same font, the used
//! glyphs embedded as a subset, so the PDF looks the same on every machine and in any paper.
//!
//! Every axis is drawn in transformed coordinates: a log axis plots `log10(v)` on a linear scale
//! and labels the ticks with the values, which is what makes exact decade ticks possible.

use super::{FAMILY, FONT, register_font};
use crate::stats::{loglog_slope, median, quantile};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::{Path, PathBuf};

/// Width of the legend column beside a plot, pixels.
const LEGEND_W: u32 = 215;

type PlotResult = std::result::Result<(), String>;
type Files = std::result::Result<Vec<PathBuf>, String>;

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

// ---------------------------------------------------------------------------------------------
// Series looks

/// Line pattern of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dash {
    /// Continuous.
    Solid,
    /// Long dashes.
    Dashed,
    /// Dots.
    Dotted,
}

/// Marker shape of a series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled triangle, point up.
    TriangleUp,
    /// Filled diamond.
    Diamond,
    /// Filled triangle, point down.
    TriangleDown,
    /// Diagonal cross.
    Cross,
    /// Upright cross.
    Plus,
}

/// How series `i` is drawn: colour, line pattern and marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Look {
    /// Colour.
    pub color: RGBColor,
    /// Line pattern.
    pub dash: Dash,
    /// Marker.
    pub marker: Marker,
}

/// Nine colours that stay apart in print and for the common colour-vision deficiencies
/// (Okabe–Ito without its yellow, plus two of ColorBrewer's Dark2).
pub const PALETTE: [RGBColor; 9] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(117, 112, 179),
    RGBColor(166, 118, 29),
];
const MARKERS: [Marker; 7] = [
    Marker::Circle,
    Marker::Square,
    Marker::TriangleUp,
    Marker::Diamond,
    Marker::TriangleDown,
    Marker::Cross,
    Marker::Plus,
];
const DASHES: [Dash; 3] = [Dash::Solid, Dash::Dashed, Dash::Dotted];

/// The look of series `i`: colour `i mod 9`, line pattern `i div 9` (solid, dashed, dotted) and
/// marker `i mod 7`, so the first 27 series differ in colour or pattern and neighbours also in
/// marker.
pub fn look(i: usize) -> Look {
    Look {
        color: PALETTE[i % PALETTE.len()],
        dash: DASHES[(i / PALETTE.len()) % DASHES.len()],
        marker: MARKERS[i % MARKERS.len()],
    }
}

// ---------------------------------------------------------------------------------------------
// Axes and ticks

/// How an axis maps values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// Linear.
    Linear,
    /// Base-10 logarithmic; values ≤ 0 are not drawn.
    Log,
    /// Base-10 logarithmic with zero: values ≤ 0 (and those more than six decades below the
    /// largest value) are drawn one decade below the smallest positive decade, at a tick labelled
    /// `0` (for gaps to the best found, which reach exactly 0).
    LogWithZero,
}

/// An axis of a figure: its title, scale and, optionally, a fixed range (in data units).
#[derive(Debug, Clone)]
pub struct Axis {
    /// Axis title.
    pub label: String,
    /// Scale.
    pub scale: Scale,
    /// Fixed range; `None` takes the data's.
    pub range: Option<(f64, f64)>,
}

impl Axis {
    /// A linear axis with the data's range.
    pub fn linear(label: &str) -> Self {
        Axis {
            label: label.into(),
            scale: Scale::Linear,
            range: None,
        }
    }
    /// A log axis with the data's range.
    pub fn log(label: &str) -> Self {
        Axis {
            label: label.into(),
            scale: Scale::Log,
            range: None,
        }
    }
    /// The same axis with a fixed range.
    pub fn with_range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some((lo, hi));
        self
    }
    /// The same axis with another scale.
    pub fn with_scale(mut self, scale: Scale) -> Self {
        self.scale = scale;
        self
    }
}

/// An axis resolved against data: range and ticks in drawing (transformed) coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Ticks {
    /// Scale.
    pub scale: Scale,
    /// Lower end, transformed.
    pub lo: f64,
    /// Upper end, transformed.
    pub hi: f64,
    /// Labelled ticks, transformed.
    pub major: Vec<f64>,
    /// Light grid lines, transformed.
    pub minor: Vec<f64>,
    /// Where zero is drawn on a [`Scale::LogWithZero`] axis, transformed.
    pub zero: Option<f64>,
}

const SUPERSCRIPT: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];

fn superscript(e: i32) -> String {
    let mut s = String::new();
    if e < 0 {
        s.push('⁻');
    }
    for c in e.unsigned_abs().to_string().chars() {
        s.push(SUPERSCRIPT[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// A tick label: `0`, `0.25`, `1`, `40`, `1000`; powers of ten outside [10⁻³, 10⁴) as `10⁻⁵`,
/// other values there as `2·10⁵`. Never floating-point noise such as `9.9999999999999e-5`.
pub fn tick_label(v: f64) -> String {
    if !v.is_finite() {
        return "–".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    let sign = if v < 0.0 { "−" } else { "" };
    let e = a.log10().floor() as i32;
    let mant = a / 10f64.powi(e);
    let (mant, e) = if (mant - 10.0).abs() < 1e-6 {
        (1.0, e + 1)
    } else {
        (mant, e)
    };
    if !(-3..4).contains(&e) {
        let m = (mant * 100.0).round() / 100.0;
        return if (m - 1.0).abs() < 1e-9 {
            format!("{sign}10{}", superscript(e))
        } else {
            format!("{sign}{}·10{}", trim(format!("{m:.2}")), superscript(e))
        };
    }
    let decimals = (3 - e).clamp(0, 6) as usize;
    format!("{sign}{}", trim(format!("{a:.decimals$}")))
}

fn trim(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A "nice" step (1, 2, 2.5 or 5 × 10ᵏ) for about `n` intervals over `span`, as (f, k).
fn nice_step(span: f64, n: usize) -> (f64, i32) {
    let raw = span / n.max(1) as f64;
    let e = raw.log10().floor() as i32;
    let m = raw / 10f64.powi(e);
    let f = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 2.5 {
        2.5
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    (f, e)
}

/// `k · f · 10ᵉ`, computed so that it is the double nearest the decimal value (0.6, not
/// 0.6000000000000001): `k · f` is exact, and so is a division by an exact power of ten.
fn step_multiple(k: i64, (f, e): (f64, i32)) -> f64 {
    let kf = k as f64 * f;
    if e >= 0 {
        kf * 10f64.powi(e)
    } else {
        kf / 10f64.powi(-e)
    }
}

fn linear_ticks(lo: f64, hi: f64, fixed: bool) -> Ticks {
    let (mut lo, mut hi) = (lo, hi);
    if hi <= lo {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        lo -= d;
        hi += d;
    }
    let fe = nice_step(hi - lo, 6);
    let step = step_multiple(1, fe);
    if !fixed {
        lo = step_multiple((lo / step + 1e-9).floor() as i64, fe);
        hi = step_multiple((hi / step - 1e-9).ceil() as i64, fe);
    }
    let k0 = (lo / step - 1e-9).ceil() as i64;
    let k1 = (hi / step + 1e-9).floor() as i64;
    let major: Vec<f64> = (k0..=k1).map(|k| step_multiple(k, fe)).collect();
    let minor = major
        .iter()
        .map(|v| v + step / 2.0)
        .filter(|v| *v < hi)
        .collect();
    Ticks {
        scale: Scale::Linear,
        lo,
        hi,
        major,
        minor,
        zero: None,
    }
}

fn log_ticks(dlo: i32, dhi: i32, scale: Scale, zero: Option<f64>) -> Ticks {
    let decades = dhi - dlo;
    let every = if decades > 8 { 2 } else { 1 };
    let mut major: Vec<f64> = (dlo..=dhi)
        .filter(|d| (d - dlo) % every == 0 || *d == dhi)
        .map(f64::from)
        .collect();
    let mut minor = Vec::new();
    for d in dlo..dhi {
        for m in 2..10 {
            let t = f64::from(d) + f64::from(m).log10();
            if decades <= 1 && (m == 2 || m == 5) {
                major.push(t);
            } else if decades <= 6 {
                minor.push(t);
            }
        }
    }
    major.sort_by(f64::total_cmp);
    let lo = zero.unwrap_or(f64::from(dlo));
    if let Some(z) = zero {
        major.insert(0, z);
    }
    Ticks {
        scale,
        lo,
        hi: f64::from(dhi),
        major,
        minor,
        zero,
    }
}

/// Resolves an axis against the values it must show.
pub fn resolve(axis: &Axis, values: &[f64]) -> Ticks {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    match axis.scale {
        Scale::Linear => {
            let (lo, hi, fixed) = match axis.range {
                Some((a, b)) => (a, b, true),
                None => {
                    let v: Vec<f64> = finite.collect();
                    if v.is_empty() {
                        (0.0, 1.0, false)
                    } else {
                        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
                        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                        (lo, hi, false)
                    }
                }
            };
            linear_ticks(lo, hi, fixed)
        }
        Scale::Log | Scale::LogWithZero => {
            let pos: Vec<f64> = match axis.range {
                Some((a, b)) => vec![a, b],
                None => finite.filter(|v| *v > 0.0).collect(),
            };
            let lo = pos.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = pos.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let (mut dlo, mut dhi) = if lo.is_finite() && lo > 0.0 {
                (
                    (lo.log10() + 1e-9).floor() as i32,
                    (hi.log10() - 1e-9).ceil() as i32,
                )
            } else {
                (0, 1)
            };
            if dhi <= dlo {
                dhi = dlo + 1;
            }
            if axis.scale == Scale::LogWithZero {
                dlo = dlo.max(dhi - 6);
                log_ticks(dlo, dhi, axis.scale, Some(f64::from(dlo - 1)))
            } else {
                log_ticks(dlo, dhi, axis.scale, None)
            }
        }
    }
}

impl Ticks {
    /// A value in drawing coordinates; `None` where the axis cannot show it.
    pub fn map(&self, v: f64) -> Option<f64> {
        if !v.is_finite() {
            return None;
        }
        match self.scale {
            Scale::Linear => Some(v),
            Scale::Log => (v > 0.0).then(|| v.log10()),
            Scale::LogWithZero => {
                let z = self.zero.unwrap_or(self.lo);
                Some(if v > 0.0 { v.log10().max(z) } else { z })
            }
        }
    }
    /// The label of a tick at drawing coordinate `t`.
    pub fn label(&self, t: f64) -> String {
        match self.scale {
            Scale::Linear => tick_label(t),
            Scale::Log | Scale::LogWithZero => {
                if self.zero.is_some_and(|z| (t - z).abs() < 1e-9) {
                    "0".into()
                } else {
                    tick_label(10f64.powf(t))
                }
            }
        }
    }
    fn clamp(&self, t: f64) -> f64 {
        t.clamp(self.lo, self.hi)
    }
}

// ---------------------------------------------------------------------------------------------
// Drawing helpers

/// A linear coordinate whose labelled ticks and light grid lines are exactly the given ones
/// (plotters' own key-point combinator loses the label formatter of `f64` ranges).
#[derive(Debug, Clone)]
struct TickRange {
    lo: f64,
    hi: f64,
    major: Vec<f64>,
    minor: Vec<f64>,
}

impl TickRange {
    fn of(t: &Ticks) -> Self {
        TickRange {
            lo: t.lo,
            hi: t.hi,
            major: t.major.clone(),
            minor: t.minor.clone(),
        }
    }
}

impl Ranged for TickRange {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let span = if self.hi > self.lo {
            self.hi - self.lo
        } else {
            1.0
        };
        let r = (v - self.lo) / span;
        limit.0 + (r * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

type Coord = Cartesian2d<TickRange, TickRange>;
type Area<DB> = DrawingArea<DB, Shift>;
/// Points in drawing coordinates.
type Points = Vec<(f64, f64)>;
type Chart<'a, DB> = ChartContext<'a, DB, Coord>;

/// Label sizes of a full figure and of a facet panel.
#[derive(Clone, Copy)]
struct Sizes {
    label: u32,
    desc: u32,
    x_area: u32,
    y_area: u32,
}
const FULL: Sizes = Sizes {
    label: 14,
    desc: 15,
    x_area: 52,
    y_area: 72,
};
const PANEL: Sizes = Sizes {
    label: 11,
    desc: 12,
    x_area: 34,
    y_area: 46,
};

#[allow(clippy::too_many_arguments)]
fn frame<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    caption: Option<&str>,
    x: &Ticks,
    y: &Ticks,
    xdesc: &str,
    ydesc: &str,
    sz: Sizes,
) -> std::result::Result<Chart<'a, DB>, String>
where
    DB::ErrorType: 'static,
{
    let mut b = ChartBuilder::on(area);
    if let Some(c) = caption {
        b.caption(c, (FAMILY, sz.desc + 1));
    }
    b.margin(8)
        .margin_right(16)
        .x_label_area_size(sz.x_area)
        .y_label_area_size(sz.y_area);
    let mut chart = b
        .build_cartesian_2d(TickRange::of(x), TickRange::of(y))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| x.label(*v))
        .y_label_formatter(&|v| y.label(*v))
        .x_desc(xdesc)
        .y_desc(ydesc)
        .label_style((FAMILY, sz.label))
        .axis_desc_style((FAMILY, sz.desc))
        .bold_line_style(BLACK.mix(0.13))
        .light_line_style(BLACK.mix(0.05))
        .axis_style(BLACK.mix(0.8))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

fn draw_line<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    pts: &[(f64, f64)],
    lk: Look,
    width: u32,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    if pts.len() < 2 {
        return Ok(());
    }
    let s = lk.color.stroke_width(width);
    let it = pts.iter().copied();
    match lk.dash {
        Dash::Solid => chart.draw_series(LineSeries::new(it, s)).map(|_| ()),
        Dash::Dashed => chart
            .draw_series(DashedLineSeries::new(it, 10, 5, s))
            .map(|_| ()),
        Dash::Dotted => chart
            .draw_series(DashedLineSeries::new(it, 2, 4, s))
            .map(|_| ()),
    }
    .map_err(err)
}

/// Draws marker `m` centred at pixel `c` of `area`.
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: (i32, i32),
    m: Marker,
    color: RGBColor,
    r: i32,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    let poly = |pts: Vec<(i32, i32)>| {
        area.draw(&(EmptyElement::at(c) + Polygon::new(pts, color.filled())))
    };
    let h = (f64::from(r) * 1.15).round() as i32;
    match m {
        Marker::Circle => {
            let pts = (0..16)
                .map(|k| {
                    let a = std::f64::consts::TAU * f64::from(k) / 16.0;
                    (
                        (f64::from(r) * a.cos()).round() as i32,
                        (f64::from(r) * a.sin()).round() as i32,
                    )
                })
                .collect();
            poly(pts)
        }
        Marker::Square => {
            let q = (f64::from(r) * 0.85).round() as i32;
            poly(vec![(-q, -q), (q, -q), (q, q), (-q, q)])
        }
        Marker::TriangleUp => poly(vec![(0, -h), (h, r - 1), (-h, r - 1)]),
        Marker::TriangleDown => poly(vec![(0, h), (h, 1 - r), (-h, 1 - r)]),
        Marker::Diamond => poly(vec![(0, -h), (h, 0), (0, h), (-h, 0)]),
        Marker::Cross | Marker::Plus => {
            let segs = if m == Marker::Cross {
                [[(-r, -r), (r, r)], [(-r, r), (r, -r)]]
            } else {
                [[(-h, 0), (h, 0)], [(0, -h), (0, h)]]
            };
            for s in segs {
                area.draw(
                    &(EmptyElement::at(c) + PathElement::new(s.to_vec(), color.stroke_width(2))),
                )
                .map_err(err)?;
            }
            return Ok(());
        }
    }
    .map_err(err)
}

/// Markers along a curve (in drawing coordinates): `count` of them at evenly spaced x, shifted
/// by the series index so that coinciding curves still show each series' marker.
#[allow(clippy::too_many_arguments)]
fn draw_curve_markers<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &Chart<'_, DB>,
    x: &Ticks,
    pts: &[(f64, f64)],
    index: usize,
    lk: Look,
    count: usize,
    r: i32,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
        return Ok(());
    };
    let shift = (index as f64 * 0.618_033_988_75).fract();
    for k in 0..count {
        let xt = x.lo + (k as f64 + shift) / count as f64 * (x.hi - x.lo);
        if xt < first.0 || xt > last.0 {
            continue;
        }
        // the curve's value at xt: the last point at or before it (curves are steps or dense)
        let y = pts
            .iter()
            .take_while(|p| p.0 <= xt)
            .last()
            .map_or(first.1, |p| p.1);
        draw_marker(root, chart.backend_coord(&(xt, y)), lk.marker, lk.color, r)?;
    }
    Ok(())
}

/// The legend: a line sample with the marker, and the name, one row per entry.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, Look)],
    lines: bool,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    let (_, h) = area.dim_in_pixel();
    let n = entries.len().max(1) as i32;
    let row = ((h as i32 - 40) / n).clamp(12, 22);
    let font = (FAMILY, if row < 16 { 11 } else { 13 })
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (k, (name, lk)) in entries.iter().enumerate() {
        let y = 30 + row * k as i32;
        if lines {
            let segs: Vec<(i32, i32)> = match lk.dash {
                Dash::Solid => vec![(6, 32)],
                Dash::Dashed => vec![(6, 15), (20, 29)],
                Dash::Dotted => vec![(6, 8), (12, 14), (18, 20), (24, 26), (30, 32)],
            };
            for (a, b) in segs {
                area.draw(&PathElement::new(
                    vec![(a, y), (b, y)],
                    lk.color.stroke_width(2),
                ))
                .map_err(err)?;
            }
        }
        draw_marker(area, (19, y), lk.marker, lk.color, 4)?;
        area.draw(&Text::new(name.clone(), (40, y), font.clone()))
            .map_err(err)?;
    }
    Ok(())
}

/// The plot area and the legend column of a titled figure.
fn split_with_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> std::result::Result<(Area<DB>, Area<DB>), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let body = root.titled(title, (FAMILY, 19)).map_err(err)?;
    let (w, _) = body.dim_in_pixel();
    Ok(body.split_horizontally(w.saturating_sub(LEGEND_W)))
}

/// A figure's SVG as a PDF (one page of the SVG's size): the text stays text, set in the
/// embedded DejaVu Sans, whose glyphs used are embedded in the file (a font subset). No system
/// font is consulted, so the same SVG gives the same page on every machine (not the same
/// bytes: `svg2pdf` writes resource dictionaries in hash-map order).
pub fn svg_to_pdf(svg: &str) -> std::result::Result<Vec<u8>, String> {
    let mut opt = svg2pdf::usvg::Options::default();
    let db = opt.fontdb_mut();
    db.load_font_data(FONT.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    let tree = svg2pdf::usvg::Tree::from_str(svg, &opt).map_err(err)?;
    svg2pdf::to_pdf(
        &tree,
        svg2pdf::ConversionOptions::default(),
        svg2pdf::PageOptions::default(),
    )
    .map_err(err)
}

/// Draws a figure with `$f` into `$dir/$name.png`, `.svg` and `.pdf`.
macro_rules! both {
    ($dir:expr, $name:expr, $size:expr, $f:expr) => {{
        register_font();
        // drawn in memory, written through the safe write of `cellseq::files::write_atomic`
        let png: PathBuf = $dir.join(format!("{}.png", $name));
        {
            let mut rgb = vec![0u8; $size.0 as usize * $size.1 as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, $size).into_drawing_area();
                $f(root)?;
            }
            let bytes = crate::plot::encode_png(&rgb, $size.0, $size.1).map_err(err)?;
            cellseq::files::write_atomic(&png, &bytes).map_err(err)?;
        }
        let svg: PathBuf = $dir.join(format!("{}.svg", $name));
        let pdf: PathBuf = $dir.join(format!("{}.pdf", $name));
        {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, $size).into_drawing_area();
                $f(root)?;
            }
            cellseq::files::write_atomic(&svg, text.as_bytes()).map_err(err)?;
            cellseq::files::write_atomic(&pdf, &svg_to_pdf(&text)?).map_err(err)?;
        }
        Ok(vec![png, svg, pdf])
    }};
}

// ---------------------------------------------------------------------------------------------
// Box plots

/// One group of values: name, look index, values.
pub type Group = (String, usize, Vec<f64>);

fn draw_box<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    xlabel: &str,
    groups: &[Group],
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let body = root.titled(title, (FAMILY, 19)).map_err(err)?;
    let all: Vec<f64> = groups.iter().flat_map(|g| g.2.iter().copied()).collect();
    let x = resolve(&Axis::linear(xlabel), &all);
    let k = groups.len().max(1);
    let y = Ticks {
        scale: Scale::Linear,
        lo: -0.6,
        hi: k as f64 - 0.4,
        major: (0..k).map(|i| i as f64).collect(),
        minor: Vec::new(),
        zero: None,
    };
    let names: Vec<&str> = groups.iter().map(|g| g.0.as_str()).collect();
    let mut chart = ChartBuilder::on(&body)
        .margin(8)
        .margin_right(24)
        .x_label_area_size(FULL.x_area)
        .y_label_area_size(110)
        .build_cartesian_2d(TickRange::of(&x), TickRange::of(&y))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_label_formatter(&|v| x.label(*v))
        .y_label_formatter(&|v| {
            let i = v.round();
            if (v - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < k {
                names[k - 1 - i as usize].to_string()
            } else {
                String::new()
            }
        })
        .x_desc(xlabel)
        .label_style((FAMILY, FULL.label))
        .axis_desc_style((FAMILY, FULL.desc))
        .bold_line_style(BLACK.mix(0.10))
        .light_line_style(BLACK.mix(0.04))
        .draw()
        .map_err(err)?;
    for (i, (_, li, v)) in groups.iter().enumerate() {
        let v: Vec<f64> = v.iter().copied().filter(|a| a.is_finite()).collect();
        if v.is_empty() {
            continue;
        }
        let c = look(*li).color;
        let yc = (k - 1 - i) as f64;
        let (q1, q2, q3) = (quantile(&v, 0.25), median(&v), quantile(&v, 0.75));
        let iqr = q3 - q1;
        let lo = v
            .iter()
            .copied()
            .filter(|&a| a >= q1 - 1.5 * iqr)
            .fold(f64::INFINITY, f64::min);
        let hi = v
            .iter()
            .copied()
            .filter(|&a| a <= q3 + 1.5 * iqr)
            .fold(f64::NEG_INFINITY, f64::max);
        let boxr = [(q1, yc - 0.3), (q3, yc + 0.3)];
        chart
            .draw_series([Rectangle::new(boxr, c.mix(0.25).filled())])
            .map_err(err)?;
        chart
            .draw_series([Rectangle::new(boxr, c.stroke_width(2))])
            .map_err(err)?;
        for seg in [
            [(q2, yc - 0.3), (q2, yc + 0.3)],
            [(q3, yc), (hi, yc)],
            [(q1, yc), (lo, yc)],
            [(hi, yc - 0.15), (hi, yc + 0.15)],
            [(lo, yc - 0.15), (lo, yc + 0.15)],
        ] {
            chart
                .draw_series(LineSeries::new(seg, c.stroke_width(2)))
                .map_err(err)?;
        }
        for &a in v.iter().filter(|&&a| a < lo || a > hi) {
            draw_marker(&root, chart.backend_coord(&(a, yc)), Marker::Circle, c, 3)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Horizontal box plot of one value per group (solver); whiskers at 1.5 IQR, outliers as dots.
/// Returns the files written (PNG, SVG and PDF).
pub fn box_plot(dir: &Path, name: &str, title: &str, xlabel: &str, groups: &[Group]) -> Files {
    let h = 110 + 30 * groups.len().max(2) as u32;
    both!(dir, name, (900, h), |r| draw_box(r, title, xlabel, groups))
}

// ---------------------------------------------------------------------------------------------
// Runtime against size

/// Points (n, seconds) per solver: name, look index, points.
pub type ScalingSeries = (String, usize, Vec<(f64, f64)>);

fn draw_scaling<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    data: &[ScalingSeries],
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    let (plot, legend) = split_with_legend(&root, "Runtime against instance size")?;
    let pts: Vec<&(f64, f64)> = data.iter().flat_map(|d| d.2.iter()).collect();
    let x = resolve(
        &Axis::log("cells n"),
        &pts.iter().map(|p| p.0).collect::<Vec<_>>(),
    );
    let y = resolve(
        &Axis::log("wall seconds per trial (mean; machine-dependent)"),
        &pts.iter().map(|p| p.1).collect::<Vec<_>>(),
    );
    let mut chart = frame(
        &plot,
        None,
        &x,
        &y,
        "cells n",
        "wall seconds per trial (mean)",
        FULL,
    )?;
    let mut entries = Vec::new();
    for (name, li, pts) in data {
        let lk = look(*li);
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
            .collect();
        if pts.is_empty() {
            continue;
        }
        let label = match loglog_slope(&pts) {
            Some((b, a)) => {
                // the fit over the series' own sizes, not beyond
                let xs = pts.iter().map(|p| p.0.log10());
                let x0 = xs.clone().fold(f64::INFINITY, f64::min);
                let x1 = xs.fold(f64::NEG_INFINITY, f64::max);
                let line: Vec<(f64, f64)> =
                    [x0, x1].iter().map(|&t| (t, y.clamp(a + b * t))).collect();
                draw_line(&mut chart, &line, lk, 1)?;
                format!("{name} (slope {b:.2})")
            }
            None => name.clone(),
        };
        for p in &pts {
            let (Some(px), Some(py)) = (x.map(p.0), y.map(p.1)) else {
                continue;
            };
            draw_marker(
                &root,
                chart.backend_coord(&(px, py)),
                lk.marker,
                lk.color,
                5,
            )?;
        }
        entries.push((label, lk));
    }
    draw_legend(&legend, &entries, true)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Runtime against size, log-log, with a fitted slope per solver (dashed or dotted like the
/// solver's curves). Returns the files written.
pub fn scaling_plot(dir: &Path, data: &[ScalingSeries]) -> Files {
    both!(dir, "runtime_vs_size", (1000, 580), |r| draw_scaling(
        r, data
    ))
}

// ---------------------------------------------------------------------------------------------
// Curves

/// One curve: name, look index, and points (x, y, lower band, upper band) in data units.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend name.
    pub name: String,
    /// Look index (see [`look`]); keep it the same for a solver in every figure.
    pub look: usize,
    /// Points (x, y, band low, band high), x increasing.
    pub points: Vec<(f64, f64, f64, f64)>,
}

/// What a curve figure shows.
#[derive(Debug, Clone)]
pub struct CurveSpec {
    /// Figure title.
    pub title: String,
    /// x axis.
    pub x: Axis,
    /// y axis.
    pub y: Axis,
    /// Draw as a step function (values hold until the next point).
    pub step: bool,
}

/// A curve in drawing coordinates: its line and the outline of its band.
fn mapped(x: &Ticks, y: &Ticks, c: &Curve, step: bool) -> (Points, Points) {
    let mut pts: Vec<(f64, f64, f64, f64)> = Vec::new();
    for p in &c.points {
        let (Some(px), Some(py)) = (x.map(p.0), y.map(p.1)) else {
            continue;
        };
        let q = (
            x.clamp(px),
            y.clamp(py),
            y.clamp(y.map(p.2).unwrap_or(y.lo)),
            y.clamp(y.map(p.3).unwrap_or(y.hi)),
        );
        if px > x.hi {
            // beyond the right edge: the curve holds its last value up to the edge
            if let Some(&last) = pts.last() {
                pts.push((x.hi, last.1, last.2, last.3));
            }
            break;
        }
        pts.push(q);
    }
    let mut line = Vec::new();
    for (k, p) in pts.iter().enumerate() {
        if step && k > 0 {
            line.push((p.0, pts[k - 1].1));
        }
        line.push((p.0, p.1));
    }
    let mut band: Vec<(f64, f64)> = Vec::new();
    for (k, p) in pts.iter().enumerate() {
        if step && k > 0 {
            band.push((p.0, pts[k - 1].3));
        }
        band.push((p.0, p.3));
    }
    for (k, p) in pts.iter().enumerate().rev() {
        band.push((p.0, p.2));
        if step && k > 0 {
            band.push((p.0, pts[k - 1].2));
        }
    }
    (line, band)
}

fn axis_values(curves: &[Curve], x: bool, bands: bool) -> Vec<f64> {
    curves
        .iter()
        .flat_map(|c| c.points.iter())
        .flat_map(|p| {
            if x {
                vec![p.0]
            } else if bands {
                vec![p.1, p.2, p.3]
            } else {
                vec![p.1]
            }
        })
        .filter(|v| v.is_finite())
        .collect()
}

fn draw_curves<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    spec: &CurveSpec,
    curves: &[Curve],
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    let (plot, legend) = split_with_legend(&root, &spec.title)?;
    let x = resolve(&spec.x, &axis_values(curves, true, false));
    let y = resolve(&spec.y, &axis_values(curves, false, false));
    let mut chart = frame(&plot, None, &x, &y, &spec.x.label, &spec.y.label, FULL)?;
    let mut entries = Vec::new();
    for (i, c) in curves.iter().enumerate() {
        let lk = look(c.look);
        let (line, _) = mapped(&x, &y, c, spec.step);
        entries.push((c.name.clone(), lk));
        if line.is_empty() {
            continue;
        }
        draw_line(&mut chart, &line, lk, 2)?;
        draw_curve_markers(&root, &chart, &x, &line, i, lk, 5, 4)?;
    }
    draw_legend(&legend, &entries, true)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Curves on one plot (convergence, ECDF, performance profile): each in its look, with markers
/// and a legend beside the plot; no bands (see [`facet_plot`]). Returns the files written.
pub fn curve_plot(dir: &Path, name: &str, spec: &CurveSpec, curves: &[Curve]) -> Files {
    both!(dir, name, (1000, 580), |r| draw_curves(r, spec, curves))
}

fn draw_facets<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    spec: &CurveSpec,
    curves: &[Curve],
    reference: Option<&Curve>,
    cols: usize,
) -> PlotResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(err)?;
    let body = root.titled(&spec.title, (FAMILY, 19)).map_err(err)?;
    let mut all: Vec<Curve> = curves.to_vec();
    all.extend(reference.cloned());
    let x = resolve(&spec.x, &axis_values(&all, true, false));
    let y = resolve(&spec.y, &axis_values(&all, false, true));
    let rows = curves.len().div_ceil(cols).max(1);
    let panels = body.split_evenly((rows, cols));
    for (c, area) in curves.iter().zip(&panels) {
        let lk = look(c.look);
        let mut chart = frame(area, Some(&c.name), &x, &y, "", "", PANEL)?;
        if let Some(r) = reference.filter(|r| r.name != c.name) {
            let (line, _) = mapped(&x, &y, r, spec.step);
            let grey = Look {
                color: RGBColor(110, 110, 110),
                dash: Dash::Dashed,
                marker: Marker::Circle,
            };
            draw_line(&mut chart, &line, grey, 1)?;
        }
        let (line, band) = mapped(&x, &y, c, spec.step);
        if line.is_empty() {
            let (w, h) = area.dim_in_pixel();
            let font = (FAMILY, PANEL.label + 1)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center));
            area.draw(&Text::new(
                "no median: most runs without a value",
                (w as i32 / 2 + PANEL.y_area as i32 / 2, h as i32 / 2),
                font,
            ))
            .map_err(err)?;
            continue;
        }
        chart
            .draw_series([Polygon::new(band, lk.color.mix(0.22))])
            .map_err(err)?;
        draw_line(
            &mut chart,
            &line,
            Look {
                dash: Dash::Solid,
                ..lk
            },
            2,
        )?;
    }
    root.present().map_err(err)?;
    Ok(())
}

/// Small multiples: one panel per curve with its quartile band, the `reference` curve dashed
/// grey in every panel, shared axes (their titles go into `spec.title`). Returns the files
/// written.
pub fn facet_plot(
    dir: &Path,
    name: &str,
    spec: &CurveSpec,
    curves: &[Curve],
    reference: Option<&Curve>,
) -> Files {
    let cols = if curves.len() <= 4 {
        curves.len().max(1)
    } else {
        4
    };
    let rows = curves.len().div_ceil(cols).max(1) as u32;
    both!(dir, name, (1200, 60 + 230 * rows), |r| draw_facets(
        r, spec, curves, reference, cols
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_clean() {
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(1e-4 * (1.0 - 1e-14)), "10⁻⁴");
        assert_eq!(tick_label(10f64.powf(-5.0)), "10⁻⁵");
        assert_eq!(tick_label(0.001), "0.001");
        assert_eq!(tick_label(0.25), "0.25");
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(40.0), "40");
        assert_eq!(tick_label(1000.0), "1000");
        assert_eq!(tick_label(1e4), "10⁴");
        assert_eq!(tick_label(2e5), "2·10⁵");
        assert_eq!(tick_label(10f64.powf(6.0)), "10⁶");
        assert_eq!(tick_label(-2.5), "−2.5");
    }

    #[test]
    fn log_axes_have_decade_ticks() {
        let t = resolve(&Axis::log("x"), &[3e-6, 0.7, 12.0]);
        assert_eq!((t.lo, t.hi), (-6.0, 2.0));
        assert_eq!(t.major, (-6..=2).map(f64::from).collect::<Vec<_>>());
        let labels: Vec<String> = t.major.iter().map(|&m| t.label(m)).collect();
        assert_eq!(
            labels,
            [
                "10⁻⁶", "10⁻⁵", "10⁻⁴", "0.001", "0.01", "0.1", "1", "10", "100"
            ]
        );
        // less than a decade: 1, 2, 5 ticks
        let t = resolve(&Axis::log("x"), &[1.5, 4.0]);
        let labels: Vec<String> = t.major.iter().map(|&m| t.label(m)).collect();
        assert_eq!(labels, ["1", "2", "5", "10"]);
    }

    #[test]
    fn log_axis_with_zero_draws_zero_a_decade_below() {
        let t = resolve(
            &Axis::linear("gap").with_scale(Scale::LogWithZero),
            &[0.0, 0.02, 40.0],
        );
        assert_eq!(t.zero, Some(-3.0));
        assert_eq!(t.label(-3.0), "0");
        assert_eq!(t.map(0.0), Some(-3.0));
        assert_eq!(t.map(0.02), Some(0.02f64.log10()));
        assert_eq!(t.hi, 2.0);
    }

    #[test]
    fn linear_ticks_are_multiples_of_a_nice_step() {
        let t = resolve(&Axis::linear("y"), &[0.013, 0.96]);
        assert_eq!(t.major, vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]);
        let labels: Vec<String> = t.major.iter().map(|&m| t.label(m)).collect();
        assert_eq!(labels, ["0", "0.2", "0.4", "0.6", "0.8", "1"]);
        let t = resolve(&Axis::linear("y").with_range(0.0, 1.02), &[]);
        assert_eq!((t.lo, t.hi), (0.0, 1.02));
    }

    #[test]
    fn looks_are_distinct_for_many_series() {
        let looks: Vec<Look> = (0..27).map(look).collect();
        for i in 0..looks.len() {
            for j in 0..i {
                assert!(
                    (looks[i].color, looks[i].dash) != (looks[j].color, looks[j].dash),
                    "{i} and {j} look alike"
                );
            }
        }
    }
}
