//! `proxform.run`: a batch of seeded runs, returned as its summary (JSON text, loaded into a
//! dict by the package), the per-run table and the first run's trajectories as numpy columns.

use std::sync::{Arc, Mutex};

use numpy::PyArray1;
use proxform_sim::measure::trajectory::RowSink;
use proxform_sim::{
    run_batch_stoppable, AxisErrors, JournalHeader, RunOptions, RunSummary, Shard, Trajectory, TrajectoryRow,
};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::background;
use crate::scenario::PyScenario;
use crate::shard::PyRuns;

/// Most runs in one batch (as the command line allows).
const MAX_RUNS: u64 = 10_000_000;

/// Largest first run index (as `--first-run` allows).
const MAX_FIRST_RUN: u64 = 1 << 52;

/// The first run's trajectories, column by column, as `trajectories.csv` holds them (same
/// names and units: SI and radians for the states, m and degrees for the errors).
#[derive(Default)]
struct Columns {
    t_s: Vec<f64>,
    uav: Vec<u32>,
    state: [Vec<f64>; 9],
    error: [Vec<f64>; 6],
    in_envelope: Vec<bool>,
    within_allowable: Vec<bool>,
    outcome: Vec<&'static str>,
}

/// A row sink that appends to shared [`Columns`].
struct ColumnSink(Arc<Mutex<Columns>>);

impl RowSink for ColumnSink {
    fn row(&mut self, r: &TrajectoryRow) {
        let Ok(mut c) = self.0.lock() else { return };
        c.t_s.push(r.t);
        c.uav.push(r.uav + 1);
        for k in 0..9 {
            c.state[k].push(r.state[k]);
        }
        for k in 0..6 {
            c.error[k].push(if k < 3 { r.error[k] } else { r.error[k].to_degrees() });
        }
        c.in_envelope.push(r.in_envelope);
        c.within_allowable.push(r.within_allowable);
        c.outcome.push(r.outcome);
    }

    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}

const STATE_COLUMNS: [&str; 9] =
    ["x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps", "alpha_rad", "beta_rad", "gamma_rad"];
const ERROR_COLUMNS: [&str; 6] = ["err_x_m", "err_y_m", "err_z_m", "err_alpha_deg", "err_beta_deg", "err_gamma_deg"];
const AXES: [&str; 6] = ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"];

fn trajectory_dict<'py>(py: Python<'py>, c: Columns) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t_s", PyArray1::from_vec(py, c.t_s))?;
    d.set_item("uav", PyArray1::from_vec(py, c.uav))?;
    for (name, col) in STATE_COLUMNS.iter().zip(c.state) {
        d.set_item(name, PyArray1::from_vec(py, col))?;
    }
    for (name, col) in ERROR_COLUMNS.iter().zip(c.error) {
        d.set_item(name, PyArray1::from_vec(py, col))?;
    }
    d.set_item("in_envelope", PyArray1::from_vec(py, c.in_envelope))?;
    d.set_item("within_allowable", PyArray1::from_vec(py, c.within_allowable))?;
    d.set_item("outcome", c.outcome)?;
    Ok(d)
}

