//! `optimize` and `import` of drawings (SVG, DXF): read, sequence, verify, write.

use super::gcode::{ImportArgs, OptimizeArgs};
use super::rows::{Table, say_wrote, write_output};
use anyhow::{Context as _, bail};
use cellseq::SolverKind;
use cellseq::files::read_text;
use cellseq::formats::save_instance;
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
    let mut opts = svg_options(
        &d,
        &a.drawing,
        !a.no_reversible,
        SolverKind::Greedy,
        None,
        1,
    )?;
    if fmt == "dxf" {
        opts.cut = !a.drawing.no_inner_first;
    }
    let inst = pipe::import(&d, &opts)?;
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
    let file = path.display().to_string();
    let text = read_text(path)?;
    // the tolerance is given in mm; the reader works in user units
    Ok(svg::read::read_mm(
        &file,
        &text,
        d.tolerance,
        svg::ReadOptions {
            tolerance: d.tolerance,
            skip_unsupported: d.skip_unsupported,
            max_points: d.max_points,
        },
    )?)
}

fn svg_options(
    d: &svg::Drawing,
    a: &DrawingArgs,
    reversible: bool,
    solver: SolverKind,
    time_limit: Option<f64>,
    seed: u64,
) -> anyhow::Result<pipe::Options> {
    use pipe::{Blocks, Pens};
    if a.no_scopes && !matches!(a.pens, Pens::Auto | Pens::None) {
        bail!(
            "--no-scopes is --pens none: it cannot go with --pens {}",
            a.pens.name()
        );
    }
    if a.keep_group_order && a.blocks == Blocks::None {
        bail!("--keep-group-order keeps plain groups as blocks: it cannot go with --blocks none");
    }
    Ok(pipe::Options {
        solver,
        time_limit,
        max_evals: None,
        params: Default::default(),
        seed,
        reversible,
        scopes: !a.no_scopes,
        pens: a.pens,
        blocks: a.blocks,
        cut: a.cut,
        free_groups: !a.keep_group_order,
        contain_tol: a.contain_tol / d.mm_per_unit,
        max_starts: a.max_starts,
    })
}

/// The solver (default `drawing`), whether strokes may be reversed (by default yes) and the
/// pipeline options of `optimize` on drawing `d`.
fn optimize_options(
    a: &OptimizeArgs,
    d: &svg::Drawing,
) -> anyhow::Result<(SolverKind, bool, pipe::Options)> {
    let reversible = !a.no_reversible;
    let solver = match &a.solver {
        Some(s) => s.parse()?,
        None => pipe::DRAWING_SOLVER,
    };
    let mut opts = svg_options(d, &a.drawing, reversible, solver, a.time_limit, a.seed)?;
    opts.max_evals = a.max_evals;
    Ok((solver, reversible, opts))
}

/// The budget of the whole command, from its start (reading counts); `--time-limit` was
/// range-checked by its parser, and `Allowance::new` checks it again.
fn allowance(a: &OptimizeArgs) -> anyhow::Result<cellseq_programs::optimize::Allowance> {
    Ok(cellseq_programs::optimize::Allowance::new(
        a.time_limit,
        a.max_evals,
    )?)
}

/// The semantics line of the report: the reading kept, why, and the others tried.
fn say_semantics(out: &pipe::Optimized) {
    let others: Vec<String> = out
        .tried
        .iter()
        .filter(|(r, _)| *r != out.reading)
        .map(|(r, up)| format!("{r}: {up:.1} mm"))
        .collect();
    let also = if others.is_empty() {
        String::new()
    } else {
        format!("; also tried {}", others.join(", "))
    };
    say!("semantics: {} ({}){also}", out.reading, out.semantics);
}

/// The semantics of the JSON report.
fn json_semantics(out: &pipe::Optimized) -> serde_json::Value {
    serde_json::json!({
        "pens": out.reading.pens.name(),
        "blocks": out.reading.blocks.name(),
        "inner_first": out.reading.inner_first,
        "why": out.semantics,
        "tried": out.tried.iter().map(|(r, up)| serde_json::json!({
            "pens": r.pens.name(),
            "blocks": r.blocks.name(),
            "inner_first": r.inner_first,
            "pen_up_total_mm": up,
        })).collect::<Vec<_>>(),
    })
}

/// The elements the reader skipped, and the note when the original order was kept.
fn say_skipped(d: &svg::Drawing, note: Option<&String>) {
    for s in &d.skipped {
        say!("skipped: {s}");
    }
    if let Some(n) = note {
        say!("note: the drawing is kept in its original order ({n})");
    }
}

