//! Experiment plans: `cellseq.run_plan`.

use crate::convert;
use crate::errors::{guard, rs, value_error};
use cellseq_lab::plan::Plan;
use cellseq_lab::results::{Row, read_strict};
use cellseq_lab::run::{RunOptions, run_plan as lab_run};
use pyo3::prelude::*;
use pyo3::types::PyList;
use std::path::{Path, PathBuf};

/// Runs (or resumes) the experiment plan at `plan` (a TOML file, as `cellseq run`) into `out`
/// (default `results/<plan name>`), with `threads` workers (default all cores) and only shard
/// `(i, n)` when given, and returns the rows of its `results.csv` as dicts (one per trial, in
/// plan order; the columns of docs/harness.md). The same plan and seeds give the same rows
/// (evaluation budgets) on any machine and thread count.
///
/// The GIL is released while the plan runs; a run cannot be interrupted from Python (it is
/// resumable: run it again to finish what was left).
#[pyfunction]
#[pyo3(signature = (plan, out=None, threads=None, shard=None))]
pub fn run_plan<'py>(
    py: Python<'py>,
    plan: PathBuf,
    out: Option<PathBuf>,
    threads: Option<usize>,
    shard: Option<(usize, usize)>,
) -> PyResult<Bound<'py, PyList>> {
    if threads == Some(0) {
        return Err(value_error("threads must be at least 1"));
    }
    if let Some((i, n)) = shard
        && (n == 0 || i == 0 || i > n)
    {
        return Err(value_error(format!(
            "shard ({i}, {n}): expected (i, n) with 1 <= i <= n"
        )));
    }
    let rows: Vec<Row> = py.detach(|| {
        guard("run_plan", || {
            let p = rs(Plan::load(&plan))?;
            let out = out.unwrap_or_else(|| Path::new("results").join(&p.file.name));
            let opts = RunOptions {
                threads,
                shard,
                out,
                progress: false,
                throttle_ms: 0,
                replace_foreign: false,
            };
            let s = rs(lab_run(&p, &opts))?;
            rs(read_strict::<Row>(&s.files.results))
        })
    })?;
    let items: Vec<Bound<'py, PyAny>> = rows
        .iter()
        .map(|r| convert::to_py(py, r))
        .collect::<PyResult<_>>()?;
    PyList::new(py, items)
}