/// The per-run table: the columns of `runs.csv`, at full precision.
pub(crate) fn runs_dict<'py>(py: Python<'py>, seed: u64, runs: &[RunSummary]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&RunSummary) -> f64| PyArray1::from_vec(py, runs.iter().map(f).collect());
    d.set_item("seed", PyArray1::from_vec(py, vec![seed; runs.len()]))?;
    d.set_item("run", PyArray1::from_vec(py, runs.iter().map(|r| r.run).collect()))?;
    d.set_item("pass", PyArray1::from_vec(py, runs.iter().map(|r| r.pass).collect()))?;
    d.set_item("judged_steps", PyArray1::from_vec(py, runs.iter().map(|r| r.judged_steps).collect()))?;
    for (k, a) in AXES.iter().enumerate() {
        d.set_item(format!("max_err_{a}"), col(&|r| AxisErrors::from_si(r.max_abs_error).as_array()[k]))?;
    }
    for (k, a) in AXES.iter().enumerate() {
        d.set_item(format!("rms_err_{a}"), col(&|r| AxisErrors::from_si(r.rms_error).as_array()[k]))?;
    }
    d.set_item("min_separation_m", col(&|r| r.min_separation_m))?;
    d.set_item("close_pairs", PyArray1::from_vec(py, runs.iter().map(|r| r.close_pairs).collect()))?;
    d.set_item("adjustments_per_uav_minute", col(&RunSummary::adjustments_per_uav_minute))?;
    d.set_item("held_fraction", col(&|r| r.held_fraction))?;
    d.set_item("within_allowable_fraction", col(&|r| r.within_allowable_fraction))?;
    d.set_item("control_effort", col(&|r| r.control_effort))?;
    d.set_item("radio_sent_per_uav_s", col(&|r| r.radio_sent_per_uav_s))?;
    d.set_item("radio_used_per_uav_s", col(&|r| r.radio_used_per_uav_s))?;
    d.set_item("order_mean", col(&|r| r.order_mean))?;
    d.set_item("order_min", col(&|r| r.order_min))?;
    d.set_item("connectivity_min", col(&|r| r.connectivity_min))?;
    d.set_item("alone_s_per_uav", col(&|r| r.alone_s_per_uav))?;
    d.set_item("path_deviation_m", col(&|r| r.path_deviation_m))?;
    // The columns of sensor faults, forming, changes of formation, what was flown and the
    // robust checks, as runs.csv has them: each group when some run has it (NaN for a run
    // without, or a value it does not have).
    type Column = (&'static str, fn(&RunSummary) -> Option<f64>);
    type Group = (fn(&RunSummary) -> bool, &'static [Column]);
    let groups: [Group; 5] = [
        (
            |r| r.sensor_faults.is_some(),
            &[
                ("healthy_pass", |r| r.sensor_faults.map(|m| f64::from(u8::from(m.healthy_pass)))),
                ("rejoin_s", |r| r.sensor_faults.map(|m| m.rejoin_s)),
            ],
        ),
        (
            |r| r.forming.is_some(),
            &[
                ("time_to_form_s", |r| r.forming.map(|m| m.time_to_form_s)),
                ("transient_error_ratio", |r| r.forming.map(|m| m.transient_error_ratio)),
                ("settled_error_ratio", |r| r.forming.and_then(|m| m.settled_error_ratio)),
            ],
        ),
        (
            |r| r.transitions.is_some(),
            &[
                ("transition_s", |r| r.transitions.map(|m| m.transition_s)),
                ("transition_error_ratio", |r| r.transitions.map(|m| m.transient_error_ratio)),
                ("transition_closest_m", |r| r.transitions.map(|m| m.closest_m)),
            ],
        ),
        (
            |r| r.flown.is_some(),
            &[
                ("path_length_m_per_uav", |r| r.flown.map(|m| m.path_length_m_per_uav)),
                ("delta_v_mps_per_uav", |r| r.flown.map(|m| m.delta_v_mps_per_uav)),
                ("work_j_per_kg_per_uav", |r| r.flown.map(|m| m.work_j_per_kg_per_uav)),
            ],
        ),
        (
            |r| r.isolation.is_some(),
            &[
                ("isolating_s_per_uav", |r| r.isolation.map(|m| m.isolating_s_per_uav)),
                ("isolated_per_uav_s", |r| r.isolation.map(|m| m.isolated_per_uav_s)),
                ("own_suspect_s_per_uav", |r| r.isolation.map(|m| m.own_suspect_s_per_uav)),
                ("own_suspect_episodes", |r| r.isolation.map(|m| m.own_suspect_episodes as f64)),
            ],
        ),
    ];
    for (has, columns) in groups {
        if runs.iter().any(has) {
            for (name, value) in columns {
                d.set_item(*name, col(&|r| value(r).unwrap_or(f64::NAN)))?;
            }
        }
    }
    Ok(d)
}

/// What `run` returns: the summary (JSON text), the per-run columns, the first run's
/// trajectory columns (or None) and the runs' exact results.
type RunOut<'py> = (String, Bound<'py, PyDict>, Option<Bound<'py, PyDict>>, PyRuns);

/// Runs `runs` seeded flights of `scenario` (run r draws from streams keyed by (seed, r), as
/// `proxform run --seed S --runs N`); returns (summary as JSON text, per-run columns, the first
/// run's trajectory columns or None).
#[pyfunction]
#[pyo3(signature = (scenario, seed = 1, runs = 1, threads = 0, trajectories = true, adjust = true, progress = None, first_run = 0))]
#[expect(clippy::too_many_arguments, reason = "one argument per keyword of the Python signature")]
pub fn run<'py>(
    py: Python<'py>,
    scenario: &Bound<'py, PyScenario>,
    seed: u64,
    runs: u64,
    threads: usize,
    trajectories: bool,
    adjust: bool,
    progress: Option<&Bound<'py, PyAny>>,
    first_run: u64,
) -> PyResult<RunOut<'py>> {
    if !(1..=MAX_RUNS).contains(&runs) {
        return Err(PyValueError::new_err(format!("runs = {runs}: from 1 to {MAX_RUNS}")));
    }
    if first_run > MAX_FIRST_RUN {
        return Err(PyValueError::new_err(format!("first_run = {first_run}: from 0 to 2^52")));
    }
    let sc = scenario.get().inner.clone();
    let options = RunOptions { adjustment_enabled: adjust, ..RunOptions::default() };
    let columns = Arc::new(Mutex::new(Columns::default()));
    let record = trajectories
        .then(|| Trajectory::for_flight(sc.steps(), Some(Box::new(ColumnSink(columns.clone())) as Box<dyn RowSink>)));
    // One tick per run, or per step for a single run.
    let total = if runs > 1 { runs } else { sc.steps() };
    let result = background::run(py, threads, total, progress, move |h| {
        run_batch_stoppable(&sc, options, (seed, first_run, runs), record, &|| h.tick(), &h.stop)
    })?;
    let header = JournalHeader::new(scenario.get().inner.as_ref(), options, (seed, first_run, runs))
        .map_err(|e| PyRuntimeError::new_err(format!("cannot describe the batch: {e}")))?;
    let summary = serde_json::to_string(&result.summary)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot write the summary: {e}")))?;
    let runs_table = runs_dict(py, seed, &result.runs)?;
    let shard = PyRuns::new(Shard { header, runs: result.runs, totals: result.totals });
    // The trajectory (and its sink) is dropped with the result: the columns are ours alone.
    drop(result.first_trajectory);
    let traj = match trajectories {
        true => {
            let c = Arc::try_unwrap(columns)
                .ok()
                .and_then(|m| m.into_inner().ok())
                .ok_or_else(|| PyRuntimeError::new_err("the trajectory is still in use"))?;
            Some(trajectory_dict(py, c)?)
        }
        false => None,
    };
    Ok((summary, runs_table, traj, shard))
}
