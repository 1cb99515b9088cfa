//! `cellseq.solve` and its `Result`.

use crate::convert;
use crate::errors::{guard, rs, value_error};
use crate::info::{objective, report_dict, solver_kind};
use crate::instance::PyInstance;
use crate::run::{Spec, run_polling};
use cellseq::{Instance, Solved};
use numpy::IntoPyArray;
use numpy::ndarray::Array2;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;

/// A verified result: the sequence with the independent checker's report, the lower bound,
/// whether the solver proved optimality, and how it was found.
#[pyclass(name = "Result", module = "cellseq", frozen)]
pub struct PyResultObj {
    solved: Solved,
    inst: Arc<Instance>,
}

#[pymethods]
impl PyResultObj {
    /// The cost of the sequence, by the independent checker.
    #[getter]
    fn cost(&self) -> f64 {
        self.solved.cost()
    }
    /// The order of cells as `(cell, mode)` pairs of 0-based indices.
    #[getter]
    fn sequence<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        convert::sequence_to_py(py, &self.solved.sequence)
    }
    /// A valid lower bound on the optimum, when one is known.
    #[getter]
    fn lower_bound(&self) -> Option<f64> {
        self.solved.lower_bound
    }
    /// True when the solver proved the sequence optimal.
    #[getter]
    fn proven_optimal(&self) -> bool {
        self.solved.proven_optimal
    }
    /// The gap between cost and lower bound, in percent of the bound.
    #[getter]
    fn certified_gap_percent(&self) -> Option<f64> {
        self.solved.certified_gap_percent()
    }
    /// The checker's figures: `cost, air_length, cut_length, path_length, lifts,
    /// tool_changes, machining_time`.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        report_dict(py, &self.solved.report)
    }
    /// The anytime trace: a float64 array of shape `(k, 3)`, one row per improvement of the
    /// best cost: evaluations, seconds, cost.
    #[getter]
    fn trace<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = &self.solved.trace;
        let flat: Vec<f64> = t
            .iter()
            .flat_map(|p| [p.evaluations as f64, p.elapsed_s, p.best])
            .collect();
        let a = Array2::from_shape_vec((t.len(), 3), flat)
            .map_err(|e| value_error(format!("trace: {e}")))?;
        Ok(a.into_pyarray(py).into_any())
    }
    /// The solver's registry name.
    #[getter]
    fn solver(&self) -> &'static str {
        self.solved.solver.name()
    }
    /// The seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.solved.seed
    }
    /// The objective the sequence was scored by (`time`, `air` or `matrix`).
    #[getter]
    fn objective(&self) -> &'static str {
        self.solved.objective.name()
    }
    /// Evaluations counted.
    #[getter]
    fn evaluations(&self) -> u64 {
        self.solved.evaluations
    }
    /// Seconds the solver ran.
    #[getter]
    fn elapsed_s(&self) -> f64 {
        self.solved.elapsed_s
    }
    /// The solver's parameters, defaults filled in (as text).
    #[getter]
    fn params(&self) -> std::collections::BTreeMap<String, String> {
        self.solved.params.values().clone()
    }
    /// The object `cellseq solve --json` prints for this result (`best_known` and
    /// `gap_percent` from `best_known` when given).
    #[pyo3(signature = (best_known=None))]
    fn to_dict<'py>(
        &self,
        py: Python<'py>,
        best_known: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        convert::json_to_py(py, &self.solved.to_json(&self.inst, best_known))
    }
    /// Writes the solution file (`cellseq-solution/1`, read by `cellseq eval`), atomically.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| guard("save", || rs(self.solved.save(&self.inst, &path))))
    }
    fn __repr__(&self) -> String {
        let lb = self
            .solved
            .lower_bound
            .map_or("None".to_string(), |b| b.to_string());
        format!(
            "<cellseq.Result {} on '{}': cost {}, lower_bound {lb}, proven_optimal {}>",
            self.solved.solver.name(),
            self.inst.name,
            self.solved.cost(),
            if self.solved.proven_optimal {
                "True"
            } else {
                "False"
            }
        )
    }
}

/// Solves `instance` with the registry solver `solver` (see `cellseq.solvers()`), checks the
/// result with the independent checker and returns a `Result`.
///
/// Budget: `time_limit` seconds and/or `max_evals` evaluations (an evaluation budget gives the
/// same result on any machine); without either, each solver's own stopping rule. `params`
/// sets solver parameters (an unknown solver or parameter raises `CellseqError`, a
/// `ValueError`, listing the valid ones). `objective`: `time` or `air` for geometric
/// instances (default `time`); matrix instances are scored by their matrix. `lower_bound`
/// computes a bound after the solve (as `cellseq solve` does). `progress(evaluations,
/// seconds, best_cost)` is called on every improvement.
///
/// The GIL is released while the solver runs; Ctrl-C (or an exception in `progress`) stops
/// the solver and raises in the caller.
#[pyfunction]
#[pyo3(signature = (instance, solver="auto", time_limit=None, max_evals=None, seed=1,
    params=None, *, objective=None, lower_bound=true, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn solve(
    py: Python<'_>,
    instance: &PyInstance,
    solver: &str,
    time_limit: Option<f64>,
    max_evals: Option<u64>,
    seed: u64,
    params: Option<&Bound<'_, PyDict>>,
    objective: Option<&str>,
    lower_bound: bool,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyResultObj> {
    let mut budget = cellseq::Budget::default();
    if let Some(t) = time_limit {
        budget.time_limit = Some(rs(cellseq::solve::checked_seconds("time_limit", t))?);
    }
    budget.max_evals = max_evals;
    let spec = Spec {
        solver: solver_kind(solver)?,
        params: convert::params(params)?,
        seed,
        budget,
        objective: Some(self::objective(&instance.inner, objective)?),
        lower_bound,
    };
    // parameters refused before anything runs
    rs(spec.build().validated_params())?;
    if let Some(cb) = progress
        && !cb.is_callable()
    {
        return Err(value_error("progress must be callable"));
    }
    let inst = Arc::clone(&instance.inner);
    let solved = run_polling(py, "solve", progress, |fwd, stop| {
        rs(spec.build().observe(fwd).stop_when(stop).run(&inst))
    })?;
    Ok(PyResultObj {
        solved,
        inst: Arc::clone(&instance.inner),
    })
}
