//! Per-run metrics: the formation errors, separations and corrections of one flight.
//!
//! Errors and adjustments are accumulated over every follower; per-UAV detail is kept for the
//! first [`PER_UAV_MAX`] followers (every follower of any formation up to that size), so a run
//! of a million UAVs stays small: about 130 bytes per follower and run in flight, folded into
//! the batch's totals when the run ends (`batch::runs::PerUavTotals`).

use proxform_core::state::{State9, P};

use proxform_scenario::Scenario;

use super::observer::{formation_error_to, Observer, StepFrame, StepOutcome};
use super::verdict::{formed_at, Criterion, Evidence, FollowerJudge, Window};

/// Followers with per-UAV detail in summaries (the first ones).
pub const PER_UAV_MAX: usize = 4096;

/// One follower's statistics over a run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// Steps judged as a follower (0: it never flew as one).
    pub judged_steps: u64,
    /// Whether it met the run's criterion over its own errors (`measure::verdict`); false when
    /// it never flew.
    pub pass: bool,
}

/// What one run measured, small enough to keep for thousands of runs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunSummary {
    /// Run index within its batch.
    pub run: u64,
    /// True when every follower stayed within every allowable error for the whole flight; for
    /// a formation that did not start in its slots, from a time no later than the scenario's
    /// `form_within_s` to the end.
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
    /// Smallest distance between any two flying UAVs over the flight, from their true
    /// positions (m; ∞ when fewer than two flew).
    pub min_separation_m: f64,
    /// Largest distance of the navigator (once it is gone, of the formation's estimate of its
    /// slot) from its planned path over the flight (m).
    pub path_deviation_m: f64,
    /// When the latest of the navigator's successors began to lead, and which UAV (METHOD §8;
    /// None: the navigator led throughout, or nobody took over).
    pub succession: Option<(f64, u32)>,
    /// RMS model error σm per state parameter over all follower steps.
    pub model_error_rms: [f64; P],
    /// Flight duration (s).
    pub duration_s: f64,
    /// Fraction of follower steps whose course stayed inside the envelope (held).
    pub held_fraction: f64,
    /// Fraction of follower steps with every error within the allowable errors.
    pub within_allowable_fraction: f64,
    /// Mean control effort per follower step: root sum of squares of the inputs, each over its
    /// per-step limit.
    pub control_effort: f64,
    /// Distinct pairs ever closer than the safety distance.
    pub close_pairs: u64,
    /// Radio messages sent per UAV per second (every broadcasting UAV sends one a period).
    pub radio_sent_per_uav_s: f64,
    /// Received radio messages a UAV used (of UAVs it did not perceive onboard), per UAV per
    /// second.
    pub radio_used_per_uav_s: f64,
    /// Follower steps measured: 0 when no follower flew (nothing to judge: not a pass).
    pub judged_steps: u64,
    /// Order (polarisation) |Σ v_i/|v_i|| / N: mean over the flight.
    pub order_mean: f64,
    /// Order: smallest over the flight.
    pub order_min: f64,
    /// Fraction of the UAVs in the largest connected group of the sensing graph (UAVs within
    /// sensing range of each other): smallest over the sampled steps.
    pub connectivity_min: f64,
    /// Seconds per follower flown alone (nothing perceived), mean.
    pub alone_s_per_uav: f64,
    /// Faults of a UAV's own sensor (stuck or glitching), when the scenario has any.
    pub sensor_faults: Option<SensorFaultMetrics>,
    /// What the robust fusion and the own-sensor check did, when either is on.
    pub isolation: Option<IsolationMetrics>,
    /// How the formation formed, when it did not start in its slots (scattered starts, UAVs
    /// joining).
    pub forming: Option<FormingMetrics>,
    /// How the formation changed in flight, when it has `[[formation.change]]`s or its slots
    /// were re-assigned after a loss.
    pub transitions: Option<TransitionMetrics>,
    /// What the followers flew, when the formation forms, changes or may be re-assigned.
    pub flown: Option<FlownMetrics>,
    /// Follower-seconds flown without an agent (a distributed flight whose agent was gone:
    /// the UAV held its course, uncontrolled). A run with any does not pass.
    pub uncontrolled_s: f64,
}

/// What the followers flew over a run (means per follower).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlownMetrics {
    /// Distance flown (m).
    pub path_length_m_per_uav: f64,
    /// Velocity change flown, Σ|v_k − v_{k−1}| (m/s): the manoeuvring a propulsion pays for,
    /// turns at constant speed included.
    pub delta_v_mps_per_uav: f64,
    /// Specific mechanical work, Σ|Δ(½|v|² + g·z)| (J/kg): energy put into (or taken out of)
    /// speed and height, drag aside; times the mass, joules.
    pub work_j_per_kg_per_uav: f64,
}

/// How the changes of formation of a run went.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TransitionMetrics {
    /// The slowest change: from its start, how long until every follower was within its
    /// allowable errors of the new formation and stayed there until the next change or the
    /// end (s; ∞ when some follower was still outside them then).
    pub transition_s: f64,
    /// Largest error over its allowable error during the changes (any axis, any follower).
    pub transient_error_ratio: f64,
    /// Largest error over its allowable error before the first change.
    pub before_error_ratio: f64,
    /// Smallest distance between two flying UAVs during the changes (m; ∞ when none flew).
    pub closest_m: f64,
}

/// A follower removed in flight: out of its errors at the last frame it flew, it neither
/// formed nor completed the change it was in.
#[derive(Debug, Clone, Copy)]
struct Leaving {
    uav: usize,
    /// At the last frame it flew so far: when, and whether out of its errors.
    last: Option<(f64, bool)>,
    /// Gone, and counted.
    gone: bool,
}

/// One change of formation, as measured: its window (until the next change or the end) and
/// the last time in it that a follower was outside its allowable errors (∞: one left out of
/// them).
#[derive(Debug, Clone, Copy)]
struct Transition {
    at_s: f64,
    until_s: f64,
    last_out: f64,
    ratio: f64,
    /// Cut short by a re-assignment (a loss known while it was in force): the re-assignment's
    /// window judges whether the formation completed it.
    superseded: bool,
}

impl Transition {
    /// The window's last frame: the one before the next change, or the flight's last (`t_last`).
    fn last_frame(&self, dt: f64, t_last: f64) -> f64 {
        if self.until_s.is_finite() {
            (self.until_s - dt).min(t_last)
        } else {
            t_last
        }
    }
}

/// How a formation that did not start in its slots came together.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FormingMetrics {
    /// From this time on (s) every follower stayed within every allowable error: 0 when none
    /// ever left them, ∞ when some follower was outside them at the end (not formed).
    pub time_to_form_s: f64,
    /// Largest error over its allowable error (any axis, any follower) before that time.
    pub transient_error_ratio: f64,
    /// Largest error over its allowable error, over the whole flight, of the followers that
    /// started in their slots and did not join: how far the others
    /// were pushed by those forming. None when every follower started off its slot.
    pub settled_error_ratio: Option<f64>,
}

