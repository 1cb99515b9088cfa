//! Pictures of instances and solutions (SVG or PNG, with plotters).
//!
//! Cells are drawn in the XY plane, coloured by tool: an open cell as a line from its entry
//! (filled dot) to its exit (hollow square); a closed cell as a hollow circle at its start
//! point; other candidate modes as small dots. With a sequence, the air moves between
//! consecutive cells (from the home position on) are drawn in grey, in order, with the mode
//! the sequence chose. Text uses the font of [`super`] ([`super::FONT`]), so no system font
//! package is needed.

use super::register_font;
use cellseq::error::{Error, Result};
use cellseq::model::{Instance, Sequence};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Output picture format, from the file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PictureFormat {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics.
    Png,
}

impl PictureFormat {
    /// `.svg` or `.png` (case-insensitive); anything else is an error naming the file.
    pub fn of(path: &Path) -> Result<PictureFormat> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
        {
            Some(e) if e == "svg" => Ok(PictureFormat::Svg),
            Some(e) if e == "png" => Ok(PictureFormat::Png),
            _ => Err(Error::invalid(
                path.display().to_string(),
                "the picture must be a .svg or .png file",
            )),
        }
    }
}

/// Draws `inst` (and the air moves of `seq`, if given) to `out` (.svg or .png).
pub fn plot(inst: &Instance, seq: Option<&Sequence>, caption: &str, out: &Path) -> Result<()> {
    let fmt = PictureFormat::of(out)?;
    if inst.is_matrix() {
        return Err(Error::invalid(
            inst.name.clone(),
            "matrix instances (TSPLIB SOP, PCGTSP) have no geometry to plot",
        ));
    }
    register_font();
    let file = out.display().to_string();
    let (w, h) = picture_size(inst);
    let err = |e: String| Error::invalid(&file, format!("drawing failed: {e}"));
    // Drawn in memory and written once, through the safe write of `cellseq::files::write_atomic`.
    let bytes = match fmt {
        PictureFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                draw(&root, inst, seq, caption).map_err(err)?;
                root.present().map_err(|e| err(e.to_string()))?;
            }
            text.into_bytes()
        }
        PictureFormat::Png => {
            let mut rgb = vec![0u8; w as usize * h as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
                draw(&root, inst, seq, caption).map_err(err)?;
                root.present().map_err(|e| err(e.to_string()))?;
            }
            encode_png(&rgb, w, h).map_err(err)?
        }
    };
    cellseq::files::write_atomic(out, &bytes)
}

/// Encodes an RGB8 buffer of `w` × `h` pixels as PNG.
pub fn encode_png(rgb: &[u8], w: u32, h: u32) -> std::result::Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// The XY bounding box of every entry/exit point: (xmin, xmax, ymin, ymax), padded.
pub fn bounds(inst: &Instance) -> (f64, f64, f64, f64) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for c in &inst.cells {
        for m in &c.modes {
            for p in [m.entry, m.exit] {
                x0 = x0.min(p.x);
                x1 = x1.max(p.x);
                y0 = y0.min(p.y);
                y1 = y1.max(p.y);
            }
        }
    }
    if x0 > x1 {
        return (0.0, 1.0, 0.0, 1.0);
    }
    let pad = 0.05 * (x1 - x0).max(y1 - y0).max(1.0);
    (x0 - pad, x1 + pad, y0 - pad, y1 + pad)
}

