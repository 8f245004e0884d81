//! The fast engine: every phase of a step run over all UAVs as arrays, for large swarms.
//!
//! The reference engine ([`crate::world`]) steps one [`proxform_core::Agent`] object per UAV,
//! each with its own tracks and controller, through every phase. This engine runs the same
//! method over flat arrays: the true states, one array of every UAV's tracks in compact f32
//! records (`tracks`), the inputs and the per-UAV records, with per-thread scratch allocated
//! once. Its controller step is the reference's own ([`proxform_core::controller::UavView`]
//! over the records, `tracks::StepTracks`), and so is its sensor
//! ([`crate::world::sensing::ProximitySensor::pick`]); the noise of what it picks is drawn in
//! bulk (`update`).
//! A step is:
//! 0. **membership**: the faults in force, the navigator's succession and slot re-assignment
//!    (the reference engine's own [`crate::world::membership::Membership`]);
//!    **environment** (with wind, a position-fix bias or bursty radio losses): every UAV's
//!    wind, bias and radio channel over the step, by the reference engine's own pass
//!    ([`crate::world::environment`]);
//! 1. **index**: the neighbour grid over the positions;
//! 2. **radio**: the broadcasters' messages (their own measurements), composed once, and
//!    with `relay_navigator` each follower's relay of its track of the navigator;
//! 3. per block of [`BLOCK`] UAVs, in parallel: **perceive** (areas, references, radio,
//!    close-range detections from the true geometry), **measure** (noise drawn in bulk, only
//!    for what was observed), **decide** (the controller on the tracks), **actuate** (the
//!    plant's input for the decision, with the actuation error);
//! 4. **propagate**: every UAV through its vehicle in the wind, in place (the reference
//!    engine's plant, [`crate::world::plant`]: the same vehicles, the same navigator);
//! 5. **measure**: the observers see the new states.
//!
//! Positions inside the controller are relative to each UAV's reference point, which moves
//! with the navigator's path (`update::View::shift`), so f32 tracks keep their resolution
//! however far the swarm flies; the true states stay in f64.
//!
//! Random numbers come from the counter-based streams of [`crate::random::bulk`], keyed by
//! (seed, run, UAV, source, step): results do not depend on the thread count. They are other
//! numbers than the reference engine's, so the two engines agree in distribution, not bit for
//! bit (`tests/fast_engine.rs` checks the distributions). [`setup::supports`] says which
//! scenarios it runs; the rest run on the reference engine.

mod setup;
mod tracks;
mod update;

use proxform_core::controller::{relative_speed_bound, AvoidanceMemory};
use proxform_core::controller::{OwnFix, TurnTrend};
use proxform_core::grid::NeighbourGrid;
use proxform_core::own_estimate::OwnEstimate;
use proxform_core::state::{Input, VX, X};
use proxform_core::State9;
use proxform_scenario::Scenario;
use rayon::prelude::*;

use crate::measure::observer::{Observer, StepFrame, UavStep};
use crate::random::RunKey;
use crate::world::airwaves::Airwaves;
use crate::world::environment::{self, EnvStep, UavEnv};
use crate::world::measurement::{self, Message};
use crate::world::membership::Membership;
use crate::world::navigator_check::NavigatorCheck;
use crate::world::options::RunOptions;
use crate::world::plant;
use crate::world::reach::Reach;
use crate::world::sensing::ProximitySensor;
use proxform_scenario::radio::RadioModel;
use setup::Consts;
pub use setup::{supports, Unsupported};
use tracks::{Owner, Track};
use update::{Autopilot, Scratch, View};

/// UAVs per block of the per-UAV phases.
pub const BLOCK: usize = 256;

/// Step numbers of the warm-up's draws, far from the flight's.
const WARMUP_DRAW_BASE: u64 = 1 << 62;

