//! Conversions between Python values and cellseq's: parameters, sequences, JSON values.

use crate::errors::value_error;
use cellseq::model::{Sequence, Visit};
use cellseq::params::ParamValue;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::collections::BTreeMap;

/// Solver parameters from a dict of names to `int`, `float`, `bool` or `str` values.
pub fn params(given: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, ParamValue)>> {
    let Some(d) = given else {
        return Ok(Vec::new());
    };
    let mut out = Vec::with_capacity(d.len());
    for (k, v) in d.iter() {
        let name: String = k
            .extract()
            .map_err(|_| value_error(format!("parameter names are strings, got {k:?}")))?;
        out.push((name.clone(), param_value(&name, &v)?));
    }
    Ok(out)
}

/// One parameter value (a bool is checked before an int: `True` is an `int` in Python).
fn param_value(name: &str, v: &Bound<'_, PyAny>) -> PyResult<ParamValue> {
    if v.is_instance_of::<PyBool>() {
        return Ok(ParamValue::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<u64>() {
            Ok(n) => Ok(ParamValue::Int(n)),
            Err(_) => Err(value_error(format!(
                "parameter '{name}': {v} is not a non-negative integer below 2**64"
            ))),
        };
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(ParamValue::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(ParamValue::Text(v.extract()?));
    }
    Err(value_error(format!(
        "parameter '{name}': expected an int, float, bool or str, got {}",
        v.get_type().name()?
    )))
}

/// Generator parameters (text, as on the command line) from a dict of any simple values.
pub fn text_params(given: Option<&Bound<'_, PyDict>>) -> PyResult<BTreeMap<String, String>> {
    Ok(params(given)?
        .into_iter()
        .map(|(k, v)| (k, v.to_text()))
        .collect())
}

/// A sequence from a Python iterable: each item a cell index (mode 0) or a `(cell, mode)`
/// pair of 0-based indices.
pub fn sequence(seq: &Bound<'_, PyAny>) -> PyResult<Sequence> {
    let mut out = Vec::new();
    for (p, item) in seq.try_iter()?.enumerate() {
        let item = item?;
        let visit = if let Ok(c) = item.extract::<usize>() {
            Visit::new(c, 0)
        } else if let Ok((c, m)) = item.extract::<(usize, usize)>() {
            Visit::new(c, m)
        } else {
            return Err(value_error(format!(
                "sequence position {p}: expected a cell index or a (cell, mode) pair of \
                 non-negative integers, got {item}"
            )));
        };
        out.push(visit);
    }
    Ok(out)
}

/// A sequence as a list of `(cell, mode)` tuples.
pub fn sequence_to_py<'py>(py: Python<'py>, seq: &Sequence) -> PyResult<Bound<'py, PyList>> {
    let items: Vec<Bound<'py, PyTuple>> = seq
        .iter()
        .map(|v| PyTuple::new(py, [v.cell, v.mode]))
        .collect::<PyResult<_>>()?;
    PyList::new(py, items)
}

/// A JSON value as the Python value `json.loads` would give.
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_u64(), n.as_i64()) {
            (Some(u), _) => u.into_pyobject(py)?.into_any(),
            (None, Some(i)) => i.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items: Vec<Bound<'py, PyAny>> = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<_>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A serializable value as a Python value, through JSON.
pub fn to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let j = serde_json::to_value(v)
        .map_err(|e| crate::errors::value_error(format!("cannot convert a value: {e}")))?;
    json_to_py(py, &j)
}