/// How a formation rode out faults of some UAVs' own sensors.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SensorFaultMetrics {
    /// Every follower without a sensor fault stayed within every allowable error.
    pub healthy_pass: bool,
    /// Largest |error| over the followers without a sensor fault: x, y, z (m), α, β, γ (rad).
    pub healthy_max_abs_error: [f64; 6],
    /// How long after a fault ended its UAV was back within every allowable error, until its
    /// next fault or the end of the flight (s; the slowest of the run's faults; 0 when it
    /// never left them; ∞ when it was still out at the end).
    pub rejoin_s: f64,
}

/// What the robust fusion and the own-sensor check did over a run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct IsolationMetrics {
    /// Seconds per follower in which its fusion left at least one neighbour out.
    pub isolating_s_per_uav: f64,
    /// Neighbours left out, summed over followers and steps, per follower-second.
    pub isolated_per_uav_s: f64,
    /// Seconds per follower flown on its own prediction (own measurement refused).
    pub own_suspect_s_per_uav: f64,
    /// Episodes of refused own measurements, all followers.
    pub own_suspect_episodes: u64,
}

impl RunSummary {
    /// Adjustments per follower per minute of flight.
    pub fn adjustments_per_uav_minute(&self) -> f64 {
        self.adjustments as f64 / (self.followers.max(1) as f64 * (self.duration_s / 60.0))
    }
}

#[derive(Debug, Clone, Default)]
struct Acc {
    max_abs: [f64; 6],
    sum_sq: [f64; 6],
    adjustments: u64,
    alone: u64,
    held: u64,
    within: u64,
    follower_steps: u64,
    effort: f64,
    isolating: u64,
    isolated: u64,
    suspect: u64,
    uncontrolled: u64,
}

/// Observer accumulating a [`RunSummary`].
#[derive(Debug, Clone)]
pub struct RunMetrics {
    nav: usize,
    total: Acc,
    sample: Vec<(usize, Acc)>,
    /// The run's criterion, and each sampled follower's evidence for it.
    criterion: Criterion,
    judges: Vec<FollowerJudge>,
    samples: u64,
    followers: u64,
    separation: super::separation::Separation,
    /// The navigator's start (its path's origin) and the largest distance from its path so far.
    start: [f64; 3],
    path_deviation: f64,
    succession: Option<(f64, u32)>,
    path_bound: f64,
    range: f64,
    model_sq: State9,
    model_n: u64,
    allowable: [f64; 6],
    radio_sent: u64,
    radio_used: u64,
    uav_steps: u64,
    order_sum: f64,
    order_min: f64,
    connectivity_min: f64,
    dt: f64,
    /// UAVs with a sensor fault, sorted, each once.
    faulty: Vec<usize>,
    /// The UAVs the "other followers" of the sensor faults leave out, sorted: those with a
    /// sensor fault, and the joiners (out of their errors by design until they have formed).
    not_healthy: Vec<usize>,
    /// The followers removed in flight, and whether each was out of its allowable errors at
    /// the last frame it flew.
    leaving: Vec<Leaving>,
    /// Each sensor fault's aftermath: its UAV, when the fault ends, when the UAV's next
    /// sensor fault starts (∞ for its last), and the last time in between that the UAV was
    /// outside its allowable errors.
    aftermaths: Vec<Aftermath>,
    /// Largest |error| of the followers without a sensor fault.
    healthy_max: [f64; 6],
    /// Whether the robust fusion or the own-sensor check is on.
    isolating: bool,
    /// Per UAV: whether it refused its own measurement in the previous step (episodes).
    suspect_before: Vec<bool>,
    suspect_episodes: u64,
    t_last: f64,
    /// Forming: measured at all, the last time a follower was outside its allowable errors,
    /// the largest error ratio so far and at that time, and the distance flown by all.
    forming: bool,
    /// Changes of formation in flight, and the largest error ratio before the first.
    transitions: Vec<Transition>,
    /// Separation during the changes (made when the formation may change).
    change_separation: Option<super::separation::Separation>,
    before_ratio: f64,
    /// Where forming is judged to (exclusive, s): the first change of formation, but for a
    /// re-assignment made while the formation was still forming, which forming carries on
    /// through (to the next scheduled change, or the end).
    forming_until: f64,
    last_out_any: f64,
    ratio_so_far: f64,
    ratio_before_formed: f64,
    /// Per UAV: started in its slot and does not join (judged from the start).
    settled: Vec<bool>,
    settled_ratio: f64,
    /// Whether what the followers flew is measured, and its sums.
    flown: bool,
    path_m: f64,
    delta_v: f64,
    work: f64,
    /// Per UAV: velocity and specific energy at the last frame (NaN: not flying then).
    last_flown: Vec<[f64; 4]>,
}

/// Steps between connectivity samples for swarms larger than [`CONNECTIVITY_EVERY_STEP_UP_TO`].
const CONNECTIVITY_STRIDE: u64 = 50;
/// Formations up to this size get their connectivity measured at every step.
const CONNECTIVITY_EVERY_STEP_UP_TO: usize = 64;

