//! Observers see every step of a run; metrics and recorders are observers.
//!
//! The engine calls [`Observer::on_step`] once with the initial states (k = 0, no decisions)
//! and once after every step with the new states and the decisions that produced them.

use proxform_core::state::{self, State9};
use proxform_core::Formation;
use proxform_core::Outcome;

use proxform_scenario::Scenario;

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
    /// Per UAV: flying (false once removed, or before it joins).
    pub active: &'a [bool],
    /// Radio messages sent in the step that led here (one per broadcasting UAV).
    pub radio_sent: usize,
    /// The formation flown, indexed by UAV, when slots were re-assigned in flight (None: the
    /// scenario's formation in force, [`Scenario::formation_at`]).
    pub formation: Option<&'a Formation>,
    /// Slots were re-assigned in the step that led here.
    pub reassigned: bool,
    /// The navigator's successor, once it leads (METHOD §8; None: the navigator leads), and
    /// where it carries the navigator's slot: the planned path's position moved by the
    /// successor's own distance from its target.
    pub successor: Option<(usize, [f64; 3])>,
}

impl<'a> StepFrame<'a> {
    /// A frame of the scenario's own formation (no re-assignment).
    pub fn new(k: u64, t: f64, states: &'a [State9], uavs: &'a [UavStep], active: &'a [bool]) -> Self {
        Self { k, t, states, uavs, active, radio_sent: 0, formation: None, reassigned: false, successor: None }
    }

    /// The formation the UAVs fly now, indexed by UAV.
    pub fn formation<'x>(&'x self, scenario: &'x Scenario) -> &'x Formation {
        self.formation.unwrap_or_else(|| scenario.formation_at(self.t))
    }

    /// The errors' reference now: the navigator's state, or the formation's estimate of its
    /// slot ([`navigator_reference`]).
    pub fn navigator_reference(&self, scenario: &Scenario) -> State9 {
        navigator_reference(scenario, self.formation(scenario), self.states, self.active, self.successor.map(|s| s.1))
    }
}

/// What one UAV's update produced, besides its next state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UavStep {
    /// The controller's outcome at t_{k−1} (None for the navigator and at k = 0).
    pub outcome: Option<StepOutcome>,
    /// Effect on the state of the actuation error of the last step (true minus commanded):
    /// the model error σm of eq. 17. Kept in f32: it only feeds an RMS statistic.
    pub model_error: [f32; 9],
    /// Radio messages it used in the step: they reached it (in range, not lost) from UAVs it
    /// did not perceive onboard.
    pub radio_used: u16,
    /// Size of its input: the root sum of squares of each input over its per-step limit.
    pub effort: f32,
    /// Neighbours its robust fusion left out in the step.
    pub isolated: u16,
    /// It flew on its own prediction, its own measurement failing the own-sensor check.
    pub own_suspect: bool,
    /// Its agent (outside the engine) was gone: it flew on without one, holding its course (a
    /// multirotor hovering once its autopilot's failsafe took over).
    pub uncontrolled: bool,
}

/// What a UAV's controller did in a step: its [`Outcome`] without the envelope distance (one
/// byte, so that a step's records of a large swarm stay small).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepOutcome {
    /// Kept its course inside the envelope.
    Held,
    /// Left the envelope and adjusted.
    Adjusted,
    /// Perceived nothing.
    Alone,
}

impl From<Outcome> for StepOutcome {
    fn from(o: Outcome) -> Self {
        match o {
            Outcome::Held => StepOutcome::Held,
            Outcome::Adjusted { .. } => StepOutcome::Adjusted,
            Outcome::Alone => StepOutcome::Alone,
        }
    }
}

impl StepOutcome {
    /// Its name in trajectories ("held", "adjusted", "alone"), as [`Outcome::label`].
    pub fn label(self) -> &'static str {
        match self {
            StepOutcome::Held => "held",
            StepOutcome::Adjusted => "adjusted",
            StepOutcome::Alone => "alone",
        }
    }
}

/// Something that watches a run.
pub trait Observer {
    /// Called for the initial state and after every step.
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>);

    /// Whether the run should go on; asked before every step. A run stopped early (a user's
    /// interrupt) is incomplete: its metrics describe the steps flown only.
    fn keep_going(&self) -> bool {
        true
    }
}

/// Watches nothing.
impl Observer for () {
    fn on_step(&mut self, _: &Scenario, _: &StepFrame<'_>) {}
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        (**self).on_step(scenario, frame);
    }

    fn keep_going(&self) -> bool {
        (**self).keep_going()
    }
}

impl<A: Observer, B: Observer> Observer for (A, B) {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        self.0.on_step(scenario, frame);
        self.1.on_step(scenario, frame);
    }

    fn keep_going(&self) -> bool {
        self.0.keep_going() && self.1.keep_going()
    }
}

