//! `proxform.Controller` and `proxform.Controllers`: the formation controller alone (the core's
//! agent step), for other simulators. One UAV per `Controller`; many UAVs stepped in one call,
//! from arrays, by `Controllers`.
//!
//! At the boundary: states are 9 numbers, x, y, z (m), vx, vy, vz (m/s), α, β, γ (rad), world
//! frame x forward, y left, z up; UAVs are numbered from 1; times in seconds. Everything is
//! checked before it reaches the controller (finite numbers, known UAVs, time that does not go
//! back), so bad input raises ValueError and never reaches the method.

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use proxform_core::state::{Input, State9};
use proxform_core::{Agent, Decision, Observation, ObservationSource, Outcome, UavId};
use proxform_scenario::Scenario;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;

use crate::scenario::PyScenario;

/// Outcome codes of [`PyControllers::step`], in this order.
const OUTCOMES: [&str; 3] = ["held", "adjusted", "alone"];

fn code(o: &Outcome) -> i8 {
    match o {
        Outcome::Held => 0,
        Outcome::Adjusted { .. } => 1,
        Outcome::Alone => 2,
    }
}

fn bad(message: String) -> PyErr {
    PyValueError::new_err(message)
}

/// A state from 9 numbers, all finite; `what` names it in an error (built only then).
fn state_from(v: &[f64], what: impl Fn() -> String) -> PyResult<State9> {
    if v.len() != 9 {
        return Err(bad(format!(
            "{}: a state has 9 numbers (x, y, z, vx, vy, vz, α, β, γ), found {}",
            what(),
            v.len()
        )));
    }
    if let Some(k) = v.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!("{}: component {k} is {}, not a finite number", what(), v[k])));
    }
    Ok(State9::from_column_slice(v))
}

/// Rows of an (n, 9) array as states; `n` the expected rows (None: any).
pub fn states_from(a: &PyReadonlyArray2<'_, f64>, n: impl Into<Option<usize>>, what: &str) -> PyResult<Vec<State9>> {
    let shape = a.shape();
    let n = n.into();
    if shape[1] != 9 || n.is_some_and(|n| n != shape[0]) {
        let rows = n.map_or("n".to_string(), |n| n.to_string());
        return Err(bad(format!("{what}: expected shape ({rows}, 9), found ({}, {})", shape[0], shape[1])));
    }
    let view = a.as_array();
    let mut row = [0.0; 9];
    (0..shape[0])
        .map(|i| {
            for (r, v) in row.iter_mut().zip(view.row(i)) {
                *r = *v;
            }
            state_from(&row, || format!("{what}[{i}]"))
        })
        .collect()
}

/// `obj` as a numpy array of `dtype` ("float64", "int64"): itself when it already is one,
/// else converted by `numpy.asarray` (lists, other dtypes). A conversion that fails raises
/// ValueError naming `what`.
fn array_like<'py>(obj: &Bound<'py, PyAny>, dtype: &str, what: &str) -> PyResult<Bound<'py, PyAny>> {
    let np = obj.py().import("numpy")?;
    np.call_method1("ascontiguousarray", (obj, dtype))
        .map_err(|e| bad(format!("{what}: expected numbers convertible to {dtype}: {e}")))
}

/// `obj` as a contiguous int64 array of whole numbers: integers as they are, floats only when
/// every one is a whole number within ±2^53 (1.9 is refused, never truncated to 1), booleans
/// refused.
fn whole_like<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyAny>> {
    let np = obj.py().import("numpy")?;
    let a = np.call_method1("asarray", (obj,)).map_err(|e| bad(format!("{what}: expected whole numbers: {e}")))?;
    let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
    match kind.as_str() {
        "b" => return Err(bad(format!("{what}: expected whole numbers, found booleans"))),
        "f" => {
            let whole = np.call_method1("trunc", (&a,))?;
            let small = np.call_method1("less_equal", (np.call_method1("abs", (&a,))?, 9_007_199_254_740_992.0f64))?;
            let ok: bool = np.call_method1("array_equal", (&a, &whole))?.extract::<bool>()?
                && np.call_method1("all", (small,))?.extract::<bool>()?;
            if !ok {
                let flat = a.call_method0("ravel")?;
                let bad_at = np.call_method1("flatnonzero", (np.call_method1("not_equal", (&a, &whole))?,))?;
                let first = match bad_at.len()? {
                    0 => String::from("a number beyond ±2^53"),
                    _ => flat.get_item(bad_at.get_item(0)?)?.str()?.to_string(),
                };
                return Err(bad(format!("{what}: expected whole numbers, found {first}")));
            }
        }
        _ => {}
    }
    array_like(&a, "int64", what)
}

