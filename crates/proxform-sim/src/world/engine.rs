//! The stepping engine: fixed Δt, double-buffered state, named phases, seeded noise streams.
//!
//! One step reads snapshot k and writes k + 1, in phases:
//! 1. **schedule**: the faults in force (removals, joins, sensor faults, radio blackouts);
//! 2. **index**: the neighbour grid over the active UAVs' positions;
//! 3. **environment**: each UAV's wind, position-fix bias and radio channel over the step;
//! 4. **radio**: the messages arriving now, drawn once for all receivers;
//! 5. per UAV, over blocks of [`super::phases::BLOCK`] UAVs ([`super::phases`]): **perceive** (onboard detections and radio
//!    messages), **estimate** (its noisy measurement of its own state), **decide** (its
//!    [`Agent::step`]), **actuate** (the actuation error), **propagate** (vehicle and wind);
//! 6. **measure**: the observers see the new snapshot.
//!
//! Each phase of a block runs over all of the block's UAVs before the next starts, so a
//! block's observations stay in one small buffer (bounded memory at any swarm size) and a
//! structure-of-arrays engine can replace the buffers without changing the phases. All
//! randomness comes from [`crate::random`] streams keyed by (seed, run, UAV, source) and the
//! step ([`StreamKey`]), so a UAV's update does not depend on which thread runs its block:
//! large swarms are stepped in parallel with identical results.

use proxform_core::grid::NeighbourGrid;
use proxform_core::state::{self, State9};
use proxform_core::vehicle::VehicleModel;
use proxform_core::{Agent, Decision};
use proxform_scenario::Scenario;

use super::airwaves::Airwaves;
use super::environment::{EnvStep, UavEnv};
use super::measurement::{self, OwnSensors};
use super::membership::Membership;
use super::navigator_check::NavigatorCheck;
use super::options::{NeighbourSearch, RunOptions};
use super::phases::{for_each_block, for_each_block_in_order, Mode, StepContext};
use super::reach::Reach;
use super::remote::{holding, Agents, Phase, Sensed, StepRequest};
use super::sensing::{noisy, ProximitySensor, Scene};
use crate::measure::observer::{Observer, StepFrame, UavStep};
use crate::random::{RunKey, Source, StreamKey};

/// Swarms at least this large are stepped in parallel within the run.
pub const PARALLEL_MIN_UAVS: usize = 1024;

/// Step counters of the warm-up draws, far from those of the flight.
const WARMUP_STEP_BASE: u64 = 1 << 62;

/// One simulated flight: the world, and the agents it steps.
pub struct Simulation<'s> {
    world: World<'s>,
    /// Every follower's agent (None for the navigator, which flies its path, and for every UAV
    /// when the agents run outside the engine).
    agents: Vec<Option<Agent>>,
    /// Agents outside the engine, if any, with the buffers of their requests.
    outside: Option<Outside<'s>>,
    /// The states being written this step.
    next: Vec<State9>,
    /// What each UAV's last update produced.
    uavs: Vec<UavStep>,
}

impl std::fmt::Debug for Simulation<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("world", &self.world)
            .field("agents", &self.agents.len())
            .field("outside", &self.outside.is_some())
            .finish()
    }
}

/// Agents outside the engine and what passes between them and the world each step.
struct Outside<'s> {
    agents: Box<dyn Agents + 's>,
    /// The flight's run of the batch.
    run: u64,
    sensed: Sensed,
    decisions: Vec<Decision>,
    /// The decisions by UAV index (None: navigator, inactive).
    by_uav: Vec<Option<Decision>>,
    /// Followers taken out of the flight because their agent is gone.
    absent: Vec<bool>,
    /// Of those, the ones whose autopilot is in its failsafe by now.
    failsafe: Vec<bool>,
    /// The navigator (an outside controller may fly it).
    navigator: usize,
}

