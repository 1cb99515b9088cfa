//! Pictures of instances and solutions (SVG or PNG, with plotters).
//!
//! Cells are drawn in the XY plane, coloured by tool: an open cell as a line from its entry
//! (filled dot) to its exit (hollow square); a closed cell as a hollow circle at its start
//! point; other candidate modes as small dots. With a sequence, the air moves between
//! consecutive cells (from the home position on) are drawn in grey, in order, with the mode
//! the sequence chose. Text uses the DejaVu Sans font embedded in the binary
//! (`assets/fonts/DejaVuSans.ttf`, free licence in `assets/fonts/DejaVu-LICENSE.txt`), so no
//! system font package is needed.

use crate::error::{Error, Result};
use crate::model::{Instance, Sequence};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// The embedded font (DejaVu Sans, Bitstream Vera derived free licence).
pub const FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The embedded font is a valid TTF; a failure would only lose the text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

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
    // Drawn in memory and written once, through the safe write of `formats::write_atomic`.
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
    crate::formats::write_atomic(out, &bytes)
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
