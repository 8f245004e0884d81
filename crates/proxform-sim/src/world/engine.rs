//! The stepping engine: fixed Δt, double-buffered state, named phases, seeded noise streams.
//!
//! One step reads snapshot k and writes k + 1, in phases:
//! 1. **schedule**: the faults in force (removals, joins, sensor faults, radio blackouts);
//! 2. **index**: the neighbour grid over the active UAVs' positions;
//! 3. **environment**: each UAV's wind, position-fix bias and radio channel over the step;
//! 4. **radio**: the messages arriving now, drawn once for all receivers;
//! 5. per UAV, over blocks of [`BLOCK`] UAVs: **perceive** (onboard detections and radio
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

use std::collections::VecDeque;
use std::ops::Range;

use proxform_core::grid::NeighbourGrid;
use proxform_core::state::{self, Input, State9};
use proxform_core::{Agent, Decision, Observation, ObservationSource, Outcome};
use proxform_scenario::faults::{self as schedule, Fault};
use proxform_scenario::Scenario;
use rand::RngExt;
use rayon::prelude::*;

use super::environment::{EnvStep, UavEnv};
use super::faults::{self, FaultStep};
use super::options::{NeighbourSearch, RunOptions};
use super::sensing::{noisy, Link, PerceptionDraws, ProximitySensor, Scene, SensorScratch};
use crate::measure::observer::{Observer, StepFrame, UavStep};
use crate::random::{RunKey, Source, StreamKey};

/// Swarms at least this large are stepped in parallel within the run.
pub const PARALLEL_MIN_UAVS: usize = 1024;

/// UAVs per block of the per-UAV phases.
pub const BLOCK: usize = 64;

/// Step counters of the warm-up draws, far from those of the flight.
const WARMUP_STEP_BASE: u64 = 1 << 62;

/// One simulated flight: the world, and the agents it steps.
#[derive(Debug)]
pub struct Simulation<'s> {
    world: World<'s>,
    /// Every follower's agent (None for the navigator, which flies its path).
    agents: Vec<Option<Agent>>,
    /// The states being written this step.
    next: Vec<State9>,
    /// What each UAV's last update produced.
    uavs: Vec<UavStep>,
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
    /// The radio messages arriving this step (sender, state sent), computed once for all
    /// receivers.
    broadcasts: Vec<(u32, State9)>,
    /// True states of the last `delay + 1` steps, oldest first (radio with delay only).
    history: VecDeque<Vec<State9>>,
    active: Vec<bool>,
    faults: FaultStep,
    sensor: ProximitySensor,
    start: [f64; 3],
    parallel: bool,
}

