//! Agents outside the engine: the world senses for them and applies what they decide.
//!
//! With [`super::engine::Simulation::with_agents`], the engine runs every world phase as usual
//! but splits the per-UAV phases around the decision: **perceive** and **estimate** for every
//! block, one [`Agents::decide`] call for all followers (a network transport sends each UAV
//! what it sensed and waits for its decision), then **actuate** and **propagate**. Every random
//! draw comes from the same keyed streams as in the fused path, so agents that step exactly as
//! the in-process ones give bit-identical flights.

use std::ops::Range;

use proxform_core::state::State9;
use proxform_core::{Decision, Input, Observation, Outcome, UavId};

/// Which part of the flight a request belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// The warm-up before t = 0: agents step, their inputs are discarded, and they forget their
    /// own-state estimate when the flight starts.
    Warm,
    /// The flight.
    Fly,
}

/// What every active follower sensed in one update period.
#[derive(Debug, Clone, Default)]
pub struct Sensed {
    /// The followers, in UAV order.
    pub uavs: Vec<UavId>,
    /// Each one's measurement of its own state.
    pub own: Vec<State9>,
    /// Each one's span of `heard`.
    pub spans: Vec<Range<usize>>,
    /// What they perceived onboard and heard by radio.
    pub heard: Vec<Observation>,
}

impl Sensed {
    pub(super) fn clear(&mut self) {
        self.uavs.clear();
        self.own.clear();
        self.spans.clear();
        self.heard.clear();
    }

    /// Number of followers.
    pub fn len(&self) -> usize {
        self.uavs.len()
    }

    /// True when no follower is active.
    pub fn is_empty(&self) -> bool {
        self.uavs.is_empty()
    }

    /// Follower `j`'s observations.
    pub fn heard_of(&self, j: usize) -> &[Observation] {
        &self.heard[self.spans[j].clone()]
    }
}

/// One update period's question to the agents.
#[derive(Debug, Clone, Copy)]
pub struct StepRequest<'a> {
    /// Run of the batch (each run's flight starts with fresh agents).
    pub run: u64,
    /// Flight step k (t = k Δt), or the warm-up step counted from its start.
    pub k: u64,
    /// Time of the update (s; negative in the warm-up).
    pub t_s: f64,
    /// Warm-up or flight.
    pub phase: Phase,
    /// What each active follower sensed.
    pub sensed: &'a Sensed,
    /// Every UAV's true state, by UAV: for the world's own simulated autopilots, which fly
    /// their targets from where their vehicle is (never sent to an agent).
    pub truth: &'a [State9],
}

/// The decision of an agent that did not answer in time: hold the course (no new input).
pub fn holding() -> Decision {
    Decision::without_areas(Outcome::Held, Input::zeros())
}

/// Followers whose agents run outside the engine.
pub trait Agents {
    /// One decision per entry of `request.sensed`, in its order, into `out` (cleared first);
    /// an agent that did not answer gets [`holding`].
    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>);

    /// Whether UAV `uav`'s agent is there (asked once per flight step for every follower the
    /// scenario has flying). A follower whose agent is gone leaves the flight as a removed UAV
    /// does; when its agent is back, it joins in its slot, as a scheduled join does.
    fn present(&mut self, uav: UavId) -> bool {
        let _ = uav;
        true
    }

    /// Whether the autopilot of UAV `uav`, whose agent is not there ([`Agents::present`] false),
    /// is in its failsafe by now: its own timeout since the last command it had has passed (PX4's
    /// offboard loss, 1 s by default). In its failsafe it flies what
    /// [`proxform_core::VehicleModel::failsafe_hold`] says (a multirotor hovers); before, it
    /// holds its course. By default at once.
    fn failsafe(&mut self, uav: UavId) -> bool {
        let _ = uav;
        true
    }

    /// Says that UAV `uav`'s decision this step was refused: a non-finite number in it, or far
    /// beyond what its vehicle can do in a period ([`proxform_core::VehicleModel::plausible`]).
    /// The UAV holds, as if its agent had not answered. For those that report on the agents
    /// (by default nothing is done).
    fn refused(&mut self, uav: UavId) {
        let _ = uav;
    }

    /// A decision that flies the navigator this flight step instead of its path (an outside
    /// controller in charge of it: a MAVLink offboard program), given its true state `truth`
    /// at time `t_s` (s); None (the default) while it flies its path.
    fn navigator(&mut self, t_s: f64, truth: &State9) -> Option<Decision> {
        let _ = (t_s, truth);
        None
    }

    /// The flight time (s) of the update that UAV `uav`'s decision applied this step was
    /// decided on, when its agent said (on the own clock a decision may act a period or more
    /// after its update); None (the default) when it is not known or none was applied. What
    /// the same decision sent another way (a MAVLink setpoint stamped with that instant) is
    /// matched by.
    fn decided_on(&mut self, uav: UavId) -> Option<f64> {
        let _ = uav;
        None
    }
}

impl<A: Agents + ?Sized> Agents for &mut A {
    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        (**self).decide(request, out);
    }

    fn present(&mut self, uav: UavId) -> bool {
        (**self).present(uav)
    }

    fn failsafe(&mut self, uav: UavId) -> bool {
        (**self).failsafe(uav)
    }

    fn refused(&mut self, uav: UavId) {
        (**self).refused(uav);
    }

    fn navigator(&mut self, t_s: f64, truth: &State9) -> Option<Decision> {
        (**self).navigator(t_s, truth)
    }

    fn decided_on(&mut self, uav: UavId) -> Option<f64> {
        (**self).decided_on(uav)
    }
}

/// The in-process agents behind the [`Agents`] interface: what a remote agent does with each
/// request (forget the own-state estimate when the flight starts, then step). Used to check
/// that the split path is the fused path.
#[derive(Debug)]
pub struct LocalAgents {
    agents: Vec<Option<proxform_core::Agent>>,
    flying: bool,
}

impl LocalAgents {
    /// Every follower's agent of `scenario`.
    pub fn new(scenario: &proxform_scenario::Scenario) -> Self {
        let nav = scenario.navigator();
        let agents = (0..scenario.len() as u32).map(|i| (UavId(i) != nav).then(|| scenario.agent(UavId(i)))).collect();
        Self { agents, flying: false }
    }
}

impl Agents for LocalAgents {
    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        out.clear();
        if request.phase == Phase::Fly && !self.flying {
            self.flying = true;
            for a in self.agents.iter_mut().flatten() {
                a.forget_own_estimate();
            }
        }
        let s = request.sensed;
        for j in 0..s.len() {
            let d = match self.agents.get_mut(s.uavs[j].index()).and_then(Option::as_mut) {
                Some(a) => a.step(request.t_s, &s.own[j], s.heard_of(j)),
                None => holding(),
            };
            out.push(d);
        }
    }
}