/// Everything of a flight but the agents: read by every block while the agents step.
#[derive(Debug)]
struct World<'s> {
    scenario: &'s Scenario,
    options: RunOptions,
    run: RunKey,
    k: u64,
    current: Vec<State9>,
    grid: NeighbourGrid,
    /// Per-UAV environment (wind, position-fix bias, radio channel), empty when not needed.
    env: Vec<UavEnv>,
    /// The radio messages on their way and arriving this step (composed once for all
    /// receivers), and the arriving ones' index by sender position.
    air: Airwaves,
    reach: Reach,
    /// Who flies and who leads (faults, succession, re-assignment).
    members: Membership,
    sensor: ProximitySensor,
    start: [f64; 3],
    parallel: bool,
    /// What the navigator broadcasts of itself, checked ([`NavigatorCheck`]).
    navigator_check: NavigatorCheck,
}

impl<'s> Simulation<'s> {
    /// A flight of `scenario` for run `run` of seed `seed`.
    pub fn new(scenario: &'s Scenario, options: RunOptions, seed: u64, run: u64) -> Self {
        let nav = scenario.navigator().index();
        let agents =
            (0..scenario.len()).map(|i| (i != nav).then(|| scenario.agent(proxform_core::UavId(i as u32)))).collect();
        Self::build(scenario, options, (seed, run), agents, None).warmed()
    }

    /// A flight whose followers' agents run outside the engine ([`super::remote`]): each step
    /// the world asks `agents` for every active follower's decision, between its sensing and
    /// its actuation (the warm-up included). Stepped in order on one thread. With agents that
    /// step as the in-process ones, the flight is bit-identical to [`Self::new`]'s.
    pub fn with_agents(
        scenario: &'s Scenario,
        options: RunOptions,
        (seed, run): (u64, u64),
        agents: Box<dyn Agents + 's>,
    ) -> Self {
        let n = scenario.len();
        let outside = Outside {
            agents,
            run,
            sensed: Sensed::default(),
            decisions: Vec::new(),
            by_uav: vec![None; n],
            absent: vec![false; n],
            failsafe: vec![false; n],
            navigator: scenario.navigator().index(),
        };
        let none = (0..n).map(|_| None).collect();
        let mut sim = Self::build(scenario, options, (seed, run), none, Some(outside));
        sim.world.parallel = false;
        sim.warmed()
    }

    fn build(
        scenario: &'s Scenario,
        options: RunOptions,
        (seed, run): (u64, u64),
        agents: Vec<Option<Agent>>,
        outside: Option<Outside<'s>>,
    ) -> Self {
        let n = scenario.len();
        let nav = scenario.navigator().index();
        let s0 = scenario.initial()[nav];
        let starts = super::placement::initial_states(scenario, RunKey::new(seed, run));
        let world = World {
            scenario,
            options,
            run: RunKey::new(seed, run),
            k: 0,
            current: starts.clone(),
            env: super::environment::initial(scenario),
            grid: NeighbourGrid::new(),
            air: Airwaves::default(),
            reach: Reach::new(),
            members: Membership::new(scenario),
            sensor: ProximitySensor::of(scenario),
            start: [s0[state::X], s0[state::Y], s0[state::Z]],
            parallel: n >= PARALLEL_MIN_UAVS,
            navigator_check: NavigatorCheck::default(),
        };
        Self { world, agents, outside, next: starts, uavs: vec![UavStep::default(); n] }
    }

    fn warmed(mut self) -> Self {
        self.warm_up();
        self
    }