impl<'s> Simulation<'s> {
    /// A flight of `scenario` for run `run` of seed `seed`.
    pub fn new(scenario: &'s Scenario, options: RunOptions, seed: u64, run: u64) -> Self {
        let n = scenario.len();
        let nav = scenario.navigator().index();
        let agents = (0..n).map(|i| (i != nav).then(|| scenario.agent(proxform_core::UavId(i as u32)))).collect();
        let s0 = scenario.initial()[nav];
        let areas = scenario.controller().areas;
        let world = World {
            scenario,
            options,
            run: RunKey::new(seed, run),
            k: 0,
            current: scenario.initial().to_vec(),
            env: super::environment::initial(scenario),
            grid: NeighbourGrid::new(),
            broadcasts: Vec::new(),
            history: VecDeque::new(),
            active: (0..n).map(|i| schedule::is_active(scenario.faults(), i, 0.0)).collect(),
            faults: FaultStep { radio_up: true, ..FaultStep::default() },
            sensor: ProximitySensor::new(areas.areas, areas.sensing_range_m, scenario.noise().sigma()),
            start: [s0[state::X], s0[state::Y], s0[state::Z]],
            parallel: n >= PARALLEL_MIN_UAVS,
        };
        Self { world, agents, next: scenario.initial().to_vec(), uavs: vec![UavStep::default(); n] }.warmed()
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
        let steps = (sc.warmup_s() / sc.dt_s()).round() as u64;
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
            let key = self.world.run.at(WARMUP_STEP_BASE + w);
            self.world.send_radio(Some((0, key)));
            let world = &self.world;
            let ctx = world.context(key, t, Some(&world.current), Mode::Warm(&ideal));
            let parallel = world.parallel;
            for_each_block(&mut self.agents, &mut self.next, &mut self.uavs, areas, parallel, |b, blk| {
                ctx.warm(b, blk)
            });
        }
        std::mem::swap(&mut self.world.current, &mut self.next);
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
        n * (2 * std::mem::size_of::<State9>() + std::mem::size_of::<UavStep>()) + self.world.grid.heap_bytes() + agents
    }

    fn frame(&self) -> StepFrame<'_> {
        let w = &self.world;
        StepFrame { k: w.k, t: w.t(), states: &w.current, uavs: &self.uavs, active: &w.active }
    }

    /// Advances one update period.
    pub fn step(&mut self) {
        let w = &mut self.world;
        w.apply_schedule();
        if w.options.neighbour_search == NeighbourSearch::Grid {
            w.index_positions();
        }
        w.advance_environment();
        let delay = u64::from(w.scenario.radio().delay_steps);
        w.remember_sent_states(delay);
        let sent_step = if delay == 0 || w.history.len() as u64 == delay + 1 { Some(w.k - delay) } else { None };
        w.send_radio(sent_step.map(|s| (delay, w.run.at(s))));
        let w = &self.world;
        let sent = match (delay, sent_step) {
            (_, None) => None,
            (0, Some(_)) => Some(&w.current[..]),
            (_, Some(_)) => w.history.front().map(|h| &h[..]),
        };
        let ctx = w.context(w.run.at(w.k), w.t(), sent, Mode::Fly);
        let (areas, parallel) = (w.scenario.controller().areas.areas, w.parallel);
        for_each_block(&mut self.agents, &mut self.next, &mut self.uavs, areas, parallel, |b, blk| ctx.fly(b, blk));
        std::mem::swap(&mut self.world.current, &mut self.next);
        self.world.k += 1;
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
            self.world.perceive_initial(&mut self.uavs);
            observer.on_step(sc, &self.frame());
        }
        let end = (self.world.k + steps).min(sc.steps());
        while self.world.k < end {
            self.step();
            observer.on_step(sc, &self.frame());
        }
    }
}

impl<'s> World<'s> {
    fn t(&self) -> f64 {
        self.k as f64 * self.scenario.dt_s()
    }

    /// Phase 1, schedule: removals, joins, and the sensor and radio faults in force now.
    fn apply_schedule(&mut self) {
        let sc = self.scenario;
        if sc.faults().is_empty() {
            return;
        }
        let t = self.t();
        for f in sc.faults() {
            match *f {
                Fault::Remove { uav, .. } => {
                    self.active[uav.index()] = schedule::is_active(sc.faults(), uav.index(), t)
                }
                Fault::Join { uav, offset_m, .. } => {
                    let i = uav.index();
                    let now = schedule::is_active(sc.faults(), i, t);
                    if now && !self.active[i] {
                        // Appears in its slot relative to the navigator (or to the formation's
                        // estimate of it), shifted by the offset.
                        let reference = crate::measure::observer::navigator_reference(sc, &self.current, &self.active);
                        let mut s = sc.slot_state(i, &reference);
                        s[0] += offset_m.x;
                        s[1] += offset_m.y;
                        s[2] += offset_m.z;
                        self.current[i] = s;
                    }
                    self.active[i] = now;
                }
                _ => {}
            }
        }
        let key = self.run.at(self.k);
        let sigma = sc.noise().sigma();
        let current = &self.current;
        self.faults = faults::gather(sc.faults(), t, &self.faults, |i| {
            noisy(&current[i], &sigma, &mut key.rng(i as u64, Source::OwnState))
        });
    }

    /// Phase 2, index: the neighbour grid over the active UAVs.
    fn index_positions(&mut self) {
        let active = &self.active;
        let range = self.scenario.controller().areas.sensing_range_m;
        self.grid.rebuild_ids(
            self.current.iter().enumerate().filter(|(i, _)| active[*i]).map(|(i, s)| (i as u32, [s[0], s[1], s[2]])),
            range,
        );
    }

    /// Phase 3, environment: every active UAV's wind, position-fix bias and radio channel over
    /// the step.
    fn advance_environment(&mut self) {
        if self.env.is_empty() {
            return;
        }
        let step = EnvStep::new(self.scenario, &self.run, self.k, self.t());
        let (current, active) = (&self.current, &self.active);
        let adv = |(i, e): (usize, &mut UavEnv)| {
            if active[i] {
                step.advance(i, &current[i], e);
            }
        };
        if self.parallel {
            self.env.par_iter_mut().enumerate().with_min_len(1024).for_each(adv);
        } else {
            self.env.iter_mut().enumerate().for_each(adv);
        }
    }

