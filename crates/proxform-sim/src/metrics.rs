//! Per-run metrics: the formation errors, separations and corrections of one flight.
//!
//! Errors and adjustments are accumulated over every follower; per-UAV detail is kept for the
//! first [`PER_UAV_SAMPLE`] followers only, so a run of a million UAVs stays small.

use proxform_core::state::{State9, P};
use proxform_core::Outcome;

use crate::observer::{formation_error_to, navigator_reference, Observer, StepFrame};
use crate::scenario::Scenario;

/// Followers with per-UAV detail in summaries and tables.
pub const PER_UAV_SAMPLE: usize = 32;

/// One follower's statistics over a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UavStats {
    /// UAV index.
    pub uav: u32,
    /// Max |error| x, y, z (m), α, β, γ (rad).
    pub max_abs_error: [f64; 6],
    /// RMS error over the flight, same units.
    pub rms_error: [f64; 6],
    /// Number of adjustments.
    pub adjustments: u64,
    /// Steps flown alone (nothing perceived).
    pub alone_steps: u64,
}

/// What one run measured, small enough to keep for thousands of runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunSummary {
    /// Run index within its batch.
    pub run: u64,
    /// True when every follower stayed within every allowable error for the whole flight.
    pub pass: bool,
    /// Number of followers.
    pub followers: u64,
    /// Max |error| over all followers: x, y, z (m), α, β, γ (rad).
    pub max_abs_error: [f64; 6],
    /// RMS error over all followers and steps, same units.
    pub rms_error: [f64; 6],
    /// Adjustments of all followers.
    pub adjustments: u64,
    /// Steps flown alone, all followers.
    pub alone_steps: u64,
    /// Per-UAV detail for the first followers.
    pub per_uav: Vec<UavStats>,
    /// Smallest distance between any two UAVs (m); separations beyond the sensing range are
    /// not tracked and count as the sensing range.
    pub min_separation_m: f64,
    /// RMS model error σm per state parameter over all follower steps.
    pub model_error_rms: [f64; P],
    /// Flight duration (s).
    pub duration_s: f64,
}

#[derive(Debug, Clone, Default)]
struct Acc {
    max_abs: [f64; 6],
    sum_sq: [f64; 6],
    adjustments: u64,
    alone: u64,
}

/// Observer accumulating a [`RunSummary`].
#[derive(Debug, Clone)]
pub struct RunMetrics {
    nav: usize,
    total: Acc,
    sample: Vec<(usize, Acc)>,
    samples: u64,
    followers: u64,
    min_sep: f64,
    range: f64,
    model_sq: State9,
    model_n: u64,
    allowable: [f64; 6],
}

impl RunMetrics {
    /// Metrics for `scenario`.
    pub fn new(scenario: &Scenario) -> Self {
        let nav = scenario.navigator.index();
        let sample =
            (0..scenario.len()).filter(|&i| i != nav).take(PER_UAV_SAMPLE).map(|i| (i, Acc::default())).collect();
        Self {
            nav,
            total: Acc::default(),
            sample,
            samples: 0,
            followers: scenario.len() as u64 - 1,
            min_sep: f64::INFINITY,
            range: scenario.controller.areas.sensing_range_m,
            model_sq: State9::zeros(),
            model_n: 0,
            allowable: scenario.allowable.as_array(),
        }
    }