    /// The formation's flight before t = 0 (METHOD §9 Choice, see README): for
    /// `scenario.warmup_s()`, every follower perceives its neighbours in the ideal formation
    /// around the navigator's path and steps its agent, whose inputs are discarded, so that at
    /// t = 0 its neighbour tracks know their rates. The formation is then maintained from an
    /// established flight rather than from a standing start.
    fn warm_up(&mut self) {
        let sc = self.world.scenario;
        // A scattered formation has no established flight to watch: its agents start cold.
        let steps = if sc.placement().in_slots() { (sc.warmup_s() / sc.dt_s()).round() as u64 } else { 0 };
        if steps == 0 {
            return;
        }
        let nav = sc.navigator().index();
        let areas = sc.controller().areas.areas;
        let ideal = sc.radio().ideal();
        // The ideal states are written into `next`'s buffer (unused until the first step).
        std::mem::swap(&mut self.world.current, &mut self.next);
        for w in 0..steps {
            let t = -((steps - w) as f64) * sc.dt_s();
            let nav_state = sc.path().state_at(t, self.world.start);
            for (i, s) in self.world.current.iter_mut().enumerate() {
                *s = if i == nav { nav_state } else { sc.slot_state(i, &nav_state) };
            }
            self.world.index_positions();
            self.world.note_speeds();
            let key = self.world.run.at(WARMUP_STEP_BASE + w);
            self.world.send_radio((key, t), 0, false, &self.agents);
            let world = &self.world;
            let ctx = world.context(key, t, Mode::Warm(&ideal));
            let parallel = world.parallel;
            match &mut self.outside {
                Some(out) => {
                    out.sense(&ctx, (&mut self.agents, &mut self.next, &mut self.uavs), areas);
                    out.ask(w, t, Phase::Warm, &world.current, (sc.vehicle(), sc.dt_s()));
                }
                None => for_each_block(&mut self.agents, &mut self.next, &mut self.uavs, areas, parallel, |b, blk| {
                    ctx.warm(b, blk)
                }),
            }
        }
        std::mem::swap(&mut self.world.current, &mut self.next);
        // The flight's radio starts afresh: nothing of the warm-up is on the air.
        self.world.air.clear();
        for a in self.agents.iter_mut().flatten() {
            a.forget_own_estimate();
        }
    }

    /// Forces serial or parallel stepping within the run (results are identical).
    pub fn with_parallel(mut self, parallel: bool) -> Self {
        self.world.parallel = parallel;
        self
    }

    /// Current step index.
    pub fn k(&self) -> u64 {
        self.world.k
    }

    /// Current time (s).
    pub fn t(&self) -> f64 {
        self.world.t()
    }

    /// Current true states.
    pub fn states(&self) -> &[State9] {
        &self.world.current
    }

    /// Bytes held by the engine's per-UAV buffers, the grid and the agents (shared setup and
    /// scenario excluded).
    pub fn heap_bytes(&self) -> usize {
        let n = self.next.len();
        let agents: usize = self.agents.iter().flatten().map(|a| a.heap_bytes() + std::mem::size_of::<Agent>()).sum();
        n * (2 * std::mem::size_of::<State9>() + std::mem::size_of::<UavStep>())
            + self.world.grid.heap_bytes()
            + self.world.reach.heap_bytes()
            + agents
    }

    /// Bytes a flight of `sc` will hold (as [`Self::heap_bytes`]), estimated before it is
    /// built: every follower's agent as large as the first one's, the per-UAV buffers, and the
    /// neighbour grid (about 32 bytes a UAV).
    pub fn bytes_estimate(sc: &Scenario) -> usize {
        let n = sc.len();
        let nav = sc.navigator();
        let agent = (0..n as u32)
            .map(proxform_core::UavId)
            .find(|&u| u != nav)
            .map_or(0, |u| sc.agent(u).heap_bytes() + std::mem::size_of::<Agent>());
        n * (3 * std::mem::size_of::<State9>() + std::mem::size_of::<UavStep>() + 32) + n.saturating_sub(1) * agent
    }