/// Formation errors of UAV `i` in formation `f` (the one in force, indexed by UAV:
/// [`StepFrame::formation`]) relative to the reference `nav_state` (METHOD §7):
/// `e_i = X_i − (X_nav + W_i,nav)`, as x, y, z (m) and α, β, γ (rad, wrapped; a component that
/// is not a number is +∞). W is the one
/// the controllers use: for a formation that turns as a rigid body (the controller's
/// `turn_feedforward`) in a course frame (the fixed wing) the slot's heading and bank in the
/// turn are part of it, so a wing UAV flying along its own velocity in a coordinated turn is not
/// counted as a yaw error. The turn rate is the vehicle's from the reference's state alone
/// ([`proxform_core::VehicleModel::turn_rate`]: the fixed wing's from its bank; a heading's rate,
/// zero here, enters only W's velocity part, which the errors do not use).
#[inline]
pub fn formation_error_to(
    scenario: &Scenario,
    f: &Formation,
    states: &[State9],
    nav_state: &State9,
    i: usize,
) -> [f64; 6] {
    let nav = scenario.navigator().index();
    let mut slot = *nav_state;
    let turn = scenario
        .controller()
        .turn_feedforward
        .then(|| scenario.vehicle().turn_rate(nav_state, nav_state, scenario.dt_s()));
    f.add_w_with(turn, &f.slots[i], &f.slots[nav], nav_state, &mut slot);
    let e = proxform_core::state::difference(&states[i], &slot);
    // An error that is not a number (a state gone non-finite) is as large as errors get: it
    // fails the run, however the statistics over it take their maxima.
    [e[0], e[1], e[2], e[6], e[7], e[8]].map(|v| if v.is_nan() { f64::INFINITY } else { v })
}

/// The navigator's state, or, once it is gone, the formation's estimate of its slot: the mean
/// over flying followers of `X_i − W_i,nav` in formation `f` (indexed by UAV; attitudes
/// averaged as small differences from the first follower's). In a frame that turns (course,
/// heading) a follower's own course or heading is not the frame's in a turn (a slot off the
/// navigator flies faster or slower, and its course leans by its rate over the radius): the
/// frame's yaw and the navigator's horizontal position are then fitted to the followers'
/// positions as one rigid body (least squares over the slots' offsets), and the estimate
/// takes that yaw as its course or heading.
pub fn navigator_reference(
    scenario: &Scenario,
    f: &Formation,
    states: &[State9],
    active: &[bool],
    carried: Option<[f64; 3]>,
) -> State9 {
    let nav = scenario.navigator().index();
    let mut estimate = fitted(scenario, f, states, active);
    // Once a successor leads, the navigator's slot is where the leader carries it (the path,
    // moved by the leader's own distance from its target): the followers still making for
    // their slots (a change, a re-assignment, a joiner) do not move it.
    if let Some(p) = carried.filter(|_| !active[nav]) {
        for k in 0..3 {
            estimate[state::X + k] = p[k];
        }
    }
    estimate
}

