//! The aggregate of a batch, folded run by run in run order: what a [`Summary`] says of the
//! runs, with memory of a few numbers per run (the columns whose quantiles it reports), so a
//! batch of any size, a resumed batch and shards merged all aggregate through the same fold.
//!
//! Sums are taken in run order starting from the empty sum, exactly as `Iterator::sum` over
//! the runs would; maxima, minima, counts and the per-follower totals do not depend on the
//! order. Feeding the same runs in the same order gives a bit-identical summary.

use proxform_scenario::Scenario;

use crate::batch::runs::{
    AxisErrors, FlownSummary, FormingSummary, IsolationSummary, PerUavTotals, SensorFaultSummary, Summary,
    SwarmMetrics, TransitionSummary,
};
use crate::measure::metrics::RunSummary;
use crate::measure::stats::{quantile, quantile_of};

/// Counts over a batch's runs that the report prints next to the summary's fractions (not
/// part of `summary.json`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunCounts {
    /// Runs that passed.
    pub passed: u64,
    /// Runs in which every follower without a sensor fault passed.
    pub healthy_passed: u64,
    /// Runs whose formation formed (every follower within its allowable errors at the end).
    pub formed: u64,
    /// Runs whose formation formed by the scenario's `form_within_s`.
    pub formed_in_time: u64,
}

/// A running sum in order, from the empty sum (`Iterator::sum`'s own start).
#[derive(Debug, Clone, Copy)]
struct OrderedSum(f64);

impl Default for OrderedSum {
    fn default() -> Self {
        Self(std::iter::empty::<f64>().sum())
    }
}

impl OrderedSum {
    fn add(&mut self, v: f64) {
        self.0 += v;
    }
}

/// How many runs had one optional part (faults, forming, ...) and the ordered sums of its
/// means.
#[derive(Debug, Clone)]
struct Part<const M: usize> {
    count: u64,
    sums: [OrderedSum; M],
}

impl<const M: usize> Default for Part<M> {
    fn default() -> Self {
        Self { count: 0, sums: [OrderedSum::default(); M] }
    }
}

impl<const M: usize> Part<M> {
    fn add(&mut self, values: [f64; M]) {
        self.count += 1;
        for (s, v) in self.sums.iter_mut().zip(values) {
            s.add(v);
        }
    }

    fn mean(&self, k: usize) -> f64 {
        self.sums[k].0 / self.count as f64
    }
}

/// The fold of a batch's runs into its [`Summary`]; see the module's paragraph.
#[derive(Debug, Clone)]
pub struct Aggregator {
    n: f64,
    runs: u64,
    counts: RunCounts,
    form_within_s: Option<f64>,
    unjudged: u64,
    max_abs: [Vec<f64>; 6],
    rms_sq: [OrderedSum; 6],
    adjustments: OrderedSum,
    model: [f64; 9],
    min_separation_m: f64,
    safety_distance_m: f64,
    unsafe_runs: u64,
    path_bound_m: f64,
    path_deviation_m_max: f64,
    off_path_runs: u64,
    succession_runs: u64,
    succession_latest_s: Option<f64>,
    uncontrolled: Option<super::runs::UncontrolledSummary>,
    swarm: [OrderedSum; 8],
    close_pairs_max: u64,
    order_min: f64,
    connectivity_min: f64,
    faults: Part<0>,
    fault_worst: [f64; 6],
    rejoin_s: Vec<f64>,
    forming: Part<0>,
    forming_t: Vec<f64>,
    forming_transient: f64,
    forming_settled: Option<f64>,
    transitions: Part<0>,
    transition_t: Vec<f64>,
    transition_ratio: f64,
    transition_closest_m: f64,
    flown: Part<3>,
    isolation: Part<3>,
    own_suspect_episodes: u64,
    per_uav: PerUavTotals,
}

impl Aggregator {
    /// An empty fold of a batch of `runs` runs of `scenario` (the number divides the means as
    /// the runs come, so it is known in advance).
    pub fn new(scenario: &Scenario, runs: u64) -> Self {
        Self {
            n: runs.max(1) as f64,
            runs: 0,
            counts: RunCounts::default(),
            form_within_s: scenario.form_within_s(),
            unjudged: 0,
            max_abs: Default::default(),
            rms_sq: Default::default(),
            adjustments: OrderedSum::default(),
            model: [0.0; 9],
            min_separation_m: f64::INFINITY,
            safety_distance_m: scenario.safety_distance_m(),
            unsafe_runs: 0,
            path_bound_m: scenario.allowable().path_m,
            path_deviation_m_max: 0.0,
            off_path_runs: 0,
            succession_runs: 0,
            succession_latest_s: None,
            uncontrolled: None,
            swarm: Default::default(),
            close_pairs_max: 0,
            order_min: 1.0,
            connectivity_min: 1.0,
            faults: Part::default(),
            fault_worst: [0.0; 6],
            rejoin_s: Vec::new(),
            forming: Part::default(),
            forming_t: Vec::new(),
            forming_transient: 0.0,
            forming_settled: None,
            transitions: Part::default(),
            transition_t: Vec::new(),
            transition_ratio: 0.0,
            transition_closest_m: f64::INFINITY,
            flown: Part::default(),
            isolation: Part::default(),
            own_suspect_episodes: 0,
            per_uav: PerUavTotals::default(),
        }
    }