/// A UAV number given as one Python int (a bool, a float such as 2.0, or anything else raises
/// a TypeError naming the argument `what`).
fn uav_number(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<i64> {
    let kind = obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
    if obj.is_instance_of::<pyo3::types::PyBool>() || !obj.is_instance_of::<pyo3::types::PyInt>() {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!("{what}: a UAV number (an int), not {kind} {obj}")));
    }
    obj.extract::<i64>().map_err(|_| bad(format!("{what} = {obj}: not a UAV number of this scenario")))
}

/// Checks a neighbour's number (from 1) against the formation and the observer.
fn neighbour_id(id: i64, me: UavId, uavs: usize, what: impl Fn() -> String) -> PyResult<UavId> {
    if id < 1 || id as u64 > uavs as u64 {
        return Err(bad(format!("{}: UAV {id} is not in the formation (UAVs 1 to {uavs})", what())));
    }
    let id = UavId((id - 1) as u32);
    if id == me {
        return Err(bad(format!("{}: UAV {} cannot observe itself", what(), id.0 + 1)));
    }
    Ok(id)
}

fn age_from(a: f64, what: impl Fn() -> String) -> PyResult<f64> {
    if !(a.is_finite() && a >= 0.0) {
        return Err(bad(format!("{}: an age is a finite number of seconds ≥ 0, found {a}", what())));
    }
    Ok(a)
}

/// The agent of UAV `uav` (from 1) of `sc`: a follower, not the navigator.
fn agent_of(sc: &Scenario, uav: i64) -> PyResult<(UavId, Agent)> {
    let n = sc.len();
    if uav < 1 || uav as u64 > n as u64 {
        return Err(bad(format!("uav = {uav}: the scenario has UAVs 1 to {n}")));
    }
    let id = UavId((uav - 1) as u32);
    if id == sc.navigator() {
        return Err(bad(format!("uav = {uav} is the navigator: it flies its path and runs no controller")));
    }
    let agent = Agent::new(sc.agents(), id).map_err(|e| bad(format!("uav = {uav}: {e}")))?;
    Ok((id, agent))
}

/// Time of a step: finite and never before the previous step's.
fn check_time(t_s: f64, last: Option<f64>) -> PyResult<()> {
    if !t_s.is_finite() {
        return Err(bad(format!("t_s = {t_s}: a time is a finite number of seconds")));
    }
    if let Some(l) = last.filter(|l| t_s < *l) {
        return Err(bad(format!("t_s = {t_s} is before the previous step's {l}: time does not go back")));
    }
    Ok(())
}

/// What one step decided.
#[pyclass(name = "Decision", module = "proxform._proxform", frozen)]
pub struct PyDecision {
    /// "held", "adjusted" or "alone".
    #[pyo3(get)]
    outcome: &'static str,
    /// The input for the coming period, 6 numbers: for the kinematic vehicle the velocity
    /// changes Δvx, Δvy, Δvz (m/s) and attitude changes Δα, Δβ, Δγ (rad); for the fixed wing
    /// roll-rate, yaw-rate, pitch-rate and acceleration commands as fractions of their limits,
    /// then two zeros (see docs/python.md). Zero unless adjusted.
    #[pyo3(get)]
    input: [f64; 6],
    /// Σ((X − O)/Δ)² of the course before an adjustment (None unless adjusted).
    #[pyo3(get)]
    normalised_sq: Option<f64>,
    /// Azimuth areas that held a neighbour.
    #[pyo3(get)]
    occupied_areas: u16,
    /// Main references perceived.
    #[pyo3(get)]
    main_refs: u16,
    /// Neighbours the robust fusion left out (scenario key `controller.isolation_gate`).
    #[pyo3(get)]
    isolated: u16,
    /// True when the UAV refused its own measurement and decided on its own prediction
    /// (scenario key `controller.own_gate_m`).
    #[pyo3(get)]
    own_suspect: bool,
    /// For the multirotor, what its autopilot flies from now on: [vx, vy, vz] (world frame,
    /// m/s) and yaw β (rad), absolute (chosen at the state the UAV was given when it adjusted;
    /// the last one while it holds); None before its first adjustment and for the other
    /// vehicles.
    #[pyo3(get)]
    setpoint: Option<[f64; 4]>,
}