/// [`navigator_reference`] without a leader: the fit to every flying follower.
fn fitted(scenario: &Scenario, f: &Formation, states: &[State9], active: &[bool]) -> State9 {
    let nav = scenario.navigator().index();
    if active[nav] {
        return states[nav];
    }
    let mut sum = State9::zeros();
    let mut base: Option<State9> = None;
    let mut n = 0.0;
    let flying = || states.iter().enumerate().filter(|(i, _)| *i != nav && active[*i]);
    for (i, s) in flying() {
        let w = f.w(&f.slots[i], &f.slots[nav], s);
        let implied = s - w;
        let b = *base.get_or_insert(implied);
        sum += proxform_core::state::difference(&implied, &b);
        n += 1.0;
    }
    let Some(b) = base else { return states[nav] };
    let mut estimate = b + sum / n;
    if f.frame == proxform_core::FormationFrame::World {
        return estimate;
    }
    // The rigid fit: the centroids of the positions and of the offsets, then the yaw that
    // best turns the centred offsets onto the centred positions.
    let offset = |i: usize| f.slots[i].offset_m - f.slots[nav].offset_m;
    let (mut x, mut d) = ([0.0; 2], [0.0; 2]);
    for (i, s) in flying() {
        let o = offset(i);
        x = [x[0] + s[state::X] / n, x[1] + s[state::Y] / n];
        d = [d[0] + o.x / n, d[1] + o.y / n];
    }
    let (mut dot, mut cross) = (0.0, 0.0);
    for (i, s) in flying() {
        let o = offset(i);
        let (dx, dy) = (o.x - d[0], o.y - d[1]);
        let (px, py) = (s[state::X] - x[0], s[state::Y] - x[1]);
        dot += dx * px + dy * py;
        cross += dx * py - dy * px;
    }
    let spread = dot.hypot(cross);
    if spread.is_nan() || spread <= 1e-6 {
        // One follower, or all in one place: no yaw to fit.
        return estimate;
    }
    let (c, s) = (dot / spread, cross / spread);
    estimate[state::X] = x[0] - (c * d[0] - s * d[1]);
    estimate[state::Y] = x[1] - (s * d[0] + c * d[1]);
    let yaw = s.atan2(c);
    match f.frame {
        proxform_core::FormationFrame::Course => {
            let h = estimate[state::VX].hypot(estimate[state::VY]);
            estimate[state::VX] = h * c;
            estimate[state::VY] = h * s;
            // The nose: the course and the followers' mean crab (heading less course).
            let mut crab = 0.0;
            for (i, st) in flying() {
                let course = st[state::VY].atan2(st[state::VX]);
                crab += proxform_core::angle::wrap_pi(st[state::BETA] - f.slots[i].attitude_offset_rad.y - course) / n;
            }
            estimate[state::BETA] = proxform_core::angle::wrap_pi(yaw + crab + f.slots[nav].attitude_offset_rad.y);
        }
        _ => estimate[state::BETA] = yaw,
    }
    estimate
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_core::state::{BETA, VX, VY, X, Y, Z};
    use proxform_scenario::builtin::paper;

    #[test]
    fn in_a_turn_a_lost_navigator_is_fitted_to_the_followers_as_one_rigid_body() {
        // The paper's six in a course frame, turning left at ω about the navigator, each
        // follower exactly at its slot with its rigid-body velocity v + ω × r (its own course
        // and nose lean by ω·r/v): the fit puts the navigator where it is, on its course and
        // its nose; taking each follower's own course for its frame misses it by metres.
        let mut f = (**paper().formation()).clone();
        f.frame = proxform_core::FormationFrame::Course;
        let (v, omega, psi) = (70.0, 0.05, 0.3_f64);
        let mut nav = State9::zeros();
        (nav[X], nav[Y], nav[Z]) = (100.0, -40.0, 300.0);
        (nav[VX], nav[VY], nav[BETA]) = (v * psi.cos(), v * psi.sin(), psi);
        let states: Vec<State9> = (0..6)
            .map(|i| {
                let mut s = nav + f.w(&f.slots[i], &f.slots[0], &nav);
                let (rx, ry) = (s[X] - nav[X], s[Y] - nav[Y]);
                s[VX] -= omega * ry;
                s[VY] += omega * rx;
                // A coordinated turn in calm air: the nose along its own course.
                s[BETA] = s[VY].atan2(s[VX]);
                s
            })
            .collect();
        let mut active = [true; 6];
        active[0] = false;
        let sc = paper();
        let r = navigator_reference(&sc, &f, &states, &active, None);
        for k in [X, Y, Z] {
            assert!((r[k] - nav[k]).abs() < 1e-6, "axis {k}: {} vs {}", r[k], nav[k]);
        }
        assert!((r[VY].atan2(r[VX]) - psi).abs() < 1e-9);
        assert!((r[BETA] - psi).abs() < 1e-9, "{}", r[BETA]);
        // Each follower's own course: the mean misses by more than a metre.
        let naive: f64 = (1..6)
            .map(|i| {
                let s = &states[i];
                let implied = s - f.w(&f.slots[i], &f.slots[0], s);
                (implied[Y] - nav[Y]) / 5.0
            })
            .sum();
        assert!(naive.abs() > 1.0, "{naive}");
    }

    #[test]
    fn the_error_is_the_offset_from_the_slot_and_a_lost_navigator_is_estimated_from_the_slots() {
        let sc = paper();
        let mut nav = State9::zeros();
        nav[VX] = 70.0;
        nav[Z] = 300.0;
        let mut states: Vec<State9> = (0..6).map(|i| sc.slot_state(i, &nav)).collect();
        states[4][X] += 1.0;
        states[4][Y] -= 2.0;
        states[4][BETA] += 0.01;
        let e = formation_error_to(&sc, sc.formation(), &states, &nav, 4);
        for (k, want) in [1.0, -2.0, 0.0, 0.0, 0.01, 0.0].into_iter().enumerate() {
            assert!((e[k] - want).abs() < 1e-9, "component {k}: {} vs {want}", e[k]);
        }
        assert_eq!(formation_error_to(&sc, sc.formation(), &states, &nav, 2), [0.0; 6]);
        // Without the navigator, the reference is the mean of the followers' implied
        // navigator states: UAV5's offset moves it by a fifth.
        let mut active = [true; 6];
        assert_eq!(navigator_reference(&sc, sc.formation(), &states, &active, None), nav);
        active[0] = false;
        let r = navigator_reference(&sc, sc.formation(), &states, &active, None);
        assert!((r[X] - 0.2).abs() < 1e-9 && (r[Y] + 0.4).abs() < 1e-9 && (r[Z] - 300.0).abs() < 1e-9, "{r:?}");
    }

    #[test]
    fn an_error_that_is_not_a_number_is_infinite_and_fails() {
        let sc = paper();
        let nav = State9::zeros();
        let mut states: Vec<State9> = (0..6).map(|i| sc.slot_state(i, &nav)).collect();
        states[3][Y] = f64::NAN;
        states[3][BETA] = f64::INFINITY;
        let e = formation_error_to(&sc, sc.formation(), &states, &nav, 3);
        assert_eq!((e[1], e[4]), (f64::INFINITY, f64::INFINITY));
        assert_eq!(e[0], 0.0);
        // A NaN navigator makes every follower's error infinite.
        let lost = State9::from_element(f64::NAN);
        assert!(formation_error_to(&sc, sc.formation(), &states, &lost, 2).iter().all(|v| *v == f64::INFINITY));
    }
}