fn optimize_svg(a: &OptimizeArgs) -> anyhow::Result<()> {
    let file = a.input.display().to_string();
    let allowance = allowance(a)?;
    let t0 = allowance.started;
    let d = read_svg(&a.input, &a.drawing)?;
    let read_s = t0.elapsed().as_secs_f64();
    let (solver, reversible, opts) = optimize_options(a, &d)?;
    let mut out = pipe::optimize_within(&d, &opts, &allowance)?;
    let (text, segments) = pipe::render(&d, &mut out, pipe::Output::Svg)?;
    write_output(a.output.as_deref(), &text)?;
    let total_s = t0.elapsed().as_secs_f64();
    if a.json {
        let v = serde_json::json!({
            "input": file,
            "output": a.output.as_ref().map(|p| p.display().to_string()),
            "solver": solver.name(),
            "strokes": d.strokes.len(),
            "scopes": out.scopes,
            "precedence_edges": out.edges,
            "reversible": reversible,
            "verified_segments": segments,
            "skipped": d.skipped,
            "read_s": read_s,
            "solve_s": out.solve_s,
            "total_s": total_s,
            "kept_original_scopes": out.kept_original,
            "groups_reordered": out.groups_reordered,
            "semantics": json_semantics(&out),
            "kept_note": out.note,
            "before": out.before,
            "after": out.after,
        });
        say!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        say!(
            "{file}: {} strokes in {} scope(s); solver {} ({:.3} s, total {:.3} s); {} segments verified identical",
            d.strokes.len(),
            out.scopes,
            solver,
            out.solve_s,
            total_s,
            segments
        );
        say_skipped(&d, out.note.as_ref());
        say_semantics(&out);
        if out.groups_reordered {
            say!(
                "top-level groups drawn in a shorter order than the file's (--keep-group-order keeps it)"
            );
        }
        let (b, f) = (&out.before, &out.after);
        let t = Table::new(20);
        t.saved("pen-up mm (layer)", b.pen_up_mm, f.pen_up_mm);
        t.saved("pen-up mm (total)", b.pen_up_total_mm, f.pen_up_total_mm);
        t.counts("pen lifts", b.lifts, f.lifts);
        t.values("pen-down mm", b.draw_mm, f.draw_mm);
        say_wrote(a.output.as_deref());
    }
    Ok(())
}

fn read_dxf(path: &Path, d: &DrawingArgs) -> anyhow::Result<svg::Drawing> {
    let file = path.display().to_string();
    let bytes = cellseq::files::read_bytes(path)?;
    let units = match &d.units {
        Some(u) => Some(
            cellseq_programs::dxf::unit_mm(u)
                .with_context(|| format!("--units {u}: use mm, cm, m, in, ft, mil or um"))?,
        ),
        None => None,
    };
    let mut o = cellseq_programs::dxf::ReadOptions {
        tolerance: d.tolerance,
        join: d.join_tol,
        skip_unsupported: d.skip_unsupported,
        units,
    };
    let dr = cellseq_programs::dxf::read(&file, &bytes, o)?;
    if dr.mm_per_unit == 1.0 {
        return Ok(dr);
    }
    o.tolerance /= dr.mm_per_unit;
    o.join /= dr.mm_per_unit;
    Ok(cellseq_programs::dxf::read(&file, &bytes, o)?)
}

fn optimize_dxf(a: &OptimizeArgs) -> anyhow::Result<()> {
    use cellseq_programs::dxf;
    let file = a.input.display().to_string();
    let allowance = allowance(a)?;
    let t0 = allowance.started;
    let d = read_dxf(&a.input, &a.drawing)?;
    for w in &d.warnings {
        eprintln!("warning: {file}: {w}");
    }
    let (solver, reversible, mut opts) = optimize_options(a, &d)?;
    opts.cut = !a.drawing.no_inner_first;
    let mut out = pipe::optimize_within(&d, &opts, &allowance)?;
    let post = dxf::Post {
        safe_height: a.drawing.safe_height,
        depth: a.drawing.cut_depth,
        feed: a.drawing.feed,
        plunge_feed: a.drawing.plunge_feed,
        spindle: a.drawing.spindle,
        laser_power: a.drawing.laser_power,
    };
    let preview = a
        .output
        .as_ref()
        .and_then(|o| o.extension())
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    let kind = if preview {
        pipe::Output::Svg
    } else {
        pipe::Output::Gcode(&post)
    };
    let (text, segments) = pipe::render(&d, &mut out, kind)?;
    write_output(a.output.as_deref(), &text)?;
    let total_s = t0.elapsed().as_secs_f64();
    let closed = d.strokes.iter().filter(|s| s.closed).count();
    if a.json {
        let v = serde_json::json!({
            "input": file,
            "output": a.output.as_ref().map(|p| p.display().to_string()),
            "output_kind": if preview { "svg" } else { "gcode" },
            "solver": solver.name(),
            "contours": d.strokes.len(),
            "closed_contours": closed,
            "layers": d.layers.len() - 1,
            "scopes": out.scopes,
            "inner_first_edges": out.edges,
            "reversible": reversible,
            "verified_segments": segments,
            "skipped": d.skipped,
            "warnings": d.warnings,
            "mm_per_unit": d.mm_per_unit,
            "semantics": json_semantics(&out),
            "kept_note": out.note,
            "solve_s": out.solve_s,
            "total_s": total_s,
            "before": out.before,
            "after": out.after,
        });
        say!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        say!(
            "{file}: {} contours ({closed} closed) on {} layer(s); {} inner-first edges; solver {} ({:.3} s); {} segments verified identical",
            d.strokes.len(),
            d.layers.len() - 1,
            out.edges,
            solver,
            out.solve_s,
            segments
        );
        say_skipped(&d, out.note.as_ref());
        say_semantics(&out);
        say!(
            "travel mm (file order -> optimized): {:.1} -> {:.1}; pierces {} -> {}",
            out.before.pen_up_total_mm,
            out.after.pen_up_total_mm,
            out.before.lifts,
            out.after.lifts
        );
        say_wrote(a.output.as_deref());
    }
    Ok(())
}
