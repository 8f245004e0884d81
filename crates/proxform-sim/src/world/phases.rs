//! The per-UAV phases of a step, run over blocks of [`BLOCK`] UAVs: **perceive** (onboard
//! detections and radio messages), **estimate** (the UAV's noisy measurement of its own
//! state), **decide** (its [`Agent::step`]), **actuate** (the actuation error) and
//! **propagate** (vehicle and wind). Each phase runs over all of a block's UAVs before the next
//! starts; a block's observations stay in one small buffer of the thread that runs it.

use std::ops::Range;

use proxform_core::state::{self, Input, State9};
use proxform_core::{Agent, Decision, Observation, ObservationSource};
use proxform_scenario::radio::RadioModel;
use proxform_scenario::Scenario;
use rand::RngExt;
use rayon::prelude::*;

use super::environment::UavEnv;
use super::faults::FaultStep;
use super::measurement::{Message, OwnSensors};
use super::options::RunOptions;
use super::plant;
use super::remote::Sensed;
use super::sensing::{place_in_own_frame, Link, PerceptionDraws, ProximitySensor, Scene, SensorScratch};
use crate::measure::observer::UavStep;
use crate::random::{Source, StreamKey};

/// Half the interval over which a successor's planned velocity is differenced (s).
const PLANNED_DIFF_S: f64 = 0.01;

/// UAVs per block of the per-UAV phases.
pub const BLOCK: usize = 64;

/// Runs `f` on every block of [`BLOCK`] UAVs (its first index and its slices of the agents,
/// next states and per-UAV records), in parallel or in order; each block gets the scratch of
/// the thread that runs it.
pub(super) fn for_each_block(
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
        for_each_block_in_order(agents, next, uavs, areas, f);
    }
}

/// [`for_each_block`] in order on this thread, with a function that may change what it
/// captures (the split path of [`super::remote`] gathers what every block sensed).
pub(super) fn for_each_block_in_order(
    agents: &mut [Option<Agent>],
    next: &mut [State9],
    uavs: &mut [UavStep],
    areas: usize,
    mut f: impl FnMut(usize, &mut Block<'_>),
) {
    let mut scratch = BlockScratch::new(areas);
    let blocks = agents.chunks_mut(BLOCK).zip(next.chunks_mut(BLOCK)).zip(uavs.chunks_mut(BLOCK));
    for (b, ((agents, next), uavs)) in blocks.enumerate() {
        f(b * BLOCK, &mut Block { agents, next, uavs, scratch: &mut scratch });
    }
}

/// Which pass of the per-UAV phases a step runs.
#[derive(Debug, Clone, Copy)]
pub(super) enum Mode<'a> {
    /// The flight: every phase, with the scenario's radio and faults.
    Fly,
    /// The warm-up: perceive (over an ideal radio), estimate and decide; nothing applied.
    Warm(&'a RadioModel),
}

/// One block's slices and the scratch of the thread that runs it.
pub(super) struct Block<'b> {
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

/// Who leads the formation this step: the navigator, or its successor flying its own slot of
/// the formation flown (indexed by UAV) along the navigator's path, from its take-over.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Leading<'a> {
    pub uav: usize,
    pub formation: &'a proxform_core::Formation,
    pub take_over: Option<proxform_core::succession::TakeOver>,
    /// Its move to a new slot (a change of formation, a re-assignment) while it leads.
    pub moving: Option<proxform_core::succession::TakeOver>,
    /// An outside controller has flown the navigator: from then on it flies back to and along
    /// its path through its vehicle (it is where it was flown, never put back on the path).
    pub flown_outside: bool,
}

impl Leading<'_> {
    /// The leader's target at `t`.
    pub(crate) fn target(&self, sc: &Scenario, start: [f64; 3], t: f64) -> State9 {
        let slot = self.slot(sc, start, t);
        self.take_over.map_or(slot, |k| k.target(t, &slot))
    }

    /// Its next state from `me` at `t`: its autopilot flies it toward its target (the
    /// navigator along its path; a successor to its own slot on it) through its vehicle and
    /// the wind where it is (`e`).
    pub(crate) fn next(&self, sc: &Scenario, start: [f64; 3], (t, me): (f64, &State9), e: &UavEnv) -> State9 {
        let autopilot = sc.agents().controller();
        let path = |s| self.target(sc, start, t + s);
        let u = if self.uav == sc.navigator().index() {
            autopilot.input_along_path(me, path)
        } else {
            autopilot.input_to_slot_on_path(me, path)
        };
        sc.vehicle().propagate_in_wind(me, &u, sc.dt_s(), e.wind_now.into(), e.wind_next.into())
    }

    /// Its slot on the path at `t`, on its way there when it moves to a new one.
    pub(crate) fn slot(&self, sc: &Scenario, start: [f64; 3], t: f64) -> State9 {
        let slot = slot_on_path(sc, self.formation, start, self.uav, t);
        self.moving.map_or(slot, |m| m.target(t, &slot))
    }
}