    /// Adds the per-follower totals of some runs (folded as they ended; any order).
    pub fn add_totals(&mut self, totals: &PerUavTotals) {
        self.per_uav.merge(totals);
    }

    /// Adds the next run, in run order.
    pub fn add(&mut self, r: &RunSummary) {
        let n = self.n;
        self.runs += 1;
        self.counts.passed += u64::from(r.pass);
        self.unjudged += u64::from(r.judged_steps == 0);
        for k in 0..6 {
            self.max_abs[k].push(r.max_abs_error[k]);
            self.rms_sq[k].add(r.rms_error[k] * r.rms_error[k]);
        }
        self.adjustments.add(r.adjustments_per_uav_minute());
        // eq. 17: σm measured as the RMS actuation-error effect per step.
        for k in 0..9 {
            self.model[k] += r.model_error_rms[k].powi(2) / n;
        }
        self.min_separation_m = self.min_separation_m.min(r.min_separation_m);
        self.unsafe_runs += u64::from(r.min_separation_m < self.safety_distance_m);
        self.path_deviation_m_max = self.path_deviation_m_max.max(r.path_deviation_m);
        self.off_path_runs += u64::from(r.path_deviation_m > self.path_bound_m);
        if r.uncontrolled_s > 0.0 {
            let u = self.uncontrolled.get_or_insert(super::runs::UncontrolledSummary { runs: 0, max_s: 0.0 });
            u.runs += 1;
            u.max_s = u.max_s.max(r.uncontrolled_s);
        }
        if let Some((t, _)) = r.succession {
            self.succession_runs += 1;
            self.succession_latest_s = Some(self.succession_latest_s.map_or(t, |l: f64| l.max(t)));
        }
        for (s, v) in self.swarm.iter_mut().zip([
            r.held_fraction,
            r.within_allowable_fraction,
            r.control_effort,
            r.close_pairs as f64,
            r.radio_sent_per_uav_s,
            r.radio_used_per_uav_s,
            r.order_mean,
            r.alone_s_per_uav,
        ]) {
            s.add(v);
        }
        self.close_pairs_max = self.close_pairs_max.max(r.close_pairs);
        self.order_min = self.order_min.min(r.order_min);
        self.connectivity_min = self.connectivity_min.min(r.connectivity_min);
        if let Some(f) = r.sensor_faults {
            self.faults.add([]);
            self.counts.healthy_passed += u64::from(f.healthy_pass);
            for k in 0..6 {
                self.fault_worst[k] = self.fault_worst[k].max(f.healthy_max_abs_error[k]);
            }
            self.rejoin_s.push(f.rejoin_s);
        }
        if let Some(f) = r.forming {
            self.forming.add([]);
            self.counts.formed += u64::from(f.time_to_form_s.is_finite());
            self.counts.formed_in_time +=
                u64::from(self.form_within_s.is_some_and(|limit| f.time_to_form_s <= limit + 1e-9));
            self.forming_t.push(f.time_to_form_s);
            self.forming_transient = self.forming_transient.max(f.transient_error_ratio);
            if let Some(v) = f.settled_error_ratio {
                self.forming_settled = Some(self.forming_settled.map_or(v, |s: f64| s.max(v)));
            }
        }
        if let Some(c) = r.transitions {
            self.transitions.add([]);
            self.transition_t.push(c.transition_s);
            self.transition_ratio = self.transition_ratio.max(c.transient_error_ratio);
            self.transition_closest_m = self.transition_closest_m.min(c.closest_m);
        }
        if let Some(f) = r.flown {
            self.flown.add([f.path_length_m_per_uav, f.delta_v_mps_per_uav, f.work_j_per_kg_per_uav]);
        }
        if let Some(i) = r.isolation {
            self.isolation.add([i.isolating_s_per_uav, i.isolated_per_uav_s, i.own_suspect_s_per_uav]);
            self.own_suspect_episodes += i.own_suspect_episodes;
        }
    }

    /// Runs added so far.
    pub fn len(&self) -> u64 {
        self.runs
    }

    /// True before the first run.
    pub fn is_empty(&self) -> bool {
        self.runs == 0
    }