    /// Keeps the true states of the last `delay + 1` steps (a delayed radio sends from them).
    fn remember_sent_states(&mut self, delay: u64) {
        if delay == 0 {
            return;
        }
        let mut old =
            if self.history.len() as u64 > delay { self.history.pop_front() } else { None }.unwrap_or_default();
        old.clear();
        old.extend_from_slice(&self.current);
        self.history.push_back(old);
    }

    /// Phase 4, radio: the messages arriving now, sent `delay` steps ago at the step of `key`
    /// (none before the first arrives).
    fn send_radio(&mut self, sent: Option<(u64, StreamKey)>) {
        let Some((delay, key)) = sent else {
            self.broadcasts.clear();
            return;
        };
        let states = if delay == 0 { &self.current[..] } else { self.history.front().map_or(&[][..], |h| &h[..]) };
        super::sensing::broadcasts(self.scenario, states, key, self.parallel, &mut self.broadcasts);
    }

    /// The read-only view of this step that the block phases share.
    fn context<'a>(&'a self, key: StreamKey, t: f64, sent: Option<&'a [State9]>, mode: Mode<'a>) -> StepContext<'a> {
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
                dependencies: self.scenario.dependencies(),
            },
            sensor: &self.sensor,
            active: &self.active,
            faults: &self.faults,
            sent,
            broadcasts: &self.broadcasts,
            env: &self.env,
            mode,
        }
    }

    /// Nearest-neighbour distances of the initial state, for the separation metric.
    fn perceive_initial(&mut self, uavs: &mut [UavStep]) {
        let range = self.scenario.controller().areas.sensing_range_m;
        self.index_positions();
        for (i, s) in self.current.iter().enumerate() {
            if !self.active[i] {
                continue;
            }
            let mut best = (f64::INFINITY, u32::MAX);
            self.grid.for_each_within([s[0], s[1], s[2]], range, |j, _, d2| {
                if j as usize != i && d2 < best.0 {
                    best = (d2, j);
                }
            });
            uavs[i].nearest_m = best.0.sqrt();
            uavs[i].nearest_id = best.1;
        }
    }
}

/// Runs `f` on every block of [`BLOCK`] UAVs (its first index and its slices of the agents,
/// next states and per-UAV records), in parallel or in order; each block gets the scratch of
/// the thread that runs it.
fn for_each_block(
    agents: &mut [Option<Agent>],
    next: &mut [State9],
    uavs: &mut [UavStep],
    areas: usize,
    parallel: bool,
    f: impl Fn(usize, &mut Block<'_>) + Sync + Send,
) {
    if parallel {
        agents
            .par_chunks_mut(BLOCK)
            .zip(next.par_chunks_mut(BLOCK))
            .zip(uavs.par_chunks_mut(BLOCK))
            .enumerate()
            .for_each_init(
                || BlockScratch::new(areas),
                |scratch, (b, ((agents, next), uavs))| f(b * BLOCK, &mut Block { agents, next, uavs, scratch }),
            );
    } else {
        let mut scratch = BlockScratch::new(areas);
        let blocks = agents.chunks_mut(BLOCK).zip(next.chunks_mut(BLOCK)).zip(uavs.chunks_mut(BLOCK));
        for (b, ((agents, next), uavs)) in blocks.enumerate() {
            f(b * BLOCK, &mut Block { agents, next, uavs, scratch: &mut scratch });
        }
    }
}

/// Which pass of the per-UAV phases a step runs.
#[derive(Debug, Clone, Copy)]
enum Mode<'a> {
    /// The flight: every phase, with the scenario's radio and faults.
    Fly,
    /// The warm-up: perceive (over an ideal radio), estimate and decide; nothing applied.
    Warm(&'a proxform_scenario::radio::RadioModel),
}

/// One block's slices and the scratch of the thread that runs it.
struct Block<'b> {
    agents: &'b mut [Option<Agent>],
    next: &'b mut [State9],
    uavs: &'b mut [UavStep],
    scratch: &'b mut BlockScratch,
}

/// Per-thread working memory of the block phases, allocated once per thread and step.
#[derive(Debug, Clone)]
struct BlockScratch {
    sensor: SensorScratch,
    /// What every UAV of the block perceived, one span each.
    heard: Vec<Observation>,
    spans: Vec<Range<usize>>,
    /// Each UAV's measurement of its own state.
    own: Vec<State9>,
    /// Each follower's decision (None: navigator or inactive).
    decisions: Vec<Option<Decision>>,
    /// Each follower's input as applied (with the actuation error).
    applied: Vec<Input>,
}