    fn frame(&self) -> StepFrame<'_> {
        let w = &self.world;
        StepFrame {
            k: w.k,
            t: w.t(),
            states: &w.current,
            uavs: &self.uavs,
            active: &w.members.active,
            radio_sent: w.air.sent(),
            formation: w.members.reassigned_formation(),
            reassigned: w.members.reassigned_at(w.k),
            successor: w.carried().map(|p| (w.members.lead.leader.index(), p)),
        }
    }

    /// Advances one update period.
    pub fn step(&mut self) {
        self.world.apply_schedule();
        if let Some(out) = &mut self.outside {
            out.apply_membership(&self.world);
        }
        self.reassign_slots();
        let w = &mut self.world;
        if w.options.neighbour_search == NeighbourSearch::Grid {
            w.index_positions();
        }
        w.note_speeds();
        w.advance_environment();
        let delay = w.scenario.radio().delay_steps as usize;
        w.send_radio((w.run.at(w.k), w.t()), delay, true, &self.agents);
        let w = &self.world;
        let ctx = w.context(w.run.at(w.k), w.t(), Mode::Fly);
        let (areas, parallel) = (w.scenario.controller().areas.areas, w.parallel);
        match &mut self.outside {
            Some(out) => {
                let bufs = (&mut self.agents, &mut self.next, &mut self.uavs);
                out.sense(&ctx, bufs, areas);
                out.ask(w.k, w.t(), Phase::Fly, &w.current, (w.scenario.vehicle(), w.scenario.dt_s()));
                let by_uav = &out.by_uav;
                for_each_block_in_order(&mut self.agents, &mut self.next, &mut self.uavs, areas, |b, blk| {
                    ctx.apply(b, blk, by_uav)
                });
                for (u, gone) in self.uavs.iter_mut().zip(&out.absent) {
                    u.uncontrolled = *gone;
                }
            }
            None => {
                for_each_block(&mut self.agents, &mut self.next, &mut self.uavs, areas, parallel, |b, blk| {
                    ctx.fly(b, blk)
                });
            }
        }
        if let Some(out) = &self.outside {
            self.world.members.navigator_flown_outside |= out.by_uav[out.navigator].is_some();
        }
        std::mem::swap(&mut self.world.current, &mut self.next);
        self.world.k += 1;
    }

    /// Slot re-assignment (`formation.reassign_on_loss`) and the navigator's succession, when
    /// a loss becomes known, and at every change of formation after one. A lost leader's
    /// successor ([`assignment::successor`]) flies the navigator's path at its own slot from
    /// then on, and every table that named the navigator names it. With re-assignment, from
    /// the positions of the UAVs and of the slots now, every UAV still flying gets its slot by
    /// [`assignment::after_loss`]. The agents fly the result from this step on (so a later
    /// formation's vacated slot is at its own edge), those that join later too; the formation
    /// flown is kept relabelled for the measures.
    fn reassign_slots(&mut self) {
        // Agents outside the engine do not receive new slots (the command line refuses such a
        // scenario with them): nothing is re-assigned.
        if self.outside.is_some() {
            return;
        }
        let w = &mut self.world;
        let (sc, t) = (w.scenario, w.t());
        let leader = w.members.lead.leader;
        let Some(r) = w.members.reassign(sc, (t, w.k), (w.start, &w.current)) else { return };
        // A successor flies by its autopilot from now on.
        if r.lead.leader != leader {
            self.agents[r.lead.leader.index()] = None;
        }
        // Every agent, flying or not: one that joins later flies the tables in force then (the
        // membership's, as the fast engine's controllers read them).
        for (i, a) in self.agents.iter_mut().enumerate() {
            if let Some(a) = a {
                // The relabelled tables name UAVs of the formation, other than the owner.
                a.reassign(sc.agents(), proxform_core::UavId(i as u32), &r)
                    .expect("a relabelled formation is valid for every UAV");
            }
        }
    }

    /// Runs the whole flight, showing every step (and the initial state) to `observer`.
    pub fn run(self, observer: &mut impl Observer) {
        let steps = self.world.scenario.steps();
        self.run_steps(steps, observer);
    }

    /// Runs `steps` update periods (or fewer if the flight ends first), showing each to
    /// `observer` (the measure phase).
    pub fn run_steps(mut self, steps: u64, observer: &mut impl Observer) {
        let sc = self.world.scenario;
        if self.world.k == 0 {
            observer.on_step(sc, &self.frame());
        }
        let end = (self.world.k + steps).min(sc.steps());
        while self.world.k < end && observer.keep_going() {
            self.step();
            observer.on_step(sc, &self.frame());
        }
    }
}

/// What the sensor reports for the followers' collision avoidance (none for the baselines).
pub(crate) fn close_watch(sc: &Scenario) -> proxform_core::controller::CloseWatch {
    let p = sc.controller();
    match (sc.method(), p.avoid_m) {
        (proxform_core::Method::Proximity, Some(d)) => proxform_core::controller::CloseWatch::new(
            d,
            sc.agents().controller().braking_mps2(),
            p.dt_s,
            p.areas.sensing_range_m,
        ),
        _ => proxform_core::controller::CloseWatch::default(),
    }
}

