//! `optimize` and `import` of drawings (SVG, DXF): read, sequence, verify, write.

use super::gcode::{ImportArgs, OptimizeArgs};
use super::rows::{Table, say_wrote, write_output};
use anyhow::bail;
use cellseq::SolverKind;
use cellseq::files::read_text;
use cellseq::formats::save_instance;
use cellseq_programs::job::{self, Report};
use cellseq_programs::optimize::strokes as pipe;
use cellseq_programs::svg;
use clap::Args;
use std::path::Path;

/// Options of SVG and DXF input.
#[derive(Args, Debug, Clone)]
pub struct DrawingArgs {
    /// Curve flattening tolerance (mm).
    #[arg(long, default_value_t = 0.01, value_parser = super::ranges::tolerance)]
    pub tolerance: f64,
    /// Sequence the whole drawing at once instead of layer by layer / colour by colour (the
    /// same as `--pens none`).
    #[arg(long)]
    pub no_scopes: bool,
    /// What a pen is: the strokes of one pen are drawn together, pens in the file's order.
    /// `layer`: a layer is a pen (AxiDraw, Inkscape); `colour`: a stroke colour is a pen
    /// inside each layer (vpype --attr stroke, LightBurn); `none`: one pen, as --no-scopes;
    /// `auto`: `layer` when the file has Inkscape layers (every DXF layer), else `colour`,
    /// and the strictest reading too when it differs (the shorter is kept; see
    /// docs/drawings.md).
    #[arg(long, default_value = "auto", value_name = "layer|colour|none|auto", value_parser = parse_pens)]
    pub pens: pipe::Pens,
    /// What a plain group that is a child of the root (not an Inkscape layer) is. `group`: a
    /// part, drawn as one block with its own pen order, the order of the blocks free;
    /// `none`: only grouping, a run of such groups is ordered by pen alone; `auto`: `group`
    /// for boxes.py files, else `none` and `group` both, the shorter kept.
    #[arg(long, default_value = "auto", value_name = "group|none|auto", value_parser = parse_blocks)]
    pub blocks: pipe::Blocks,
    /// Cut mode: strokes inside a closed stroke are drawn/cut before it.
    #[arg(long)]
    pub cut: bool,
    /// SVG: draw the file's plain top-level groups (boxes.py parts, …) in the file's order.
    /// By default only Inkscape layers keep their order; plain groups between them are drawn
    /// in the order of least pen-up travel, each still as one contiguous block (see
    /// docs/drawings.md).
    #[arg(long)]
    pub keep_group_order: bool,
    /// Containment tolerance of cut mode (mm).
    #[arg(long, default_value_t = 0.01, value_parser = super::ranges::contain_tol)]
    pub contain_tol: f64,
    /// Start-vertex candidates per closed stroke when reversible.
    #[arg(long, default_value_t = 8, value_parser = super::ranges::max_starts)]
    pub max_starts: usize,
    /// SVG: drop the elements that are not sequenced (text, images, `<use>`, metadata, …)
    /// from the output instead of keeping them as they are; DXF: skip unsupported entities
    /// (text, hatches, …) instead of refusing the file.
    #[arg(long)]
    pub skip_unsupported: bool,
    /// Most points a drawing may have after flattening its curves (a cap against hostile
    /// files; raise it for huge drawings).
    #[arg(long, default_value_t = 10_000_000, value_name = "N", value_parser = super::ranges::max_points)]
    pub max_points: usize,
    /// DXF: chain loose pieces whose endpoints are closer than this (mm).
    #[arg(long, default_value_t = 0.001, value_parser = super::ranges::join_tol)]
    pub join_tol: f64,
    /// DXF: do not put inner contours first (cut mode is on by default for DXF).
    #[arg(long)]
    pub no_inner_first: bool,
    /// DXF G-code post: safe height (mm).
    #[arg(long, default_value_t = 5.0, value_parser = super::ranges::safe_height)]
    pub safe_height: f64,
    /// DXF G-code post: cutting depth below Z0 (mm).
    #[arg(long, default_value_t = 1.0, value_parser = super::ranges::cut_depth)]
    pub cut_depth: f64,
    /// DXF G-code post: cutting feed (mm/min).
    #[arg(long, default_value_t = 1000.0, value_parser = super::ranges::feed)]
    pub feed: f64,
    /// DXF G-code post: plunge / pierce feed (mm/min).
    #[arg(long, default_value_t = 300.0, value_parser = super::ranges::plunge_feed)]
    pub plunge_feed: f64,
    /// DXF G-code post: spindle speed (M3 S… before the first cut, M5 at the end); 0 writes
    /// no spindle words (the operator's spindle state is left alone).
    #[arg(long, default_value_t = 0.0, conflicts_with = "laser_power", value_parser = super::ranges::spindle)]
    pub spindle: f64,
    /// DXF G-code post for a laser: power S (M4 S…, off on rapids; M5 at the end), no Z moves.
    #[arg(long, default_value_t = 0.0, value_name = "S", value_parser = super::ranges::laser_power)]
    pub laser_power: f64,
    /// DXF: the drawing unit when the file does not say (`$INSUNITS`): mm, cm, m, in, ft, mil
    /// or um (default mm, with a warning).
    #[arg(long, value_name = "UNIT")]
    pub units: Option<String>,
}

