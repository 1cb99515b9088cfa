//! Real programs: G-code and drawings optimized as `cellseq optimize` does (text or a path in,
//! the new text and the report of `--json` out, verified the same way).

use crate::convert;
use crate::errors::{guard, rs, value_error};
use crate::info::solver_kind;
use cellseq::files::{ensure_not_input, read_text, write_atomic};
use cellseq_programs::optimize::Allowance;
use cellseq_programs::optimize::gcode as gpipe;
use cellseq_programs::optimize::strokes as spipe;
use cellseq_programs::{dxf, gcode, svg};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// An optimized program or drawing: the new text, and the report `cellseq optimize --json`
/// prints for it (before and after figures, what was verified, where the original was kept).
#[pyclass(name = "Optimized", module = "cellseq", frozen)]
pub struct PyOptimized {
    /// The new text.
    #[pyo3(get)]
    text: String,
    /// The report (JSON value).
    report: serde_json::Value,
    /// The input file, when read from one.
    input: Option<PathBuf>,
}

#[pymethods]
impl PyOptimized {
    /// The report as a dict (the object of `cellseq optimize --json`).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::json_to_py(py, &self.report)
    }
    /// Writes the text to `path` atomically; writing over the input file needs
    /// `overwrite_input=True`.
    #[pyo3(signature = (path, overwrite_input=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, overwrite_input: bool) -> PyResult<()> {
        py.detach(|| {
            guard("save", || {
                if let Some(i) = &self.input {
                    rs(ensure_not_input(i, &path, overwrite_input))?;
                }
                rs(write_atomic(&path, self.text.as_bytes()))
            })
        })
    }
    fn __repr__(&self) -> String {
        format!("<cellseq.Optimized: {} bytes>", self.text.len())
    }
}

/// The input text and the name errors use: exactly one of `path` and `text`.
fn source(path: Option<&Path>, text: Option<String>) -> PyResult<(String, String)> {
    match (path, text) {
        (Some(p), None) => Ok((p.display().to_string(), rs(read_text(p))?)),
        (None, Some(t)) => Ok(("<text>".to_string(), t)),
        _ => Err(value_error("give exactly one of path and text")),
    }
}

/// A time limit checked as the command line checks it.
fn limit(t: Option<f64>) -> PyResult<Option<f64>> {
    if let Some(t) = t {
        rs(cellseq::solve::checked_seconds("time_limit", t))?;
    }
    Ok(t)
}

/// Optimizes a G-code program (LinuxCNC, Fanuc-style, GRBL) as `cellseq optimize` does: cells
/// sequenced group by group (tool blocks keep their order unless `merge_tool_blocks`), the
/// program written state-exact and verified move by move against the original (every cut in
/// the original's machine state, no new motion), never worse than the input on air travel,
/// lifts and time, else the original order is kept and the report says so.
///
/// Give `path` or `text`. `time_limit` covers the whole call; without it and without
/// `max_evals`, a deterministic evaluation budget. `reversible`: `None` (on for 2-D programs:
/// laser, plasma, plotter; off with Z moves), `True` or `False`. Returns an `Optimized` (its
/// `.text`, `.report`, `.save(path)`); raises `ParseError` with the line of a refused word.
#[pyfunction]
#[pyo3(signature = (path=None, *, text=None, solver="auto", time_limit=None, max_evals=None,
    seed=1, merge_tool_blocks=false, reversible=None, margin=0.5))]
