//! Batches of seeded runs, in parallel, aggregated into one summary.
//!
//! Run r of seed S draws from streams keyed by (S, r), so each run's result is fixed by the
//! seed and its index whatever thread runs it; results are collected in run order and
//! aggregated sequentially, so the summary is bit-identical for any thread count.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use proxform_scenario::Scenario;

pub use crate::batch::aggregate::{Aggregator, RunCounts};
use crate::measure::metrics::{RunMetrics, RunSummary};
use crate::measure::observer::Observer;
use crate::measure::trajectory::Trajectory;
use crate::world::engine::Simulation;
use crate::world::options::RunOptions;
use crate::world::remote::Agents;

/// Per-axis errors: x, y, z (m) and α, β, γ (deg).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AxisErrors {
    /// x (m).
    pub x_m: f64,
    /// y (m).
    pub y_m: f64,
    /// z (m).
    pub z_m: f64,
    /// α (deg).
    pub alpha_deg: f64,
    /// β (deg).
    pub beta_deg: f64,
    /// γ (deg).
    pub gamma_deg: f64,
}

impl AxisErrors {
    /// From SI values (m, rad).
    pub fn from_si(v: [f64; 6]) -> Self {
        Self {
            x_m: v[0],
            y_m: v[1],
            z_m: v[2],
            alpha_deg: v[3].to_degrees(),
            beta_deg: v[4].to_degrees(),
            gamma_deg: v[5].to_degrees(),
        }
    }

    /// As an array in report units.
    pub fn as_array(&self) -> [f64; 6] {
        [self.x_m, self.y_m, self.z_m, self.alpha_deg, self.beta_deg, self.gamma_deg]
    }
}

/// Followers that flew without their agents, over a batch.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct UncontrolledSummary {
    /// Runs with any (they do not pass).
    pub runs: u64,
    /// Follower-seconds flown without an agent: the most in one run.
    pub max_s: f64,
}

/// Aggregate of a batch.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Scenario name.
    pub scenario: String,
    /// Number of UAVs.
    pub uavs: u64,
    /// Number of runs.
    pub runs: u64,
    /// Base seed.
    pub seed: u64,
    /// Index of the batch's first run (`--first-run`; left out of the JSON when 0): the runs
    /// are `first_run ..= first_run + runs - 1`.
    #[serde(skip_serializing_if = "is_zero")]
    pub first_run: u64,
    /// Fraction of runs in which every follower stayed within every allowable error (a run in
    /// which no follower flew does not pass).
    pub pass_fraction: f64,
    /// Runs in which no follower flew: nothing to judge.
    pub unjudged_runs: u64,
    /// Largest |error| over all runs and followers.
    pub worst_abs_error: AxisErrors,
    /// 99th percentile (nearest rank) over runs of each run's largest |error|.
    pub p99_abs_error: AxisErrors,
    /// Median over runs of each run's largest |error|.
    pub median_abs_error: AxisErrors,
    /// RMS error over all runs, followers and steps.
    pub rms_error: AxisErrors,
    /// The allowable errors.
    pub allowable_error: AxisErrors,
    /// Predicted error band of eq. 17, σ = sqrt(σm² + σn²), per axis.
    pub predicted_sigma: AxisErrors,
    /// Smallest separation between two UAVs over all runs (m).
    pub min_separation_m: f64,
    /// The scenario's safety distance (m).
    pub safety_distance_m: f64,
    /// Runs in which some pair came closer than the safety distance (they do not pass).
    pub unsafe_runs: u64,
    /// Largest distance of the navigator (or the formation's estimate of its slot, once it is
    /// gone) from its planned path over all runs (m), the bound, and the runs beyond it (they
    /// do not pass).
    pub path_deviation_m_max: f64,
    /// See `path_deviation_m_max`.
    pub path_bound_m: f64,
    /// See `path_deviation_m_max`.
    pub off_path_runs: u64,
    /// Runs in which the navigator's successor took over (METHOD §8), and the latest time
    /// (s) at which one began to lead (None when none did).
    pub succession_runs: u64,
    /// See `succession_runs`.
    pub succession_latest_s: Option<f64>,
    /// Adjustments per follower per minute of flight, mean over runs.
    pub adjustments_per_uav_minute: f64,
    /// Swarm and control metrics, each the mean over runs of the run's value.
    pub swarm: SwarmMetrics,
    /// Numbers (from 1) of the followers with per-UAV detail (the first followers).
    pub per_uav: Vec<u32>,
    /// Per listed follower: largest |error| over all runs.
    pub per_uav_worst: Vec<AxisErrors>,
    /// Per follower: mean adjustments per run.
    pub per_uav_adjustments: Vec<f64>,
    /// Per follower: the runs in which it flew as a follower, and those in which it met the
    /// run's criterion over its own errors (`measure::verdict`).
    pub per_uav_runs_flown: Vec<u64>,
    /// See `per_uav_runs_flown`.
    pub per_uav_runs_passed: Vec<u64>,
    /// Faults of some UAVs' own sensors, when the scenario has any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_faults: Option<SensorFaultSummary>,
    /// What the robust fusion and the own-sensor check did, when either is on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub isolation: Option<IsolationSummary>,
    /// How the formations formed, when they did not start in their slots.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forming: Option<FormingSummary>,
    /// How the changes of formation went, when the scenario has any (left out of the JSON
    /// otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transitions: Option<TransitionSummary>,
    /// What the followers flew, when the formation forms, changes or may be re-assigned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flown: Option<FlownSummary>,
    /// Runs in which a follower flew without its agent (a distributed flight): none of them
    /// passes. Left out of the JSON when there were none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncontrolled: Option<UncontrolledSummary>,
    /// Counts the report prints beside the fractions (not written to the JSON).
    #[serde(skip)]
    pub counts: RunCounts,
}

