//! `proxform.Scenario` (the Rust side): a checked scenario, loaded from TOML text, a dict or a
//! built-in name; its resolved values; overrides that meet the same checks.

use std::sync::Arc;

use numpy::{PyArray1, PyArray2};
use proxform_scenario::{builtin, load, resolved, Scenario, ScenarioSpec};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors;
use crate::values;

/// A checked scenario. Build it with `proxform.Scenario.from_file`, `from_toml`, `from_dict`
/// or `builtin`; it cannot be changed, only derived (`with_values`).
#[pyclass(name = "Scenario", module = "proxform._proxform", frozen)]
pub struct PyScenario {
    pub(crate) inner: Arc<Scenario>,
}

impl PyScenario {
    pub(crate) fn new(inner: Scenario) -> Self {
        Self { inner: Arc::new(inner) }
    }
}

/// Parses and checks TOML text; errors name `source`, the key and the line.
fn from_text(py: Python<'_>, text: &str, source: &str, with_line: bool) -> PyResult<Scenario> {
    let sc = load::parse(text, source).map_err(|e| errors::from_load(py, &e, with_line))?;
    // `engine = "fast"` on a scenario the fast engine does not run.
    if let Err(e) = proxform_sim::engine_for(&sc) {
        let line = load::locate(text, "engine").filter(|_| with_line);
        let message = match line {
            Some(l) => format!("{source}:{l}: engine: {e}"),
            None => format!("{source}: engine: {e}"),
        };
        return Err(errors::scenario_error(py, &message, Some("engine"), line, source));
    }
    Ok(sc)
}

/// A Python dict as TOML text, or the key that has no TOML form.
fn dict_text(py: Python<'_>, d: &Bound<'_, PyAny>, source: &str) -> PyResult<toml::Value> {
    if !d.is_instance_of::<PyDict>() {
        return Err(values::not_a_dict("a scenario", d));
    }
    values::to_toml(d, "").map_err(|e| {
        errors::scenario_error(py, &format!("{source}: {}: {}", e.key, e.message), Some(&e.key), None, source)
    })
}

fn toml_text(v: &toml::Value) -> PyResult<String> {
    toml::to_string(v).map_err(|e| PyValueError::new_err(format!("cannot write the scenario as TOML: {e}")))
}

#[pymethods]
impl PyScenario {
    /// A scenario from TOML text; `source` names it in errors (a file name, say).
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>"))]
    fn from_toml(py: Python<'_>, text: &str, source: &str) -> PyResult<Self> {
        from_text(py, text, source, true).map(Self::new)
    }

    /// A scenario from a dict with the keys of a scenario file (nested dicts for tables,
    /// lists of dicts for `[[fault]]` and the like). Errors name the key; a dict has no lines.
    #[staticmethod]
    #[pyo3(signature = (d, source = "<dict>"))]
    fn from_dict(py: Python<'_>, d: &Bound<'_, PyAny>, source: &str) -> PyResult<Self> {
        let value = dict_text(py, d, source)?;
        from_text(py, &toml_text(&value)?, source, false).map(Self::new)
    }

    /// A built-in scenario by name (`proxform.builtin_names()`); `uavs` sizes `swarm`.
    #[staticmethod]
    #[pyo3(signature = (name, uavs = None))]
    fn builtin(py: Python<'_>, name: &str, uavs: Option<usize>) -> PyResult<Self> {
        let spec = builtin::spec_by_name(name, uavs).map_err(|m| errors::scenario_error(py, &m, None, None, name))?;
        Scenario::try_from(spec).map(Self::new).map_err(|e| errors::from_spec(py, &e, name))
    }

    /// This scenario with some values changed, given as a dict shaped like the file
    /// (`{"controller": {"lambda": 0.5}, "duration_s": 30}`): tables are merged key by key,
    /// and the result meets every check a file meets.
    fn with_values(&self, py: Python<'_>, changes: &Bound<'_, PyAny>) -> PyResult<Self> {
        let source = format!("{} (with values)", self.inner.name());
        let over = dict_text(py, changes, &source)?;
        let mut base = toml::Value::try_from(self.inner.spec())
            .map_err(|e| PyRuntimeError::new_err(format!("cannot write the scenario's spec: {e}")))?;
        values::merge(&mut base, over);
        from_text(py, &toml_text(&base)?, &source, false).map(Self::new)
    }