impl From<Decision> for PyDecision {
    fn from(d: Decision) -> Self {
        let mut input = [0.0; 6];
        input.copy_from_slice(d.input.as_slice());
        let normalised_sq = match d.outcome {
            Outcome::Adjusted { normalised_sq } => Some(normalised_sq),
            _ => None,
        };
        Self {
            outcome: d.outcome.label(),
            input,
            normalised_sq,
            occupied_areas: d.occupied_areas,
            main_refs: d.main_refs,
            isolated: d.isolated,
            own_suspect: d.own_suspect,
            setpoint: d.setpoint.map(|s| [s.velocity_mps[0], s.velocity_mps[1], s.velocity_mps[2], s.yaw_rad]),
        }
    }
}

#[pymethods]
impl PyDecision {
    fn __repr__(&self) -> String {
        format!("Decision(outcome={:?}, input={:?})", self.outcome, self.input)
    }
}

/// The controller of one UAV: built from a scenario and the UAV's number, stepped once per
/// update period with its own (measured) state and what it observed of its neighbours.
#[pyclass(name = "Controller", module = "proxform._proxform")]
pub struct PyController {
    scenario: std::sync::Arc<Scenario>,
    id: UavId,
    agent: Agent,
    last_t: Option<f64>,
    heard: Vec<Observation>,
}

#[pymethods]
impl PyController {
    /// The controller of UAV `uav` (from 1; not the navigator) of `scenario`, running the
    /// scenario's method (the proximity method or a baseline).
    #[new]
    fn new(scenario: &Bound<'_, PyScenario>, uav: &Bound<'_, PyAny>) -> PyResult<Self> {
        let sc = scenario.get().inner.clone();
        let (id, agent) = agent_of(&sc, uav_number(uav, "uav")?)?;
        Ok(Self { scenario: sc, id, agent, last_t: None, heard: Vec::with_capacity(16) })
    }