fn picture_size(inst: &Instance) -> (u32, u32) {
    let (x0, x1, y0, y1) = bounds(inst);
    let aspect = ((y1 - y0) / (x1 - x0)).clamp(0.2, 3.0);
    let w = 1200u32;
    let h = (w as f64 * aspect) as u32 + 120;
    (w, h.min(3000))
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    inst: &Instance,
    seq: Option<&Sequence>,
    caption: &str,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let (x0, x1, y0, y1) = bounds(inst);
    let mut chart = ChartBuilder::on(root)
        .caption(caption, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("x (mm)")
        .y_desc("y (mm)")
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(e)?;
    let tools = inst.used_tools();
    let n = inst.n();
    let small = n > 2000;
    let (dot, mark) = if small { (1, 2) } else { (2, 4) };
    // chosen mode per cell
    let mut chosen = vec![0usize; n];
    if let Some(s) = seq {
        for v in s {
            if v.cell < n {
                chosen[v.cell] = v.mode;
            }
        }
    }
    // air moves first, under the cells
    if let Some(s) = seq {
        let mut prev = (inst.machine.home.x, inst.machine.home.y);
        let grey = RGBColor(110, 110, 110).mix(0.8);
        let mut moves = Vec::with_capacity(s.len());
        for v in s {
            let Some(m) = inst.cells.get(v.cell).and_then(|c| c.modes.get(v.mode)) else {
                continue;
            };
            moves.push(vec![prev, (m.entry.x, m.entry.y)]);
            prev = (m.exit.x, m.exit.y);
        }
        chart
            .draw_series(
                moves
                    .into_iter()
                    .map(|pts| PathElement::new(pts, grey.stroke_width(1))),
            )
            .map_err(e)?
            .label("air move")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], grey));
    }
    for (ti, t) in tools.iter().enumerate() {
        let col = Palette99::pick(ti).to_rgba();
        let cells: Vec<usize> = (0..n).filter(|&i| inst.cells[i].tool == *t).collect();
        let label = inst
            .tool(t)
            .map(|tl| format!("{} (D{})", tl.id, tl.diameter))
            .unwrap_or_else(|| t.to_string());
        // cutting lines of open cells
        chart
            .draw_series(cells.iter().filter_map(|&i| {
                let m = inst.cells[i].modes.get(chosen[i])?;
                (m.entry != m.exit).then(|| {
                    PathElement::new(
                        vec![(m.entry.x, m.entry.y), (m.exit.x, m.exit.y)],
                        col.stroke_width(2),
                    )
                })
            }))
            .map_err(e)?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], col.filled()));
        // other modes: small dots
        chart
            .draw_series(cells.iter().flat_map(|&i| {
                let c = &inst.cells[i];
                let k = chosen[i];
                c.modes
                    .iter()
                    .enumerate()
                    .filter(move |(j, _)| *j != k)
                    .map(move |(_, m)| {
                        Circle::new((m.entry.x, m.entry.y), 1, col.mix(0.5).filled())
                    })
            }))
            .map_err(e)?;
        // entry dots, exit squares, closed circles
        chart
            .draw_series(cells.iter().filter_map(|&i| {
                let m = inst.cells[i].modes.get(chosen[i])?;
                Some(Circle::new((m.entry.x, m.entry.y), dot + 1, col.filled()))
            }))
            .map_err(e)?;
        chart
            .draw_series(cells.iter().filter_map(|&i| {
                let m = inst.cells[i].modes.get(chosen[i])?;
                (m.entry == m.exit).then(|| {
                    EmptyElement::at((m.exit.x, m.exit.y))
                        + Circle::new((0, 0), mark + 2, col.stroke_width(1))
                })
            }))
            .map_err(e)?;
        chart
            .draw_series(cells.iter().filter_map(|&i| {
                let m = inst.cells[i].modes.get(chosen[i])?;
                (m.entry != m.exit).then(|| {
                    EmptyElement::at((m.exit.x, m.exit.y))
                        + Rectangle::new([(-mark, -mark), (mark, mark)], col.stroke_width(1))
                })
            }))
            .map_err(e)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(e)?;
    Ok(())
}

/// One panel of a program or drawing picture: cutting polylines and air moves in the XY
/// plane (mm), in the file's own coordinates.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// Pen-down / cutting polylines, in order.
    pub cuts: Vec<Vec<(f64, f64)>>,
    /// Air moves (pen up, rapid), in order.
    pub air: Vec<[(f64, f64); 2]>,
}

impl Panel {
    /// Total air length (XY).
    pub fn air_length(&self) -> f64 {
        self.air
            .iter()
            .map(|[a, b]| ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt())
            .sum()
    }
}

