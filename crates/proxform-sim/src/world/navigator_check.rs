//! The navigator's check of its own sensor before it broadcasts: what it says of itself is
//! what it believes, as a follower decides on what it believes.
//!
//! The navigator flies its plan, so nothing it decides rests on its own measurement; but the
//! followers take its broadcast as it comes (the robust fusion weighs every other neighbour
//! down when it strays, never the navigator), and those out of sensing range hear nothing
//! else of it. So with the own-sensor check or filter on (`own_gate_m`, `own_filter_gain`), the
//! navigator runs the followers' [`OwnEstimate`] on its own readings, predicting each from the
//! last by how its autopilot moved it, and broadcasts the result: a stuck sensor or a
//! position jump is refused there as in a follower, instead of dragging every UAV that leans
//! on it. Both engines compose the navigator's message through it.

use proxform_core::controller::ControllerParams;
use proxform_core::own_estimate::OwnEstimate;
use proxform_core::state::{self, State9};

/// The navigator's own estimate, and its last step.
#[derive(Debug, Clone, Default)]
pub struct NavigatorCheck {
    own: OwnEstimate,
    /// The last step checked: its time (s), the state broadcast, the reading, the true state.
    last: Option<(f64, State9, State9, State9)>,
}

impl NavigatorCheck {
    /// What the navigator broadcasts at `t` of its reading `measured`, its true state being
    /// `truth`: the reading itself while `params` use neither the check nor the filter.
    pub fn checked(&mut self, params: &ControllerParams, t: f64, (truth, measured): (&State9, &State9)) -> State9 {
        if !OwnEstimate::used(params) {
            return *measured;
        }
        if let Some((t0, own0, measured0, truth0)) = self.last {
            // It knows how it moved since: its autopilot flew it (a step skipped makes the
            // estimate start again from the reading: `OwnEstimate::estimate`).
            let next = own0 + state::difference(truth, &truth0);
            self.own.expect_state((t0, params.dt_s), (&own0, &measured0), next);
        }
        let (own, _) = self.own.estimate(params, t, measured);
        self.last = Some((t, own, *measured, *truth));
        own
    }

    /// Forgets what it remembers (after a warm-up, whose readings are not the flight's).
    pub fn forget(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The navigator flying straight at 70 m/s: its true state at `t`.
    fn truth(t: f64) -> State9 {
        let mut s = State9::zeros();
        s[state::X] = 70.0 * t;
        s[state::VX] = 70.0;
        s
    }

    #[test]
    fn a_stuck_reading_is_not_broadcast_and_a_clean_one_is_as_read() {
        let params = ControllerParams { own_gate_m: Some(3.0), ..ControllerParams::default() };
        let mut check = NavigatorCheck::default();
        let dt = params.dt_s;
        for k in 0..20 {
            let t = k as f64 * dt;
            let mut reading = truth(t);
            reading[state::Y] = 0.01 * (k % 3) as f64;
            assert_eq!(check.checked(&params, t, (&truth(t), &reading)), reading, "step {k}");
        }
        // The sensor sticks at 2 s: the navigator broadcasts where it knows it flew.
        let frozen = truth(2.0);
        for k in 20..70 {
            let t = k as f64 * dt;
            let said = check.checked(&params, t, (&truth(t), &frozen));
            assert!((said[state::X] - 70.0 * t).abs() < 0.1, "step {k}: {} vs {}", said[state::X], 70.0 * t);
        }
        // Without the check or the filter, the reading goes out as it is.
        let off = ControllerParams::default();
        let mut plain = NavigatorCheck::default();
        for k in 0..5 {
            let t = k as f64 * dt;
            assert_eq!(plain.checked(&off, t, (&truth(t), &frozen)), frozen);
        }
    }
}
