//! `proxform.compare`: methods side by side under the same conditions, as `proxform compare`
//! runs them, returned as two tables of numpy columns (every run, and every cell).

use numpy::PyArray1;
use proxform_scenario::comparison::{CompareError, Comparison, BUILT_IN};
use proxform_scenario::{builtin, load, Scenario, ScenarioSpec};
use proxform_sim::compare::{flights, run_comparison_stoppable, summarise};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::Value;

use crate::{background, errors};

/// Rows of serialisable records as columns: numbers as float64 (whole numbers as uint64 or
/// int64), true/false as bool, text as lists of str.
fn columns<'py, T: serde::Serialize>(py: Python<'py>, rows: &[T]) -> PyResult<Bound<'py, PyDict>> {
    let values: Vec<serde_json::Map<String, Value>> = rows
        .iter()
        .map(|r| match serde_json::to_value(r) {
            Ok(Value::Object(m)) => Ok(m),
            _ => Err(PyRuntimeError::new_err("a table row is not a record")),
        })
        .collect::<PyResult<_>>()?;
    let d = PyDict::new(py);
    let Some(first) = values.first() else { return Ok(d) };
    for (key, sample) in first {
        let col = values.iter().map(|m| m.get(key).unwrap_or(&Value::Null));
        match sample {
            Value::Bool(_) => {
                d.set_item(key, PyArray1::from_vec(py, col.map(|v| v.as_bool() == Some(true)).collect()))?
            }
            Value::Number(n) if n.is_u64() => {
                d.set_item(key, PyArray1::from_vec(py, col.map(|v| v.as_u64().unwrap_or(0)).collect()))?
            }
            Value::Number(_) => {
                d.set_item(key, PyArray1::from_vec(py, col.map(|v| v.as_f64().unwrap_or(f64::NAN)).collect()))?
            }
            _ => d.set_item(key, col.map(|v| v.as_str().unwrap_or_default().to_string()).collect::<Vec<_>>())?,
        }
    }
    Ok(d)
}

fn compare_error(py: Python<'_>, e: &CompareError, source: &str) -> PyErr {
    match e {
        CompareError::File(l) => errors::from_load(py, l, true),
        other => errors::scenario_error(py, &format!("{source}: {other}"), None, None, source),
    }
}

/// Runs a comparison given as TOML text (`text`, named `source` in errors; None: the built-in
/// comparison). Its `scenario` is a built-in name or a file, read by `read_text(name)`.
/// `seeds` and `duration_s` override the file's, as on the command line. Returns (rows,
/// cells) as column dicts.
#[pyfunction]
#[pyo3(signature = (text, source, read_text, seeds = None, duration_s = None, threads = 0, progress = None))]
#[expect(clippy::too_many_arguments, reason = "one argument per keyword of the Python signature")]
pub fn compare<'py>(
    py: Python<'py>,
    text: Option<&str>,
    source: &str,
    read_text: &Bound<'py, PyAny>,
    seeds: Option<u64>,
    duration_s: Option<f64>,
    threads: usize,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let text = text.unwrap_or(BUILT_IN);
    // The base scenario's spec, checked where it was read, with the duration written in.
    let resolve = |s: &str| -> Result<ScenarioSpec, String> {
        let mut spec = if builtin::NAMES.contains(&s) {
            builtin::spec_by_name(s, None)?
        } else {
            let file: String = read_text.call1((s,)).and_then(|t| t.extract()).map_err(|e| e.to_string())?;
            let spec = load::parse_spec(&file, s).map_err(|e| e.to_string())?;
            load::check(spec.clone(), &file, s).map_err(|e| e.to_string())?;
            spec
        };
        if let Some(d) = duration_s {
            spec.duration_s = Some(d);
            Scenario::try_from(spec.clone()).map_err(|e| format!("duration_s: {}", e.message))?;
        }
        Ok(spec)
    };
    let cmp = Comparison::parse_spec(text, source)
        .and_then(|mut spec| {
            if let Some(n) = seeds {
                spec.seeds = n;
            }
            Comparison::from_spec(spec, text, source, resolve)
        })
        .map_err(|e| compare_error(py, &e, source))?;
    let total = flights(&cmp);
    let rows = background::run(py, threads, total, progress, move |h| {
        run_comparison_stoppable(&cmp, &|| h.tick(), &h.stop).map_err(|e| e.to_string()).transpose()
    })?
    .map_err(PyValueError::new_err)?;
    let cells = summarise(&rows);
    Ok((columns(py, &rows)?, columns(py, &cells)?))
}