impl RunMetrics {
    /// Metrics for `scenario`.
    pub fn new(scenario: &Scenario) -> Self {
        let nav = scenario.navigator().index();
        let aftermaths = aftermaths(scenario);
        let sample: Vec<(usize, Acc)> =
            (0..scenario.len()).filter(|&i| i != nav).take(PER_UAV_MAX).map(|i| (i, Acc::default())).collect();
        let settled_uavs = settled(scenario);
        let forming = !scenario.placement().in_slots()
            || scenario.faults().iter().any(|f| matches!(f, proxform_scenario::faults::Fault::Join { .. }));
        let changes = scenario.schedule().stages().len();
        let judges = sample
            .iter()
            .map(|(i, _)| FollowerJudge::new(settled_uavs.get(*i).copied().unwrap_or(false), changes))
            .collect();
        Self {
            nav,
            total: Acc::default(),
            sample,
            criterion: Criterion { form_within_s: scenario.form_within_s(), forming },
            judges,
            samples: 0,
            followers: scenario.len() as u64 - 1,
            separation: super::separation::Separation::new(scenario.safety_distance_m()),
            start: {
                let s0 = &scenario.initial()[nav];
                [s0[0], s0[1], s0[2]]
            },
            path_deviation: 0.0,
            succession: None,
            path_bound: scenario.allowable().path_m,
            range: scenario.controller().areas.sensing_range_m,
            model_sq: State9::zeros(),
            model_n: 0,
            allowable: scenario.allowable().as_array(),
            radio_sent: 0,
            radio_used: 0,
            uav_steps: 0,
            order_sum: 0.0,
            order_min: f64::INFINITY,
            connectivity_min: f64::INFINITY,
            dt: scenario.dt_s(),
            not_healthy: {
                let joiners = scenario.faults().iter().filter_map(|f| match f {
                    proxform_scenario::faults::Fault::Join { uav, .. } => Some(uav.index()),
                    _ => None,
                });
                let mut u: Vec<usize> = aftermaths.iter().map(|a| a.uav).chain(joiners).collect();
                u.sort_unstable();
                u.dedup();
                u
            },
            leaving: scenario
                .faults()
                .iter()
                .filter_map(|f| match f {
                    proxform_scenario::faults::Fault::Remove { uav, .. } if uav.index() != nav => {
                        Some(Leaving { uav: uav.index(), last: None, gone: false })
                    }
                    _ => None,
                })
                .collect(),
            faulty: {
                let mut u: Vec<usize> = aftermaths.iter().map(|a| a.uav).collect();
                u.dedup();
                u
            },
            aftermaths,
            healthy_max: [0.0; 6],
            isolating: {
                let p = scenario.controller();
                p.isolation_gate.is_some() || p.own_gate_m.is_some()
            },
            suspect_before: Vec::new(),
            suspect_episodes: 0,
            t_last: 0.0,
            forming,
            transitions: {
                let stages = scenario.schedule().stages();
                (0..stages.len())
                    .map(|k| Transition {
                        at_s: stages[k].at_s,
                        until_s: stages.get(k + 1).map_or(f64::INFINITY, |s| s.at_s),
                        last_out: f64::NEG_INFINITY,
                        ratio: 0.0,
                        superseded: false,
                    })
                    .collect()
            },
            change_separation: (!scenario.schedule().is_empty() || scenario.reassign_on_loss().is_some())
                .then(|| super::separation::Separation::new(scenario.safety_distance_m())),
            before_ratio: 0.0,
            forming_until: scenario.schedule().stages().first().map_or(f64::INFINITY, |s| s.at_s),
            last_out_any: f64::NEG_INFINITY,
            ratio_so_far: 0.0,
            ratio_before_formed: 0.0,
            settled: settled_uavs,
            settled_ratio: 0.0,
            flown: !scenario.placement().in_slots()
                || !scenario.schedule().is_empty()
                || scenario.reassign_on_loss().is_some()
                || scenario.faults().iter().any(|f| matches!(f, proxform_scenario::faults::Fault::Join { .. })),
            path_m: 0.0,
            delta_v: 0.0,
            work: 0.0,
            last_flown: Vec::new(),
        }
    }

    /// What the followers flew in the period that ends at `frame` (nothing before the first).
    fn fly(&mut self, frame: &StepFrame<'_>, speeds: f64) {
        let n = frame.states.len();
        if self.last_flown.len() != n {
            self.last_flown = vec![[f64::NAN; 4]; n];
        }
        if frame.k > 0 {
            self.path_m += speeds * self.dt;
        }
        for (i, s) in frame.states.iter().enumerate() {
            let last = &mut self.last_flown[i];
            if i == self.nav || !frame.active[i] {
                *last = [f64::NAN; 4];
                continue;
            }
            let v = [s[3], s[4], s[5]];
            let e = 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + proxform_core::vehicle::G * s[2];
            if !last[0].is_nan() {
                self.delta_v += ((v[0] - last[0]).powi(2) + (v[1] - last[1]).powi(2) + (v[2] - last[2]).powi(2)).sqrt();
                self.work += (e - last[3]).abs();
            }
            *last = [v[0], v[1], v[2], e];
        }
    }

