//! The leader's check of its own sensor before it broadcasts: what it says of itself is what
//! it believes, as a follower decides on what it believes.
//!
//! The leader (the navigator, or its successor once it leads) flies its plan by its
//! autopilot, so nothing it decides rests on its own measurement; but the followers take its
//! broadcast as it comes (the robust fusion weighs every other neighbour down when it
//! strays, never the leader), and those out of sensing range hear nothing else of it. So
//! with the own-sensor check or filter on (`own_gate_m`, `own_filter_gain`), the leader runs
//! the followers' [`OwnEstimate`] on its own readings and broadcasts the result: a stuck
//! sensor or a position jump is refused there as in a follower, instead of dragging every UAV
//! that leans on it.
//!
//! Its prediction is how its autopilot moved it since the last step, from where it started
//! (its plan's start, or where it was when it took the lead): it does not drift as a
//! follower's dead reckoning does, so its gate never widens, and a jump beyond the gate is
//! refused however long it lasts (one within it, as for a follower, is not seen). Both engines compose the leader's message through it.

use proxform_core::controller::ControllerParams;
use proxform_core::own_estimate::OwnEstimate;
use proxform_core::state::{self, State9};

/// The leader's own estimate, and its last step.
#[derive(Debug, Clone, Default)]
pub struct NavigatorCheck {
    own: OwnEstimate,
    /// The last step checked: the leader then, the time (s), the state broadcast, the reading,
    /// the true state.
    last: Option<(u32, f64, State9, State9, State9)>,
}

impl NavigatorCheck {
    /// What leader `leader` broadcasts at `t` of its reading `measured`, its true state being
    /// `truth`: the reading itself while `params` use neither the check nor the filter.
    pub fn checked(
        &mut self,
        params: &ControllerParams,
        (leader, t): (u32, f64),
        (truth, measured): (&State9, &State9),
    ) -> State9 {
        if !OwnEstimate::used(params) {
            return *measured;
        }
        // Its prediction does not drift: the gate need not widen.
        let params = ControllerParams { own_gate_growth_mps: 0.0, ..*params };
        let dt = params.dt_s;
        let expected = match self.last {
            Some((l, t0, own0, measured0, truth0)) if l == leader => {
                // It knows how it moved since: its autopilot flew it (a step skipped makes the
                // estimate start again from the reading: `OwnEstimate::estimate`).
                let next = own0 + state::difference(truth, &truth0);
                self.own.expect_state((t0, dt), (&own0, &measured0), next);
                next
            }
            _ => {
                // A new leader (or the flight's first step): it starts where it knows it is,
                // come from where its velocity says it was a period ago.
                self.own = OwnEstimate::default();
                let mut before = *truth;
                for k in 0..3 {
                    before[state::X + k] -= dt * truth[state::VX + k];
                }
                self.own.expect_state((t - dt, dt), (&before, &before), *truth);
                *truth
            }
        };
        let (own, refused) = self.own.estimate(&params, t, measured);
        // A refused reading tells it nothing, not even its velocity: a follower dead-reckons
        // with that velocity because its prediction drifts; the leader's does not, and a
        // reading stuck before it took the lead would carry a frozen velocity on in every
        // broadcast.
        let own = if refused { expected } else { own };
        self.last = Some((leader, t, own, *measured, *truth));
        own
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leader flying straight at 70 m/s: its true state at `t`.
    fn truth(t: f64) -> State9 {
        let mut s = State9::zeros();
        s[state::X] = 70.0 * t;
        s[state::VX] = 70.0;
        s
    }

    /// What `check` broadcasts of leader 0 over steps `steps`, its reading `reading(t)`.
    fn said(
        check: &mut NavigatorCheck,
        params: &ControllerParams,
        steps: std::ops::Range<usize>,
        reading: impl Fn(f64) -> State9,
    ) -> Vec<State9> {
        let dt = params.dt_s;
        steps.map(|k| k as f64 * dt).map(|t| check.checked(params, (0, t), (&truth(t), &reading(t)))).collect()
    }

    fn noisy(t: f64) -> State9 {
        let mut s = truth(t);
        s[state::Y] = 0.01 * ((t * 10.0).round() % 3.0);
        s
    }

    #[test]
    fn a_stuck_reading_is_not_broadcast_and_a_clean_one_is_as_read() {
        let params = ControllerParams { own_gate_m: Some(3.0), ..ControllerParams::default() };
        let mut check = NavigatorCheck::default();
        let clean = said(&mut check, &params, 0..20, noisy);
        assert!(clean.iter().enumerate().all(|(k, s)| *s == noisy(k as f64 * 0.1)), "taken as read");
        // The sensor sticks at 2 s: the leader broadcasts where it knows it flew.
        let frozen = truth(2.0);
        for (k, s) in (20..70).zip(said(&mut check, &params, 20..70, |_| frozen)) {
            let t = k as f64 * 0.1;
            assert!((s[state::X] - 70.0 * t).abs() < 0.1, "step {k}: {} vs {}", s[state::X], 70.0 * t);
        }
        // Without the check or the filter, the reading goes out as it is.
        let mut plain = NavigatorCheck::default();
        assert!(said(&mut plain, &ControllerParams::default(), 0..5, |_| frozen).iter().all(|s| *s == frozen));
    }

    #[test]
    fn a_jump_from_the_first_step_or_lasting_long_is_refused_and_a_new_leader_is_checked_afresh() {
        let params = ControllerParams { own_gate_m: Some(3.0), ..ControllerParams::default() };
        let jumped = |t: f64| {
            let mut s = noisy(t);
            s[state::Y] += 10.0;
            s
        };
        // From the flight's first step, for 60 s: never broadcast.
        let mut check = NavigatorCheck::default();
        let out = said(&mut check, &params, 0..600, jumped);
        assert!(out.iter().all(|s| s[state::Y].abs() < 0.1), "a jump got through");
        // Back to clean readings: taken at once.
        let back = said(&mut check, &params, 600..610, noisy);
        assert!(back.iter().zip(600..).all(|(s, k)| *s == noisy(k as f64 * 0.1)));
        // Another leader from 61 s, its reading off from its first step: refused as well.
        let t = 61.0;
        let s = check.checked(&params, (1, t), (&truth(t), &jumped(t)));
        assert!(s[state::Y].abs() < 0.1, "{}", s[state::Y]);
        // A leader whose sensor stuck before it took the lead, in a turn: its broadcasts
        // follow how it flies, not the frozen reading's position nor its velocity.
        let turning = |t: f64| {
            let mut s = truth(t);
            s[state::VY] = 2.0 * t;
            s[state::Y] = t * t;
            s
        };
        let frozen = turning(59.0);
        let mut check = NavigatorCheck::default();
        for k in 0..50 {
            let t = 60.0 + k as f64 * 0.1;
            let s = check.checked(&params, (2, t), (&turning(t), &frozen));
            let e = turning(t);
            assert!((s[state::VY] - e[state::VY]).abs() < 1e-6, "step {k}: {} vs {}", s[state::VY], e[state::VY]);
            assert!((s[state::Y] - e[state::Y]).abs() < 1e-6, "step {k}");
        }
    }
}