    /// The summary of run `run` lasting `duration_s`.
    pub fn finish(self, run: u64, duration_s: f64) -> RunSummary {
        let steps = self.samples.max(1) as f64;
        let rms = |a: &Acc, n: f64| a.sum_sq.map(|v| (v / n).sqrt());
        let pass = self.total.max_abs.iter().zip(&self.allowable).all(|(v, a)| v <= a);
        let mn = self.model_n.max(1) as f64;
        let mut model_error_rms = [0.0; P];
        for (k, v) in model_error_rms.iter_mut().enumerate() {
            *v = (self.model_sq[k] / mn).sqrt();
        }
        RunSummary {
            run,
            pass,
            followers: self.followers,
            max_abs_error: self.total.max_abs,
            rms_error: rms(&self.total, steps * self.followers.max(1) as f64),
            adjustments: self.total.adjustments,
            alone_steps: self.total.alone,
            per_uav: self
                .sample
                .iter()
                .map(|(i, a)| UavStats {
                    uav: *i as u32,
                    max_abs_error: a.max_abs,
                    rms_error: rms(a, steps),
                    adjustments: a.adjustments,
                    alone_steps: a.alone,
                })
                .collect(),
            min_separation_m: self.min_sep.min(self.range),
            model_error_rms,
            duration_s,
        }
    }
}

#[inline]
fn accumulate(acc: &mut Acc, e: &[f64; 6], outcome: Option<Outcome>) {
    for k in 0..6 {
        let a = e[k].abs();
        if a > acc.max_abs[k] {
            acc.max_abs[k] = a;
        }
        acc.sum_sq[k] += e[k] * e[k];
    }
    match outcome {
        Some(Outcome::Adjusted { .. }) => acc.adjustments += 1,
        Some(Outcome::Alone) => acc.alone += 1,
        _ => {}
    }
}

/// Followers per chunk of the (possibly parallel) metric pass; partial results are combined
/// in chunk order, so the result does not depend on the number of threads.
const CHUNK: usize = 4096;

/// Partial sums over one chunk of UAVs.
#[derive(Debug, Clone, Default)]
struct Partial {
    acc: Acc,
    model_sq: State9,
    model_n: u64,
    min_sep: f64,
}

fn partial(
    nav: usize,
    scenario: &Scenario,
    frame: &StepFrame<'_>,
    reference: &State9,
    range: std::ops::Range<usize>,
) -> Partial {
    let mut p = Partial { min_sep: f64::INFINITY, ..Partial::default() };
    for i in range {
        if !frame.active[i] {
            continue;
        }
        let u = &frame.uavs[i];
        p.min_sep = p.min_sep.min(u.nearest_m);
        if i == nav {
            continue;
        }
        let e = formation_error_to(scenario, frame.states, reference, i);
        accumulate(&mut p.acc, &e, u.outcome);
        match u.outcome {
            Some(Outcome::Adjusted { .. }) => {
                for k in 0..P {
                    p.model_sq[k] += f64::from(u.model_error[k]).powi(2);
                }
                p.model_n += 1;
            }
            Some(Outcome::Held) => p.model_n += 1,
            _ => {}
        }
    }
    p
}

impl Observer for RunMetrics {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        use rayon::prelude::*;
        self.samples += 1;
        let n = frame.states.len();
        let nav = self.nav;
        let reference = navigator_reference(scenario, frame.states, frame.active);
        let parts: Vec<Partial> = if n >= crate::engine::PARALLEL_MIN_UAVS {
            (0..n.div_ceil(CHUNK))
                .into_par_iter()
                .map(|c| partial(nav, scenario, frame, &reference, c * CHUNK..((c + 1) * CHUNK).min(n)))
                .collect()
        } else {
            vec![partial(nav, scenario, frame, &reference, 0..n)]
        };
        for p in parts {
            for k in 0..6 {
                self.total.max_abs[k] = self.total.max_abs[k].max(p.acc.max_abs[k]);
                self.total.sum_sq[k] += p.acc.sum_sq[k];
            }
            self.total.adjustments += p.acc.adjustments;
            self.total.alone += p.acc.alone;
            self.model_sq += p.model_sq;
            self.model_n += p.model_n;
            self.min_sep = self.min_sep.min(p.min_sep);
        }
        for (i, acc) in self.sample.iter_mut() {
            if !frame.active[*i] {
                continue;
            }
            let e = formation_error_to(scenario, frame.states, &reference, *i);
            accumulate(acc, &e, frame.uavs[*i].outcome);
        }
    }
}
