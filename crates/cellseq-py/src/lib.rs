//! The Python bindings of cellseq: the extension module `cellseq._cellseq`, which the pure
//! Python package `cellseq` (python/cellseq) re-exports with its helpers and type stubs.
//!
//! Every call converts cellseq's errors into Python exceptions (`errors`), catches a Rust
//! panic before it reaches Python, and releases the GIL while Rust works; solves run on a Rust
//! thread while the caller polls for Ctrl-C (`run`).

// No unsafe code of ours (PyO3's macros expand to their own).
#![deny(unsafe_code)]

mod convert;
mod errors;
mod info;
mod instance;
mod lab;
mod paths;
mod programs;
mod run;
mod solve;

use pyo3::prelude::*;

/// cellseq's core, solvers, checker, programs and lab, for Python (see the `cellseq` package).
#[pymodule]
fn _cellseq(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("CellseqError", py.get_type::<errors::CellseqError>())?;
    m.add("ParseError", py.get_type::<errors::ParseError>())?;
    m.add("SolverError", py.get_type::<errors::SolverError>())?;
    m.add("InternalError", py.get_type::<errors::InternalError>())?;
    m.add_class::<instance::PyInstance>()?;
    m.add_class::<solve::PyResultObj>()?;
    m.add_class::<programs::PyOptimized>()?;
    m.add_function(wrap_pyfunction!(instance::read, m)?)?;
    m.add_function(wrap_pyfunction!(instance::generate, m)?)?;
    m.add_function(wrap_pyfunction!(info::generators, m)?)?;
    m.add_function(wrap_pyfunction!(info::solvers, m)?)?;
    m.add_function(wrap_pyfunction!(info::check, m)?)?;
    m.add_function(wrap_pyfunction!(info::bounds, m)?)?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(programs::optimize_gcode, m)?)?;
    m.add_function(wrap_pyfunction!(programs::optimize_drawing, m)?)?;
    m.add_function(wrap_pyfunction!(paths::sequence_paths, m)?)?;
    m.add_function(wrap_pyfunction!(lab::run_plan, m)?)?;
    Ok(())
}