impl BlockScratch {
    fn new(areas: usize) -> Self {
        Self {
            sensor: SensorScratch::new(areas),
            heard: Vec::with_capacity(BLOCK * (areas + 8)),
            spans: Vec::with_capacity(BLOCK),
            own: Vec::with_capacity(BLOCK),
            decisions: Vec::with_capacity(BLOCK),
            applied: Vec::with_capacity(BLOCK),
        }
    }
}

/// Read-only view of one step, shared by the threads that run the blocks.
struct StepContext<'a> {
    scenario: &'a Scenario,
    options: RunOptions,
    key: StreamKey,
    t: f64,
    start: [f64; 3],
    scene: Scene<'a>,
    sensor: &'a ProximitySensor,
    active: &'a [bool],
    faults: &'a FaultStep,
    /// True states when the radio messages arriving now were sent.
    sent: Option<&'a [State9]>,
    /// The radio messages arriving now.
    broadcasts: &'a [(u32, State9)],
    /// Per-UAV environment (empty when the scenario needs none).
    env: &'a [UavEnv],
    mode: Mode<'a>,
}

impl StepContext<'_> {
    /// What the links allow UAV `i` this step.
    fn link(&self, i: usize) -> Link<'_> {
        let sc = self.scenario;
        let (radio, dropout, reference_dropout, radio_up, channel_bad, delay_s) = match self.mode {
            // An ideal link; observations of main references keep their own dropout when the
            // scenario sets one (see `Scenario::reference_dropout_set`).
            Mode::Warm(ideal) => (ideal, 0.0, sc.reference_dropout_set().unwrap_or(0.0), true, false, 0.0),
            Mode::Fly => (
                sc.radio(),
                sc.dropout(),
                sc.reference_dropout(),
                self.faults.radio_up,
                self.env.get(i).is_some_and(|e| e.channel_bad),
                f64::from(sc.radio().delay_steps) * sc.dt_s(),
            ),
        };
        Link {
            active: self.active,
            dropout,
            reference_dropout,
            radio_up,
            radio,
            sent: self.sent,
            broadcasts: self.broadcasts,
            delay_s,
            channel_bad,
            onboard: sc.method().uses_onboard_sensing(),
        }
    }

    /// Perceive: what each active UAV of the block senses onboard and hears by radio, into
    /// `heard`; its nearest neighbour and radio count into its record.
    fn perceive(&self, first: usize, blk: &mut Block<'_>) {
        let s = &mut *blk.scratch;
        s.heard.clear();
        s.spans.clear();
        for (b, aux) in blk.uavs.iter_mut().enumerate() {
            let i = first + b;
            let from = s.heard.len();
            if self.active[i] {
                let uk = self.key.run().uav(i as u64);
                let mut draws = PerceptionDraws {
                    sensing: self.key.rng_of(uk, Source::Sensing),
                    radio: self.key.rng_of(uk, Source::Radio),
                };
                let link = self.link(i);
                let nearest = self.sensor.perceive(i, &self.scene, &link, &mut draws, &mut s.sensor, &mut s.heard);
                if matches!(self.mode, Mode::Fly) {
                    (aux.nearest_m, aux.nearest_id) = nearest;
                    aux.radio_msgs =
                        s.heard[from..].iter().filter(|o| o.source == ObservationSource::Radio).count() as u16;
                }
            }
            s.spans.push(from..s.heard.len());
        }
    }

    /// Estimate: each active follower's noisy measurement of its own state (with its
    /// position-fix bias and sensor faults, in flight).
    fn estimate(&self, first: usize, blk: &mut Block<'_>) {
        let sigma = self.scenario.noise().sigma();
        let s = &mut *blk.scratch;
        s.own.clear();
        for b in 0..blk.agents.len() {
            let i = first + b;
            let mut own = self.scene.states[i];
            if self.active[i] && blk.agents[b].is_some() {
                own = noisy(&own, &sigma, &mut self.key.rng(i as u64, Source::OwnState));
                if let (Mode::Fly, Some(e)) = (self.mode, self.env.get(i)) {
                    for k in 0..3 {
                        own[k] += e.gnss_bias[k];
                    }
                }
                if matches!(self.mode, Mode::Fly) {
                    self.faults.corrupt(i, &mut own);
                }
            }
            s.own.push(own);
        }
    }

    /// Decide: each active follower's agent steps on its measurement and what it perceived.
    fn decide(&self, blk: &mut Block<'_>, first: usize) {
        let s = &mut *blk.scratch;
        s.decisions.clear();
        for (b, agent) in blk.agents.iter_mut().enumerate() {
            let decision = match agent {
                Some(a) if self.active[first + b] => Some(a.step(self.t, &s.own[b], &s.heard[s.spans[b].clone()])),
                _ => None,
            };
            s.decisions.push(decision);
        }
    }

    /// Actuate: the input each follower applies, its command scaled by `1 + ε` per component
    /// (the actuation error) when it adjusted.
    fn actuate(&self, first: usize, blk: &mut Block<'_>) {
        let sc = self.scenario;
        let s = &mut *blk.scratch;
        s.applied.clear();
        for (b, d) in s.decisions.iter().enumerate() {
            let commanded = match d {
                Some(d) if self.options.adjustment_enabled => d.input,
                _ => Input::zeros(),
            };
            let adjusted = d.is_some_and(|d| matches!(d.outcome, Outcome::Adjusted { .. }));
            let applied = if adjusted && sc.actuation_error() > 0.0 {
                let mut rng = self.key.rng((first + b) as u64, Source::Actuation);
                commanded.map(|u| u * (1.0 + sc.actuation_error() * rng.random_range(-1.0..=1.0)))
            } else {
                commanded
            };
            s.applied.push(applied);
        }
    }

    /// Propagate: each UAV's next state (the navigator along its path, a follower through its
    /// vehicle and the wind), and what its update produced.
    fn propagate(&self, first: usize, blk: &mut Block<'_>) {
        let sc = self.scenario;
        let dt = sc.dt_s();
        let s = &*blk.scratch;
        for b in 0..blk.agents.len() {
            let i = first + b;
            let (next, aux) = (&mut blk.next[b], &mut blk.uavs[b]);
            let me = &self.scene.states[i];
            if !self.active[i] {
                *next = *me;
                *aux = UavStep::default();
                continue;
            }
            let (Some(agent), Some(decision)) = (&blk.agents[b], s.decisions[b]) else {
                *next = sc.path().state_at(self.t + dt, self.start);
                aux.outcome = None;
                aux.model_error = [0.0; 9];
                continue;
            };
            let applied = s.applied[b];
            let commanded = if self.options.adjustment_enabled { decision.input } else { Input::zeros() };
            // The model error is zero when the input was applied as commanded: the plant is
            // then propagated once.
            let exact = applied == commanded;
            let vehicle = sc.vehicle();
            let model_error = if sc.wind().is_calm() {
                *next = vehicle.propagate(me, &applied, dt);
                if exact {
                    State9::zeros()
                } else {
                    state::difference(next, &vehicle.propagate(me, &commanded, dt))
                }
            } else {
                // The vehicle moves through the air; the wind carries it.
                let e = self.env.get(i).copied().unwrap_or_default();
                let (w_now, w_next) = (e.wind_now, e.wind_next);
                let mut air = *me;
                for k in 0..3 {
                    air[3 + k] -= w_now[k];
                }
                let carry = |mut x: State9| {
                    for k in 0..3 {
                        x[3 + k] += w_next[k];
                        x[k] += 0.5 * dt * (w_now[k] + w_next[k]);
                    }
                    x
                };
                *next = carry(vehicle.propagate(&air, &applied, dt));
                if exact {
                    State9::zeros()
                } else {
                    state::difference(next, &carry(vehicle.propagate(&air, &commanded, dt)))
                }
            };
            aux.model_error = std::array::from_fn(|k| model_error[k] as f32);
            aux.outcome = Some(decision.outcome);
            let scale = agent.vehicle().input_scale(dt);
            aux.effort = (0..agent.vehicle().n_inputs())
                .map(|j| if scale[j] > 0.0 { (decision.input[j] / scale[j]).powi(2) } else { 0.0 })
                .sum::<f64>()
                .sqrt() as f32;
        }
    }

    /// A flight step of the block starting at UAV `first`: every per-UAV phase.
    fn fly(&self, first: usize, blk: &mut Block<'_>) {
        self.perceive(first, blk);
        self.estimate(first, blk);
        self.decide(blk, first);
        self.actuate(first, blk);
        self.propagate(first, blk);
    }

    /// A warm-up step of the block: perceive, estimate, decide; nothing applied.
    fn warm(&self, first: usize, blk: &mut Block<'_>) {
        self.perceive(first, blk);
        self.estimate(first, blk);
        self.decide(blk, first);
    }
}