/// Where the mission path puts UAV `i` at `t` (the path starting at `start`): the navigator
/// on the path, any other UAV at its slot of formation `f` (indexed by UAV) around it, with
/// the slot's own velocity (a slot off the navigator moves faster or slower in a turn of the
/// formation: the velocity is the slot's position differenced over [`PLANNED_DIFF_S`]
/// either side).
pub(crate) fn slot_on_path(sc: &Scenario, f: &proxform_core::Formation, start: [f64; 3], i: usize, t: f64) -> State9 {
    let nav = sc.navigator().index();
    let (Some(mine), Some(its)) = (f.slots.get(i), f.slots.get(nav)) else {
        return sc.path().state_at(t, start);
    };
    let at = |t: f64| {
        let on_path = sc.path().state_at(t, start);
        on_path + f.w(mine, its, &on_path)
    };
    let mut s = at(t);
    if i != nav {
        let h = PLANNED_DIFF_S;
        let (ahead, behind) = (at(t + h), at(t - h));
        for k in 0..3 {
            s[state::VX + k] = (ahead[state::X + k] - behind[state::X + k]) / (2.0 * h);
        }
    }
    s
}

/// Read-only view of one step, shared by the threads that run the blocks.
pub(super) struct StepContext<'a> {
    pub scenario: &'a Scenario,
    pub options: RunOptions,
    pub key: StreamKey,
    pub t: f64,
    pub start: [f64; 3],
    pub scene: Scene<'a>,
    pub sensor: &'a ProximitySensor,
    pub active: &'a [bool],
    pub faults: &'a FaultStep,
    /// The radio messages arriving now, and their index by sender position.
    pub messages: &'a [Message],
    pub reach: &'a super::reach::Reach,
    /// Per-UAV environment (empty when the scenario needs none).
    pub env: &'a [UavEnv],
    /// Who leads (the navigator, or its successor) and how.
    pub lead: Leading<'a>,
    /// Flight or warm-up.
    pub mode: Mode<'a>,
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
            messages: self.messages,
            reach: self.reach,
            delay_s,
            channel_bad,
            onboard: sc.method().uses_onboard_sensing(),
            fuse: sc.fuses_radio(),
        }
    }

    /// Perceive: what each active UAV of the block senses onboard and hears by radio, into
    /// `heard`; how many radio messages it used into its record.
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
                self.sensor.perceive(i, &self.scene, &link, &mut draws, &mut s.sensor, &mut s.heard);
                if matches!(self.mode, Mode::Fly) {
                    aux.radio_used =
                        s.heard[from..].iter().filter(|o| o.source == ObservationSource::Radio).count() as u16;
                }
            }
            s.spans.push(from..s.heard.len());
        }
    }

    /// Estimate: each active follower's noisy measurement of its own state (with its
    /// position-fix bias and sensor faults, in flight). With relative sensing, its onboard
    /// observations, measured relative to it, are then placed in the world with that
    /// measurement: each moves by the measurement's error (`own − truth`).
    fn estimate(&self, first: usize, blk: &mut Block<'_>) {
        let sensors = OwnSensors {
            sigma: self.scenario.noise().sigma(),
            key: self.key,
            env: self.env,
            faults: matches!(self.mode, Mode::Fly).then_some(self.faults),
        };
        let nav = self.scenario.navigator().index();
        let s = &mut *blk.scratch;
        s.own.clear();
        let relative = self.scenario.relative_sensing();
        for b in 0..blk.agents.len() {
            let i = first + b;
            let truth = &self.scene.states[i];
            let own = if self.active[i] && i != nav { sensors.measure(i, truth) } else { *truth };
            if relative && i != nav {
                let error = state::difference(&own, truth);
                for o in s.heard[s.spans[b].clone()].iter_mut() {
                    place_in_own_frame(o, &error);
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

    /// Actuate: the input each follower applies, its command with the actuation error
    /// ([`plant::actuated`]) when it adjusted.
    fn actuate(&self, first: usize, blk: &mut Block<'_>) {
        let s = &mut *blk.scratch;
        let adjust = self.options.adjustment_enabled;
        s.applied.clear();
        for (b, d) in s.decisions.iter().enumerate() {
            let commanded = plant::commanded(self.scenario, &self.scene.states[first + b], d.as_ref(), adjust);
            let mut rng = None;
            let draw = || {
                let rng = rng.get_or_insert_with(|| self.key.rng((first + b) as u64, Source::Actuation));
                rng.random_range(-1.0..=1.0)
            };
            s.applied.push(plant::actuated(self.scenario, commanded, d.as_ref(), adjust, draw));
        }
    }

    /// Propagate: each UAV's next state (the navigator along its path, a follower through its
    /// vehicle and the wind), and what its update produced.
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    fn propagate(&self, first: usize, blk: &mut Block<'_>) {
        let sc = self.scenario;
        let dt = sc.dt_s();
        let nav = sc.navigator().index();
        let s = &*blk.scratch;
        for b in 0..blk.next.len() {
            let i = first + b;
            let (next, aux) = (&mut blk.next[b], &mut blk.uavs[b]);
            let me = &self.scene.states[i];
            if !self.active[i] {
                *next = *me;
                *aux = UavStep::default();
                continue;
            }
            let e = self.env.get(i).copied().unwrap_or_default();
            if i == nav && s.decisions[b].is_some() {
                // An outside controller flies the navigator (only agents outside the engine
                // give it a decision): through its vehicle and the wind, as a follower.
                let applied = s.applied[b];
                *next = sc.vehicle().propagate_in_wind(me, &applied, dt, e.wind_now.into(), e.wind_next.into());
                *aux = UavStep::default();
                continue;
            }
            if i == self.lead.uav && (i != nav || sc.navigator_flies() || self.lead.flown_outside) {
                *next = self.lead.next(sc, self.start, (self.t, me), &e);
                *aux = UavStep::default();
                continue;
            }
            let Some(decision) = s.decisions[b].filter(|_| i != nav) else {
                // The navigator on its path: nothing decided on what it perceived, so it used
                // no radio message (as a successor flown by its autopilot, and as on the fast
                // engine).
                *next = plant::on_path(sc, self.start, self.t + dt);
                aux.outcome = None;
                aux.model_error = [0.0; 9];
                aux.isolated = 0;
                aux.own_suspect = false;
                aux.radio_used = 0;
                continue;
            };
            let applied = s.applied[b];
            let commanded = plant::commanded(sc, me, Some(&decision), self.options.adjustment_enabled);
            *next = plant::next_state(sc, me, &applied, &e);
            aux.model_error = plant::model_error(sc, me, (&applied, &commanded), next, &e);
            aux.outcome = Some(decision.outcome.into());
            aux.isolated = decision.isolated;
            aux.own_suspect = decision.own_suspect;
            aux.effort = plant::effort(sc, &decision.input);
        }
    }

    /// A flight step of the block starting at UAV `first`: every per-UAV phase.
    pub fn fly(&self, first: usize, blk: &mut Block<'_>) {
        self.perceive(first, blk);
        self.estimate(first, blk);
        self.decide(blk, first);
        self.actuate(first, blk);
        self.propagate(first, blk);
    }

    /// A warm-up step of the block: perceive, estimate, decide; nothing applied.
    pub fn warm(&self, first: usize, blk: &mut Block<'_>) {
        self.perceive(first, blk);
        self.estimate(first, blk);
        self.decide(blk, first);
    }

    /// For agents outside the engine ([`super::remote`]), the phases before the decision:
    /// perceive and estimate, then each active follower's measurement and observations
    /// appended to `out`.
    pub fn sense(&self, first: usize, blk: &mut Block<'_>, out: &mut Sensed) {
        self.perceive(first, blk);
        self.estimate(first, blk);
        let nav = self.scenario.navigator().index();
        let s = &*blk.scratch;
        for b in 0..blk.next.len() {
            let i = first + b;
            if self.active[i] && i != nav {
                let from = out.heard.len();
                out.heard.extend_from_slice(&s.heard[s.spans[b].clone()]);
                out.uavs.push(proxform_core::UavId(i as u32));
                out.own.push(s.own[b]);
                out.spans.push(from..out.heard.len());
            }
        }
    }

    /// For agents outside the engine, the phases after the decision: actuate and propagate
    /// with `decisions` (indexed by UAV; None for the navigator and inactive UAVs). Needs the
    /// block's measurements of the same step ([`Self::sense`] just before, in the same order).
    pub fn apply(&self, first: usize, blk: &mut Block<'_>, decisions: &[Option<Decision>]) {
        let s = &mut *blk.scratch;
        s.decisions.clear();
        s.decisions.extend_from_slice(&decisions[first..first + blk.next.len()]);
        self.actuate(first, blk);
        self.propagate(first, blk);
    }
}