#[allow(clippy::too_many_arguments)]
pub fn optimize_gcode(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    solver: &str,
    time_limit: Option<f64>,
    max_evals: Option<u64>,
    seed: u64,
    merge_tool_blocks: bool,
    reversible: Option<bool>,
    margin: f64,
) -> PyResult<PyOptimized> {
    let allowance = Allowance::new(limit(time_limit)?, max_evals);
    let solver = solver_kind(solver)?;
    if !(margin.is_finite() && (0.0..=1e6).contains(&margin)) {
        return Err(value_error(format!(
            "margin must be a number of mm in [0, 1e6], got {margin}"
        )));
    }
    let opts = gpipe::Options {
        solver,
        time_limit,
        max_evals,
        seed,
        merge: merge_tool_blocks,
        margin,
        reversible,
    };
    py.detach(|| {
        guard("optimize_gcode", || {
            let t0 = std::time::Instant::now();
            let (file, text) = source(path.as_deref(), text)?;
            let parsed = rs(gcode::parse(&file, &text))?;
            let parse_s = t0.elapsed().as_secs_f64();
            let mut out = rs(gpipe::optimize_within(&parsed, &opts, &allowance))?;
            out.timings.parse_s = parse_s;
            let reversed = out.reversed.iter().filter(|&&r| r).count();
            let report = serde_json::json!({
                "input": file,
                "output": null,
                "solver": solver.name(),
                "cells": parsed.layout.cells.len(),
                "tool_blocks": parsed.layout.blocks.len(),
                "groups": out.groups,
                "verified_cutting_moves": out.cuts,
                "verified_events": out.events,
                "inner_first_dropped_groups": out.inner_first_dropped,
                "kept_original_order": out.kept_original(),
                "kept": out.kept,
                "kept_note": out.note,
                "reversal": out.reversal_on,
                "reversible_cells": out.reversible_cells,
                "reversed_cells": reversed,
                "timings": out.timings,
                "solve_s": out.timings.solve_s,
                "total_s": allowance.started.elapsed().as_secs_f64(),
                "before": out.before,
                "after": out.after,
            });
            Ok(PyOptimized {
                text: out.text,
                report,
                input: path.clone(),
            })
        })
    })
}

/// Options of a drawing, as `cellseq optimize` takes them.
struct DrawingOpts {
    format: String,
    tolerance: f64,
    skip_unsupported: bool,
    max_points: usize,
    pipe: spipe::Options,
    output: String,
}

/// Reads an SVG as the command line does (the tolerance is in mm; the reader works in user
/// units, known after a first read).
fn read_svg(file: &str, text: &str, o: &DrawingOpts) -> PyResult<svg::Drawing> {
    let probe = rs(svg::read(
        file,
        text,
        svg::ReadOptions {
            tolerance: 1e9,
            skip_unsupported: true,
            max_points: o.max_points,
        },
    ))?;
    rs(svg::read(
        file,
        text,
        svg::ReadOptions {
            tolerance: o.tolerance / probe.mm_per_unit,
            skip_unsupported: o.skip_unsupported,
            max_points: o.max_points,
        },
    ))
}

/// Reads a DXF (millimetre tolerances scaled to the drawing's unit).
fn read_dxf(file: &str, bytes: &[u8], o: &DrawingOpts) -> PyResult<svg::Drawing> {
    let mut r = dxf::ReadOptions {
        tolerance: o.tolerance,
        join: 0.001,
        skip_unsupported: o.skip_unsupported,
        units: None,
    };
    let d = rs(dxf::read(file, bytes, r))?;
    if d.mm_per_unit == 1.0 {
        return Ok(d);
    }
    r.tolerance /= d.mm_per_unit;
    r.join /= d.mm_per_unit;
    rs(dxf::read(file, bytes, r))
}

/// A drawing's content: text (SVG, or DXF given as text) or a DXF file's bytes.
enum Input {
    Text(String),
    Bytes(Vec<u8>),
}

/// Runs the drawing pipeline on `file`'s `text` and builds the report of `--json`.
fn run_drawing(
    file: &str,
    input: Input,
    mut o: DrawingOpts,
) -> PyResult<(String, serde_json::Value)> {
    let t0 = std::time::Instant::now();
    let d = match input {
        Input::Bytes(b) => read_dxf(file, &b, &o)?,
        Input::Text(t) if o.format == "dxf" => read_dxf(file, t.as_bytes(), &o)?,
        Input::Text(t) => read_svg(file, &t, &o)?,
    };
    let read_s = t0.elapsed().as_secs_f64();
    o.pipe.contain_tol /= d.mm_per_unit;
    let mut out = rs(spipe::optimize(&d, &o.pipe))?;
    let post = dxf::Post::default();
    let kind = if o.output == "gcode" {
        spipe::Output::Gcode(&post)
    } else {
        spipe::Output::Svg
    };
    let (new_text, segments) = rs(spipe::render(&d, &mut out, kind))?;
    let report = serde_json::json!({
        "input": file,
        "output": null,
        "output_kind": o.output,
        "solver": o.pipe.solver.name(),
        "strokes": d.strokes.len(),
        "closed_strokes": d.strokes.iter().filter(|s| s.closed).count(),
        "scopes": out.scopes,
        "precedence_edges": out.edges,
        "reversible": o.pipe.reversible,
        "verified_segments": segments,
        "skipped": d.skipped,
        "warnings": d.warnings,
        "mm_per_unit": d.mm_per_unit,
        "read_s": read_s,
        "solve_s": out.solve_s,
        "total_s": t0.elapsed().as_secs_f64(),
        "kept_original_scopes": out.kept_original,
        "groups_reordered": out.groups_reordered,
        "kept_note": out.note,
        "before": out.before,
        "after": out.after,
    });
    Ok((new_text, report))
}

