//! The stepping engine: fixed Δt, double-buffered state, seeded noise streams.
//!
//! Every UAV observes snapshot k before any UAV writes k + 1. Each follower gets a noisy
//! estimate of its own state and noisy observations of the UAVs within its sensing range,
//! runs its controller, and its plant applies the input with the actuation error. The
//! navigator flies its scripted path. All randomness comes from [`crate::rng`] streams keyed
//! by (seed, run, UAV, source) and the step number.

use proxform_core::state::{self, Input, State9};
use proxform_core::{Decision, Observation, ObservationSource, Outcome, ProximityController, UavId};
use rand::RngExt;
use rand_distr::StandardNormal;

use crate::observer::{Observer, StepFrame};
use crate::rng::{stream_key, Source, StepRng};
use crate::scenario::{Scenario, ScenarioError};

/// Random stream keys of one UAV.
#[derive(Debug, Clone, Copy)]
struct Keys {
    own: u64,
    sensing: u64,
    actuation: u64,
}

/// One simulated flight.
#[derive(Debug)]
pub struct Simulation<'s> {
    scenario: &'s Scenario,
    k: u64,
    current: Vec<State9>,
    next: Vec<State9>,
    controllers: Vec<Option<ProximityController>>,
    decisions: Vec<Option<Decision>>,
    model_error: Vec<State9>,
    keys: Vec<Keys>,
    observations: Vec<Observation>,
    sigma: State9,
    start: [f64; 3],
}

impl<'s> Simulation<'s> {
    /// A flight of `scenario` for run `run` of seed `seed`.
    pub fn new(scenario: &'s Scenario, seed: u64, run: u64) -> Result<Self, ScenarioError> {
        scenario.validate()?;
        let n = scenario.len();
        let nav = scenario.navigator.index();
        let mut controllers = Vec::with_capacity(n);
        for i in 0..n {
            controllers.push(if i == nav {
                None
            } else {
                Some(ProximityController::new(
                    UavId(i as u32),
                    scenario.controller.clone(),
                    scenario.formation.clone(),
                    scenario.dependencies[i].clone(),
                    scenario.vehicle.clone(),
                )?)
            });
        }
        let keys = (0..n as u64)
            .map(|i| Keys {
                own: stream_key(seed, run, i, Source::OwnState),
                sensing: stream_key(seed, run, i, Source::Sensing),
                actuation: stream_key(seed, run, i, Source::Actuation),
            })
            .collect();
        let s0 = scenario.initial[nav];
        Ok(Self {
            scenario,
            k: 0,
            current: scenario.initial.clone(),
            next: scenario.initial.clone(),
            controllers,
            decisions: vec![None; n],
            model_error: vec![State9::zeros(); n],
            keys,
            observations: Vec::with_capacity(n),
            sigma: scenario.noise.sigma(),
            start: [s0[state::X], s0[state::Y], s0[state::Z]],
        })
    }

    /// Current step index.
    pub fn k(&self) -> u64 {
        self.k
    }

    /// Current time (s).
    pub fn t(&self) -> f64 {
        self.k as f64 * self.scenario.dt_s
    }

    /// Current true states.
    pub fn states(&self) -> &[State9] {
        &self.current
    }

    fn frame(&self) -> StepFrame<'_> {
        StepFrame {
            k: self.k,
            t: self.t(),
            states: &self.current,
            decisions: &self.decisions,
            model_error: &self.model_error,
        }
    }

    /// Advances one update period.
    pub fn step(&mut self) {
        let sc = self.scenario;
        let dt = sc.dt_s;
        let t = self.t();
        let nav = sc.navigator.index();
        let range2 = sc.controller.areas.sensing_range_m.powi(2);
        for i in 0..self.current.len() {
            let Some(ctrl) = self.controllers[i].as_mut() else {
                self.next[i] = sc.path.state_at(t + dt, self.start);
                debug_assert_eq!(i, nav);
                continue;
            };
            let me = self.current[i];
            let keys = self.keys[i];
            // Own state estimate.
            let mut rng = StepRng::new(keys.own, self.k);
            let own = noisy(&me, &self.sigma, &mut rng);
            // Onboard observations of every UAV within sensing range, from snapshot k.
            let mut rng = StepRng::new(keys.sensing, self.k);
            self.observations.clear();
            for (j, other) in self.current.iter().enumerate() {
                if j == i {
                    continue;
                }
                let d2 = (other[0] - me[0]).powi(2) + (other[1] - me[1]).powi(2) + (other[2] - me[2]).powi(2);
                if d2 > range2 {
                    continue;
                }
                self.observations.push(Observation {
                    id: UavId(j as u32),
                    state: noisy(other, &self.sigma, &mut rng),
                    age_s: 0.0,
                    source: ObservationSource::Onboard,
                });
            }
            let decision = ctrl.step(t, &own, &self.observations);
            let commanded = if sc.adjustment_enabled { decision.input } else { Input::zeros() };
            let applied = if matches!(decision.outcome, Outcome::Adjusted { .. }) && sc.actuation_error > 0.0 {
                let mut rng = StepRng::new(keys.actuation, self.k);
                commanded.map(|u| u * (1.0 + sc.actuation_error * rng.random_range(-1.0..=1.0)))
            } else {
                commanded
            };
            self.next[i] = sc.vehicle.propagate(&me, &applied, dt);
            self.model_error[i] = self.next[i] - sc.vehicle.propagate(&me, &commanded, dt);
            self.decisions[i] = Some(decision);
        }
        std::mem::swap(&mut self.current, &mut self.next);
        self.k += 1;
    }

    /// Runs the whole flight, showing every step (and the initial state) to `observer`.
    pub fn run(mut self, observer: &mut impl Observer) {
        observer.on_step(self.scenario, &self.frame());
        let steps = self.scenario.steps();
        while self.k < steps {
            self.step();
            observer.on_step(self.scenario, &self.frame());
        }
    }
}

#[inline]
fn noisy(x: &State9, sigma: &State9, rng: &mut StepRng) -> State9 {
    let mut s = *x;
    for k in 0..9 {
        if sigma[k] > 0.0 {
            let n: f64 = rng.sample(StandardNormal);
            s[k] += sigma[k] * n;
        }
    }
    s
}
