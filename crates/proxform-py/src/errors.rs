//! The package's exception: a scenario (or comparison) that could not be loaded, with the key,
//! line and source that the located errors of the scenario crate carry.

use proxform_scenario::{LoadError, SpecError};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

pyo3::create_exception!(
    proxform._proxform,
    ScenarioError,
    PyValueError,
    "A scenario or comparison that could not be loaded. Attributes: `key` (the key path, such as \
     `controller.lambda` or `fault[2].at_s`, or None), `line` (1-based line in the source text, \
     or None for a dict) and `source` (the file or source name)."
);

/// A [`ScenarioError`] with its attributes set.
pub fn scenario_error(py: Python<'_>, message: &str, key: Option<&str>, line: Option<usize>, source: &str) -> PyErr {
    let err = ScenarioError::new_err(message.to_string());
    let value = err.value(py);
    // Setting attributes on a fresh exception instance cannot fail short of memory; if it
    // did, the message alone still says everything.
    let _ = value.setattr("key", key);
    let _ = value.setattr("line", line);
    let _ = value.setattr("source", source);
    err
}

/// A located load error; `with_line` false for sources whose lines mean nothing to the user
/// (a dict turned into TOML).
pub fn from_load(py: Python<'_>, e: &LoadError, with_line: bool) -> PyErr {
    let line = e.line.filter(|_| with_line);
    let message = match (with_line, &e.key) {
        (true, _) => e.to_string(),
        (false, Some(key)) => format!("{}: {key}: {}", e.source_name, e.message),
        (false, None) => format!("{}: {}", e.source_name, e.message),
    };
    scenario_error(py, &message, e.key.as_deref(), line, &e.source_name)
}

/// A conversion error of a spec that has no text (a built-in with an override).
pub fn from_spec(py: Python<'_>, e: &SpecError, source: &str) -> PyErr {
    scenario_error(py, &format!("{source}: {}: {}", e.key, e.message), Some(&e.key), None, source)
}