fn parse_pens(s: &str) -> Result<pipe::Pens, String> {
    pipe::Pens::parse(s).ok_or_else(|| format!("'{s}': use layer, colour, none or auto"))
}

fn parse_blocks(s: &str) -> Result<pipe::Blocks, String> {
    pipe::Blocks::parse(s).ok_or_else(|| format!("'{s}': use group, none or auto"))
}

/// `optimize` of a drawing (`fmt` is `svg` or `dxf`).
pub fn optimize(a: &OptimizeArgs, fmt: &str) -> anyhow::Result<()> {
    match fmt {
        "svg" => optimize_svg(a),
        "dxf" => optimize_dxf(a),
        other => bail!("{}: {other} input is not supported", a.input.display()),
    }
}

/// `import` of a drawing (`fmt` is `svg` or `dxf`).
pub fn import(a: &ImportArgs, fmt: &str) -> anyhow::Result<()> {
    if fmt != "svg" && fmt != "dxf" {
        bail!("{}: {fmt} input is not supported", a.input.display());
    }
    let file = a.input.display().to_string();
    let d = if fmt == "svg" {
        read_svg(&a.input, &a.drawing)?
    } else {
        read_dxf(&a.input, &a.drawing)?
    };
    let mut drawing = drawing_options(&a.drawing, false);
    if fmt == "dxf" {
        drawing.cut = Some(!a.drawing.no_inner_first);
    }
    let jo = job::Options {
        solver: Some(SolverKind::Greedy),
        reversible: Some(!a.no_reversible),
        drawing,
        ..Default::default()
    };
    let format = if fmt == "dxf" {
        job::Format::Dxf
    } else {
        job::Format::Svg
    };
    let inst = pipe::import(&d, &job::drawing_options(&d, format, &jo))?;
    cellseq::validate::validate(&inst, &file)?;
    save_instance(&a.output, &inst)?;
    say!(
        "{}: {} strokes, {} precedence edges -> {}",
        file,
        inst.n(),
        inst.precedence.len(),
        a.output.display()
    );
    Ok(())
}

fn read_svg(path: &Path, d: &DrawingArgs) -> anyhow::Result<svg::Drawing> {
    let text = read_text(path)?;
    Ok(job::read_svg(
        &path.display().to_string(),
        &text,
        &drawing_options(d, false),
    )?)
}

/// The drawing options of `a` for the library ([`job::DrawingOptions`]); `svg_output` for a DXF
/// preview.
fn drawing_options(a: &DrawingArgs, svg_output: bool) -> job::DrawingOptions {
    let (pens, blocks) = if a.no_scopes {
        (pipe::Pens::None, pipe::Blocks::None)
    } else {
        (a.pens, a.blocks)
    };
    job::DrawingOptions {
        tolerance: a.tolerance,
        pens,
        blocks,
        cut: if a.cut { Some(true) } else { None },
        keep_group_order: a.keep_group_order,
        contain_tol: a.contain_tol,
        max_starts: a.max_starts,
        skip_unsupported: a.skip_unsupported,
        max_points: a.max_points,
        join_tol: a.join_tol,
        units: a.units.clone(),
        svg_output,
        post: cellseq_programs::dxf::Post {
            safe_height: a.safe_height,
            depth: a.cut_depth,
            feed: a.feed,
            plunge_feed: a.plunge_feed,
            spindle: a.spindle,
            laser_power: a.laser_power,
        },
    }
}