fn is_zero(v: &u64) -> bool {
    *v == 0
}

/// How the changes of formation of a batch went.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TransitionSummary {
    /// Fraction of runs in which every change was completed before the next (or the end).
    pub completed_fraction: f64,
    /// Each run's slowest change (s): median over runs (∞ counts for a run with one not
    /// completed).
    pub transition_s_median: f64,
    /// The same, 99th percentile (nearest rank).
    pub transition_s_p99: f64,
    /// The same, largest.
    pub transition_s_max: f64,
    /// Largest error over its allowable error during the changes, over all runs.
    pub transient_error_ratio_max: f64,
    /// Smallest distance between two UAVs during the changes, over all runs (m).
    pub closest_m: f64,
}

/// How the formations of a batch formed (scattered starts, UAVs joining).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FormingSummary {
    /// Fraction of runs in which every follower was within every allowable error at the end.
    pub formed_fraction: f64,
    /// Time from which every follower stayed within its allowable errors (s): median over
    /// runs (∞ counts for a run that did not form).
    pub time_to_form_s_median: f64,
    /// The same, 99th percentile (nearest rank).
    pub time_to_form_s_p99: f64,
    /// The same, largest.
    pub time_to_form_s_max: f64,
    /// Largest error over its allowable error before forming, over all runs.
    pub transient_error_ratio_max: f64,
    /// Largest error over its allowable error of the followers that started in their slots
    /// and did not join, over all runs (None when every follower started off its slot).
    pub settled_error_ratio_max: Option<f64>,
}

/// What the followers of a batch flew (means over runs of the means per follower).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct FlownSummary {
    /// Distance flown (m).
    pub path_length_m_per_uav: f64,
    /// Velocity change flown, Σ|Δv| (m/s).
    pub delta_v_mps_per_uav: f64,
    /// Specific mechanical work, Σ|Δ(½v² + g·z)| (J/kg).
    pub work_j_per_kg_per_uav: f64,
}

/// How the formations of a batch rode out faults of some UAVs' own sensors.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SensorFaultSummary {
    /// Fraction of runs in which every follower without a sensor fault stayed within every
    /// allowable error.
    pub healthy_pass_fraction: f64,
    /// Largest |error| of the followers without a sensor fault, over all runs.
    pub healthy_worst_abs_error: AxisErrors,
    /// Time from a fault's end until its UAV was back within its allowable errors, until its
    /// next fault or the end of the flight, the slowest of each run's faults (s): median over
    /// runs.
    pub rejoin_s_median: f64,
    /// The same, 99th percentile (nearest rank; ∞ when some UAV never came back).
    pub rejoin_s_p99: f64,
    /// The same, largest.
    pub rejoin_s_max: f64,
}

/// What the robust fusion and the own-sensor check did over a batch (means over runs, but the
/// episodes, a total).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct IsolationSummary {
    /// Seconds per follower in which its fusion left at least one neighbour out.
    pub isolating_s_per_uav: f64,
    /// Neighbours left out per follower-second.
    pub isolated_per_uav_s: f64,
    /// Seconds per follower flown on its own prediction.
    pub own_suspect_s_per_uav: f64,
    /// Episodes of refused own measurements, all runs and followers.
    pub own_suspect_episodes: u64,
}