/// Optimizes a drawing (SVG, or DXF) as `cellseq optimize` does: strokes sequenced per layer
/// and colour by the `drawing` solver (reversal and other start vertices of closed strokes on
/// unless `reversible=False`), Inkscape layers in the file's order, plain top-level groups as
/// blocks in the shortest order unless `keep_group_order`, inner closed strokes before the
/// enclosing ones with `cut` (on by default for DXF), unsequenced elements kept verbatim; the
/// output is verified to hold the same segments before it is returned.
///
/// Give `path` or `text` (`format` `svg` or `dxf`, by default from the path's extension, else
/// `svg`). `output`: `svg` (default for SVG, a preview for DXF) or `gcode` (default for DXF:
/// its simple post). Tolerances are in mm. Returns an `Optimized`.
#[pyfunction]
#[pyo3(signature = (path=None, *, text=None, format=None, output=None, solver="drawing",
    time_limit=None, max_evals=None, seed=1, params=None, reversible=true, scopes=true,
    cut=None, keep_group_order=false, tolerance=0.01, contain_tol=0.01, max_starts=8,
    skip_unsupported=false, max_points=10_000_000))]
#[allow(clippy::too_many_arguments)]
pub fn optimize_drawing(
    py: Python<'_>,
    path: Option<PathBuf>,
    text: Option<String>,
    format: Option<&str>,
    output: Option<&str>,
    solver: &str,
    time_limit: Option<f64>,
    max_evals: Option<u64>,
    seed: u64,
    params: Option<&Bound<'_, PyDict>>,
    reversible: bool,
    scopes: bool,
    cut: Option<bool>,
    keep_group_order: bool,
    tolerance: f64,
    contain_tol: f64,
    max_starts: usize,
    skip_unsupported: bool,
    max_points: usize,
) -> PyResult<PyOptimized> {
    let format = match format {
        Some(f) => f.to_ascii_lowercase(),
        None => path
            .as_ref()
            .and_then(|p| p.extension())
            .and_then(|e| e.to_str())
            .map_or("svg".to_string(), |e| e.to_ascii_lowercase()),
    };
    if format != "svg" && format != "dxf" {
        return Err(value_error(format!(
            "format '{format}': drawings are svg or dxf (G-code: optimize_gcode)"
        )));
    }
    let output = output
        .map(str::to_string)
        .unwrap_or_else(|| if format == "dxf" { "gcode" } else { "svg" }.into());
    if output != "svg" && output != "gcode" || (output == "gcode" && format != "dxf") {
        return Err(value_error(format!(
            "output '{output}': svg, or gcode for a DXF input"
        )));
    }
    for (name, v) in [("tolerance", tolerance), ("contain_tol", contain_tol)] {
        if !(v.is_finite() && v > 0.0 && v <= 1e6) {
            return Err(value_error(format!(
                "{name} must be in (0, 1e6] mm, got {v}"
            )));
        }
    }
    if !(1..=1000).contains(&max_starts) {
        return Err(value_error(format!(
            "max_starts must be in 1..=1000, got {max_starts}"
        )));
    }
    let o = DrawingOpts {
        tolerance,
        skip_unsupported,
        max_points,
        output,
        pipe: spipe::Options {
            solver: solver_kind(solver)?,
            time_limit: limit(time_limit)?,
            max_evals,
            params: convert::text_params(params)?,
            seed,
            reversible,
            scopes,
            cut: cut.unwrap_or(format == "dxf"),
            free_groups: !keep_group_order,
            contain_tol,
            max_starts,
        },
        format,
    };
    py.detach(|| {
        guard("optimize_drawing", || {
            let (file, input) = match (&path, text) {
                (Some(p), None) if o.format == "dxf" => (
                    p.display().to_string(),
                    Input::Bytes(std::fs::read(p).map_err(|e| {
                        crate::errors::to_py(cellseq::Error::io(p.display().to_string(), e))
                    })?),
                ),
                (p, t) => {
                    let (f, t) = source(p.as_deref(), t)?;
                    (f, Input::Text(t))
                }
            };
            let (new_text, report) = run_drawing(&file, input, o)?;
            Ok(PyOptimized {
                text: new_text,
                report,
                input: path.clone(),
            })
        })
    })
}
