//! Observers see every step of a run; metrics and recorders are observers.
//!
//! The engine calls [`Observer::on_step`] once with the initial states (k = 0, no decisions)
//! and once after every step with the new states and the decisions that produced them.

use proxform_core::state::State9;
use proxform_core::Decision;

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
    /// Decisions taken at t_{k−1} (None for the navigator and at k = 0).
    pub decisions: &'a [Option<Decision>],
    /// Per UAV: effect on the state of the actuation error of the last step (true minus
    /// commanded), the model error σm of eq. 17.
    pub model_error: &'a [State9],
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