    /// One update period at `t_s` (s). `own`: the UAV's own measured state (9 numbers).
    /// `neighbours`: an (n, 10) array whose rows are a UAV number then its 9-number state, or a
    /// sequence of (number, state) pairs. `ages`: how old each observation is (s, default 0);
    /// `radio`: which came over the radio rather than the UAV's own sensors (default none).
    #[pyo3(signature = (t_s, own, neighbours, ages = None, radio = None))]
    fn step(
        &mut self,
        t_s: f64,
        own: &Bound<'_, PyAny>,
        neighbours: &Bound<'_, PyAny>,
        ages: Option<Vec<f64>>,
        radio: Option<Vec<bool>>,
    ) -> PyResult<PyDecision> {
        check_time(t_s, self.last_t)?;
        let own = match own.extract::<PyReadonlyArray1<'_, f64>>() {
            Ok(a) => state_from(&a.as_array().to_vec(), || "own".into())?,
            Err(_) => {
                state_from(&own.extract::<Vec<f64>>().map_err(|_| bad("own: expected 9 numbers".into()))?, || {
                    "own".into()
                })?
            }
        };
        // A numpy array of another dtype is converted; a list of pairs is read as such.
        let converted;
        let neighbours = match neighbours.extract::<PyReadonlyArray2<'_, f64>>() {
            Err(_) if neighbours.is_instance_of::<numpy::PyUntypedArray>() => {
                converted = array_like(neighbours, "float64", "neighbours")?;
                &converted
            }
            _ => neighbours,
        };
        let n = self.scenario.len();
        self.heard.clear();
        if let Ok(a) = neighbours.extract::<PyReadonlyArray2<'_, f64>>() {
            let shape = a.shape();
            if shape[1] != 10 && shape[0] > 0 {
                return Err(bad(format!(
                    "neighbours: expected shape (n, 10), a UAV number then its state, found ({}, {})",
                    shape[0], shape[1]
                )));
            }
            let view = a.as_array();
            for i in 0..shape[0] {
                let row = view.row(i);
                let raw = row[0];
                if raw.fract() != 0.0 || !raw.is_finite() {
                    return Err(bad(format!("neighbours[{i}]: UAV number {raw} is not a whole number")));
                }
                let what = || format!("neighbours[{i}]");
                let id = neighbour_id(raw as i64, self.id, n, what)?;
                let mut s = [0.0; 9];
                for (x, v) in s.iter_mut().zip(row.iter().skip(1)) {
                    *x = *v;
                }
                let state = state_from(&s, what)?;
                self.heard.push(Observation { id, state, age_s: 0.0, source: ObservationSource::Onboard });
            }
        } else {
            let pairs: Vec<(i64, Vec<f64>)> = neighbours.extract().map_err(|_| {
                bad("neighbours: expected an (n, 10) array or a sequence of (UAV number, state) pairs".into())
            })?;
            for (i, (raw, s)) in pairs.iter().enumerate() {
                let what = || format!("neighbours[{i}]");
                let id = neighbour_id(*raw, self.id, n, what)?;
                let state = state_from(s, what)?;
                self.heard.push(Observation { id, state, age_s: 0.0, source: ObservationSource::Onboard });
            }
        }
        if let Some(ages) = ages {
            if ages.len() != self.heard.len() {
                return Err(bad(format!("ages: {} for {} neighbours", ages.len(), self.heard.len())));
            }
            for (i, (o, a)) in self.heard.iter_mut().zip(ages).enumerate() {
                o.age_s = age_from(a, || format!("ages[{i}]"))?;
            }
        }
        if let Some(radio) = radio {
            if radio.len() != self.heard.len() {
                return Err(bad(format!("radio: {} for {} neighbours", radio.len(), self.heard.len())));
            }
            for (o, r) in self.heard.iter_mut().zip(radio) {
                o.source = if r { ObservationSource::Radio } else { ObservationSource::Onboard };
            }
        }
        self.last_t = Some(t_s);
        Ok(self.agent.step(t_s, &own, &self.heard).into())
    }

    /// The state one period after `state` under `input`, by the scenario's vehicle model
    /// (what the simulator's plant does without wind and actuation error).
    fn propagate<'py>(&self, py: Python<'py>, state: Vec<f64>, input: Vec<f64>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = state_from(&state, || "state".into())?;
        if input.len() != 6 || input.iter().any(|v| !v.is_finite()) {
            return Err(bad(format!("input: expected 6 finite numbers, found {input:?}")));
        }
        let u = Input::from_column_slice(&input);
        let (vehicle, dt) = (self.scenario.vehicle(), self.scenario.dt_s());
        // A command far beyond what the vehicle can do in one period at this state (the fixed
        // wing's model returned −inf for one) is refused, naming the bounds; near them (as a
        // decision made at a slightly other state is) it is flown.
        if !vehicle.plausible(&x, &u, None, dt) {
            let (lo, hi) = vehicle.input_bounds(&x, dt);
            let j = (0..u.len()).find(|&j| u[j] < lo[j] || u[j] > hi[j]).unwrap_or(0);
            return Err(bad(format!(
                "input[{j}] = {:?}: far beyond what the vehicle can do in one period at this state ({:?} to {:?})",
                u[j], lo[j], hi[j]
            )));
        }
        let next = vehicle.propagate(&x, &u, dt);
        if !proxform_core::state::is_finite(&next) {
            return Err(bad("the vehicle's model gives no finite state for this state and input".into()));
        }
        Ok(PyArray1::from_slice(py, next.as_slice()))
    }

    /// The UAV's number (from 1).
    #[getter]
    fn uav(&self) -> u32 {
        self.id.0 + 1
    }
}

/// The controllers of many UAVs of one scenario, stepped together from arrays (in parallel
/// for large swarms; the results do not depend on the thread count).
#[pyclass(name = "Controllers", module = "proxform._proxform")]
pub struct PyControllers {
    scenario: std::sync::Arc<Scenario>,
    ids: Vec<UavId>,
    agents: Vec<Agent>,
    last_t: Option<f64>,
    heard: Vec<Observation>,
    offsets: Vec<usize>,
}

