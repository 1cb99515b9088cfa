//! The registry listing, the independent checker and lower bounds.

use crate::convert;
use crate::errors::{guard, rs, value_error};
use crate::instance::PyInstance;
use cellseq::model::Objective;
use cellseq::params::{ParamKind, ParamSpec};
use cellseq::{BoundOptions, Report, SolverKind};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::sync::Arc;

/// Parameter declarations as a list of dicts.
pub fn param_specs<'py>(py: Python<'py>, specs: &[ParamSpec]) -> PyResult<Bound<'py, PyList>> {
    let items: Vec<Bound<'py, PyDict>> = specs
        .iter()
        .map(|p| {
            let d = PyDict::new(py);
            d.set_item("name", p.name)?;
            d.set_item("default", p.default)?;
            let kind = match p.kind {
                ParamKind::Int(r) => {
                    d.set_item("range", r.to_string())?;
                    "int".to_string()
                }
                ParamKind::Float(r) => {
                    d.set_item("range", r.to_string())?;
                    "float".to_string()
                }
                ParamKind::Bool => "bool".to_string(),
                ParamKind::Choice(c) => format!("one of {}", c.join(", ")),
                ParamKind::Text => "text".to_string(),
            };
            d.set_item("kind", kind)?;
            d.set_item("help", p.help)?;
            Ok(d)
        })
        .collect::<PyResult<_>>()?;
    PyList::new(py, items)
}

/// Every registry solver: `[{"name", "summary", "params": [{"name", "default", "kind",
/// "help"}]}]`, the default (`auto`) first.
#[pyfunction]
pub fn solvers(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let items: Vec<Bound<'_, PyDict>> = SolverKind::ALL
        .iter()
        .map(|k| {
            let info = k.info();
            let d = PyDict::new(py);
            d.set_item("name", info.name)?;
            d.set_item("summary", info.summary)?;
            d.set_item("params", param_specs(py, info.params)?)?;
            Ok(d)
        })
        .collect::<PyResult<_>>()?;
    PyList::new(py, items)
}

/// The solver of registry name `name`, or a `ValueError` listing the known ones.
pub fn solver_kind(name: &str) -> PyResult<SolverKind> {
    rs(name.parse::<SolverKind>())
}

/// The objective named `name` (`time`, `air`, `matrix`), or the instance's default for `None`.
pub fn objective(inst: &cellseq::Instance, name: Option<&str>) -> PyResult<Objective> {
    let asked = match name {
        None => None,
        Some(n) => Some(Objective::parse(n).ok_or_else(|| {
            value_error(format!(
                "unknown objective '{n}' (known: time, air, matrix)"
            ))
        })?),
    };
    rs(cellseq::solve::objective_for(inst, asked))
}

/// The checker's report as a dict.
pub fn report_dict<'py>(py: Python<'py>, r: &Report) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("cost", r.cost)?;
    d.set_item("air_length", r.air_length)?;
    d.set_item("cut_length", r.cut_length)?;
    d.set_item("path_length", r.path_length)?;
    d.set_item("lifts", r.lifts)?;
    d.set_item("tool_changes", r.tool_changes)?;
    d.set_item("machining_time", r.machining_time)?;
    Ok(d)
}

/// Checks `sequence` on `instance` with the independent checker (it shares no code with the
/// solvers' cost model) and returns its report: `cost, air_length, cut_length, path_length,
/// lifts, tool_changes, machining_time`. `sequence` holds cell indices (mode 0) or `(cell,
/// mode)` pairs, 0-based. Raises `CellseqError` (a `ValueError`) naming the broken rule
/// (a missing or repeated cell, a precedence pair out of order, a mode that does not exist).
#[pyfunction]
#[pyo3(signature = (instance, sequence, objective=None))]
pub fn check<'py>(
    py: Python<'py>,
    instance: &PyInstance,
    sequence: &Bound<'py, PyAny>,
    objective: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let seq = convert::sequence(sequence)?;
    let obj = self::objective(&instance.inner, objective)?;
    let inst = Arc::clone(&instance.inner);
    let r = py.detach(move || {
        guard("check", || {
            cellseq::check(&inst, &seq, obj).map_err(|v| value_error(v.to_string()))
        })
    })?;
    report_dict(py, &r)
}

/// Valid lower bounds on the optimum of `instance`: `{"best", "best_name", "parts": [{"name",
/// "value", "seconds"}]}` (degree, assignment, Lagrangian, sec, qpath, kNN degree: each where
/// its size limits allow).
#[pyfunction]
#[pyo3(signature = (instance, objective=None))]
pub fn bounds<'py>(
    py: Python<'py>,
    instance: &PyInstance,
    objective: Option<&str>,
) -> PyResult<Bound<'py, PyDict>> {
    let obj = self::objective(&instance.inner, objective)?;
    let inst = Arc::clone(&instance.inner);
    let b = py.detach(move || {
        guard("bounds", || {
            rs(cellseq::lower_bounds(&inst, obj, &BoundOptions::default()))
        })
    })?;
    let d = PyDict::new(py);
    d.set_item("best", b.best)?;
    d.set_item("best_name", b.best_name)?;
    let parts: Vec<Bound<'py, PyDict>> = b
        .parts
        .iter()
        .map(|p| {
            let x = PyDict::new(py);
            x.set_item("name", p.name)?;
            x.set_item("value", p.value)?;
            x.set_item("seconds", p.seconds)?;
            Ok(x)
        })
        .collect::<PyResult<_>>()?;
    d.set_item("parts", parts)?;
    Ok(d)
}

/// Every generator kind: `[{"name", "summary", "params": [{"name", "default", "kind",
/// "help"}]}]`.
#[pyfunction]
pub fn generators(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let items: Vec<Bound<'_, PyDict>> = cellseq::generate::KINDS
        .iter()
        .map(|k| {
            let d = PyDict::new(py);
            d.set_item("name", k.name)?;
            d.set_item("summary", k.summary)?;
            d.set_item("params", param_specs(py, k.params)?)?;
            Ok(d)
        })
        .collect::<PyResult<_>>()?;
    PyList::new(py, items)
}