/// One block's slices of the per-UAV arrays, with its index: records, inputs, tracks and their
/// counts, avoidance memory.
type BlockSlices<'b> = (
    usize,
    (
        ((&'b mut [UavStep], &'b mut [[f32; 6]]), ((&'b mut [Track], &'b mut [u8]), &'b mut Vec<OwnEstimate>)),
        (&'b mut Vec<(u32, AvoidanceMemory)>, (&'b mut Vec<Autopilot>, &'b mut Vec<Option<OwnFix>>)),
    ),
);

/// One flight on the fast engine.
pub struct FastSimulation<'s> {
    sc: &'s Scenario,
    c: Consts,
    options: RunOptions,
    run: RunKey,
    k: u64,
    /// True states (f64), indexed by UAV.
    states: Vec<State9>,
    /// What each UAV's last update produced.
    uavs: Vec<UavStep>,
    /// Each UAV's input as applied this step.
    applied: Vec<[f32; 6]>,
    /// Who flies and who leads (the reference engine's own: faults, succession,
    /// re-assignment).
    members: Membership,
    /// `capacity` tracks per UAV, then how many each uses.
    tracks: Vec<Track>,
    used: Vec<u8>,
    /// Each UAV's estimate of its own state (what it remembers only while the own-sensor check
    /// or filter is on: 8 bytes a UAV otherwise).
    /// Per block (each empty while the check and the filter are off: nothing a UAV).
    own: Vec<Vec<OwnEstimate>>,
    /// What each UAV's autopilot flies (its setpoint and turn trend), per block; empty where
    /// the vehicle keeps neither.
    autopilot: Vec<Vec<Autopilot>>,
    /// Each UAV's last own position fix, per block (relative sensing: the frame of its tracks;
    /// empty without).
    frames: Vec<Vec<Option<OwnFix>>>,
    /// Collision avoidance's memory (its sides alone) of the UAVs whose rule remembers a side,
    /// per block (few UAVs of a large swarm ever have one; each is lent to the thread's rule
    /// for the UAV's update).
    avoid: Vec<Vec<(u32, AvoidanceMemory)>>,
    grid: NeighbourGrid,
    /// Each UAV's wind and position-fix bias (the reference engine's, from the same streams),
    /// empty when the scenario has neither.
    env: Vec<UavEnv>,
    /// The radio's messages on their way and arriving (the reference engine's own delay line).
    air: Airwaves,
    /// The sensor (the reference engine's own).
    sensor: ProximitySensor,
    /// The warm-up's radio, without losses.
    ideal: RadioModel,
    /// The messages' index by sender position.
    reach: Reach,
    /// Origins of the reference points of the last steps.
    ring: Vec<[f64; 3]>,
    /// The formation change in force at the last step (None: the first formation).
    stage: Option<usize>,
    start: [f64; 3],
    origin0: [f64; 3],
    parallel: bool,
    /// What the navigator broadcasts of itself, checked (the reference engine's own).
    navigator_check: NavigatorCheck,
}

impl std::fmt::Debug for FastSimulation<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FastSimulation").field("uavs", &self.states.len()).field("k", &self.k).finish()
    }
}

