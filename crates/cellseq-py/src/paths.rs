//! `cellseq.sequence_paths`: the order and direction in which to draw a list of polylines (a
//! plotter layer), with the `drawing` solver. The vpype plugin's `cellsort` uses it.

use crate::convert;
use crate::errors::{guard, rs, value_error};
use crate::info::solver_kind;
use crate::run::{Spec, run_polling};
use cellseq::geom::Point3;
use cellseq::model::{Cell, Instance, Machine, Metadata, Mode, Objective, StepKind, Tool, Visit};
use cellseq::{Sequence, SolverKind};
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// How a mode draws its path: backwards (open paths), and from which vertex (closed paths).
#[derive(Clone, Copy)]
struct Orient {
    reversed: bool,
    start: usize,
}

/// One polyline's points as `(x, y)` pairs from a `(k, 2)` array (any numeric dtype).
fn points(i: usize, item: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 2]>> {
    let owned;
    let arr: PyReadonlyArray2<'_, f64> = match item.extract() {
        Ok(a) => a,
        Err(_) => {
            let np = item.py().import("numpy")?;
            owned = np
                .call_method1("asarray", (item, "float64"))
                .map_err(|e| value_error(format!("path {i}: not an array of numbers ({e})")))?;
            owned
                .extract()
                .map_err(|_| value_error(format!("path {i}: expected a (k, 2) array of x, y")))?
        }
    };
    let shape = arr.shape();
    if shape[1] != 2 || shape[0] == 0 {
        return Err(value_error(format!(
            "path {i}: expected a (k, 2) array with k >= 1, got shape {:?}",
            shape
        )));
    }
    let a = arr.as_array();
    let pts: Vec<[f64; 2]> = (0..shape[0]).map(|r| [a[[r, 0]], a[[r, 1]]]).collect();
    if pts
        .iter()
        .flatten()
        .any(|v| !v.is_finite() || v.abs() > 1e9)
    {
        return Err(value_error(format!(
            "path {i}: coordinates must be finite numbers of magnitude at most 1e9"
        )));
    }
    Ok(pts)
}

/// A path drawn as a loop: at least three distinct vertices, the last repeating the first.
fn is_closed(p: &[[f64; 2]]) -> bool {
    p.len() >= 4 && p[0] == p[p.len() - 1]
}