/// What [`PyControllers::step`] returns: inputs (n, 6) and outcome codes (n,).
type StepArrays<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<i8>>);

/// Below this many UAVs a step runs on the calling thread.
const PARALLEL_FROM: usize = 512;

#[pymethods]
impl PyControllers {
    /// The controllers of `uavs` (numbers from 1; default: every UAV but the navigator).
    #[new]
    #[pyo3(signature = (scenario, uavs = None))]
    fn new(scenario: &Bound<'_, PyScenario>, uavs: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let sc = scenario.get().inner.clone();
        let nav = sc.navigator().0 as i64 + 1;
        // Each UAV number as Controller's `uav` is checked (a whole number, not 2.9), the
        // argument named.
        let uavs: Vec<i64> = match uavs {
            None => (1..=sc.len() as i64).filter(|u| *u != nav).collect(),
            Some(list) => {
                let items = list.try_iter().map_err(|_| {
                    bad(format!(
                        "uavs: a sequence of UAV numbers (from 1), not {}",
                        list.get_type().name().map_or_else(|_| "that".into(), |n| n.to_string())
                    ))
                })?;
                let mut out = Vec::new();
                for (k, item) in items.enumerate() {
                    let item = item?;
                    let whole =
                        !item.is_instance_of::<pyo3::types::PyBool>() && !item.is_instance_of::<pyo3::types::PyFloat>();
                    match item.extract::<i64>() {
                        Ok(u) if whole => out.push(u),
                        _ => {
                            let kind = item.get_type().name().map_or_else(|_| "?".into(), |n| n.to_string());
                            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                                "uavs[{k}]: a UAV number (an int), not {kind} {item}"
                            )));
                        }
                    }
                }
                out
            }
        };
        let mut seen = vec![false; sc.len()];
        let mut ids = Vec::with_capacity(uavs.len());
        let mut agents = Vec::with_capacity(uavs.len());
        for u in uavs {
            let (id, agent) = agent_of(&sc, u)?;
            if std::mem::replace(&mut seen[id.index()], true) {
                return Err(bad(format!("uavs: UAV {u} is listed twice")));
            }
            ids.push(id);
            agents.push(agent);
        }
        Ok(Self { scenario: sc, ids, agents, last_t: None, heard: Vec::new(), offsets: Vec::new() })
    }

    /// The UAVs' numbers (from 1), in the order of every array of `step`.
    #[getter]
    fn uavs(&self) -> Vec<u32> {
        self.ids.iter().map(|i| i.0 + 1).collect()
    }

    /// The outcome names of the codes `step` returns.
    #[classattr]
    fn outcomes() -> (&'static str, &'static str, &'static str) {
        (OUTCOMES[0], OUTCOMES[1], OUTCOMES[2])
    }

    /// One update period at `t_s` for every UAV. `own`: (n, 9) own measured states, in the
    /// order of `uavs`. Observations: `counts[i]` rows of `ids` (m,) and `states` (m, 9) belong
    /// to UAV i, in order; `ages` (m,) optional (s, default 0). Returns (inputs (n, 6),
    /// outcome codes (n,) int8: 0 held, 1 adjusted, 2 alone).
    #[pyo3(signature = (t_s, own, counts, ids, states, ages = None))]
    #[expect(clippy::too_many_arguments, reason = "one argument per keyword of the Python signature")]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t_s: f64,
        own: &Bound<'py, PyAny>,
        counts: &Bound<'py, PyAny>,
        ids: &Bound<'py, PyAny>,
        states: &Bound<'py, PyAny>,
        ages: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<StepArrays<'py>> {
        check_time(t_s, self.last_t)?;
        // Arrays of the right dtype are read in place; anything else is converted first.
        fn read<'py, T: numpy::Element>(
            obj: &Bound<'py, PyAny>,
            dtype: &str,
            what: &str,
        ) -> PyResult<Bound<'py, PyAny>> {
            match obj.cast::<numpy::PyArrayDyn<T>>() {
                Ok(_) => Ok(obj.clone()),
                Err(_) => array_like(obj, dtype, what),
            }
        }
        let own = read::<f64>(own, "float64", "own")?;
        let own: PyReadonlyArray2<'py, f64> = own.extract().map_err(|_| bad("own: expected an (n, 9) array".into()))?;
        let counts = match counts.cast::<numpy::PyArrayDyn<i64>>() {
            Ok(_) => counts.clone(),
            Err(_) => whole_like(counts, "counts")?,
        };
        let counts: PyReadonlyArray1<'py, i64> =
            counts.extract().map_err(|_| bad("counts: expected a 1-D array of whole numbers".into()))?;
        let ids = match ids.cast::<numpy::PyArrayDyn<i64>>() {
            Ok(_) => ids.clone(),
            Err(_) => whole_like(ids, "ids")?,
        };
        let ids: PyReadonlyArray1<'py, i64> =
            ids.extract().map_err(|_| bad("ids: expected a 1-D array of UAV numbers".into()))?;
        let states_any = read::<f64>(states, "float64", "states")?;
        // No observation at all may come as an empty list: shape (0,) reads as (0, 9).
        let states_any = match states_any.getattr("size")?.extract::<usize>()? {
            0 => states_any.call_method1("reshape", ((0usize, 9usize),))?,
            _ => states_any,
        };
        let states: PyReadonlyArray2<'py, f64> =
            states_any.extract().map_err(|_| bad("states: expected an (m, 9) array".into()))?;
        let ages = match ages {
            Some(a) => Some(
                read::<f64>(a, "float64", "ages")?
                    .extract::<PyReadonlyArray1<'py, f64>>()
                    .map_err(|_| bad("ages: expected a 1-D array of seconds".into()))?,
            ),
            None => None,
        };
        let n = self.agents.len();
        let own = states_from(&own, n, "own")?;
        let counts = counts.as_array();
        if counts.len() != n {
            return Err(bad(format!("counts: {} entries for {n} UAVs", counts.len())));
        }
        let ids = ids.as_array();
        let m = ids.len();
        let obs_states = states_from(&states, m, "states")?;
        let ages = match &ages {
            Some(a) if a.len() != m => return Err(bad(format!("ages: {} for {m} observations", a.len()))),
            Some(a) => Some(a.as_array()),
            None => None,
        };
        self.offsets.clear();
        self.offsets.push(0);
        for (i, &c) in counts.iter().enumerate() {
            let end = (self.offsets[i] as i64).checked_add(c).unwrap_or(i64::MAX);
            if c < 0 || end > m as i64 {
                return Err(bad(format!("counts[{i}] = {c}: the counts must be ≥ 0 and add up to {m} observations")));
            }
            self.offsets.push(end as usize);
        }
        if self.offsets[n] != m {
            return Err(bad(format!("counts add up to {}, but {m} observations were given", self.offsets[n])));
        }
        self.heard.clear();
        let uavs = self.scenario.len();
        for i in 0..n {
            for j in self.offsets[i]..self.offsets[i + 1] {
                let id = neighbour_id(ids[j], self.ids[i], uavs, || format!("ids[{j}]"))?;
                let age_s = match &ages {
                    Some(a) => age_from(a[j], || format!("ages[{j}]"))?,
                    None => 0.0,
                };
                self.heard.push(Observation { id, state: obs_states[j], age_s, source: ObservationSource::Onboard });
            }
        }
        self.last_t = Some(t_s);
        let (agents, heard, offsets) = (&mut self.agents, &self.heard, &self.offsets);
        let step = |(i, agent): (usize, &mut Agent)| agent.step(t_s, &own[i], &heard[offsets[i]..offsets[i + 1]]);
        let decisions: Vec<Decision> = if n >= PARALLEL_FROM {
            py.detach(|| agents.par_iter_mut().enumerate().map(step).collect())
        } else {
            agents.iter_mut().enumerate().map(step).collect()
        };
        let mut inputs = Vec::with_capacity(n * 6);
        for d in &decisions {
            inputs.extend_from_slice(d.input.as_slice());
        }
        let inputs = PyArray1::from_vec(py, inputs).reshape([n, 6])?;
        let codes = PyArray1::from_vec(py, decisions.iter().map(|d| code(&d.outcome)).collect());
        Ok((inputs, codes))
    }
}
