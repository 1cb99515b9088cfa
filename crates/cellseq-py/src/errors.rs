//! cellseq's errors as Python exceptions, and the guard that keeps a Rust panic from crossing
//! into Python.

use cellseq::Error;
use pyo3::exceptions::{
    PyFileNotFoundError, PyOSError, PyPermissionError, PyRuntimeError, PyValueError,
};
use pyo3::prelude::*;

pyo3::create_exception!(
    cellseq,
    CellseqError,
    PyValueError,
    "An input cellseq refuses (a malformed or invalid file, an unknown solver, generator or \
     parameter, an infeasible sequence). A `ValueError`; `.file` and `.line` name where, when \
     known (`None` otherwise)."
);
pyo3::create_exception!(
    cellseq,
    ParseError,
    CellseqError,
    "A text file (instance, program, drawing, plan) is malformed at `.file`, line `.line`."
);
pyo3::create_exception!(
    cellseq,
    SolverError,
    PyRuntimeError,
    "A solver gave up (a memory limit, an instance it does not support)."
);
pyo3::create_exception!(
    cellseq,
    InternalError,
    PyRuntimeError,
    "A bug in cellseq (a Rust panic, caught before it reached Python): please report it."
);

/// The Python exception of a cellseq error, with `.file` and `.line` where the error has them.
pub fn to_py(e: Error) -> PyErr {
    let msg = e.to_string();
    match e {
        Error::Io { file, cause } => {
            let err = match cause.kind() {
                std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(msg),
                std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(msg),
                _ => PyOSError::new_err(msg),
            };
            with_place(err, Some(file), None)
        }
        Error::Parse { file, line, .. } => {
            with_place(ParseError::new_err(msg), Some(file), Some(line))
        }
        Error::Invalid { file, .. } => with_place(CellseqError::new_err(msg), Some(file), None),
        Error::UnknownSolver { .. } | Error::Param(_) => {
            with_place(CellseqError::new_err(msg), None, None)
        }
        Error::Solver { .. } => SolverError::new_err(msg),
    }
}

/// Sets `.file` and `.line` on the exception value.
fn with_place(err: PyErr, file: Option<String>, line: Option<usize>) -> PyErr {
    Python::attach(|py| {
        let v = err.value(py);
        // attributes on a fresh exception instance cannot fail; if they did, the message
        // still names the place
        let _ = v.setattr("file", file);
        let _ = v.setattr("line", line);
    });
    err
}

/// A `CellseqError` (a `ValueError`) with `msg`.
pub fn value_error(msg: impl Into<String>) -> PyErr {
    with_place(CellseqError::new_err(msg.into()), None, None)
}

/// Converts a library result.
pub fn rs<T>(r: cellseq::Result<T>) -> PyResult<T> {
    r.map_err(to_py)
}

/// Runs `f`, turning a panic into an `InternalError` instead of unwinding into Python.
pub fn guard<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => Err(panicked(what, p)),
    }
}

/// The `InternalError` of a caught panic payload.
pub fn panicked(what: &str, p: Box<dyn std::any::Any + Send>) -> PyErr {
    let why = p
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown cause".into());
    InternalError::new_err(format!(
        "{what}: internal error (a bug, please report it): {why}"
    ))
}