    /// Fraction of the active UAVs in the largest group connected by sensing range.
    fn connectivity(&mut self, frame: &StepFrame<'_>) -> f64 {
        let states = frame.states;
        let n = states.len();
        let active = frame.active;
        let grid = self.separation.grid_mut();
        grid.rebuild_ids(
            states.iter().enumerate().filter(|(i, _)| active[*i]).map(|(i, s)| (i as u32, [s[0], s[1], s[2]])),
            self.range,
        );
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut x: u32) -> u32 {
            while p[x as usize] != x {
                let up = p[p[x as usize] as usize];
                p[x as usize] = up;
                x = up;
            }
            x
        }
        // Each pair within range once (the grid holds the active UAVs only).
        grid.for_each_pair_within(self.range, |i, j, _| {
            let (a, b) = (find(&mut parent, i), find(&mut parent, j));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        });
        let mut size = vec![0u32; n];
        let mut total = 0u32;
        for i in 0..n {
            if active[i] {
                let r = find(&mut parent, i as u32);
                size[r as usize] += 1;
                total += 1;
            }
        }
        f64::from(size.into_iter().max().unwrap_or(0)) / f64::from(total.max(1))
    }

    /// The followers removed in flight: each one's errors at every frame it flies, and at the
    /// first frame without it, if it was out of its errors at its last, the forming or the
    /// change it was in is not complete (it will never be within them).
    fn follow_leaving(&mut self, scenario: &Scenario, frame: &StepFrame<'_>, reference: &State9) {
        for l in self.leaving.iter_mut().filter(|l| !l.gone) {
            if frame.active[l.uav] {
                let e = formation_error_to(scenario, frame.formation(scenario), frame.states, reference, l.uav);
                // The ratio its row is judged by (`FollowerJudge`).
                let out = error_ratio(&e, &self.allowable) > 1.0;
                l.last = Some((frame.t, out));
                continue;
            }
            let Some((t, out)) = l.last else { continue };
            l.gone = true;
            if !out {
                continue;
            }
            if self.forming && t < self.forming_until - 1e-9 {
                self.last_out_any = f64::INFINITY;
            }
            // (In a change it flew a step in: at the change's first frame it had not moved yet.)
            for c in self.transitions.iter_mut().filter(|c| t > c.at_s + 1e-9 && t < c.until_s - 1e-9) {
                c.last_out = f64::INFINITY;
            }
        }
    }

    /// The summary of run `run` lasting `duration_s`.
    pub fn finish(self, run: u64, duration_s: f64) -> RunSummary {
        let steps = self.samples.max(1) as f64;
        let rms = |a: &Acc, n: f64| a.sum_sq.map(|v| (v / n).sqrt());
        // Formed when every follower was within its errors from some time to the last frame
        // of forming: before the first change of formation (or a re-assignment made once it
        // had formed), or the end.
        let form_end = match self.forming_until.is_finite() {
            true => (self.forming_until - self.dt).min(self.t_last),
            false => self.t_last,
        };
        let time_to_form_s = formed_at(self.last_out_any, form_end, self.dt);
        // A run in which no follower flew has nothing to judge: it does not pass. A formation
        // that did not start in its slots passes when it formed in time and stayed formed.
        let transitions = (!self.transitions.is_empty()).then(|| TransitionMetrics {
            transition_s: self
                .transitions
                .iter()
                .filter(|c| !c.superseded)
                .map(|c| {
                    // The window's last frame: the one before the next change, or the flight's.
                    let last = c.last_frame(self.dt, self.t_last);
                    if c.last_out >= last - 1e-9 {
                        f64::INFINITY
                    } else {
                        (c.last_out + self.dt - c.at_s).max(0.0)
                    }
                })
                .fold(0.0, f64::max),
            transient_error_ratio: self.transitions.iter().map(|c| c.ratio).fold(0.0, f64::max),
            before_error_ratio: self.before_ratio,
            closest_m: self.change_separation.as_ref().map_or(f64::INFINITY, |s| s.min_m()),
        });
        // The run's criterion over all followers; a pair closer than the safety distance fails
        // the run, whatever the errors.
        let within = |max_abs: &[f64; 6]| max_abs.iter().zip(&self.allowable).all(|(v, a)| v <= a);
        let evidence = Evidence {
            judged_steps: self.total.follower_steps,
            within: within(&self.total.max_abs),
            time_to_form_s,
            settled_ratio: self.settled_ratio,
            before_ratio: self.before_ratio,
            changes_completed: transitions.as_ref().map(|t| t.transition_s.is_finite()),
        };
        let safe = self.separation.close_pairs() == 0;
        // The formation must also keep to its mission: its navigator (or, once it is gone, the
        // formation's estimate of its slot) within the path bound of the planned path.
        let on_path = self.path_deviation <= self.path_bound;
        // A follower that flew without its agent (gone from a distributed flight) was not
        // controlled by the method: whatever its errors, the run does not pass.
        let controlled = self.total.uncontrolled == 0;
        let pass = safe && on_path && controlled && self.criterion.passes(&evidence);
        // Each sampled follower by the same criterion over its own errors.
        let window = |k: usize| {
            let c = &self.transitions[k];
            let last = c.last_frame(self.dt, self.t_last);
            Window { first: c.at_s, last, superseded: c.superseded }
        };
        let uav_pass: Vec<bool> = self
            .sample
            .iter()
            .zip(&self.judges)
            .map(|((_, a), j)| {
                let e = j.evidence(a.follower_steps, within(&a.max_abs), (form_end, self.dt), window);
                self.criterion.passes(&e)
            })
            .collect();
        let uav_s = self.uav_steps.max(1) as f64 * self.dt;
        let mn = self.model_n.max(1) as f64;
        let mut model_error_rms = [0.0; P];
        for (k, v) in model_error_rms.iter_mut().enumerate() {
            *v = (self.model_sq[k] / mn).sqrt();
        }
        let fs = self.total.follower_steps.max(1) as f64;
        RunSummary {
            held_fraction: self.total.held as f64 / fs,
            within_allowable_fraction: self.total.within as f64 / fs,
            control_effort: self.total.effort / fs,
            close_pairs: self.separation.close_pairs() as u64,
            radio_sent_per_uav_s: self.radio_sent as f64 / uav_s,
            radio_used_per_uav_s: self.radio_used as f64 / uav_s,
            judged_steps: self.total.follower_steps,
            order_mean: self.order_sum / steps,
            order_min: if self.order_min.is_finite() { self.order_min } else { 1.0 },
            connectivity_min: if self.connectivity_min.is_finite() { self.connectivity_min } else { 1.0 },
            alone_s_per_uav: self.total.alone as f64 * self.dt / self.followers.max(1) as f64,
            sensor_faults: (!self.faulty.is_empty()).then(|| SensorFaultMetrics {
                healthy_pass: self.total.follower_steps > 0
                    && self.healthy_max.iter().zip(&self.allowable).all(|(v, a)| v <= a),
                healthy_max_abs_error: self.healthy_max,
                rejoin_s: self
                    .aftermaths
                    .iter()
                    .map(|a| {
                        if a.last_out >= self.t_last - 1e-9 {
                            f64::INFINITY
                        } else {
                            (a.last_out + self.dt - a.end_s).max(0.0)
                        }
                    })
                    .fold(0.0, f64::max),
            }),
            forming: self.forming.then(|| FormingMetrics {
                time_to_form_s,
                transient_error_ratio: self.ratio_before_formed,
                settled_error_ratio: self.settled.iter().any(|s| *s).then_some(self.settled_ratio),
            }),
            flown: self.flown.then(|| {
                let per = self.followers.max(1) as f64;
                FlownMetrics {
                    path_length_m_per_uav: self.path_m / per,
                    delta_v_mps_per_uav: self.delta_v / per,
                    work_j_per_kg_per_uav: self.work / per,
                }
            }),
            transitions,
            isolation: self.isolating.then(|| {
                let per = self.dt / self.followers.max(1) as f64;
                IsolationMetrics {
                    isolating_s_per_uav: self.total.isolating as f64 * per,
                    isolated_per_uav_s: self.total.isolated as f64 / fs / self.dt,
                    own_suspect_s_per_uav: self.total.suspect as f64 * per,
                    own_suspect_episodes: self.suspect_episodes,
                }
            }),
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
                .zip(uav_pass)
                .map(|((i, a), pass)| UavStats {
                    uav: *i as u32,
                    max_abs_error: a.max_abs,
                    rms_error: rms(a, steps),
                    adjustments: a.adjustments,
                    alone_steps: a.alone,
                    judged_steps: a.follower_steps,
                    pass,
                })
                .collect(),
            min_separation_m: self.separation.min_m(),
            path_deviation_m: self.path_deviation,
            succession: self.succession,
            model_error_rms,
            duration_s,
            uncontrolled_s: self.total.uncontrolled as f64 * self.dt,
        }
    }
}

/// Per UAV: whether it is judged from the start, having started in its slot and not joining.
fn settled(scenario: &Scenario) -> Vec<bool> {
    use proxform_scenario::faults::Fault;
    use proxform_scenario::placement::Placement;
    let nav = scenario.navigator().index();
    let mut settled: Vec<bool> = (0..scenario.len())
        .map(|i| {
            i != nav
                && match scenario.placement() {
                    Placement::Slots => true,
                    Placement::Explicit(list) => list.iter().all(|(id, _)| id.index() != i),
                    _ => false,
                }
        })
        .collect();
    for f in scenario.faults() {
        if let Fault::Join { uav, .. } = f {
            settled[uav.index()] = false;
        }
    }
    settled
}

/// The time after one sensor fault of a UAV, until its next one.
#[derive(Debug, Clone, Copy)]
struct Aftermath {
    uav: usize,
    end_s: f64,
    until_s: f64,
    last_out: f64,
}