impl<'s> FastSimulation<'s> {
    /// A flight of `sc` for run `run` of seed `seed`, warmed up as the reference engine's.
    pub fn new(sc: &'s Scenario, options: RunOptions, seed: u64, run: u64) -> Result<Self, Unsupported> {
        supports(sc)?;
        let c = Consts::new(sc);
        let n = sc.len();
        let nav = sc.navigator().index();
        let s0 = sc.initial()[nav];
        let start = [s0[X], s0[X + 1], s0[X + 2]];
        let p0 = sc.path().state_at(0.0, start);
        // The origins as far back as a track's measurement may lie: its timeout (or coasting)
        // after its last report, which a delayed radio or a relay measured that much earlier
        // still.
        let ring_len = ((setup::oldest_steps(sc).ceil() as usize) + 3).next_power_of_two();
        let run = RunKey::new(seed, run);
        let mut sim = Self {
            sc,
            options,
            run,
            k: 0,
            // Where the UAVs start: their slots, or scattered as the reference engine scatters
            // them (the same draws).
            states: crate::world::placement::initial_states(sc, run),
            uavs: vec![UavStep::default(); n],
            applied: vec![[0.0; 6]; n],
            members: Membership::new(sc),
            tracks: vec![Track::default(); n * c.capacity],
            used: vec![0; n],
            own: (0..n.div_ceil(BLOCK))
                .map(|b| match c.own_estimate {
                    true => vec![OwnEstimate::default(); BLOCK.min(n - b * BLOCK)],
                    false => Vec::new(),
                })
                .collect(),
            autopilot: (0..n.div_ceil(BLOCK))
                .map(|b| match c.autopilot {
                    true => vec![Autopilot::default(); BLOCK.min(n - b * BLOCK)],
                    false => Vec::new(),
                })
                .collect(),
            frames: (0..n.div_ceil(BLOCK))
                .map(|b| match sc.relative_sensing() {
                    true => vec![None; BLOCK.min(n - b * BLOCK)],
                    false => Vec::new(),
                })
                .collect(),
            avoid: vec![Vec::new(); n.div_ceil(BLOCK)],
            grid: NeighbourGrid::new(),
            env: environment::initial(sc),
            air: Airwaves::default(),
            sensor: ProximitySensor::of(sc),
            ideal: sc.radio().ideal(),
            reach: Reach::new(),
            ring: vec![[p0[X], p0[X + 1], p0[X + 2]]; ring_len],
            stage: None,
            start,
            origin0: [p0[X], p0[X + 1], p0[X + 2]],
            parallel: n >= crate::world::engine::PARALLEL_MIN_UAVS,
            navigator_check: NavigatorCheck::default(),
            c,
        };
        sim.warm_up();
        Ok(sim)
    }

    /// Forces serial or parallel stepping (results are identical).
    pub fn with_parallel(mut self, parallel: bool) -> Self {
        self.parallel = parallel;
        self
    }

    /// Current true states.
    pub fn states(&self) -> &[State9] {
        &self.states
    }

    /// Bytes a flight of `sc` will hold in the engine's arrays (as [`Self::heap_bytes`]),
    /// estimated before it is built: its per-UAV arrays, its track records, the neighbour grid
    /// (about 32 bytes a UAV), each UAV's environment, own estimate, autopilot and own fix where
    /// it keeps them.
    pub fn bytes_estimate(sc: &Scenario) -> usize {
        let c = Consts::new(sc);
        let n = sc.len();
        n * (std::mem::size_of::<State9>()
            + std::mem::size_of::<UavStep>()
            + std::mem::size_of::<[f32; 6]>()
            + 2
            + c.capacity * std::mem::size_of::<Track>()
            + std::mem::size_of::<UavEnv>()
            + if c.autopilot { std::mem::size_of::<Autopilot>() } else { 0 }
            + if sc.relative_sensing() { std::mem::size_of::<Option<OwnFix>>() } else { 0 }
            + if c.own_estimate { std::mem::size_of::<OwnEstimate>() } else { 0 }
            + 32)
    }

    /// Bytes held by the engine's arrays (the scenario excluded).
    pub fn heap_bytes(&self) -> usize {
        let n = self.states.len();
        n * (std::mem::size_of::<State9>() + std::mem::size_of::<UavStep>() + std::mem::size_of::<[f32; 6]>() + 2)
            + self.tracks.len() * std::mem::size_of::<Track>()
            + self.avoid.iter().flatten().map(|a| a.1.heap_bytes()).sum::<usize>()
            + self.avoid.len() * std::mem::size_of::<Vec<(u32, AvoidanceMemory)>>()
            + self.grid.heap_bytes()
            + self.env.len() * std::mem::size_of::<UavEnv>()
            + self.reach.heap_bytes()
            + self.air.heap_bytes()
            + self.own.iter().flatten().map(|o| std::mem::size_of::<OwnEstimate>() + o.heap_bytes()).sum::<usize>()
            + self.autopilot.iter().map(|a| a.len() * std::mem::size_of::<Autopilot>()).sum::<usize>()
            + self.frames.iter().map(|f| f.len() * std::mem::size_of::<Option<OwnFix>>()).sum::<usize>()
    }