/// Swarm and control metrics of a batch (means over runs, but `close_pairs_max` and the
/// minima, which are over all runs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SwarmMetrics {
    /// Fraction of follower steps whose course stayed inside the envelope (held).
    pub held_fraction: f64,
    /// Fraction of follower steps within every allowable error.
    pub within_allowable_fraction: f64,
    /// Mean control effort per follower step (inputs over their per-step limits, root sum of
    /// squares).
    pub control_effort: f64,
    /// Distinct pairs closer than the safety distance, mean per run.
    pub close_pairs_mean: f64,
    /// The same, largest run.
    pub close_pairs_max: u64,
    /// Radio messages sent per UAV per second.
    pub radio_sent_per_uav_s: f64,
    /// Radio messages used (received from UAVs not perceived onboard) per UAV per second.
    pub radio_used_per_uav_s: f64,
    /// Order (polarisation), mean over the flight.
    pub order_mean: f64,
    /// Order, smallest over all runs and steps.
    pub order_min: f64,
    /// Largest connected group of the sensing graph as a fraction of the UAVs, smallest over
    /// all runs.
    pub connectivity_min: f64,
    /// Seconds per follower flown alone.
    pub alone_s_per_uav: f64,
}

/// A batch's results.
#[derive(Debug)]
pub struct BatchResult {
    /// Every run's summary, in run order.
    pub runs: Vec<RunSummary>,
    /// The aggregate.
    pub summary: Summary,
    /// The first run's trajectories, when asked for.
    pub first_trajectory: Option<Trajectory>,
    /// The runs' per-follower totals (their own detail is dropped from `runs`).
    pub totals: PerUavTotals,
}

/// Runs one flight and returns its summary (and its trajectory, kept in memory, when
/// `record`).
pub fn run_one(
    scenario: &Scenario,
    options: RunOptions,
    seed: u64,
    run: u64,
    record: bool,
) -> (RunSummary, Option<Trajectory>) {
    let recording = record.then(|| Trajectory::for_flight(scenario.steps(), None));
    run_one_ticking(scenario, options, (seed, run), recording, &|| {})
}

/// Observer that calls a function after every step (a progress bar's tick) and ends the run
/// early once `stop` is set.
struct Ticker<'a> {
    tick: &'a (dyn Fn() + Sync),
    stop: &'a AtomicBool,
}

impl Observer for Ticker<'_> {
    fn on_step(&mut self, _: &Scenario, frame: &crate::measure::observer::StepFrame<'_>) {
        if frame.k > 0 {
            (self.tick)();
        }
    }

    fn keep_going(&self) -> bool {
        !self.stop.load(Ordering::Relaxed)
    }
}

/// [`run_one`] of `(seed, run)` recording into `record` (if any), calling `tick` after every
/// step.
pub fn run_one_ticking(
    scenario: &Scenario,
    options: RunOptions,
    (seed, run): (u64, u64),
    record: Option<Trajectory>,
    tick: &(dyn Fn() + Sync),
) -> (RunSummary, Option<Trajectory>) {
    run_one_stoppable(scenario, options, (seed, run), record, tick, &AtomicBool::new(false))
}

/// [`run_one_ticking`] that ends early once `stop` is set.
fn run_one_stoppable(
    scenario: &Scenario,
    options: RunOptions,
    (seed, run): (u64, u64),
    record: Option<Trajectory>,
    tick: &(dyn Fn() + Sync),
    stop: &AtomicBool,
) -> (RunSummary, Option<Trajectory>) {
    let engine = crate::flight::engine_for(scenario).unwrap_or(crate::flight::EngineKind::Reference);
    let sim = crate::flight::Flight::new(scenario, engine, options, seed, run);
    observe(scenario, sim, run, record, (Ticker { tick, stop }, &mut ()))
}