fn length(p: &[[f64; 2]]) -> f64 {
    p.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// The modes of one path and how each draws it.
fn modes_of(p: &[[f64; 2]], reversible: bool, max_starts: usize) -> (Vec<Mode>, Vec<Orient>) {
    let at = |q: [f64; 2]| Point3::new(q[0], q[1], 0.0);
    let last = p.len() - 1;
    if is_closed(p) {
        let m = last; // distinct vertices
        let k = if reversible { m.min(max_starts) } else { 1 };
        let starts: Vec<usize> = (0..k).map(|j| j * m / k).collect();
        let modes = starts.iter().map(|&v| Mode::closed(at(p[v]))).collect();
        let or = starts
            .iter()
            .map(|&v| Orient {
                reversed: false,
                start: v,
            })
            .collect();
        return (modes, or);
    }
    let mut modes = vec![Mode::new(at(p[0]), at(p[last]))];
    let mut or = vec![Orient {
        reversed: false,
        start: 0,
    }];
    if reversible && p[0] != p[last] {
        modes.push(Mode::new(at(p[last]), at(p[0])));
        or.push(Orient {
            reversed: true,
            start: last,
        });
    }
    (modes, or)
}

/// Where the pen starts, as the instance's home: at `start` on the sheet, or (no start given:
/// the travel to the first path is not counted, as vpype's `pen_up_length`) far above the
/// first path's start, at a height `H` of a million times the drawing's extent `D` (at most
/// 5·10⁸): every first path then costs `H` to within `D²/2H = D/2·10⁻⁶`, a tie-break toward the
/// given order's start.
fn home(paths: &[Vec<[f64; 2]>], start: Option<[f64; 2]>) -> Point3 {
    if let Some(s) = start {
        return Point3::new(s[0], s[1], 0.0);
    }
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for q in paths.iter().flatten() {
        for a in 0..2 {
            lo[a] = lo[a].min(q[a]);
            hi[a] = hi[a].max(q[a]);
        }
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1.0);
    let first = paths.first().map_or([0.0, 0.0], |p| p[0]);
    Point3::new(first[0], first[1], (1e6 * extent).min(FREE_HOME_MAX))
}

/// Fewest paths on which the `drawing` solver searches beyond its greedy start; fewer are
/// solved by `exact`.
const DRAWING_MIN: usize = 4;

/// Highest free-start home (below the coordinate limit of 10⁹ the validator enforces).
const FREE_HOME_MAX: f64 = 5e8;

/// The instance of the paths: one cell per path, its modes its directions (open paths) or
/// start vertices (closed paths), the pen starting at `home`, no lift height (a plotter).
fn instance(
    paths: &[Vec<[f64; 2]>],
    home: Point3,
    reversible: bool,
    max_starts: usize,
) -> (Instance, Vec<Vec<Orient>>) {
    let mut orient = Vec::with_capacity(paths.len());
    let cells = paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (modes, or) = modes_of(p, reversible, max_starts);
            orient.push(or);
            let mut c = Cell::new(format!("p{i}"), "pen", modes);
            c.reversible = reversible && !is_closed(p) && p[0] != p[p.len() - 1];
            c.step = StepKind::Engrave;
            c.cut_length = length(p);
            c
        })
        .collect();
    let inst = Instance {
        name: "<paths>".into(),
        meta: Metadata {
            generator: Some("paths".into()),
            ..Metadata::default()
        },
        machine: Machine {
            home,
            tool_change: home,
            clearance: 0.0,
            initial_tool: Some("pen".into()),
            ..Machine::default()
        },
        tools: vec![Tool {
            id: "pen".into(),
            diameter: 1.0,
            name: None,
            feed: None,
        }],
        cells,
        precedence: Vec::new(),
        as_given: Some((0..paths.len()).map(|i| Visit::new(i, 0)).collect()),
        ..Instance::default()
    };
    (inst, orient)
}

/// Pen-up travel of a sequence: (from the start to the first path, between paths).
fn travel(inst: &Instance, seq: &Sequence) -> (f64, f64) {
    let d = |a: Point3, b: Point3| (a.x - b.x).hypot(a.y - b.y);
    let mut lead = 0.0;
    let mut between = 0.0;
    let mut at: Option<Point3> = None;
    for v in seq {
        let m = &inst.cells[v.cell].modes[v.mode];
        match at {
            None => lead = d(inst.machine.home, m.entry),
            Some(p) => between += d(p, m.entry),
        }
        at = Some(m.exit);
    }
    (lead, between)
}