    /// The origin of the reference points at step `k` (the navigator's path position).
    fn origin_at(&self, k: i64) -> [f64; 3] {
        let s = self.sc.path().state_at(k as f64 * self.c.dt, self.start);
        [s[X], s[X + 1], s[X + 2]]
    }

    /// The warm-up (as the reference engine's): the followers watch the ideal formation fly
    /// its path for `warmup_s` before t = 0, so that their tracks know the rates; nothing is
    /// applied.
    fn warm_up(&mut self) {
        let sc = self.sc;
        let steps = if sc.placement().in_slots() { (sc.warmup_s() / sc.dt_s()).round() as i64 } else { 0 };
        if steps == 0 {
            return;
        }
        let nav = self.c.nav;
        for w in 0..steps {
            let k = -(steps - w);
            let nav_state = sc.path().state_at(k as f64 * self.c.dt, self.start);
            for (i, s) in self.states.iter_mut().enumerate() {
                *s = if i == nav { nav_state } else { sc.slot_state(i, &nav_state) };
            }
            self.decide_all(k, WARMUP_DRAW_BASE + w as u64, true);
        }
        // Back to the start: every UAV in its slot (the only placement this engine runs).
        self.states.copy_from_slice(sc.initial());
        self.uavs.iter_mut().for_each(|u| *u = UavStep::default());
        // The flight's radio starts afresh: nothing of the warm-up is on the air.
        self.air.clear();
        // The warm-up's inputs were not applied: what each UAV expected of itself is forgotten,
        // and its autopilot was given no setpoint.
        self.own.iter_mut().flatten().for_each(OwnEstimate::forget);
        self.autopilot.iter_mut().flatten().for_each(|a| a.setpoint = None);
    }

    /// The schedule at `t` (removals, joins, sensor faults, radio blackouts), then the
    /// navigator's succession and slot re-assignment when a loss becomes known: the reference
    /// engine's own [`Membership`]. Where slots moved, every follower flies its new one from a
    /// fresh controller (as at a change of formation); a succession alone keeps every track
    /// (the tables name the successor from now on, and the successor flies by its autopilot).
    fn follow_membership(&mut self, t: f64) {
        let (sc, c, run, k) = (self.sc, &self.c, self.run, self.k);
        let own = |states: &[State9], i: usize| update::noisy_own(c, &run, k, &states[i], i);
        self.members.apply_schedule(sc, t, (self.start, &mut self.states), own);
        if let Some(r) = self.members.reassign(sc, (t, k), (self.start, &self.states)) {
            if r.moved {
                self.restart_controllers();
            }
        }
    }

    /// Every follower's controller starts afresh: its tracks restart from the next
    /// observations, avoidance remembers no side and the turn trend starts again (its
    /// autopilot flies on its setpoint).
    fn restart_controllers(&mut self) {
        self.tracks.fill(Track::default());
        self.used.fill(0);
        self.avoid.iter_mut().for_each(Vec::clear);
        self.autopilot.iter_mut().flatten().for_each(|a| a.trend = TurnTrend::default());
        self.frames.iter_mut().flatten().for_each(|f| *f = None);
    }

    /// At a change of formation every follower flies its new slot on its new table from a
    /// fresh controller, as the reference's agents do ([`proxform_core::Agent`]): its tracks
    /// restart from the next observations, avoidance remembers no side and the turn trend
    /// starts afresh (its autopilot flies on its setpoint).
    fn follow_schedule(&mut self, t: f64) {
        let stage = self.sc.schedule().stages().iter().rposition(|s| t >= s.at_s - 1e-9);
        if stage == self.stage {
            return;
        }
        self.stage = stage;
        self.restart_controllers();
    }

