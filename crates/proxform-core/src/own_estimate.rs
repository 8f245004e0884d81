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

/// How fast the own-sensor gate widens while readings are refused but still tell how the UAV
/// moves (m/s): the UAV dead-reckons with their velocity, and that drifts from the truth only
/// by what the vehicle model misses of an acceleration within a period and by the velocity
/// noise (about 0.1 m/s on the paper's path: 0.5 m over 5 s). Only an episode in which the
/// readings froze (no velocity to dead-reckon with) widens at `own_gate_growth_mps`: then the
/// wind moves the UAV off its prediction. So a position jump of a few metres is refused until
/// the gate has widened to its size ((5 − 3) m / 0.25 m/s = 8 s for a 5 m jump past a 3 m gate),
/// where the wind's rate let it in after 2 s and the UAV flew off by its size.
pub const OWN_DRIFT_MPS: f64 = 0.25;

/// A jump of the position readings from the prediction that the widened gate let in: a
/// reading back where the UAV would be without it (within the gate) is taken at once, so that
/// the end of a lasting offset costs no second refusal. (The readings taken since follow the
/// UAV, so where it would be without the jump is known as well as where it is: no drift
/// widens that test.)
#[derive(Debug, Clone, Copy)]
struct LetIn {
    jump: [f64; 3],
}

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
    /// How far the gate has widened since then (m): at [`OWN_DRIFT_MPS`] while the refused
    /// readings moved, at `own_gate_growth_mps` once one of them was frozen (stale).
    widened_m: f64,
    /// Whether a reading refused since the last accepted one was frozen: the UAV dead-reckoned
    /// without velocity readings, so the wind may have moved it off its prediction.
    blind: bool,
    /// The last jump the widened gate let in (until another is let in, or a reading returns
    /// from it).
    let_in: Option<LetIn>,
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
                let bound = |g: f64| g + pred.widened_m;
                let refused = |d: f64| d.is_nan() || gate.is_some_and(|g| d > bound(g));
                // A reading back from the jump let in last: where the UAV would be without it.
                let next_at = state::position(&pred.next);
                let far = refused(innovation) || refused(unsettled);
                let returns = far
                    && pred.let_in.zip(gate).is_some_and(|(l, g)| {
                        let without = next_at - nalgebra::Vector3::from(l.jump);
                        (at - without).norm() <= g
                    });
                if gate.is_some() && (stale || (far && !returns)) {
                    // The measurement disagrees with where the UAV knows it flew: fly on that.
                    suspect = true;
                    pred.unaccepted_s += dt;
                    pred.blind |= stale;
                    pred.widened_m += dt * if pred.blind { growth } else { OWN_DRIFT_MPS.min(growth) };
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
                    // offset included) or back from the jump let in last: the readings settle
                    // where they are now.
                    let again = pred.unaccepted_s > 0.0;
                    let pull = if again || returns { 1.0 } else { (dt / OWN_SETTLE_S).min(1.0) };
                    pred.let_in = match (returns, again) {
                        (true, _) => None,
                        (false, true) => Some(LetIn { jump: (at - next_at).into() }),
                        (false, false) => pred.let_in,
                    };
                    (pred.unaccepted_s, pred.widened_m, pred.blind) = (0.0, 0.0, false);
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
        self.expect_state((now_s, dt), (own, measured), next);
    }

    /// After `own` at `now_s` (from the reading `measured`): the state `next` the UAV expects
    /// one period `dt` on, however it knows it (a UAV whose autopilot flies it along its plan
    /// knows how it moved).
    pub fn expect_state(&mut self, (now_s, dt): (f64, f64), (own, measured): (&State9, &State9), next: State9) {
        let velocity = [own[state::VX], own[state::VX + 1], own[state::VX + 2]];
        let moved = std::array::from_fn(|k| next[state::X + k] - own[state::X + k]);
        match &mut self.prediction {
            Some(p) => (p.next, p.velocity, p.moved, p.for_s) = (next, velocity, moved, now_s + dt),
            None => {
                let settled = [own[state::X], own[state::X + 1], own[state::X + 2]];
                let last = *measured;
                let p = OwnPrediction {
                    next,
                    settled,
                    velocity,
                    moved,
                    last,
                    unaccepted_s: 0.0,
                    widened_m: 0.0,
                    blind: false,
                    let_in: None,
                    for_s: now_s + dt,
                };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::{KinematicModel, VehicleModel};

    const DT: f64 = 0.1;

    /// A UAV flying straight at 20 m/s: its true state at step `k`.
    fn truth(k: usize) -> State9 {
        let mut s = State9::zeros();
        s[state::X] = 20.0 * DT * k as f64;
        s[state::VX] = 20.0;
        s
    }

    /// `s` with its position `dy` metres to the side.
    fn aside(mut s: State9, dy: f64) -> State9 {
        s[state::X + 1] += dy;
        s
    }

    /// Whether each of 400 steps' readings `reading(k)` was refused (gate 3 m, widening 1 m/s
    /// once a reading froze).
    fn refusals(reading: impl Fn(usize) -> State9) -> Vec<bool> {
        let params = ControllerParams {
            own_gate_m: Some(3.0),
            own_gate_growth_mps: 1.0,
            dt_s: DT,
            ..ControllerParams::default()
        };
        let setup = ControllerSetup::new(params, VehicleModel::Kinematic(KinematicModel::default())).expect("valid");
        let mut own = OwnEstimate::default();
        (0..400)
            .map(|k| {
                let t = k as f64 * DT;
                let measured = reading(k);
                let (estimate, suspect) = own.estimate(setup.params(), t, &measured);
                own.expect(&setup, t, (&estimate, &measured), &Input::zeros());
                suspect
            })
            .collect()
    }

    /// How long the readings were refused from step 10 on before one was taken (s).
    fn refused_from_10(r: &[bool]) -> f64 {
        r[10..].iter().take_while(|&&x| x).count() as f64 * DT
    }

    #[test]
    fn the_gate_widens_at_the_wind_rate_only_once_a_reading_froze() {
        // Readings that move, 5 m to the side from step 10 on (a position jump): the UAV
        // dead-reckons with their velocity, so the gate widens by the dead reckoning's drift,
        // 2 m in (5 − 3) / OWN_DRIFT_MPS.
        let moving = refused_from_10(&refusals(|k| if k < 10 { truth(k) } else { aside(truth(k), 5.0) }));
        assert!((moving - 2.0 / OWN_DRIFT_MPS).abs() <= 0.2, "{moving}");
        // The reading of step 10 the last one repeated (frozen), then the jump: without
        // velocity readings the wind may have moved the UAV off its prediction, so the gate
        // widens at `own_gate_growth_mps` (1 m/s) to the episode's end: the jump is taken after
        // 2 s.
        let frozen = refused_from_10(&refusals(|k| match k {
            0..10 => truth(k),
            10 => truth(9),
            _ => aside(truth(k), 5.0),
        }));
        assert!((frozen - 2.0).abs() <= 0.2, "{frozen}");
    }

    #[test]
    fn the_end_of_a_jump_the_gate_let_in_is_taken_at_once() {
        // 5 m to the side from step 10 to step 350 (34 s): let in after 8 s; the readings back
        // where the UAV is, 26 s later, are taken at once (without the jump's memory they were
        // refused for another 8 s).
        let r = refusals(|k| if (10..350).contains(&k) { aside(truth(k), 5.0) } else { truth(k) });
        let let_in = 10 + r[10..].iter().take_while(|&&x| x).count();
        assert!(let_in < 350, "never let in");
        assert!(r[let_in..].iter().all(|&x| !x), "refused again at step {:?}", r[let_in..].iter().position(|&x| x));
    }
}
