//! Per-run metrics: the formation errors, separations and corrections of one flight.

use proxform_core::state::{State9, P};
use proxform_core::Outcome;

use crate::observer::{formation_error, Observer, StepFrame};
use crate::scenario::Scenario;

/// What one run measured, small enough to keep for thousands of runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunSummary {
    /// Run index within its batch.
    pub run: u64,
    /// True when every follower stayed within every allowable error for the whole flight.
    pub pass: bool,
    /// Per follower (in UAV order, navigator excluded): max |error| x, y, z (m), α, β, γ (rad).
    pub max_abs_error: Vec<[f64; 6]>,
    /// Per follower: RMS error over the flight, same units.
    pub rms_error: Vec<[f64; 6]>,
    /// Per follower: number of adjustments.
    pub adjustments: Vec<u64>,
    /// Per follower: steps flown alone (nothing perceived).
    pub alone_steps: Vec<u64>,
    /// Smallest distance between any two UAVs (m).
    pub min_separation_m: f64,
    /// RMS model error σm per state parameter over all follower steps.
    pub model_error_rms: [f64; P],
    /// Flight duration (s).
    pub duration_s: f64,
}

impl RunSummary {
    /// Max |error| over all followers, per axis.
    pub fn worst(&self) -> [f64; 6] {
        let mut w = [0.0f64; 6];
        for e in &self.max_abs_error {
            for k in 0..6 {
                w[k] = w[k].max(e[k]);
            }
        }
        w
    }
}

/// Observer accumulating a [`RunSummary`].
#[derive(Debug, Clone)]
pub struct RunMetrics {
    followers: Vec<usize>,
    max_abs: Vec<[f64; 6]>,
    sum_sq: Vec<[f64; 6]>,
    samples: u64,
    adjustments: Vec<u64>,
    alone: Vec<u64>,
    min_sep2: f64,
    model_sq: State9,
    model_n: u64,
    allowable: [f64; 6],
}

impl RunMetrics {
    /// Metrics for `scenario`.
    pub fn new(scenario: &Scenario) -> Self {
        let followers: Vec<usize> = (0..scenario.len()).filter(|&i| i != scenario.navigator.index()).collect();
        let nf = followers.len();
        Self {
            followers,
            max_abs: vec![[0.0; 6]; nf],
            sum_sq: vec![[0.0; 6]; nf],
            samples: 0,
            adjustments: vec![0; nf],
            alone: vec![0; nf],
            min_sep2: f64::INFINITY,
            model_sq: State9::zeros(),
            model_n: 0,
            allowable: scenario.allowable.as_array(),
        }
    }

    /// The summary of run `run` lasting `duration_s`.
    pub fn finish(self, run: u64, duration_s: f64) -> RunSummary {
        let n = self.samples.max(1) as f64;
        let rms_error = self.sum_sq.iter().map(|s| s.map(|v| (v / n).sqrt())).collect();
        let pass = self.max_abs.iter().all(|e| e.iter().zip(&self.allowable).all(|(v, a)| v <= a));
        let mn = self.model_n.max(1) as f64;
        let mut model_error_rms = [0.0; P];
        for (k, v) in model_error_rms.iter_mut().enumerate() {
            *v = (self.model_sq[k] / mn).sqrt();
        }
        RunSummary {
            run,
            pass,
            max_abs_error: self.max_abs,
            rms_error,
            adjustments: self.adjustments,
            alone_steps: self.alone,
            min_separation_m: self.min_sep2.sqrt(),
            model_error_rms,
            duration_s,
        }
    }
}

impl Observer for RunMetrics {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        self.samples += 1;
        for (f, &i) in self.followers.iter().enumerate() {
            let e = formation_error(scenario, frame.states, i);
            for k in 0..6 {
                let a = e[k].abs();
                if a > self.max_abs[f][k] {
                    self.max_abs[f][k] = a;
                }
                self.sum_sq[f][k] += e[k] * e[k];
            }
            match frame.decisions[i].map(|d| d.outcome) {
                Some(Outcome::Adjusted { .. }) => {
                    self.adjustments[f] += 1;
                    self.model_sq += frame.model_error[i].component_mul(&frame.model_error[i]);
                    self.model_n += 1;
                }
                Some(Outcome::Alone) => self.alone[f] += 1,
                Some(Outcome::Held) => self.model_n += 1,
                None => {}
            }
        }
        let s = frame.states;
        for a in 0..s.len() {
            for b in a + 1..s.len() {
                let d2 = (s[a][0] - s[b][0]).powi(2) + (s[a][1] - s[b][1]).powi(2) + (s[a][2] - s[b][2]).powi(2);
                if d2 < self.min_sep2 {
                    self.min_sep2 = d2;
                }
            }
        }
    }
}
