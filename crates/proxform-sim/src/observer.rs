//! Observers see every step of a run; metrics and recorders are observers.
//!
//! The engine calls [`Observer::on_step`] once with the initial states (k = 0, no decisions)
//! and once after every step with the new states and the decisions that produced them.

use proxform_core::state::State9;
use proxform_core::Outcome;

use crate::scenario::Scenario;

/// One step as the engine hands it to observers.
#[derive(Debug, Clone, Copy)]
pub struct StepFrame<'a> {
    /// Step index k (0 = initial state).
    pub k: u64,
    /// Time t_k (s).
    pub t: f64,
    /// True states at t_k, indexed by UAV.
    pub states: &'a [State9],
    /// Per UAV: what its last update produced.
    pub uavs: &'a [UavStep],
}

/// What one UAV's update produced, besides its next state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UavStep {
    /// The controller's outcome at t_{k−1} (None for the navigator and at k = 0).
    pub outcome: Option<Outcome>,
    /// Effect on the state of the actuation error of the last step (true minus commanded):
    /// the model error σm of eq. 17. Kept in f32: it only feeds an RMS statistic.
    pub model_error: [f32; 9],
    /// Distance to its nearest neighbour within the sensing range at t_k (m; ∞ if none).
    pub nearest_m: f64,
}

impl Default for UavStep {
    fn default() -> Self {
        Self { outcome: None, model_error: [0.0; 9], nearest_m: f64::INFINITY }
    }
}

/// Something that watches a run.
pub trait Observer {
    /// Called for the initial state and after every step.
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>);
}

impl<A: Observer, B: Observer> Observer for (A, B) {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        self.0.on_step(scenario, frame);
        self.1.on_step(scenario, frame);
    }
}

/// Formation errors of UAV `i` relative to the navigator (METHOD §7):
/// `e_i = X_i − (X_nav + W_i,nav)`, as x, y, z (m) and α, β, γ (rad, wrapped).
#[inline]
pub fn formation_error(scenario: &Scenario, states: &[State9], i: usize) -> [f64; 6] {
    let nav = scenario.navigator.index();
    let f = &scenario.formation;
    let w = f.w(&f.slots[i], &f.slots[nav], &states[nav]);
    let e = proxform_core::state::difference(&states[i], &(states[nav] + w));
    [e[0], e[1], e[2], e[6], e[7], e[8]]
}