/// The panel of an interpreted G-code program: its cutting moves (arcs in the XY plane drawn
/// as arcs) and an air move wherever one cut does not start where the previous one ended.
pub fn program_panel(title: &str, prog: &cellseq_programs::gcode::interp::Program) -> Panel {
    use cellseq_programs::gcode::interp::CutKind;
    let mut p = Panel {
        title: title.to_string(),
        ..Panel::default()
    };
    let mut at: Option<(f64, f64)> = None;
    for c in prog.lines.iter().flat_map(|l| &l.cuts) {
        let from = (c.from[0], c.from[1]);
        let to = (c.to[0], c.to[1]);
        if let Some(a) = at
            && a != from
        {
            p.air.push([a, from]);
        }
        let pts = match c.kind {
            CutKind::Arc {
                center,
                cw,
                plane: 17,
                turns,
            } => arc_pts(from, to, (center[0], center[1]), cw, turns),
            _ => vec![from, to],
        };
        // join with the previous polyline when it continues it
        match p.cuts.last_mut() {
            Some(last) if at == Some(from) => last.extend(pts.into_iter().skip(1)),
            _ => p.cuts.push(pts),
        }
        at = Some(to);
    }
    p
}

fn arc_pts(
    from: (f64, f64),
    to: (f64, f64),
    c: (f64, f64),
    cw: bool,
    turns: u32,
) -> Vec<(f64, f64)> {
    let tau = std::f64::consts::TAU;
    let r = ((from.0 - c.0).powi(2) + (from.1 - c.1).powi(2)).sqrt();
    let a0 = (from.1 - c.1).atan2(from.0 - c.0);
    let a1 = (to.1 - c.1).atan2(to.0 - c.0);
    let mut sweep = if cw {
        -(a0 - a1).rem_euclid(tau)
    } else {
        (a1 - a0).rem_euclid(tau)
    };
    if sweep == 0.0 {
        sweep = if cw { -tau } else { tau };
    }
    sweep += (turns.saturating_sub(1).min(100) as f64) * sweep.signum() * tau;
    let n = ((sweep.abs() / tau * 72.0).ceil() as usize).clamp(2, 2000);
    let mut v: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let a = a0 + sweep * i as f64 / n as f64;
            (c.0 + r * a.cos(), c.1 + r * a.sin())
        })
        .collect();
    if let Some(l) = v.last_mut() {
        *l = to;
    }
    v
}

/// The panel of drawing strokes in this order (user units scaled to mm), air moves between
/// consecutive strokes.
pub fn drawing_panel(
    title: &str,
    d: &cellseq_programs::drawing::Drawing,
    strokes: &[cellseq_programs::drawing::Stroke],
) -> Panel {
    let k = d.mm_per_unit;
    let mut p = Panel {
        title: title.to_string(),
        ..Panel::default()
    };
    let mut at: Option<(f64, f64)> = None;
    for s in strokes {
        let mut pts: Vec<(f64, f64)> = s.points.iter().map(|q| (q[0] * k, q[1] * k)).collect();
        if s.closed {
            pts.push(pts[0]);
        }
        let start = pts[0];
        if let Some(a) = at
            && a != start
        {
            p.air.push([a, start]);
        }
        at = pts.last().copied();
        p.cuts.push(pts);
    }
    p
}