/// The engine's per-UAV buffers, as the block phases take them.
type Buffers<'b> = (&'b mut Vec<Option<Agent>>, &'b mut Vec<State9>, &'b mut Vec<UavStep>);

impl Outside<'_> {
    /// Which flying followers' agents are gone: such a UAV flies on without one, holding its
    /// course, uncontrolled; it stays in the flight and is judged (and a run with one does not
    /// pass). When its agent is back it is controlled again from where it is.
    fn apply_membership(&mut self, w: &World<'_>) {
        let nav = w.scenario.navigator().index();
        for i in (0..w.scenario.len()).filter(|i| *i != nav) {
            self.absent[i] = w.members.active[i] && !self.agents.present(proxform_core::UavId(i as u32));
            self.failsafe[i] = self.absent[i] && self.agents.failsafe(proxform_core::UavId(i as u32));
        }
    }

    /// Perceive and estimate for every block, gathering what each active follower sensed.
    fn sense(&mut self, ctx: &StepContext<'_>, (agents, next, uavs): Buffers<'_>, areas: usize) {
        let sensed = &mut self.sensed;
        sensed.clear();
        for_each_block_in_order(agents, next, uavs, areas, |b, blk| ctx.sense(b, blk, sensed));
    }

    /// The agents' decisions on what was sensed, by UAV; `truth` is every UAV's true state and
    /// `(vehicle, dt)` what flies them.
    fn ask(&mut self, k: u64, t_s: f64, phase: Phase, truth: &[State9], (vehicle, dt): (&VehicleModel, f64)) {
        let request = StepRequest { run: self.run, k, t_s, phase, sensed: &self.sensed, truth };
        self.agents.decide(&request, &mut self.decisions);
        self.by_uav.iter_mut().for_each(|d| *d = None);
        for (j, u) in self.sensed.uavs.iter().enumerate() {
            // A decision with a non-finite number in it, or one no agent of this vehicle could
            // have made (far beyond what it can do in a period), is never applied: the UAV
            // holds. So does a UAV whose agent is gone, until its autopilot's failsafe takes
            // over: one flown by setpoints then hovers where it is (PX4's offboard loss), the
            // others hold their course.
            let i = u.index();
            let valid = |d: &Decision| d.is_finite() && vehicle.plausible(&truth[i], &d.input, d.setpoint.as_ref(), dt);
            let given = self.decisions.get(j).copied().filter(|_| !self.absent[i]);
            let d = given.filter(valid);
            // (In the warm-up the inputs are discarded anyway.)
            if given.is_some() && d.is_none() && phase == Phase::Fly {
                self.agents.refused(*u);
            }
            let failsafe = || Decision { setpoint: vehicle.failsafe_hold(&truth[i]), ..holding() };
            self.by_uav[i] = Some(match self.failsafe[i] {
                true => failsafe(),
                false => d.unwrap_or_else(holding),
            });
        }
        // An outside controller in charge of the navigator flies it (checked as a follower's
        // decision is; one that is not valid leaves it on its path).
        if phase == Phase::Fly {
            let nav = self.navigator;
            if let Some(d) = self.agents.navigator(t_s, &truth[nav]) {
                match d.is_finite() && vehicle.plausible(&truth[nav], &d.input, d.setpoint.as_ref(), dt) {
                    true => self.by_uav[nav] = Some(d),
                    false => self.agents.refused(proxform_core::UavId(nav as u32)),
                }
            }
        }
    }
}

impl<'s> World<'s> {
    fn t(&self) -> f64 {
        self.k as f64 * self.scenario.dt_s()
    }

    /// Where the successor, once it leads, carries the navigator's slot
    /// ([`Membership::carried`]).
    fn carried(&self) -> Option<[f64; 3]> {
        self.members.carried(self.scenario, self.t(), (self.start, &self.current))
    }

