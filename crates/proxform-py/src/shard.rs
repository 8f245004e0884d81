//! `proxform.Runs` (the Rust side): a batch's runs with their exact results, as a shard of a
//! larger batch; picklable (its journal's bytes), merged with other shards of the same batch
//! into the summary one batch of all of them would have had (`proxform.merge`).

use std::sync::Arc;

use proxform_sim::batch::merge::merge_shards;
use proxform_sim::batch::sweep;
use proxform_sim::Shard;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::scenario::PyScenario;

/// The exact results of a batch's runs (a shard): from `proxform.run`, picklable, merged by
/// `merge_runs`.
#[pyclass(name = "Runs", module = "proxform._proxform", frozen)]
pub struct PyRuns {
    pub(crate) inner: Arc<Shard>,
}

impl PyRuns {
    pub(crate) fn new(inner: Shard) -> Self {
        Self { inner: Arc::new(inner) }
    }
}

fn summary_json(s: &Shard) -> PyResult<String> {
    let summary = s.summary().map_err(|e| PyRuntimeError::new_err(format!("cannot summarise the runs: {e}")))?;
    serde_json::to_string(&summary).map_err(|e| PyRuntimeError::new_err(format!("cannot write the summary: {e}")))
}

#[pymethods]
impl PyRuns {
    /// Runs from the bytes of a journal (`runs.journal`, or a pickle's); every run of it
    /// must be done.
    #[staticmethod]
    fn from_bytes(data: &[u8]) -> PyResult<Self> {
        Shard::from_bytes(data).map(Self::new).map_err(|e| PyValueError::new_err(format!("not a batch's runs: {e}")))
    }

    /// The journal's bytes (what `runs.journal` holds for these runs).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let b = self.inner.to_bytes().map_err(|e| PyRuntimeError::new_err(format!("cannot write the runs: {e}")))?;
        Ok(PyBytes::new(py, &b))
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
        let py = slf.py();
        let ctor = py.get_type::<Self>().getattr("from_bytes")?;
        Ok((ctor, (slf.get().to_bytes(py)?,)))
    }

    /// The summary (JSON text) of exactly these runs.
    fn summary_json(&self) -> PyResult<String> {
        summary_json(&self.inner)
    }

    /// The per-run table's columns.
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        crate::run::runs_dict(py, self.inner.header.seed, &self.inner.runs)
    }

    /// The row of a sweep's table for these runs (the columns of `sweep.csv` after the keys;
    /// None where the summary has no such part).
    fn row<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let summary =
            self.inner.summary().map_err(|e| PyRuntimeError::new_err(format!("cannot summarise the runs: {e}")))?;
        let d = PyDict::new(py);
        for (k, v) in sweep::row(&summary) {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    /// The scenario the runs flew (rebuilt exactly from the spec they carry).
    fn scenario(&self) -> PyResult<PyScenario> {
        self.inner
            .header
            .scenario()
            .map(PyScenario::new)
            .map_err(|e| PyValueError::new_err(format!("the runs' scenario: {e}")))
    }

    /// The base seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.inner.header.seed
    }

    /// The first run's index.
    #[getter]
    fn first_run(&self) -> u64 {
        self.inner.header.first_run
    }

    /// The number of runs.
    fn __len__(&self) -> usize {
        self.inner.runs.len()
    }

    /// The scenario's name.
    #[getter]
    fn scenario_name(&self) -> &str {
        &self.inner.header.scenario
    }

    fn __repr__(&self) -> String {
        let h = &self.inner.header;
        format!(
            "Runs('{}', seed={}, runs {}..={})",
            h.scenario,
            h.seed,
            h.first_run,
            (h.first_run + h.runs).saturating_sub(1)
        )
    }
}

/// Shards of one batch (same scenario, seed and options; no run twice; together consecutive
/// runs) merged into one, named in errors by `names`.
#[pyfunction]
#[pyo3(signature = (shards, names = None))]
pub fn merge_runs(shards: Vec<Bound<'_, PyRuns>>, names: Option<Vec<String>>) -> PyResult<PyRuns> {
    let names = names.unwrap_or_else(|| (1..=shards.len()).map(|k| format!("shard {k}")).collect());
    if names.len() != shards.len() {
        return Err(PyValueError::new_err(format!("names: {} names for {} shards", names.len(), shards.len())));
    }
    let held: Vec<Arc<Shard>> = shards.iter().map(|s| s.get().inner.clone()).collect();
    let pairs: Vec<(&str, &Shard)> = names.iter().map(String::as_str).zip(held.iter().map(|s| &**s)).collect();
    merge_shards(&pairs).map(PyRuns::new).map_err(|e| PyValueError::new_err(e.to_string()))
}