    /// Pickled as its spec (the values given, the defaults not frozen), rebuilt by the same
    /// conversion: the same scenario, to the bit.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        let py = slf.py();
        let text = toml::to_string(slf.get().inner.spec())
            .map_err(|e| PyRuntimeError::new_err(format!("cannot write the scenario's spec: {e}")))?;
        let ctor = py.get_type::<Self>().getattr("from_toml")?;
        Ok((ctor, (text, slf.get().inner.name().to_string())))
    }

    /// The scenario as it runs, every default filled in, as TOML that loads again.
    fn to_toml(&self) -> PyResult<String> {
        resolved::to_toml(&self.inner).map_err(|e| PyValueError::new_err(format!("cannot write the scenario: {e}")))
    }

    /// The resolved values (every default filled in) as nested dicts, in the file's units.
    fn resolved<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let spec: ScenarioSpec = resolved::resolved(&self.inner);
        let value = toml::Value::try_from(&spec)
            .map_err(|e| PyRuntimeError::new_err(format!("cannot write the scenario: {e}")))?;
        values::to_python(py, &value)
    }

    /// Short name used in reports.
    #[getter]
    fn name(&self) -> &str {
        self.inner.name()
    }

    /// Number of UAVs.
    #[getter]
    fn uavs(&self) -> usize {
        self.inner.len()
    }

    /// Update period Δt (s).
    #[getter]
    fn dt_s(&self) -> f64 {
        self.inner.dt_s()
    }

    /// Flight duration (s).
    #[getter]
    fn duration_s(&self) -> f64 {
        self.inner.duration_s()
    }

    /// Number of update periods in the flight.
    #[getter]
    fn steps(&self) -> u64 {
        self.inner.steps()
    }

    /// The navigator's number (from 1).
    #[getter]
    fn navigator(&self) -> u32 {
        self.inner.navigator().0 + 1
    }

    /// The safety distance (m).
    #[getter]
    fn safety_distance_m(&self) -> f64 {
        self.inner.safety_distance_m()
    }

    /// Every UAV's initial state in its slot, shape (uavs, 9): x, y, z (m), vx, vy, vz (m/s),
    /// α, β, γ (rad). With `initial.placement` other than "slots" a run starts elsewhere (random
    /// starts are drawn per run from its seed).
    fn initial_states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows: Vec<Vec<f64>> = self.inner.initial().iter().map(|s| s.iter().copied().collect()).collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// The navigator's scripted state at time `t_s` (s), shape (9,).
    fn navigator_state<'py>(&self, py: Python<'py>, t_s: f64) -> PyResult<Bound<'py, PyArray1<f64>>> {
        if !t_s.is_finite() {
            return Err(PyValueError::new_err(format!("t_s must be a finite time, not {t_s}")));
        }
        let s0 = &self.inner.initial()[self.inner.navigator().index()];
        let s = self.inner.path().state_at(t_s, [s0[0], s0[1], s0[2]]);
        Ok(PyArray1::from_slice(py, s.as_slice()))
    }

    /// The allowable errors x, y, z (m), α, β, γ (rad), shape (6,).
    fn allowable_errors<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.allowable().as_array())
    }

    /// Formation errors of every UAV, shape (uavs, 6), relative to the navigator's state as the
    /// run's metrics measure them: x, y, z (m), α, β, γ (rad); zero for the navigator.
    fn formation_errors<'py>(
        &self,
        py: Python<'py>,
        states: numpy::PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let states = crate::controller::states_from(&states, self.inner.len(), "states")?;
        let nav = self.inner.navigator().index();
        let rows: Vec<Vec<f64>> = (0..states.len())
            .map(|i| match i == nav {
                true => vec![0.0; 6],
                false => proxform_sim::measure::observer::formation_error_to(
                    &self.inner,
                    self.inner.formation(),
                    &states,
                    &states[nav],
                    i,
                )
                .to_vec(),
            })
            .collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// Any other top-level key of the resolved scenario (`controller`, `formation`, `noise`,
    /// `vehicle`, …) as its value: `scenario.controller["lambda"]`.
    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let resolved = self.resolved(py)?;
        match resolved.cast::<PyDict>().ok().and_then(|d| d.get_item(name).ok().flatten()) {
            Some(v) => Ok(v),
            None => Err(pyo3::exceptions::PyAttributeError::new_err(format!(
                "a scenario has no key {name:?} (see scenario.resolved() for every key)"
            ))),
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario(name={:?}, uavs={}, dt_s={}, duration_s={})",
            self.inner.name(),
            self.inner.len(),
            self.inner.dt_s(),
            self.inner.duration_s()
        )
    }
}

/// The names of the built-in scenarios.
#[pyfunction]
pub fn builtin_names() -> Vec<&'static str> {
    builtin::NAMES.to_vec()
}
