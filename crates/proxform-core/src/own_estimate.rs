//! A UAV's estimate of its own state: the own-sensor check (`own_gate_m`) and the own-state
//! filter (`own_filter_gain`), with what they remember from one period to the next.
//!
//! After each decision the UAV predicts where its vehicle's model puts it one period on
//! ([`OwnEstimate::expect`]); at the next period a reading of its own state too far from that
//! prediction, or from where its velocity readings say it went, or one repeated bit for bit
//! while it moves (stale), is refused and the UAV flies on the prediction (the gate widens
//! while it does); an accepted reading is blended with the prediction by the filter's gain.
//! [`crate::Agent`] runs it, and so does any engine that steps the method per UAV.

use crate::controller::{ControllerParams, ControllerSetup};
use crate::state::{self, Input, State9};

/// How long the own-sensor check's settled position takes to follow the position readings
/// (s). A reading frozen in place (a stuck sensor) falls behind it by about the UAV's speed
/// times this, so at 1.5 m/s and above by more than a 3 m gate; noise and a position-fix bias
/// wandering over tens of seconds move it by far less.
pub const OWN_SETTLE_S: f64 = 2.0;

/// What the UAV expects of its own state, and for how long it has flown on that alone.
#[derive(Debug, Clone, Copy)]
struct OwnPrediction {
    /// The model applied to the last estimate and the input chosen.
    next: State9,
    /// Where the position readings have settled (m): moved each period by the velocity
    /// readings (trapezoid rule) and pulled toward an accepted position reading over
    /// [`OWN_SETTLE_S`] (set to it when it is the first accepted after refusals); moved as
    /// the prediction moves while readings are refused. Each reading
    /// is checked against it as against `next`, so that its position must also agree with
    /// where its velocity says the UAV went, not only with the last reading: readings frozen in
    /// place agree with the last one (the prediction is made from it) while the UAV flies on.
    settled: [f64; 3],
    /// The velocity of the estimate the UAV decided on last period (m/s).
    velocity: [f64; 3],
    /// How far the prediction moved the UAV from that estimate (m).
    moved: [f64; 3],
    /// The last reading (a reading repeated bit for bit while the UAV moves is stale).
    last: State9,
    /// Time since a measurement of its own state was last accepted (s).
    unaccepted_s: f64,
    /// The instant `next` is for (s): the last step's time plus one period.
    for_s: f64,
}

/// What a UAV remembers of its own state between periods (nothing while neither the check nor
/// the filter is on, and before its first decision: boxed, so that UAVs without them stay
/// small).
#[derive(Debug, Clone, Default)]
pub struct OwnEstimate {
    /// The own state this UAV expects at the next step: the model applied to its estimate and
    /// the input it chose.
    prediction: Option<Box<OwnPrediction>>,
}

impl OwnEstimate {
    /// Whether `params` use it: an own-sensor check, or a filter gain below 1.
    pub fn used(params: &ControllerParams) -> bool {
        params.own_filter_gain < 1.0 || params.own_gate_m.is_some()
    }