    /// Index: the neighbour grid over the flying UAVs.
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    fn index_positions(&mut self) {
        let active = &self.members.active;
        let flying = self.states.iter().enumerate().filter(|(i, _)| active[*i]);
        self.grid.rebuild_ids(flying.map(|(i, s)| (i as u32, [s[X], s[X + 1], s[X + 2]])), self.c.range);
    }

    /// Index, radio and the per-UAV phases up to the applied inputs, for step `k`.
    fn decide_all(&mut self, k: i64, draw_step: u64, warm: bool) {
        let t = k as f64 * self.c.dt;
        self.follow_schedule(t);
        let origin = self.origin_at(k);
        let len = self.ring.len();
        self.ring[update::ring_index(k as i32, len)] = origin;
        self.index_positions();
        let active = &self.members.active;
        let flying = || self.states.iter().enumerate().filter(|(i, _)| active[*i]);
        let spread = relative_speed_bound(flying().map(|(_, s)| [s[VX], s[VX + 1], s[VX + 2]]));
        self.sensor.set_speeds(spread);
        let Self {
            sc,
            c,
            run,
            states,
            uavs,
            applied,
            tracks,
            used,
            own,
            avoid,
            autopilot,
            frames,
            grid,
            env,
            air,
            reach,
            ring,
            origin0,
            sensor,
            ideal,
            members,
            navigator_check,
            ..
        } = self;
        let view = View {
            c,
            sc,
            states,
            grid,
            sensor,
            active: &members.active,
            faults: &members.faults,
            leader: members.lead.leader,
            ideal,
            run: *run,
            draw_step,
            k: k as i32,
            origin,
            origin0: *origin0,
            ring,
            messages: &[],
            reach: &Reach::new(),
            env,
            warm,
            adjust: self.options.adjustment_enabled,
            formation: members.flown(sc, t),
            dependencies: members.tables(sc, t),
        };
        // Radio: the broadcasters' own measurements.
        // The messages sent `radio.delay_s` ago arrive (without delay in the warm-up, as the
        // reference's).
        let delay = if warm { 0 } else { c.radio_delay_steps };
        let mut messages = air.buffer(delay);
        for j in measurement::senders(sc, members.lead, states.len()) {
            let s = &states[j];
            messages.push(Message {
                sender: j as u32,
                about: j as u32,
                state: update::own_measurement(&view, j),
                age_s: 0.0,
                at: [s[X], s[X + 1], s[X + 2]],
                relative: false,
            });
        }
        // (In the warm-up the navigator's readings are not checked: its sensors are ideal.)
        let leader = (members.lead.leader, t, &states[..]);
        measurement::check_navigator(sc, leader, (!warm).then_some(navigator_check), &mut messages);
        // Relays: every flying follower forwards what its tracks know of the leader, in the
        // order of the UAVs (as the reference's agents).
        let controlled = |i: usize| members.active[i] && i != c.nav && i != members.lead.leader.index();
        if sc.radio().relay_navigator {
            let cap = c.capacity;
            type Records<'r> = (&'r mut [Track], (&'r mut [u8], &'r Vec<Option<OwnFix>>));
            let relays = |(b, (tracks, (used, frames))): (usize, Records<'_>)| -> Vec<Message> {
                (0..used.len())
                    .filter(|&o| controlled(b * BLOCK + o))
                    .filter_map(|o| {
                        let (t, u) = (&mut tracks[o * cap..(o + 1) * cap], &mut used[o]);
                        update::relay(&view, b * BLOCK + o, Owner { tracks: t, used: u }, frames.get(o))
                    })
                    .collect()
            };
            let blocks: Vec<Vec<Message>> = match self.parallel {
                true => tracks
                    .par_chunks_mut(BLOCK * cap)
                    .zip(used.par_chunks_mut(BLOCK).zip(frames.par_iter()))
                    .enumerate()
                    .map(relays)
                    .collect(),
                false => tracks
                    .chunks_mut(BLOCK * cap)
                    .zip(used.chunks_mut(BLOCK).zip(frames.iter()))
                    .enumerate()
                    .map(relays)
                    .collect(),
            };
            messages.extend(blocks.into_iter().flatten());
        }
        air.send(messages, delay);
        reach.rebuild(air.arriving().iter().map(|m| m.at), sc.radio().range_m);
        let view = View { messages: air.arriving(), reach, ..view };
        let cap = c.capacity;
        let block =
            |scratch: &mut Scratch,
             (b, (((uavs, applied), ((tracks, used), own)), (avoid, (pilots, fixes)))): BlockSlices<'_>| {
                for o in 0..uavs.len() {
                    let i = b * BLOCK + o;
                    // The navigator, its successor and the UAVs not flying have no controller.
                    if !controlled(i) {
                        uavs[o] = UavStep::default();
                        applied[o] = [0.0; 6];
                        continue;
                    }
                    let at = avoid.iter().position(|a| a.0 as usize == i);
                    let mut remembered = at.map(|p| avoid.swap_remove(p).1);
                    // (Nothing to remember while the check and the filter are off.)
                    let mut none = OwnEstimate::default();
                    let kept = update::Kept {
                        tracks: Owner { tracks: &mut tracks[o * cap..(o + 1) * cap], used: &mut used[o] },
                        own: own.get_mut(o).unwrap_or(&mut none),
                        autopilot: pilots.get_mut(o),
                        frame: fixes.get_mut(o),
                        avoid: &mut remembered,
                    };
                    let u = update::update(&view, i, scratch, kept);
                    if let Some(k) = remembered {
                        avoid.push((i as u32, k));
                    }
                    uavs[o] = u.step;
                    applied[o] = u.applied;
                }
            };
        if self.parallel {
            uavs.par_chunks_mut(BLOCK)
                .zip(applied.par_chunks_mut(BLOCK))
                .zip(tracks.par_chunks_mut(BLOCK * cap).zip(used.par_chunks_mut(BLOCK)).zip(own.par_iter_mut()))
                .zip(avoid.par_iter_mut().zip(autopilot.par_iter_mut().zip(frames.par_iter_mut())))
                .enumerate()
                .for_each_init(|| Scratch::new(c, sc), block);
        } else {
            let mut scratch = Scratch::new(c, sc);
            uavs.chunks_mut(BLOCK)
                .zip(applied.chunks_mut(BLOCK))
                .zip(tracks.chunks_mut(BLOCK * cap).zip(used.chunks_mut(BLOCK)).zip(own.iter_mut()))
                .zip(avoid.iter_mut().zip(autopilot.iter_mut().zip(frames.iter_mut())))
                .enumerate()
                .for_each(|x| block(&mut scratch, x));
        }
    }

    /// Advances one update period.
    pub fn step(&mut self) {
        let k = self.k;
        let dt = self.c.dt;
        let t = k as f64 * dt;
        self.follow_membership(t);
        // Environment: every flying UAV's wind and position-fix bias over the step (the
        // reference engine's own pass, from the same streams).
        if !self.env.is_empty() {
            let step = EnvStep::new(self.sc, &self.run, k, t);
            let (states, active) = (&self.states, &self.members.active);
            crate::parallel::for_each_mut(&mut self.env, self.parallel, |i, e| {
                if active[i] {
                    step.advance(i, &states[i], e);
                }
            });
        }
        self.decide_all(k as i64, k, false);
        self.propagate();
        self.k += 1;
    }

    /// Propagate: the navigator along its path (set on it, or flown along it by its autopilot
    /// where the vehicle is flown so), the followers through their vehicle in the wind (the
    /// reference engine's plant, [`crate::world::plant`]). A function of its own: a phase of
    /// `proxform bench`'s instruction table.
    #[inline(never)]
    fn propagate(&mut self) {
        let sc = self.sc;
        let t = self.k as f64 * self.c.dt;
        let nav = self.c.nav;
        let start = self.start;
        let env = &self.env;
        let members = &self.members;
        let lead = members.leading(sc, t);
        let calm = UavEnv::default();
        let propagate = |(i, (s, u)): (usize, (&mut State9, &[f32; 6]))| {
            let e = env.get(i).unwrap_or(&calm);
            if !members.active[i] {
                return;
            }
            *s = if i == lead.uav && (i != nav || sc.navigator_flies()) {
                // Its autopilot flies it along the path (a successor: to its own slot on it).
                lead.next(sc, start, (t, s), e)
            } else if i == nav {
                plant::on_path(sc, start, (self.k + 1) as f64 * self.c.dt)
            } else {
                plant::next_state(sc, s, &Input::from_fn(|a, _| f64::from(u[a])), e)
            };
        };
        if self.parallel {
            self.states.par_iter_mut().zip(self.applied.par_iter()).enumerate().for_each(propagate);
        } else {
            self.states.iter_mut().zip(self.applied.iter()).enumerate().for_each(propagate);
        }
    }

    fn frame(&self) -> StepFrame<'_> {
        StepFrame {
            k: self.k,
            t: self.k as f64 * self.c.dt,
            states: &self.states,
            uavs: &self.uavs,
            active: &self.members.active,
            radio_sent: self.air.sent(),
            formation: self.members.reassigned_formation(),
            reassigned: self.members.reassigned_at(self.k),
            successor: self
                .members
                .carried(self.sc, self.k as f64 * self.c.dt, (self.start, &self.states))
                .map(|p| (self.members.lead.leader.index(), p)),
        }
    }

    /// Runs the whole flight, showing every step (and the initial state) to `observer`.
    pub fn run(self, observer: &mut impl Observer) {
        let steps = self.sc.steps();
        self.run_steps(steps, observer);
    }

    /// Runs `steps` update periods (or fewer if the flight ends first), showing each to
    /// `observer`.
    pub fn run_steps(mut self, steps: u64, observer: &mut impl Observer) {
        let sc = self.sc;
        if self.k == 0 {
            observer.on_step(sc, &self.frame());
        }
        let end = (self.k + steps).min(sc.steps());
        while self.k < end && observer.keep_going() {
            self.step();
            observer.on_step(sc, &self.frame());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_a_change_of_formation_every_track_restarts() {
        // The shipped V that closes into a column at 60 s: before the change the followers
        // track their neighbours (measured twice and more); at the change every controller
        // starts afresh, so no track has more than the change's own measurement.
        let text = include_str!("../../../../scenarios/change-v-column.toml").replacen(
            "name = \"change-v-column\"",
            "name = \"change-v-column\"\nengine = \"fast\"",
            1,
        );
        let sc = proxform_scenario::load::parse(&text, "change-v-column.toml").expect("valid");
        let at = sc.schedule().stages()[0].at_s;
        let mut sim = FastSimulation::new(&sc, RunOptions::default(), 1, 0).expect("supported");
        let change = (at / sim.c.dt).round() as u64;
        while sim.k < change {
            sim.step();
        }
        let twice = |sim: &FastSimulation<'_>| sim.tracks.iter().filter(|t| t.seen_twice()).count();
        let fresh = |sim: &FastSimulation<'_>| sim.tracks.iter().filter(|t| t.id().is_some()).count();
        assert!(twice(&sim) >= sc.len() - 1, "before the change: {} tracked twice", twice(&sim));
        sim.step();
        assert_eq!(twice(&sim), 0, "a track kept its history through the change");
        assert!(fresh(&sim) >= sc.len() - 1, "the change's measurements start tracks: {}", fresh(&sim));
    }
}