/// Flies `sim` (run `run`), watched by the metrics, the recorder (if any), the ticker and
/// whatever else the caller watches with.
fn observe(
    scenario: &Scenario,
    sim: crate::flight::Flight<'_>,
    run: u64,
    record: Option<Trajectory>,
    ticker: (Ticker<'_>, &mut dyn Observer),
) -> (RunSummary, Option<Trajectory>) {
    let metrics = RunMetrics::new(scenario);
    if let Some(trajectory) = record {
        let mut obs = ((metrics, trajectory), ticker);
        sim.run(&mut obs);
        (obs.0 .0.finish(run, scenario.duration_s()), Some(obs.0 .1))
    } else {
        let mut obs = (metrics, ticker);
        sim.run(&mut obs);
        (obs.0.finish(run, scenario.duration_s()), None)
    }
}

/// Runs `runs` flights of `scenario` with seed `seed` on the current rayon pool, calling
/// `progress` after each finished run, or after each step when there is a single run (a long
/// flight of a large swarm). The first run is recorded into `record_first`, if given.
pub fn run_batch(
    scenario: &Scenario,
    options: RunOptions,
    seed: u64,
    runs: u64,
    record_first: Option<Trajectory>,
    progress: &(dyn Fn() + Sync),
) -> BatchResult {
    let never = AtomicBool::new(false);
    run_batch_stoppable(scenario, options, (seed, 0, runs), record_first, progress, &never)
        .expect("a batch nobody stops runs to its end")
}

/// Flies the runs `range` of seed `seed` but those `skip` names, on the current rayon pool,
/// handing each to `done` as it ends (in any order, its per-follower detail still in it).
/// `record` records the range's first run, if it is flown. `progress` ticks after each run,
/// or after each step when the range is a single run. Once `stop` is set, the flights in
/// progress end at their next step, no new one starts and the result is None (what `done`
/// got is complete runs only); otherwise it is the recorded trajectory, if any.
pub fn fly_runs(
    scenario: &Scenario,
    options: RunOptions,
    (seed, range): (u64, std::ops::Range<u64>),
    skip: &(dyn Fn(u64) -> bool + Sync),
    record: Option<Trajectory>,
    (progress, stop): (&(dyn Fn() + Sync), &AtomicBool),
    done: &(dyn Fn(RunSummary) + Sync),
) -> Option<Option<Trajectory>> {
    let first = range.start;
    let single = range.end.saturating_sub(range.start) == 1;
    let record = std::sync::Mutex::new(record);
    let recorded = std::sync::Mutex::new(None);
    let fly = |r: u64| {
        if stop.load(Ordering::Relaxed) || skip(r) {
            return;
        }
        let rec = if r == first { record.lock().ok().and_then(|mut f| f.take()) } else { None };
        let tick: &(dyn Fn() + Sync) = if single { progress } else { &|| {} };
        let (summary, trajectory) = run_one_stoppable(scenario, options, (seed, r), rec, tick, stop);
        if stop.load(Ordering::Relaxed) {
            return;
        }
        if let (Some(t), Ok(mut slot)) = (trajectory, recorded.lock()) {
            *slot = Some(t);
        }
        done(summary);
        if !single {
            progress();
        }
    };
    if single {
        fly(first);
    } else {
        range.into_par_iter().for_each(fly);
    }
    if stop.load(Ordering::Relaxed) {
        return None;
    }
    Some(recorded.into_inner().ok().flatten())
}

/// [`run_batch`] of the runs `first_run ..` (`runs` of them) that another thread can stop
/// (a user's interrupt): once `stop` is set, the flights in progress end at their next step,
/// no new one starts, and the result is None.
pub fn run_batch_stoppable(
    scenario: &Scenario,
    options: RunOptions,
    (seed, first_run, runs): (u64, u64, u64),
    record_first: Option<Trajectory>,
    progress: &(dyn Fn() + Sync),
    stop: &AtomicBool,
) -> Option<BatchResult> {
    let collected = std::sync::Mutex::new((Vec::new(), PerUavTotals::default()));
    // Each run's per-follower detail is folded into the totals as it ends.
    let done = |mut s: RunSummary| {
        if let Ok(mut c) = collected.lock() {
            c.1.add(&std::mem::take(&mut s.per_uav));
            c.0.push(s);
        }
    };
    let range = first_run..first_run.saturating_add(runs);
    let first_trajectory =
        fly_runs(scenario, options, (seed, range), &|_| false, record_first, (progress, stop), &done)?;
    let (mut summaries, totals) = collected.into_inner().ok()?;
    summaries.sort_by_key(|r| r.run);
    let summary = aggregate_with(scenario, seed, &summaries, &totals);
    Some(BatchResult { runs: summaries, summary, first_trajectory, totals })
}

/// [`run_batch_stoppable`] with the followers' agents outside the engine
/// ([`crate::world::remote`]): the runs fly one after the other, all asking `agents`, each
/// also shown to `watch` (`progress` ticks after each run, or each step of a single run).
pub fn run_batch_with_agents(
    scenario: &Scenario,
    options: RunOptions,
    (seed, runs): (u64, u64),
    mut record_first: Option<Trajectory>,
    (progress, stop): (&(dyn Fn() + Sync), &AtomicBool),
    (agents, watch): (&mut dyn Agents, &mut dyn Observer),
) -> Option<BatchResult> {
    let mut summaries = Vec::with_capacity(runs as usize);
    let mut totals = PerUavTotals::default();
    let mut first_trajectory = None;
    for r in 0..runs {
        if stop.load(Ordering::Relaxed) {
            return None;
        }
        let sim = Simulation::with_agents(scenario, options, (seed, r), Box::new(&mut *agents));
        let tick: &(dyn Fn() + Sync) = if runs == 1 { progress } else { &|| {} };
        let (summary, trajectory) = observe(
            scenario,
            crate::flight::Flight::Reference(Box::new(sim)),
            r,
            record_first.take(),
            (Ticker { tick, stop }, &mut *watch),
        );
        if trajectory.is_some() {
            first_trajectory = trajectory;
        }
        let mut summary = summary;
        totals.add(&std::mem::take(&mut summary.per_uav));
        summaries.push(summary);
        if runs > 1 {
            progress();
        }
    }
    if stop.load(Ordering::Relaxed) {
        return None;
    }
    let summary = aggregate_with(scenario, seed, &summaries, &totals);
    Some(BatchResult { runs: summaries, summary, first_trajectory, totals })
}

/// Aggregates run summaries (in run order, their per-follower detail still in them) into a
/// [`Summary`].
pub fn aggregate(scenario: &Scenario, seed: u64, runs: &[RunSummary]) -> Summary {
    let mut per_uav = PerUavTotals::default();
    for r in runs {
        per_uav.add(&r.per_uav);
    }
    aggregate_with(scenario, seed, runs, &per_uav)
}

/// [`aggregate`] with the per-follower totals folded as the runs ended (their own detail
/// dropped); the runs are the batch's from its first.
pub fn aggregate_with(scenario: &Scenario, seed: u64, runs: &[RunSummary], per_uav: &PerUavTotals) -> Summary {
    let mut fold = Aggregator::new(scenario, runs.len() as u64);
    fold.add_totals(per_uav);
    for r in runs {
        fold.add(r);
    }
    fold.finish(scenario, seed, runs.first().map_or(0, |r| r.run))
}

/// Per-follower totals over a batch's runs, folded as each run ends (its per-UAV detail is
/// then dropped, so a batch holds one set of totals whatever its number of runs). Maxima,
/// integer sums and counts: the same in any order.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PerUavTotals {
    pub(crate) uavs: Vec<u32>,
    pub(crate) worst: Vec<[f64; 6]>,
    pub(crate) adjustments: Vec<u64>,
    pub(crate) flown: Vec<u64>,
    pub(crate) passed: Vec<u64>,
}