/// Draws panels side by side (or, with `overlay`, the last panel's cuts with every panel's
/// air moves in one picture). `y_down`: the file's y axis grows downwards (SVG), so the
/// picture is drawn that way, as a browser shows the file.
pub fn plot_panels(panels: &[Panel], y_down: bool, overlay: bool, out: &Path) -> Result<()> {
    let fmt = PictureFormat::of(out)?;
    register_font();
    let file = out.display().to_string();
    if panels.is_empty() {
        return Err(Error::invalid(&file, "nothing to plot"));
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in panels {
        for &(x, y) in p.cuts.iter().flatten().chain(p.air.iter().flatten()) {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    // the axes' ticks of a span beyond the coordinate limit never end (plotters loops)
    let limit = cellseq::validate::MAX_COORD;
    if let Some(v) = [x0, x1, y0, y1]
        .into_iter()
        .find(|v| !(v.is_finite() && v.abs() <= limit))
    {
        return Err(Error::invalid(
            &file,
            format!(
                "the drawing reaches {} mm, beyond the coordinate limit of {} mm: nothing is drawn",
                cellseq::params::float_text(v),
                cellseq::params::float_text(limit)
            ),
        ));
    }
    let pad = 0.04 * (x1 - x0).max(y1 - y0).max(1e-6);
    let bx = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    let cols = if overlay { 1 } else { panels.len() as u32 };
    let aspect = ((bx.3 - bx.2) / (bx.1 - bx.0)).clamp(0.2, 3.0);
    let pw = if cols > 1 { 800u32 } else { 1200 };
    let size = (pw * cols, ((pw as f64 * aspect) as u32 + 120).min(3000));
    let err = |e: String| Error::invalid(&file, format!("drawing failed: {e}"));
    // Drawn in memory and written once, through the safe write of `cellseq::files::write_atomic`.
    let bytes = match fmt {
        PictureFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
                draw_panels(&root, panels, bx, y_down, overlay).map_err(err)?;
                root.present().map_err(|e| err(e.to_string()))?;
            }
            text.into_bytes()
        }
        PictureFormat::Png => {
            let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
                draw_panels(&root, panels, bx, y_down, overlay).map_err(err)?;
                root.present().map_err(|e| err(e.to_string()))?;
            }
            encode_png(&rgb, size.0, size.1).map_err(err)?
        }
    };
    cellseq::files::write_atomic(out, &bytes)
}

fn draw_panels<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    panels: &[Panel],
    bx: (f64, f64, f64, f64),
    y_down: bool,
    overlay: bool,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let areas = if overlay {
        vec![root.clone()]
    } else {
        root.split_evenly((1, panels.len()))
    };
    // y down: plot -y and label the ticks with y
    let fy = |y: f64| if y_down { -y } else { y };
    let (ya, yb) = if y_down { (-bx.3, -bx.2) } else { (bx.2, bx.3) };
    let air_colours = [RGBColor(150, 150, 150), RGBColor(220, 30, 30)];
    for (i, area) in areas.iter().enumerate() {
        let shown: Vec<(usize, &Panel)> = if overlay {
            panels.iter().enumerate().collect()
        } else {
            vec![(i, &panels[i])]
        };
        let main = shown.last().expect("a panel").1;
        let caption = if overlay {
            shown
                .iter()
                .map(|(_, p)| format!("{}: air {:.0} mm", p.title, p.air_length()))
                .collect::<Vec<_>>()
                .join("   ")
        } else {
            format!("{}: air {:.0} mm", main.title, main.air_length())
        };
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(bx.0..bx.1, ya..yb)
            .map_err(e)?;
        let ylab = |v: &f64| format!("{}", if y_down { -*v } else { *v });
        chart
            .configure_mesh()
            .x_desc("x (mm)")
            .y_desc(if y_down { "y (mm, down)" } else { "y (mm)" })
            .y_label_formatter(&ylab)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(e)?;
        chart
            .draw_series(main.cuts.iter().map(|c| {
                PathElement::new(
                    c.iter().map(|&(x, y)| (x, fy(y))).collect::<Vec<_>>(),
                    RGBColor(20, 60, 200).stroke_width(1),
                )
            }))
            .map_err(e)?
            .label("cutting / pen down")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], RGBColor(20, 60, 200)));
        for (k, (j, p)) in shown.iter().enumerate() {
            let col = if overlay {
                air_colours[(k + air_colours.len() - shown.len()).min(1)]
            } else {
                air_colours[(*j).min(1)]
            };
            chart
                .draw_series(p.air.iter().map(|[a, b]| {
                    PathElement::new(vec![(a.0, fy(a.1)), (b.0, fy(b.1))], col.stroke_width(1))
                }))
                .map_err(e)?
                .label(format!("air ({})", p.title))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], col));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(e)?;
    }
    Ok(())
}