/// The order and direction in which to draw `paths` (a list of `(k, 2)` arrays of x, y: one
/// plotter layer) with the least pen-up travel: between paths only (vpype's `pen_up_length`,
/// `start=None`, the default), or also from a pen starting at `start`.
///
/// Each path is a cell: an open path may be drawn backwards (`reversible`, default on, as
/// vpype's `linesort`), a closed one (last point equal to the first, three distinct vertices
/// or more) may start at one of `max_starts` evenly spaced vertices (also only when
/// `reversible`). The registry solver `solver` (default `drawing`) sequences them with
/// `time_limit` seconds or `max_evals` evaluations (default: 4000 evaluations per path, at
/// least 10^6: deterministic); the given order is kept unless the solver's is shorter. Fewer
/// than 4 paths, where `drawing` keeps its greedy order, are solved by `exact`.
///
/// Returns a dict: `order` (path indices in drawing order), `reversed` (per position: drawn
/// backwards), `start` (per position: the index of the path's vertex it starts from),
/// `pen_up_before`/`pen_up_after` (travel between paths, vpype's metric),
/// `lead_in_before`/`lead_in_after` (from `start` to the first path; `None` without a start),
/// `kept_original`,
/// `evaluations`, `elapsed_s`. The GIL is released while it runs; Ctrl-C stops it.
#[pyfunction]
#[pyo3(signature = (paths, *, start=None, reversible=true, max_starts=8,
    solver="drawing", time_limit=None, max_evals=None, seed=1, params=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn sequence_paths<'py>(
    py: Python<'py>,
    paths: &Bound<'py, PyAny>,
    start: Option<(f64, f64)>,
    reversible: bool,
    max_starts: usize,
    solver: &str,
    time_limit: Option<f64>,
    max_evals: Option<u64>,
    seed: u64,
    params: Option<&Bound<'py, PyDict>>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    if !(1..=1000).contains(&max_starts) {
        return Err(value_error(format!(
            "max_starts must be in 1..=1000, got {max_starts}"
        )));
    }
    if let Some(s) = start
        && !(s.0.is_finite() && s.1.is_finite() && s.0.abs() <= 1e9 && s.1.abs() <= 1e9)
    {
        return Err(value_error(
            "start must be two finite numbers of magnitude at most 1e9",
        ));
    }
    let pts: Vec<Vec<[f64; 2]>> = paths
        .try_iter()?
        .enumerate()
        .map(|(i, p)| points(i, &p?))
        .collect::<PyResult<_>>()?;
    let mut budget = cellseq::Budget::default();
    if let Some(t) = time_limit {
        budget.time_limit = Some(rs(cellseq::solve::checked_seconds("time_limit", t))?);
    }
    budget.max_evals = match (time_limit, max_evals) {
        (None, None) => Some(cellseq_programs::optimize::strokes::default_evals(
            pts.len(),
        )),
        (_, n) => n,
    };
    let mut kind = solver_kind(solver)?;
    if kind == SolverKind::Drawing && pts.len() < DRAWING_MIN {
        // `drawing` keeps its greedy start below 4 strokes; Held–Karp is exact and instant
        kind = SolverKind::Exact;
    }
    let spec = Spec {
        solver: kind,
        params: convert::params(params)?,
        seed,
        budget,
        objective: Some(Objective::Air),
        lower_bound: false,
    };
    rs(spec.build().validated_params())?;
    let start = start.map(|s| [s.0, s.1]);
    let (inst, orient) = instance(&pts, home(&pts, start), reversible, max_starts);
    if !pts.is_empty() {
        rs(cellseq::validate::validate(&inst, "<paths>"))?;
    }
    let original: Sequence = inst.as_given.clone().unwrap_or_default();
    let (seq, kept, evaluations, elapsed_s) = if pts.is_empty() {
        (original.clone(), true, 0, 0.0)
    } else {
        let r = run_polling(py, "sequence_paths", progress, |fwd, stop| {
            rs(spec.build().observe(fwd).stop_when(stop).run(&inst))
        })?;
        let before = guard("sequence_paths", || {
            cellseq::check(&inst, &original, Objective::Air).map_err(|v| value_error(v.to_string()))
        })?;
        let better = r.report.cost < before.cost - 1e-9 * before.cost.abs().max(1.0);
        let seq = if better { r.sequence } else { original.clone() };
        (seq, !better, r.evaluations, r.elapsed_s)
    };
    let (lead0, between0) = travel(&inst, &original);
    let (lead1, between1) = travel(&inst, &seq);
    let lead = |l: f64| start.map(|_| l);
    let d = PyDict::new(py);
    let or: Vec<Orient> = seq.iter().map(|v| orient[v.cell][v.mode]).collect();
    d.set_item("order", seq.iter().map(|v| v.cell).collect::<Vec<_>>())?;
    d.set_item(
        "reversed",
        or.iter().map(|o| o.reversed).collect::<Vec<_>>(),
    )?;
    d.set_item("start", or.iter().map(|o| o.start).collect::<Vec<_>>())?;
    d.set_item("pen_up_before", between0)?;
    d.set_item("pen_up_after", between1)?;
    d.set_item("lead_in_before", lead(lead0))?;
    d.set_item("lead_in_after", lead(lead1))?;
    d.set_item("kept_original", kept)?;
    d.set_item("evaluations", evaluations)?;
    d.set_item("elapsed_s", elapsed_s)?;
    Ok(d)
}