impl PerUavTotals {
    /// Adds one run's per-follower detail (every run lists the same followers).
    pub fn add(&mut self, stats: &[crate::measure::metrics::UavStats]) {
        if self.uavs.is_empty() && !stats.is_empty() {
            let n = stats.len();
            self.uavs = stats.iter().map(|u| u.uav).collect();
            (self.worst, self.adjustments) = (vec![[0.0; 6]; n], vec![0; n]);
            (self.flown, self.passed) = (vec![0; n], vec![0; n]);
        }
        for (f, u) in stats.iter().enumerate().take(self.uavs.len()) {
            for k in 0..6 {
                self.worst[f][k] = self.worst[f][k].max(u.max_abs_error[k]);
            }
            self.adjustments[f] += u.adjustments;
            self.flown[f] += u64::from(u.judged_steps > 0);
            self.passed[f] += u64::from(u.pass);
        }
    }

    /// Adds the totals of other runs (of the same scenario: the same followers listed).
    pub fn merge(&mut self, other: &PerUavTotals) {
        if self.uavs.is_empty() {
            *self = other.clone();
            return;
        }
        for f in 0..self.uavs.len().min(other.uavs.len()) {
            for k in 0..6 {
                self.worst[f][k] = self.worst[f][k].max(other.worst[f][k]);
            }
            self.adjustments[f] += other.adjustments[f];
            self.flown[f] += other.flown[f];
            self.passed[f] += other.passed[f];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_scenario::builtin::paper;

    fn run(k: u64, max_y: f64, model: f64, pass: bool) -> RunSummary {
        RunSummary {
            run: k,
            pass,
            followers: 5,
            max_abs_error: [0.1, max_y, 0.1, 0.001, 0.001, 0.001],
            rms_error: [0.02; 6],
            adjustments: 300,
            alone_steps: 0,
            per_uav: Vec::new(),
            min_separation_m: 90.0 + k as f64,
            path_deviation_m: 0.0,
            succession: None,
            model_error_rms: [model; 9],
            duration_s: 60.0,
            flown: None,
            uncontrolled_s: 0.0,
            held_fraction: 0.5,
            within_allowable_fraction: 1.0,
            control_effort: 0.1,
            close_pairs: k,
            radio_sent_per_uav_s: 0.0,
            radio_used_per_uav_s: 0.0,
            judged_steps: 100,
            order_mean: 1.0,
            order_min: 1.0,
            connectivity_min: 1.0,
            alone_s_per_uav: 0.0,
            sensor_faults: None,
            isolation: None,
            forming: None,
            transitions: None,
        }
    }

    #[test]
    fn a_stopped_batch_ends_at_the_next_step_and_returns_nothing() {
        use std::sync::atomic::AtomicU64;
        let sc = paper();
        // A single run ticks per step: stop it after 10 of its 1000 steps.
        let (stop, steps) = (AtomicBool::new(false), AtomicU64::new(0));
        let tick = || {
            if steps.fetch_add(1, Ordering::Relaxed) + 1 == 10 {
                stop.store(true, Ordering::Relaxed);
            }
        };
        assert!(run_batch_stoppable(&sc, RunOptions::default(), (1, 0, 1), None, &tick, &stop).is_none());
        assert_eq!(steps.load(Ordering::Relaxed), 10);
        // Many runs tick per run: no new run starts once stopped.
        let (stop, runs) = (AtomicBool::new(false), AtomicU64::new(0));
        let tick = || {
            runs.fetch_add(1, Ordering::Relaxed);
            stop.store(true, Ordering::Relaxed);
        };
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("threads");
        let out = pool.install(|| run_batch_stoppable(&sc, RunOptions::default(), (1, 0, 1000), None, &tick, &stop));
        assert!(out.is_none());
        assert!(runs.load(Ordering::Relaxed) <= 2 + 2, "{runs:?} runs finished after the stop");
        // Never stopped: the whole batch.
        let never = AtomicBool::new(false);
        let all = run_batch_stoppable(&sc, RunOptions::default(), (1, 0, 2), None, &|| {}, &never).expect("a result");
        assert_eq!(all.runs.len(), 2);
    }

    #[test]
    fn the_summary_aggregates_runs_and_predicts_eq_17s_band() {
        let sc = paper();
        // 100 runs whose largest y errors are 0.01, 0.02, … 1.00 m; half of them pass.
        let runs: Vec<RunSummary> = (0..100).map(|k| run(k, 0.01 * (k + 1) as f64, 0.03, k % 2 == 0)).collect();
        let s = aggregate(&sc, 7, &runs);
        assert_eq!(s.pass_fraction, 0.5);
        assert!((s.p99_abs_error.y_m - 0.99).abs() < 1e-12 && (s.median_abs_error.y_m - 0.5).abs() < 1e-12);
        assert_eq!(s.worst_abs_error.y_m, 1.0);
        assert_eq!((s.min_separation_m, s.unsafe_runs), (90.0, 0));
        assert_eq!(s.swarm.close_pairs_max, 99);
        // 300 adjustments by 5 followers in one minute.
        assert!((s.adjustments_per_uav_minute - 60.0).abs() < 1e-9);
        // eq. 17: σ = sqrt(σm² + σn²), σn the paper's 0.02 m.
        assert!((s.predicted_sigma.x_m - (0.03f64.powi(2) + 0.02f64.powi(2)).sqrt()).abs() < 1e-12);
        let sigma_att = (0.03f64.powi(2) + 0.01f64.to_radians().powi(2)).sqrt().to_degrees();
        assert!((s.predicted_sigma.alpha_deg - sigma_att).abs() < 1e-9, "{:?}", s.predicted_sigma);
    }
}