/// Every fault of a UAV's own sensor (stuck or glitching), by UAV and time.
fn aftermaths(scenario: &Scenario) -> Vec<Aftermath> {
    use proxform_scenario::faults::Fault;
    let mut out: Vec<(usize, f64, f64)> = scenario
        .faults()
        .iter()
        .filter_map(|f| match *f {
            Fault::Glitch { uav, at_s, duration_s, .. } | Fault::StuckSensor { uav, at_s, duration_s } => {
                Some((uav.index(), at_s, at_s + duration_s))
            }
            _ => None,
        })
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    (0..out.len())
        .map(|k| {
            let (uav, _, end_s) = out[k];
            let until_s = out.get(k + 1).filter(|n| n.0 == uav).map_or(f64::INFINITY, |n| n.1);
            Aftermath { uav, end_s, until_s, last_out: f64::NEG_INFINITY }
        })
        .collect()
}

/// |x|, and +∞ for NaN: a UAV whose state is no longer a number is as far out as can be (a
/// NaN compared with a bound is never greater, so it would pass every check silently).
#[inline]
fn magnitude(x: f64) -> f64 {
    if x.is_nan() {
        f64::INFINITY
    } else {
        x.abs()
    }
}

/// A follower's formation error `e` over its allowable errors, its worst axis (∞ for NaN): above
/// 1, it is out of them.
#[inline]
fn error_ratio(e: &[f64; 6], allowable: &[f64; 6]) -> f64 {
    (0..6).map(|k| magnitude(e[k]) / allowable[k]).fold(0.0, f64::max)
}

#[inline]
fn accumulate(acc: &mut Acc, e: &[f64; 6], outcome: Option<StepOutcome>) {
    acc.follower_steps += 1;
    for k in 0..6 {
        let a = magnitude(e[k]);
        if a > acc.max_abs[k] {
            acc.max_abs[k] = a;
        }
        acc.sum_sq[k] += e[k] * e[k];
    }
    match outcome {
        Some(StepOutcome::Adjusted) => acc.adjustments += 1,
        Some(StepOutcome::Alone) => acc.alone += 1,
        Some(StepOutcome::Held) => acc.held += 1,
        None => {}
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
    radio_used: u64,
    active: u64,
    heading: [f64; 3],
    healthy_max: [f64; 6],
    /// Largest error over its allowable error among the chunk's followers.
    max_ratio: f64,
    /// The same among those judged from the start ([`RunMetrics`]'s `settled`).
    settled_ratio: f64,
    /// Sum of the followers' speeds (m/s).
    speed_sum: f64,
}

fn partial(
    (nav, settled): (usize, &[bool]),
    not_healthy: &[usize],
    scenario: &Scenario,
    frame: &StepFrame<'_>,
    reference: &State9,
    range: std::ops::Range<usize>,
) -> Partial {
    let mut p = Partial::default();
    let allowable = scenario.allowable().as_array();
    for i in range {
        if !frame.active[i] {
            continue;
        }
        let u = &frame.uavs[i];
        p.radio_used += u64::from(u.radio_used);
        p.active += 1;
        let s = &frame.states[i];
        let speed = (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]).sqrt();
        if speed > 0.0 {
            for k in 0..3 {
                p.heading[k] += s[3 + k] / speed;
            }
        }
        if i == nav {
            continue;
        }
        let e = formation_error_to(scenario, frame.formation(scenario), frame.states, reference, i);
        accumulate(&mut p.acc, &e, u.outcome);
        p.speed_sum += speed;
        let ratio = error_ratio(&e, &allowable);
        p.max_ratio = p.max_ratio.max(ratio);
        if settled.get(i).copied().unwrap_or(false) {
            p.settled_ratio = p.settled_ratio.max(ratio);
        }
        if not_healthy.binary_search(&i).is_err() {
            for k in 0..6 {
                p.healthy_max[k] = p.healthy_max[k].max(magnitude(e[k]));
            }
        }
        p.acc.isolating += u64::from(u.isolated > 0);
        p.acc.isolated += u64::from(u.isolated);
        p.acc.suspect += u64::from(u.own_suspect);
        p.acc.uncontrolled += u64::from(u.uncontrolled);
        if e.iter().zip(&allowable).all(|(e, a)| e.abs() <= *a) {
            p.acc.within += 1;
        }
        p.acc.effort += f64::from(u.effort);
        match u.outcome {
            Some(StepOutcome::Adjusted) => {
                for k in 0..P {
                    p.model_sq[k] += f64::from(u.model_error[k]).powi(2);
                }
                p.model_n += 1;
            }
            Some(StepOutcome::Held) => p.model_n += 1,
            _ => {}
        }
    }
    p
}