/// The library options of `optimize` on a file of format `fmt` (`gcode`, `svg`, `dxf`).
pub(super) fn job_options(a: &OptimizeArgs, fmt: &str) -> anyhow::Result<job::Options> {
    use pipe::{Blocks, Pens};
    let d = &a.drawing;
    if d.no_scopes && !matches!(d.pens, Pens::Auto | Pens::None) {
        bail!(
            "--no-scopes is --pens none: it cannot go with --pens {}",
            d.pens.name()
        );
    }
    if d.keep_group_order && d.blocks == Blocks::None {
        bail!("--keep-group-order keeps plain groups as blocks: it cannot go with --blocks none");
    }
    let solver = a.solver.as_deref().map(str::parse).transpose()?;
    let reversible = if a.reversible {
        Some(true)
    } else if a.no_reversible {
        Some(false)
    } else {
        None
    };
    let mut drawing = drawing_options(d, false);
    if fmt == "dxf" {
        drawing.cut = Some(!d.no_inner_first);
        drawing.svg_output = a
            .output
            .as_ref()
            .and_then(|o| o.extension())
            .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    }
    Ok(job::Options {
        solver,
        time_limit: a.time_limit,
        max_evals: a.max_evals,
        seed: a.seed,
        params: Default::default(),
        reversible,
        merge_tool_blocks: a.merge_tool_blocks,
        margin: a.margin,
        drawing,
    })
}

/// The elements the reader skipped, and the note when the original order was kept.
fn say_skipped(skipped: &[String], note: Option<&String>) {
    for s in skipped {
        say!("skipped: {s}");
    }
    if let Some(n) = note {
        say!("note: the drawing is kept in its original order ({n})");
    }
}

fn optimize_svg(a: &OptimizeArgs) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let opts = job_options(a, "svg")?;
    let mut j = job::optimize_file_as(&a.input, Some("svg"), &opts)?;
    write_output(a.output.as_deref(), &j.text)?;
    j.report.set_total_s(t0.elapsed().as_secs_f64());
    if a.json {
        let v = j.report.to_json(a.output.as_deref());
        say!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let Report::Svg(r) = &j.report else {
        bail!("{}: not read as SVG", a.input.display());
    };
    say!(
        "{}: {} strokes in {} scope(s); solver {} ({:.3} s, total {:.3} s); {} segments verified identical",
        r.input,
        r.strokes,
        r.scopes,
        r.solver,
        r.solve_s,
        r.total_s,
        r.verified_segments
    );
    say_skipped(&r.skipped, r.kept_note.as_ref());
    say!("semantics: {}", r.semantics.line());
    if r.groups_reordered {
        say!(
            "top-level groups drawn in a shorter order than the file's (--keep-group-order keeps it)"
        );
    }
    let (b, f) = (&r.before, &r.after);
    let t = Table::new(20);
    t.saved("pen-up mm (layer)", b.pen_up_mm, f.pen_up_mm);
    t.saved("pen-up mm (total)", b.pen_up_total_mm, f.pen_up_total_mm);
    t.counts("pen lifts", b.lifts, f.lifts);
    t.values("pen-down mm", b.draw_mm, f.draw_mm);
    say_wrote(a.output.as_deref());
    Ok(())
}

fn read_dxf(path: &Path, d: &DrawingArgs) -> anyhow::Result<svg::Drawing> {
    let bytes = cellseq::files::read_bytes(path)?;
    Ok(job::read_dxf(
        &path.display().to_string(),
        &bytes,
        &drawing_options(d, false),
    )?)
}

fn optimize_dxf(a: &OptimizeArgs) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let opts = job_options(a, "dxf")?;
    let mut j = job::optimize_file_as(&a.input, Some("dxf"), &opts)?;
    write_output(a.output.as_deref(), &j.text)?;
    j.report.set_total_s(t0.elapsed().as_secs_f64());
    let Report::Dxf(r) = &j.report else {
        bail!("{}: not read as DXF", a.input.display());
    };
    for w in &r.warnings {
        eprintln!("warning: {}: {w}", r.input);
    }
    if a.json {
        let v = j.report.to_json(a.output.as_deref());
        say!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    say!(
        "{}: {} contours ({} closed) on {} layer(s); {} inner-first edges; solver {} ({:.3} s); {} segments verified identical",
        r.input,
        r.contours,
        r.closed_contours,
        r.layers,
        r.inner_first_edges,
        r.solver,
        r.solve_s,
        r.verified_segments
    );
    say_skipped(&r.skipped, r.kept_note.as_ref());
    say!("semantics: {}", r.semantics.line());
    say!(
        "travel mm (file order -> optimized): {:.1} -> {:.1}; pierces {} -> {}",
        r.before.pen_up_total_mm,
        r.after.pen_up_total_mm,
        r.before.lifts,
        r.after.lifts
    );
    say_wrote(a.output.as_deref());
    Ok(())
}
