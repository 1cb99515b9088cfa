//! `cellseq.Instance`: reading, building from a NumPy matrix, generating, saving.

use crate::convert;
use crate::errors::{guard, rs, value_error};
use cellseq::Instance;
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Arc;

/// An instance: cells (each with one or more modes), precedence, and either geometry (a
/// machine, tools, cells' entry and exit points) or an explicit cost matrix.
///
/// Make one with `cellseq.read(path)`, `Instance.from_matrix(costs, precedence)` or
/// `cellseq.generate(kind, seed, params)`.
#[pyclass(name = "Instance", module = "cellseq", frozen)]
pub struct PyInstance {
    /// Shared with the solver threads.
    pub inner: Arc<Instance>,
}

impl PyInstance {
    /// Wraps an instance.
    pub fn new(inst: Instance) -> Self {
        PyInstance {
            inner: Arc::new(inst),
        }
    }
}

/// Reads an instance file (`.sop`, `.pcglns`, `.pcgtsp`, cellseq `.json`).
#[pyfunction]
pub fn read(py: Python<'_>, path: PathBuf) -> PyResult<PyInstance> {
    let inst = py.detach(|| guard("read", || rs(cellseq::load(&path))))?;
    Ok(PyInstance::new(inst))
}

/// The row-major costs of a square matrix, read in place when the array is a C-contiguous
/// float64 array (the one copy is the instance's own), converted by NumPy otherwise.
fn matrix_costs(costs: &Bound<'_, PyAny>) -> PyResult<(usize, Vec<f64>)> {
    let owned;
    let arr: PyReadonlyArray2<'_, f64> = match costs.extract() {
        Ok(a) => a,
        Err(_) => {
            let np = costs.py().import("numpy")?;
            owned = np
                .call_method1("ascontiguousarray", (costs, "float64"))
                .map_err(|e| value_error(format!("costs: not a numeric matrix ({e})")))?;
            owned
                .extract()
                .map_err(|_| value_error("costs: expected a 2-D array of numbers"))?
        }
    };
    let shape = arr.shape();
    if shape[0] != shape[1] {
        return Err(value_error(format!(
            "costs: expected a square matrix, got shape {} x {}",
            shape[0], shape[1]
        )));
    }
    // a C-contiguous array is the row-major matrix as it is; any other layout (Fortran
    // order, a strided view) is read in logical (row-major) order
    let v = match arr.as_slice() {
        Ok(s) if arr.is_c_contiguous() => s.to_vec(),
        _ => arr.as_array().iter().copied().collect(),
    };
    Ok((shape[0], v))
}