    /// The state to decide on at `now_s` from the reading `measured` of the UAV's own state,
    /// and whether the reading was refused (the UAV flies on its prediction).
    pub fn estimate(&mut self, params: &ControllerParams, now_s: f64, measured: &State9) -> (State9, bool) {
        let (gain, gate, dt) = (params.own_filter_gain, params.own_gate_m, params.dt_s);
        let growth = params.own_gate_growth_mps;
        let mut suspect = false;
        // A prediction made for another instant (an agent on its own clock that skipped
        // periods: stopped, or without updates) says nothing of this one: the measurement is
        // taken as it is and the prediction starts again from it.
        if self.prediction.as_ref().is_some_and(|p| (p.for_s - now_s).abs() > 0.5 * dt) {
            self.prediction = None;
        }
        let own = match self.prediction.as_deref_mut() {
            Some(pred) => {
                let at = state::position(measured);
                let innovation = (at - state::position(&pred.next)).norm();
                // No sensor with noise repeats a reading to the bit, nor a noise-free one of a
                // UAV that moves: a repeated reading is stale.
                let moving = pred.velocity.iter().map(|v| v * v).sum::<f64>().sqrt() * dt > 1e-6;
                let stale = moving && measured == &pred.last;
                pred.last = *measured;
                let settled: [f64; 3] =
                    std::array::from_fn(|k| pred.settled[k] + 0.5 * dt * (pred.velocity[k] + measured[state::VX + k]));
                let unsettled = (at - nalgebra::Vector3::from(settled)).norm();
                let bound = |g: f64| g + growth * pred.unaccepted_s;
                let refused = |d: f64| d.is_nan() || gate.is_some_and(|g| d > bound(g));
                if gate.is_some() && (stale || refused(innovation) || refused(unsettled)) {
                    // The measurement disagrees with where the UAV knows it flew: fly on that.
                    suspect = true;
                    pred.unaccepted_s += dt;
                    for k in 0..3 {
                        pred.settled[k] += pred.moved[k];
                    }
                    // Dead reckoning goes on with the reading's velocity unless the reading is
                    // frozen: a fix refused for its position (an offset, or a good one the
                    // prediction lost while the wind moved the UAV) still tells how it moves,
                    // so the prediction stops drifting from the UAV and the widening gate
                    // takes the readings again.
                    let mut own = pred.next;
                    if !stale {
                        for k in 0..3 {
                            own[state::VX + k] = measured[state::VX + k];
                        }
                    }
                    own
                } else {
                    // Accepted again after refusals (within the widened gate, a lasting
                    // offset included): the readings settle where they are now.
                    let pull = if pred.unaccepted_s > 0.0 { 1.0 } else { (dt / OWN_SETTLE_S).min(1.0) };
                    pred.unaccepted_s = 0.0;
                    for k in 0..3 {
                        pred.settled[k] = settled[k] + pull * (at[k] - settled[k]);
                    }
                    if gain < 1.0 {
                        // Position and velocity are filtered; attitude, measured far more finely
                        // than its tolerances, is taken as measured (filtering it would only
                        // add lag).
                        let mut own = pred.next + gain * state::difference(measured, &pred.next);
                        for k in state::ALPHA..=state::GAMMA {
                            own[k] = measured[k];
                        }
                        own
                    } else {
                        *measured
                    }
                }
            }
            None => *measured,
        };
        (own, suspect)
    }

    /// After deciding at `now_s` on `own` (from the reading `measured`): where the vehicle's
    /// model puts the UAV one period on under `input` (what the vehicle flies), for the next
    /// period's check.
    pub fn expect(&mut self, setup: &ControllerSetup, now_s: f64, (own, measured): (&State9, &State9), input: &Input) {
        let dt = setup.params().dt_s;
        let next = setup.vehicle().predict(own, input, dt);
        let velocity = [own[state::VX], own[state::VX + 1], own[state::VX + 2]];
        let moved = std::array::from_fn(|k| next[state::X + k] - own[state::X + k]);
        match &mut self.prediction {
            Some(p) => (p.next, p.velocity, p.moved, p.for_s) = (next, velocity, moved, now_s + dt),
            None => {
                let settled = [own[state::X], own[state::X + 1], own[state::X + 2]];
                let last = *measured;
                let p = OwnPrediction { next, settled, velocity, moved, last, unaccepted_s: 0.0, for_s: now_s + dt };
                self.prediction = Some(Box::new(p));
            }
        }
    }

    /// Forgets the prediction (after inputs that were not applied, such as a warm-up's).
    pub fn forget(&mut self) {
        self.prediction = None;
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.prediction.as_ref().map_or(0, |_| std::mem::size_of::<OwnPrediction>())
    }
}
