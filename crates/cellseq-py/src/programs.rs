//! Real programs: G-code and drawings optimized as `cellseq optimize` does (text or a path in,
//! the new text and the report of `--json` out, verified the same way).

use crate::convert;
use crate::errors::{guard, rs, value_error};
use crate::info::solver_kind;
use cellseq::files::{ensure_not_input, read_text, write_atomic};
use cellseq_programs::job;
use cellseq_programs::optimize::strokes::{Blocks, Pens};
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
    let opts = job::Options {
        solver: Some(solver_kind(solver)?),
        time_limit,
        max_evals,
        seed,
        merge_tool_blocks,
        margin,
        reversible,
        ..Default::default()
    };
    py.detach(|| {
        guard("optimize_gcode", || {
            let (file, text) = source(path.as_deref(), text)?;
            let j = rs(job::optimize_source(
                &file,
                text.as_bytes(),
                job::Format::Gcode,
                &opts,
            ))?;
            Ok(PyOptimized {
                report: j.report.to_json(None),
                text: j.text,
                input: path.clone(),
            })
        })
    })
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
/// its simple post). `pens` (`layer`, `colour`, `none`, `auto`) and `blocks` (`group`, `none`,
/// `auto`) are the command line's `--pens` and `--blocks`; `scopes=False` is `pens="none",
/// blocks="none"`. Tolerances are in mm. Returns an `Optimized`.
#[pyfunction]
#[pyo3(signature = (path=None, *, text=None, format=None, output=None, solver="drawing",
    time_limit=None, max_evals=None, seed=1, params=None, reversible=true, scopes=true,
    pens="auto", blocks="auto", cut=None, keep_group_order=false, tolerance=0.01, contain_tol=0.01, max_starts=8,
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
    pens: &str,
    blocks: &str,
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
    let pens = Pens::parse(pens)
        .ok_or_else(|| value_error(format!("pens '{pens}': use layer, colour, none or auto")))?;
    let blocks = Blocks::parse(blocks)
        .ok_or_else(|| value_error(format!("blocks '{blocks}': use group, none or auto")))?;
    let (pens, blocks) = if scopes {
        (pens, blocks)
    } else if matches!(pens, Pens::Auto | Pens::None) {
        (Pens::None, Blocks::None)
    } else {
        return Err(value_error(
            "scopes=False is pens='none': it cannot go with another pens",
        ));
    };
    let opts = job::Options {
        solver: Some(solver_kind(solver)?),
        time_limit,
        max_evals,
        seed,
        params: convert::text_params(params)?,
        reversible: Some(reversible),
        drawing: job::DrawingOptions {
            tolerance,
            pens,
            blocks,
            cut,
            keep_group_order,
            contain_tol,
            max_starts,
            skip_unsupported,
            max_points,
            svg_output: output == "svg",
            ..Default::default()
        },
        ..Default::default()
    };
    let fmt = if format == "dxf" {
        job::Format::Dxf
    } else {
        job::Format::Svg
    };
    py.detach(|| {
        guard("optimize_drawing", || {
            let j = match (&path, text) {
                (Some(p), None) => rs(job::optimize_file_as(p, Some(fmt.name()), &opts))?,
                (None, Some(t)) => rs(job::optimize_source("<text>", t.as_bytes(), fmt, &opts))?,
                _ => return Err(value_error("give exactly one of path and text")),
            };
            Ok(PyOptimized {
                report: j.report.to_json(None),
                text: j.text,
                input: path.clone(),
            })
        })
    })
}