    /// The summary of the runs added, of seed `seed`, its first run `first_run`.
    pub fn finish(mut self, scenario: &Scenario, seed: u64, first_run: u64) -> Summary {
        let n = self.n;
        let mut worst = [0.0f64; 6];
        let mut p99 = [0.0f64; 6];
        let mut median = [0.0f64; 6];
        let mut rms = [0.0f64; 6];
        for k in 0..6 {
            let col = &mut self.max_abs[k];
            worst[k] = col.iter().copied().fold(0.0, f64::max);
            p99[k] = quantile_of(col, 0.99);
            median[k] = quantile_of(col, 0.5);
            rms[k] = (self.rms_sq[k].0 / n).sqrt();
        }
        let sigma_n = scenario.noise().sigma();
        let idx = [0, 1, 2, 6, 7, 8];
        let predicted = idx.map(|k| (self.model[k] + sigma_n[k].powi(2)).sqrt());
        let mean = |k: usize| self.swarm[k].0 / n;
        let per_uav = self.per_uav;
        let sensor_faults = (self.faults.count > 0).then(|| {
            let p99 = quantile_of(&mut self.rejoin_s, 0.99);
            SensorFaultSummary {
                healthy_pass_fraction: self.counts.healthy_passed as f64 / self.faults.count as f64,
                healthy_worst_abs_error: AxisErrors::from_si(self.fault_worst),
                rejoin_s_median: quantile(&self.rejoin_s, 0.5),
                rejoin_s_p99: p99,
                rejoin_s_max: self.rejoin_s.last().copied().unwrap_or(0.0),
            }
        });
        let forming = (self.forming.count > 0).then(|| {
            let p99 = quantile_of(&mut self.forming_t, 0.99);
            FormingSummary {
                formed_fraction: self.counts.formed as f64 / self.forming.count as f64,
                time_to_form_s_median: quantile(&self.forming_t, 0.5),
                time_to_form_s_p99: p99,
                time_to_form_s_max: self.forming_t.last().copied().unwrap_or(0.0),
                transient_error_ratio_max: self.forming_transient,
                settled_error_ratio_max: self.forming_settled,
            }
        });
        let transitions = (self.transitions.count > 0).then(|| {
            let p99 = quantile_of(&mut self.transition_t, 0.99);
            TransitionSummary {
                completed_fraction: self.transition_t.iter().filter(|t| t.is_finite()).count() as f64
                    / self.transitions.count as f64,
                transition_s_median: quantile(&self.transition_t, 0.5),
                transition_s_p99: p99,
                transition_s_max: self.transition_t.last().copied().unwrap_or(0.0),
                transient_error_ratio_max: self.transition_ratio,
                closest_m: self.transition_closest_m,
            }
        });
        let flown = (self.flown.count > 0).then(|| FlownSummary {
            path_length_m_per_uav: self.flown.mean(0),
            delta_v_mps_per_uav: self.flown.mean(1),
            work_j_per_kg_per_uav: self.flown.mean(2),
        });
        let isolation = (self.isolation.count > 0).then(|| IsolationSummary {
            isolating_s_per_uav: self.isolation.mean(0),
            isolated_per_uav_s: self.isolation.mean(1),
            own_suspect_s_per_uav: self.isolation.mean(2),
            own_suspect_episodes: self.own_suspect_episodes,
        });
        Summary {
            scenario: scenario.name().to_string(),
            uavs: scenario.len() as u64,
            runs: self.runs,
            seed,
            first_run,
            pass_fraction: self.counts.passed as f64 / n,
            unjudged_runs: self.unjudged,
            worst_abs_error: AxisErrors::from_si(worst),
            p99_abs_error: AxisErrors::from_si(p99),
            median_abs_error: AxisErrors::from_si(median),
            rms_error: AxisErrors::from_si(rms),
            allowable_error: AxisErrors::from_si(scenario.allowable().as_array()),
            predicted_sigma: AxisErrors::from_si(predicted),
            min_separation_m: self.min_separation_m,
            safety_distance_m: self.safety_distance_m,
            unsafe_runs: self.unsafe_runs,
            path_deviation_m_max: self.path_deviation_m_max,
            path_bound_m: self.path_bound_m,
            off_path_runs: self.off_path_runs,
            succession_runs: self.succession_runs,
            succession_latest_s: self.succession_latest_s,
            adjustments_per_uav_minute: self.adjustments.0 / n,
            swarm: SwarmMetrics {
                held_fraction: mean(0),
                within_allowable_fraction: mean(1),
                control_effort: mean(2),
                close_pairs_mean: mean(3),
                close_pairs_max: self.close_pairs_max,
                radio_sent_per_uav_s: mean(4),
                radio_used_per_uav_s: mean(5),
                order_mean: mean(6),
                order_min: self.order_min,
                connectivity_min: self.connectivity_min,
                alone_s_per_uav: mean(7),
            },
            per_uav: per_uav.uavs.iter().map(|u| u + 1).collect(),
            per_uav_worst: per_uav.worst.into_iter().map(AxisErrors::from_si).collect(),
            per_uav_adjustments: per_uav.adjustments.iter().map(|&a| a as f64 / n).collect(),
            per_uav_runs_flown: per_uav.flown,
            per_uav_runs_passed: per_uav.passed,
            sensor_faults,
            forming,
            transitions,
            flown,
            isolation,
            uncontrolled: self.uncontrolled,
            counts: self.counts,
        }
    }
}