    /// Who leads, as the block phases fly it.
    fn leading(&self) -> super::phases::Leading<'_> {
        self.members.leading(self.scenario, self.t())
    }

    /// Phase 1, schedule: removals, joins, and the sensor and radio faults in force now
    /// ([`Membership::apply_schedule`]); a sensor that sticks freezes at the UAV's own
    /// measurement now.
    fn apply_schedule(&mut self) {
        let sc = self.scenario;
        let key = self.run.at(self.k);
        let sigma = sc.noise().sigma();
        let own = |current: &[State9], i: usize| noisy(&current[i], &sigma, &mut key.rng(i as u64, Source::OwnState));
        self.members.apply_schedule(sc, self.t(), (self.start, &mut self.current), own);
    }

    /// Phase 2, index: the neighbour grid over the active UAVs.
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    fn index_positions(&mut self) {
        let active = &self.members.active;
        let range = self.scenario.controller().areas.sensing_range_m;
        self.grid.rebuild_ids(
            self.current.iter().enumerate().filter(|(i, _)| active[*i]).map(|(i, s)| (i as u32, [s[0], s[1], s[2]])),
            range,
        );
    }

    /// With phase 2: how fast the active UAVs move relative to each other at most, for the
    /// sensor's close-range watch ([`proxform_core::controller::CloseWatch::for_speeds`]).
    fn note_speeds(&mut self) {
        let active = &self.members.active;
        let spread = proxform_core::controller::relative_speed_bound(
            self.current.iter().enumerate().filter(|(i, _)| active[*i]).map(|(_, s)| [s[3], s[4], s[5]]),
        );
        self.sensor.set_speeds(spread);
    }

    /// Phase 3, environment: every active UAV's wind, position-fix bias and radio channel over
    /// the step.
    fn advance_environment(&mut self) {
        if self.env.is_empty() {
            return;
        }
        let step = EnvStep::new(self.scenario, &self.run, self.k, self.t());
        let (current, active) = (&self.current, &self.members.active);
        crate::parallel::for_each_mut(&mut self.env, self.parallel, |i, e| {
            if active[i] {
                step.advance(i, &current[i], e);
            }
        });
    }

    /// Phase 4, radio: every broadcasting UAV sends its own measurement (in flight with its
    /// position-fix bias and sensor faults; the leader's checked, [`NavigatorCheck`]), and,
    /// with `relay_navigator`, every follower what
    /// its agent knows of the navigator at `t`; the messages sent `delay` steps ago arrive now
    /// (none before the first arrive).
    fn send_radio(&mut self, (key, t): (StreamKey, f64), delay: usize, flight: bool, agents: &[Option<Agent>]) {
        let sensors = OwnSensors {
            sigma: self.scenario.noise().sigma(),
            key,
            env: &self.env,
            faults: flight.then_some(&self.members.faults),
        };
        let mut now = self.air.buffer(delay);
        measurement::compose(self.scenario, &self.current, &sensors, (self.members.lead, self.parallel), &mut now);
        // (In the warm-up the navigator's readings are not checked: its sensors are ideal.)
        let check = flight.then_some(&mut self.navigator_check);
        measurement::check_navigator(self.scenario, (self.members.lead.leader, t, &self.current), check, &mut now);
        measurement::relays(
            self.scenario,
            &self.current,
            &self.members.active,
            (agents, self.members.lead.leader),
            t,
            &mut now,
        );
        self.air.send(now, delay);
        self.reach.rebuild(self.air.arriving().iter().map(|m| m.at), self.scenario.radio().range_m);
    }

    /// The read-only view of this step that the block phases share.
    fn context<'a>(&'a self, key: StreamKey, t: f64, mode: Mode<'a>) -> StepContext<'a> {
        StepContext {
            scenario: self.scenario,
            options: self.options,
            key,
            t,
            start: self.start,
            scene: Scene {
                states: &self.current,
                grid: &self.grid,
                search: self.options.neighbour_search,
                // The tables flown now (a change of formation's, re-assigned ones), as the
                // agents fly them.
                dependencies: self.members.tables(self.scenario, t),
            },
            sensor: &self.sensor,
            active: &self.members.active,
            faults: &self.members.faults,
            messages: self.air.arriving(),
            reach: &self.reach,
            env: &self.env,
            lead: self.leading(),
            mode,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::observer::StepOutcome;
    use proxform_scenario::builtin::paper_spec;
    use proxform_scenario::spec::{FaultSpec, SegmentSpec};

    /// The paper's formation on a straight, level path with no noise and no actuation error.
    fn straight(edit: impl FnOnce(&mut proxform_scenario::ScenarioSpec)) -> Scenario {
        let spec = paper_spec().with(|s| {
            s.duration_s = Some(5.0);
            s.path = proxform_scenario::spec::PathSpec {
                kind: Some("segments".into()),
                speed_kmh: Some(250.0),
                segment: vec![SegmentSpec { duration_s: Some(10.0), ..SegmentSpec::default() }],
                ..Default::default()
            };
            (s.noise.position_m, s.noise.velocity_kmh, s.noise.attitude_deg) = (Some(0.0), Some(0.0), Some(0.0));
            s.noise.actuation_error = Some(0.0);
            edit(s);
        });
        Scenario::try_from(spec).expect("valid")
    }

    #[test]
    fn an_exact_formation_on_a_straight_path_holds_and_the_navigator_flies_its_path() {
        let sc = straight(|_| {});
        let mut sim = Simulation::new(&sc, RunOptions::default(), 1, 0);
        for k in 1..=30u64 {
            sim.step();
            // The engine advances the navigator from t_(k−1) by Δt.
            let t = (k - 1) as f64 * sc.dt_s() + sc.dt_s();
            let nav = sc.path().state_at(t, [0.0; 3]);
            assert_eq!(sim.states()[0], nav, "the navigator flies its path exactly");
            for i in 1..6 {
                assert_eq!(sim.uavs[i].outcome, Some(StepOutcome::Held), "UAV {} at step {k}", i + 1);
                let e = sc.slot_state(i, &nav) - sim.states()[i];
                assert!(e.iter().all(|v| v.abs() < 1e-6), "UAV {} drifts: {e:?}", i + 1);
            }
        }
    }

    #[test]
    fn a_broadcast_carries_what_the_sender_believes() {
        // UAV1 is a beacon; its position fix glitches 20 m to the left from t = 0.
        let sc = straight(|s| {
            s.radio.beacons = Some(vec![1]);
            s.fault = vec![FaultSpec {
                kind: Some("glitch".into()),
                uav: Some(1),
                at_s: Some(0.0),
                duration_s: Some(1.0),
                offset_m: Some([0.0, 20.0, 0.0]),
            }];
        });
        let mut sim = Simulation::new(&sc, RunOptions::default(), 1, 0);
        sim.step();
        let w = &sim.world;
        assert_eq!(w.air.arriving().len(), 1);
        let m = &w.air.arriving()[0];
        assert_eq!(m.sender, 0);
        // The message says what UAV1 measured (20 m off), and the range is from where it was.
        let truth = sc.path().state_at(0.0, [0.0; 3]);
        assert!((m.state[1] - truth[1] - 20.0).abs() < 1e-9, "{} vs {}", m.state[1], truth[1]);
        assert_eq!(m.at, [truth[0], truth[1], truth[2]]);
        assert_eq!(sim.frame().radio_sent, 1);
    }

    #[test]
    fn a_uav_off_its_slot_adjusts_and_a_removed_uav_stays_where_it_vanished() {
        let sc = straight(|s| s.fault = vec![FaultSpec::remove(6, 0.0)]);
        let mut sim = Simulation::new(&sc, RunOptions::default(), 1, 0);
        sim.world.current[2][1] += 3.0; // UAV3 3 m left of its slot
        let gone = sim.states()[5];
        sim.step();
        assert_eq!(sim.uavs[2].outcome, Some(StepOutcome::Adjusted));
        assert_eq!(sim.uavs[0].outcome, None, "the navigator runs no controller");
        assert_eq!((sim.states()[5], sim.uavs[5].outcome), (gone, None));
        // With the adjustment switched off, the same UAV decides but does not move toward it.
        let mut off = Simulation::new(&sc, RunOptions { adjustment_enabled: false, ..RunOptions::default() }, 1, 0);
        off.world.current[2][1] += 3.0;
        off.step();
        sim.step();
        assert!(off.states()[2][1] > sim.states()[2][1], "{} vs {}", off.states()[2][1], sim.states()[2][1]);
    }
}