impl Observer for RunMetrics {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        self.samples += 1;
        let n = frame.states.len();
        let nav = self.nav;
        let reference = frame.navigator_reference(scenario);
        self.separation.observe(frame.states, frame.active);
        let planned = scenario.path().state_at(frame.t, self.start);
        let off = (0..3).map(|k| (reference[k] - planned[k]).powi(2)).sum::<f64>().sqrt();
        // NaN counts as off (a state that is not a number is nowhere near the path).
        self.path_deviation = if off.is_nan() { f64::INFINITY } else { self.path_deviation.max(off) };
        // The latest successor, from when it began to lead.
        if let Some((s, _)) = frame.successor.filter(|&(s, _)| self.succession.is_none_or(|(_, u)| u as usize != s)) {
            self.succession = Some((frame.t, s as u32));
        }
        self.radio_sent += frame.radio_sent as u64;
        let parallel = n >= crate::world::engine::PARALLEL_MIN_UAVS;
        let parts = crate::parallel::map_chunks(n, CHUNK, parallel, |r| {
            partial((nav, &self.settled), &self.not_healthy, scenario, frame, &reference, r)
        });
        let mut active = 0u64;
        let mut heading = [0.0f64; 3];
        let (mut step_ratio, mut speeds, mut settled_ratio) = (0.0f64, 0.0f64, 0.0f64);
        for p in parts {
            for k in 0..6 {
                self.total.max_abs[k] = self.total.max_abs[k].max(p.acc.max_abs[k]);
                self.total.sum_sq[k] += p.acc.sum_sq[k];
            }
            self.total.adjustments += p.acc.adjustments;
            self.total.alone += p.acc.alone;
            self.total.held += p.acc.held;
            self.total.within += p.acc.within;
            self.total.follower_steps += p.acc.follower_steps;
            self.total.effort += p.acc.effort;
            self.total.isolating += p.acc.isolating;
            self.total.isolated += p.acc.isolated;
            self.total.suspect += p.acc.suspect;
            self.total.uncontrolled += p.acc.uncontrolled;
            for k in 0..6 {
                self.healthy_max[k] = self.healthy_max[k].max(p.healthy_max[k]);
            }
            step_ratio = step_ratio.max(p.max_ratio);
            settled_ratio = settled_ratio.max(p.settled_ratio);
            speeds += p.speed_sum;
            self.model_sq += p.model_sq;
            self.model_n += p.model_n;
            self.radio_used += p.radio_used;
            self.uav_steps += p.active;
            active += p.active;
            for k in 0..3 {
                heading[k] += p.heading[k];
            }
        }
        if self.flown {
            self.fly(frame, speeds);
        }
        // Slots re-assigned: a change of formation from now until the next scheduled one (one
        // made with a scheduled change, in the step that began it, is that change).
        let t = frame.t;
        let (dt, transitions) = (self.dt, &self.transitions);
        let begun = || transitions.iter().any(|c| c.at_s >= t - dt - 1e-9 && c.at_s <= t + 1e-9);
        if frame.reassigned && !begun() {
            let until = scenario.schedule().stages().iter().map(|s| s.at_s).find(|&a| a > t + 1e-9);
            // A re-assignment made while the formation was still forming (a follower out of
            // its errors at the last frame before it) is forming's continuation: the formation
            // has formed when it has formed in the new slots. Made once it had formed, it ends
            // forming, as a change does.
            let still_forming = self.forming && t < self.forming_until - 1e-9 && self.last_out_any >= t - dt - 1e-9;
            if !still_forming {
                self.forming_until = self.forming_until.min(t);
            }
            for c in self.transitions.iter_mut().filter(|c| c.at_s <= t + 1e-9 && c.until_s > t) {
                (c.until_s, c.superseded) = (t, true);
            }
            let at = self.transitions.iter().position(|c| c.at_s > t).unwrap_or(self.transitions.len());
            for j in self.judges.iter_mut() {
                j.changes_last_out.insert(at, f64::NEG_INFINITY);
            }
            let change = Transition {
                at_s: t,
                until_s: until.unwrap_or(f64::INFINITY),
                last_out: f64::NEG_INFINITY,
                ratio: 0.0,
                superseded: false,
            };
            self.transitions.insert(at, change);
        }
        if let Some(sep) = self.change_separation.as_mut() {
            if self.transitions.iter().any(|c| frame.t >= c.at_s - 1e-9 && frame.t < c.until_s - 1e-9) {
                sep.observe(frame.states, frame.active);
            }
        }
        // Forming is judged up to the first change of formation (each change is judged on its
        // own), and so are the followers that started in their slots.
        let before_change = self.transitions.first().is_none_or(|c| frame.t < c.at_s - 1e-9);
        if before_change {
            self.settled_ratio = self.settled_ratio.max(settled_ratio);
        }
        let in_forming = frame.t < self.forming_until - 1e-9;
        if self.forming && in_forming {
            self.ratio_so_far = self.ratio_so_far.max(step_ratio);
            if step_ratio > 1.0 {
                // (∞ stays: a follower left out of its errors, `follow_leaving`.)
                self.last_out_any = self.last_out_any.max(frame.t);
                self.ratio_before_formed = self.ratio_so_far;
            }
        }
        for c in self.transitions.iter_mut() {
            if frame.t >= c.at_s - 1e-9 && frame.t < c.until_s - 1e-9 {
                c.ratio = c.ratio.max(step_ratio);
                if step_ratio > 1.0 {
                    c.last_out = c.last_out.max(frame.t);
                }
            }
        }
        // Before the first change (one made in flight is not known until it is made).
        if self.transitions.first().is_none_or(|c| frame.t < c.at_s - 1e-9) {
            self.before_ratio = self.before_ratio.max(step_ratio);
        }
        self.follow_leaving(scenario, frame, &reference);
        let order = (heading[0].powi(2) + heading[1].powi(2) + heading[2].powi(2)).sqrt() / (active.max(1) as f64);
        self.order_sum += order;
        self.order_min = self.order_min.min(order);
        if n <= CONNECTIVITY_EVERY_STEP_UP_TO || frame.k % CONNECTIVITY_STRIDE == 0 {
            let c = self.connectivity(frame);
            self.connectivity_min = self.connectivity_min.min(c);
        }
        self.t_last = frame.t;
        for a in self.aftermaths.iter_mut() {
            let t = frame.t;
            if !frame.active[a.uav] || t < a.end_s - 1e-9 || t >= a.until_s - 1e-9 {
                continue;
            }
            let e = formation_error_to(scenario, frame.formation(scenario), frame.states, &reference, a.uav);
            if !e.iter().zip(&self.allowable).all(|(e, al)| e.abs() <= *al) {
                a.last_out = t;
            }
        }
        if self.isolating && self.total.suspect > 0 {
            self.suspect_before.resize(n, false);
            for (u, before) in frame.uavs.iter().zip(self.suspect_before.iter_mut()) {
                self.suspect_episodes += u64::from(u.own_suspect && !*before);
                *before = u.own_suspect;
            }
        }
        let (transitions, allowable) = (&self.transitions, &self.allowable);
        for ((i, acc), judge) in self.sample.iter_mut().zip(self.judges.iter_mut()) {
            if !frame.active[*i] {
                continue;
            }
            let e = formation_error_to(scenario, frame.formation(scenario), frame.states, &reference, *i);
            accumulate(acc, &e, frame.uavs[*i].outcome);
            let ratio = error_ratio(&e, allowable);
            judge.observe(t, ratio, (before_change, in_forming), |k| {
                let c = &transitions[k];
                t >= c.at_s - 1e-9 && t < c.until_s - 1e-9
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::observer::UavStep;
    use proxform_core::state::{VX, VZ, X, Y, Z};
    use proxform_scenario::builtin::paper;

    /// The paper's six UAVs in their slots around a navigator at the origin flying along x.
    fn in_slots(sc: &Scenario) -> Vec<State9> {
        let mut nav = State9::zeros();
        nav[VX] = 70.0;
        (0..sc.len()).map(|i| sc.slot_state(i, &nav)).collect()
    }

    /// The scenario's UAVs in their slots around its navigator on its path at `t`.
    fn along_path(sc: &Scenario, t: f64) -> Vec<State9> {
        let s0 = &sc.initial()[sc.navigator().index()];
        let nav = sc.path().state_at(t, [s0[0], s0[1], s0[2]]);
        (0..sc.len()).map(|i| sc.slot_state(i, &nav)).collect()
    }

    fn frame<'a>(k: u64, states: &'a [State9], uavs: &'a [UavStep], active: &'a [bool]) -> StepFrame<'a> {
        StepFrame { radio_sent: 2, ..StepFrame::new(k, k as f64 * 0.1, states, uavs, active) }
    }

    fn step(outcome: proxform_core::Outcome, effort: f32) -> UavStep {
        UavStep { outcome: Some(outcome.into()), effort, radio_used: 1, ..UavStep::default() }
    }

    #[test]
    fn a_uav_whose_state_is_not_a_number_fails_the_run() {
        let sc = paper();
        let good = in_slots(&sc);
        let uavs = vec![UavStep::default(); 6];
        let active = [true; 6];
        let mut m = RunMetrics::new(&sc);
        for k in 0..20u64 {
            let mut states = good.clone();
            if k >= 10 {
                // A NaN compares as neither above nor below any bound: it passed every check.
                states[2][Y] = f64::NAN;
            }
            m.on_step(&sc, &frame(k, &states, &uavs, &active));
        }
        let r = m.finish(0, 2.0);
        assert!(!r.pass, "a NaN state passed");
        assert_eq!(r.max_abs_error[1], f64::INFINITY, "{:?}", r.max_abs_error);
        assert!(r.per_uav.iter().any(|u| !u.pass && u.max_abs_error[1] == f64::INFINITY), "{:?}", r.per_uav);
    }

    #[test]
    fn a_faulty_uav_is_judged_apart_and_its_return_timed_after_each_fault() {
        use proxform_scenario::spec::FaultSpec;
        let glitch = |at_s: f64| FaultSpec {
            kind: Some("glitch".into()),
            uav: Some(3),
            at_s: Some(at_s),
            duration_s: Some(1.0),
            offset_m: Some([0.0, 5.0, 0.0]),
        };
        let sc = Scenario::try_from(proxform_scenario::builtin::paper_spec().with(|s| {
            s.fault = vec![glitch(1.0), glitch(5.0)];
        }))
        .expect("valid");
        let good = in_slots(&sc);
        let uavs = vec![UavStep::default(); 6];
        let active = [true; 6];
        let mut m = RunMetrics::new(&sc);
        for k in 0..80u64 {
            let t = k as f64 * 0.1;
            let mut states = good.clone();
            // UAV3 is 2 m off its slot from 1.0 s to 3.4 s (back at 3.5 s, 1.5 s after its first
            // fault ended) and from 6.0 s to 6.4 s (back 0.5 s after the second): the slower
            // return counts, though a later fault followed it.
            if (1.0 - 1e-9..3.45).contains(&t) || (6.0 - 1e-9..6.45).contains(&t) {
                states[2][Y] += 2.0;
            }
            // UAV4, without a fault, 0.1 m off at 4 s: within its allowable errors.
            if (4.0 - 1e-9..4.05).contains(&t) {
                states[3][Y] += 0.1;
            }
            m.on_step(&sc, &frame(k, &states, &uavs, &active));
        }
        let r = m.finish(0, 8.0);
        assert!(!r.pass, "UAV3 left its allowable errors");
        let f = r.sensor_faults.expect("sensor faults");
        assert!(f.healthy_pass, "{f:?}");
        assert!((f.healthy_max_abs_error[1] - 0.1).abs() < 1e-9, "{f:?}");
        assert!((f.rejoin_s - 1.5).abs() < 1e-9, "{f:?}");
        assert!(r.isolation.is_none(), "no robust check on");
    }

    #[test]
    fn a_formation_forms_when_its_last_follower_is_back_within_its_allowable_errors() {
        let sc = Scenario::try_from(proxform_scenario::builtin::paper_spec().with(|s| {
            s.initial.placement = Some("disc".into());
            s.initial.radius_m = Some(1000.0);
        }))
        .expect("valid");
        let good = in_slots(&sc);
        let uavs = vec![UavStep::default(); 6];
        let active = [true; 6];
        let mut m = RunMetrics::new(&sc);
        for k in 0..30u64 {
            let t = k as f64 * 0.1;
            let mut states = good.clone();
            // UAV3 3 m to the left (5× its 0.6 m) until 0.9 s, then 1.2 m (2×) until 1.9 s.
            if t < 0.95 {
                states[2][Y] += 3.0;
            } else if t < 1.95 {
                states[2][Y] += 1.2;
            }
            // The formation climbs at 1 m/s from 1 s on, 0.1 m a period.
            if t > 0.95 {
                for s in states.iter_mut() {
                    s[VZ] = 1.0;
                    s[Z] += 0.1 * (k - 9) as f64;
                }
            }
            m.on_step(&sc, &frame(k, &states, &uavs, &active));
        }
        let r = m.finish(0, 3.0);
        let f = r.forming.expect("a scattered start is measured");
        assert!((f.time_to_form_s - 2.0).abs() < 1e-9, "{f:?}");
        assert!((f.transient_error_ratio - 5.0).abs() < 1e-9, "{f:?}");
        assert_eq!(f.settled_error_ratio, None, "every follower started off its slot");
        // Every follower at 70 m/s for the 29 periods after the first frame; one velocity
        // change of 1 m/s each; ½v² up by 0.5 J/kg and g·z by g·0.1 m a period for 20.
        let w = r.flown.expect("measured where the formation forms");
        assert!((w.path_length_m_per_uav - 70.0 * 0.1 * 29.0).abs() < 0.02, "{w:?}");
        assert!((w.delta_v_mps_per_uav - 1.0).abs() < 1e-9, "{w:?}");
        let work = 0.5 + proxform_core::vehicle::G * 0.1 * 20.0;
        assert!((w.work_j_per_kg_per_uav - work).abs() < 1e-6, "{w:?}");
        // In the slots from the start (the paper), nothing is measured.
        let mut plain = RunMetrics::new(&paper());
        plain.on_step(&paper(), &frame(0, &good, &uavs, &active));
        let r = plain.finish(0, 0.1);
        assert!(r.forming.is_none() && r.flown.is_none());
    }

    #[test]
    fn forming_is_judged_up_to_the_first_change_and_each_change_after_it() {
        // Scattered starts, then at 2 s a change to the same slots: UAV3 3 m off until 0.9 s
        // (formed at 1 s); in `late`, 3 m off again from 2.5 s to the end, so that the change
        // is never completed (but the formation had formed before it).
        let sc = Scenario::try_from(proxform_scenario::builtin::paper_spec().with(|s| {
            s.initial.placement = Some("disc".into());
            s.initial.radius_m = Some(1000.0);
            s.formation.change = vec![proxform_scenario::spec::FormationChangeSpec {
                at_s: Some(2.0),
                slot: s.formation.slot.clone(),
                ..Default::default()
            }];
        }))
        .expect("valid");
        let uavs = vec![UavStep::default(); 6];
        let active = [true; 6];
        let fly = |late: bool| {
            let mut m = RunMetrics::new(&sc);
            for k in 0..40u64 {
                let t = k as f64 * 0.1;
                let mut states = along_path(&sc, t);
                if t < 0.95 || (late && t > 2.45) {
                    states[2][Y] += 3.0;
                }
                m.on_step(&sc, &frame(k, &states, &uavs, &active));
            }
            m.finish(0, 4.0)
        };
        let (ok, late) = (fly(false), fly(true));
        for r in [&ok, &late] {
            let f = r.forming.expect("scattered");
            assert!((f.time_to_form_s - 1.0).abs() < 1e-9, "formed before the change: {f:?}");
        }
        assert_eq!(ok.transitions.expect("a change").transition_s, 0.0);
        assert!(ok.pass);
        assert!(late.transitions.expect("a change").transition_s.is_infinite());
        assert!(!late.pass, "a change never completed fails the run");
    }

    #[test]
    fn a_run_in_which_no_follower_flew_does_not_pass() {
        let sc = paper();
        let states = in_slots(&sc);
        let uavs = vec![UavStep::default(); 6];
        let mut m = RunMetrics::new(&sc);
        for k in 0..10 {
            m.on_step(&sc, &frame(k, &states, &uavs, &[true, false, false, false, false, false]));
        }
        let r = m.finish(0, 1.0);
        assert_eq!(r.judged_steps, 0);
        assert!(!r.pass, "nothing was judged");
    }

    #[test]
    fn a_formation_split_in_two_is_half_connected_and_opposite_headings_have_no_order() {
        let sc = paper();
        let mut states = in_slots(&sc);
        // UAVs 4-6 10 km away, flying the other way.
        for s in &mut states[3..] {
            s[X] += 10_000.0;
            s[VX] = -s[VX];
        }
        let uavs = vec![UavStep::default(); 6];
        let active = [true; 6];
        let mut m = RunMetrics::new(&sc);
        m.on_step(&sc, &frame(0, &states, &uavs, &active));
        let r = m.finish(0, 0.1);
        assert_eq!(r.connectivity_min, 0.5);
        assert!(r.order_mean.abs() < 1e-12, "{}", r.order_mean);
        // The same formation together and aligned: connected, ordered.
        let mut m = RunMetrics::new(&sc);
        m.on_step(&sc, &frame(0, &in_slots(&sc), &uavs, &active));
        let r = m.finish(0, 0.1);
        assert_eq!((r.connectivity_min, r.order_min), (1.0, 1.0));
    }

    #[test]
    fn a_pair_inside_the_safety_distance_fails_a_run_whose_errors_are_within_their_bounds() {
        use proxform_scenario::load::parse_spec;
        // The paper's six with allowable errors of 100 m: UAV5 40 m from UAV4 (the safety
        // distance is 50 m) is 60 m off its slot, within its errors.
        let spec = parse_spec(proxform_scenario::builtin::PAPER, "paper.toml").expect("parses").with(|s| {
            for v in [&mut s.allowable.x_m, &mut s.allowable.y_m, &mut s.allowable.z_m] {
                *v = Some(100.0);
            }
        });
        let sc = Scenario::try_from(spec).expect("valid");
        let good = in_slots(&sc);
        let mut near = good.clone();
        near[4][Y] = near[3][Y] - 40.0;
        let active = [true; 6];
        let mut held: Vec<UavStep> = (0..6).map(|_| step(proxform_core::Outcome::Held, 0.0)).collect();
        held[0].outcome = None;
        let judge = |states: &[State9]| {
            let mut m = RunMetrics::new(&sc);
            m.on_step(&sc, &frame(0, &good, &held, &active));
            m.on_step(&sc, &frame(1, states, &held, &active));
            m.finish(0, 0.2)
        };
        let r = judge(&near);
        assert!(r.max_abs_error[1] < 100.0 && r.close_pairs == 1, "{:?} {}", r.max_abs_error, r.close_pairs);
        assert!(!r.pass, "a pair 40 m apart with a 50 m safety distance");
        // As far off its slot but far from the others passes: UAV5 60 m above its slot.
        let mut apart = good.clone();
        apart[4][Z] += 60.0;
        let r = judge(&apart);
        assert_eq!(r.close_pairs, 0);
        assert!(r.pass, "{:?}", r.max_abs_error);
    }

    #[test]
    fn errors_fractions_effort_and_close_pairs_are_what_the_frames_say() {
        let sc = paper();
        let good = in_slots(&sc);
        let mut off = good.clone();
        off[2][Y] += 0.9; // UAV3 0.9 m off its slot: beyond the allowable 0.6 m
                          // UAV5 30 m from UAV4 (closer than the 50 m safety distance): it is 173 m behind UAV1
                          // and 100 m right of UAV4 in the layout.
        off[4][Y] = off[3][Y] - 30.0;
        let active = [true; 6];
        // Step 1: all held, no effort. Step 2: UAVs 2-6 adjusted with effort 0.5, UAV3 off,
        // and UAV4 within 30 m of UAV5 (closer than the 50 m safety distance).
        let mut held: Vec<UavStep> = (0..6).map(|_| step(proxform_core::Outcome::Held, 0.0)).collect();
        held[0].outcome = None;
        let mut adjusted: Vec<UavStep> =
            (0..6).map(|_| step(proxform_core::Outcome::Adjusted { normalised_sq: 1.0 }, 0.5)).collect();
        adjusted[0].outcome = None;
        for u in &mut adjusted[1..] {
            u.model_error = [0.03; 9];
        }
        let mut m = RunMetrics::new(&sc);
        // One more frame with every follower removed is not judged.
        let gone = [true, false, false, false, false, false];
        m.on_step(&sc, &frame(0, &good, &held, &gone));
        m.on_step(&sc, &frame(1, &good, &held, &active));
        m.on_step(&sc, &frame(2, &off, &adjusted, &active));
        let r = m.finish(0, 0.2);
        assert!(!r.pass);
        assert!((r.max_abs_error[1] - 70.0).abs() < 1e-9, "{:?}", r.max_abs_error);
        assert_eq!(r.max_abs_error[0], 0.0);
        // 10 follower steps: 5 held, 5 adjusted, 8 within the allowable errors (UAVs 3 and 5
        // off at the second step).
        assert_eq!(r.held_fraction, 0.5);
        assert_eq!(r.within_allowable_fraction, 0.8);
        assert_eq!(r.judged_steps, 10);
        assert_eq!(r.adjustments, 5);
        assert!((r.control_effort - 0.25).abs() < 1e-9, "{}", r.control_effort);
        assert_eq!(r.close_pairs, 1, "UAVs 4 and 5 are one pair");
        assert!((r.min_separation_m - 30.0).abs() < 1e-9, "{}", r.min_separation_m);
        // Radio: 2 messages sent a step over 3 steps, by 1 + 6 + 6 flying UAV-steps of 0.1 s;
        // each flying UAV used 1 a step.
        assert!((r.radio_sent_per_uav_s - 6.0 / 1.3).abs() < 1e-9, "{}", r.radio_sent_per_uav_s);
        assert!((r.radio_used_per_uav_s - 10.0).abs() < 1e-9, "{}", r.radio_used_per_uav_s);
        // σm: RMS over the held and adjusted steps of the model error (zero when held).
        assert!((r.model_error_rms[0] - 0.03 / 2f64.sqrt()).abs() < 1e-6, "{:?}", r.model_error_rms);
        // RMS y error over 3 steps × 5 followers: 0.9 once, 70 once (UAV5 moved 70 m right of
        // its slot).
        assert!((r.rms_error[1] - ((0.81f64 + 4900.0) / 15.0).sqrt()).abs() < 1e-6, "{:?}", r.rms_error);
    }
}