/// Precedence pairs from an iterable of `(before, after)` pairs.
fn pairs(precedence: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<(usize, usize)>> {
    let Some(p) = precedence else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (i, item) in p.try_iter()?.enumerate() {
        let item = item?;
        let pair = item.extract::<(usize, usize)>().map_err(|_| {
            value_error(format!(
                "precedence item {i}: expected a (before, after) pair of non-negative cell \
                 indices, got {item}"
            ))
        })?;
        out.push(pair);
    }
    Ok(out)
}

#[pymethods]
impl PyInstance {
    /// An instance given by a square cost matrix: `costs[a, b]` is the cost of cutting cell
    /// `b` right after cell `a`; `precedence` lists `(before, after)` pairs of 0-based cell
    /// indices. An open path with no fixed first or last cell (TSPLIB's SOP fixes both: give
    /// them as precedence).
    ///
    /// With `modes` (a list of mode counts, one per cell) the matrix's rows and columns are
    /// the modes of every cell, cell by cell (`sum(modes)` of them), and a sequence visits each
    /// cell once in one of its modes (the generalized problem).
    ///
    /// A C-contiguous float64 array is read in place (no intermediate copy); other arrays are
    /// converted by NumPy first. Costs must be finite, in 0..=1e12; precedence acyclic and in
    /// range. Raises `CellseqError` (a `ValueError`) otherwise.
    #[staticmethod]
    #[pyo3(signature = (costs, precedence=None, modes=None, name="matrix"))]
    fn from_matrix(
        py: Python<'_>,
        costs: &Bound<'_, PyAny>,
        precedence: Option<&Bound<'_, PyAny>>,
        modes: Option<Vec<usize>>,
        name: &str,
    ) -> PyResult<PyInstance> {
        let (size, costs) = matrix_costs(costs)?;
        let prec = pairs(precedence)?;
        let name = name.to_string();
        let inst = py.detach(move || {
            guard("from_matrix", || match modes {
                None => rs(Instance::from_matrix(&name, size, costs, &prec)),
                Some(m) => rs(Instance::from_mode_matrix(&name, &m, costs, &prec)),
            })
        })?;
        Ok(PyInstance::new(inst))
    }

    /// The instance's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }
    /// Number of cells.
    #[getter]
    fn n(&self) -> usize {
        self.inner.n()
    }
    fn __len__(&self) -> usize {
        self.inner.n()
    }
    /// Number of modes of each cell.
    #[getter]
    fn modes(&self) -> Vec<usize> {
        self.inner.cells.iter().map(|c| c.modes.len()).collect()
    }
    /// Each cell's id (its name in the file).
    #[getter]
    fn cell_ids(&self) -> Vec<String> {
        self.inner.cells.iter().map(|c| c.id.clone()).collect()
    }
    /// Precedence pairs `(before, after)` of 0-based cell indices.
    #[getter]
    fn precedence(&self) -> Vec<(usize, usize)> {
        self.inner.precedence.clone()
    }
    /// True for an explicit-matrix instance (TSPLIB SOP, PCGTSP, `from_matrix`).
    #[getter]
    fn is_matrix(&self) -> bool {
        self.inner.is_matrix()
    }
    /// The objective used when none is given: `matrix` or `time`.
    #[getter]
    fn default_objective(&self) -> &'static str {
        self.inner.default_objective().name()
    }
    /// The as-programmed order as `(cell, mode)` pairs, when the instance has one.
    #[getter]
    fn as_given<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyList>>> {
        self.inner
            .as_given
            .as_ref()
            .map(|s| convert::sequence_to_py(py, s))
            .transpose()
    }
    /// Cell positions for plotting (geometric instances): an `(n, 2)` array of each cell's
    /// first mode's entry point `x, y` (mm); `None` for matrix instances.
    #[getter]
    fn entry_points<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        if self.inner.is_matrix() {
            return Ok(None);
        }
        let xy: Vec<Vec<f64>> = self
            .inner
            .cells
            .iter()
            .map(|c| {
                let p = c.modes.first().map(|m| m.entry).unwrap_or_default();
                vec![p.x, p.y]
            })
            .collect();
        let arr = numpy::PyArray2::from_vec2(py, &xy)
            .map_err(|e| value_error(format!("entry points: {e}")))?;
        Ok(Some(arr.into_any()))
    }
    /// Generator, parameters and seed that made the instance, when generated.
    #[getter]
    fn metadata<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::to_py(py, &self.inner.meta)
    }
    /// Writes the instance (cellseq JSON, or TSPLIB SOP for a `.sop` name), atomically.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inst = Arc::clone(&self.inner);
        py.detach(move || guard("save", || rs(cellseq::save_instance(&path, &inst))))
    }
    fn __repr__(&self) -> String {
        format!(
            "<cellseq.Instance '{}': {} cells, {} precedence pairs, {}>",
            self.inner.name,
            self.inner.n(),
            self.inner.precedence.len(),
            if self.inner.is_matrix() {
                "matrix"
            } else {
                "geometric"
            }
        )
    }
}

/// Generates an instance of `kind` (`panel`, `casing`, `cabin`, `uniform`, the training
/// families: see `cellseq.generators()`) with `seed` and `params` (a dict; unknown names are
/// refused with the kind's list). The same kind, parameters and seed give the same instance.
#[pyfunction]
#[pyo3(signature = (kind, seed=1, params=None))]
pub fn generate(
    py: Python<'_>,
    kind: &str,
    seed: u64,
    params: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyInstance> {
    let given = convert::text_params(params)?;
    let kind = kind.to_string();
    let inst = py.detach(move || {
        guard("generate", || {
            rs(cellseq::generate::generate(&kind, &given, seed))
        })
    })?;
    Ok(PyInstance::new(inst))
}
