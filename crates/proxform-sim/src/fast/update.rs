//! One UAV's update in the fast engine: perceive (the reference engine's sensor picks the
//! nearest UAV per azimuth area, the main references, radio messages, close-range detections;
//! [`crate::world::sensing::ProximitySensor::pick`]), measure (noise drawn in bulk for what
//! was picked), and the proximity controller's step (METHOD §6) on its array of tracks.
//!
//! The controller's step is the reference's own ([`proxform_core::controller::UavView::step`],
//! which [`proxform_core::ProximityController::step`] runs too) over the engine's data:
//! positions relative to the UAV's reference point, tracks in compact f32 records
//! ([`super::tracks::StepTracks`]). Collision avoidance's memory is kept per UAV only while it
//! remembers a side.

use proxform_core::controller::{
    navigator_track, Avoidance, AvoidanceMemory, Decision, OwnFix, StepScratch, TurnTrend, UavView,
};
use proxform_core::grid::NeighbourGrid;
use proxform_core::own_estimate::OwnEstimate;
use proxform_core::state::{State9, X};
use proxform_core::vehicle::Setpoint;
use proxform_core::{Observation, ObservationSource, UavId};
use proxform_scenario::radio::RadioModel;
use proxform_scenario::Scenario;

use super::setup::Consts;
use super::tracks::{Owner, StepTracks};
use crate::measure::observer::UavStep;
use crate::random::bulk;
use crate::random::{RunKey, Source};
use crate::world::measurement::Message;
use crate::world::options::NeighbourSearch;
use crate::world::plant;
use crate::world::sensing::{place_in_own_frame, Link, Picks, ProximitySensor, Scene, SensorScratch};

/// Counter offset of the dropout draws in a UAV's sensing stream (the noise uses the low ones).
const DROPOUT_DRAWS: u64 = 1 << 40;
/// Counter offset of the bad channel's loss draws in a UAV's radio stream.
const BURST_DRAWS: u64 = 1 << 40;

/// What every UAV's update reads in one step.
pub struct View<'a> {
    pub c: &'a Consts,
    pub sc: &'a Scenario,
    pub states: &'a [State9],
    pub grid: &'a NeighbourGrid,
    /// The sensor (the reference engine's), its watch set for the step's speeds.
    pub sensor: &'a ProximitySensor,
    /// Which UAVs fly.
    pub active: &'a [bool],
    /// The sensor faults and the radio's state in force.
    pub faults: &'a crate::world::faults::FaultStep,
    /// Who leads (the navigator, or its successor after its loss).
    pub leader: UavId,
    /// The radio of the warm-up: without losses.
    pub ideal: &'a RadioModel,
    pub run: RunKey,
    /// Step number of the draws.
    pub draw_step: u64,
    /// Step number of the tracks (negative in the warm-up).
    pub k: i32,
    /// The origin O(k) of the reference points, and O(0).
    pub origin: [f64; 3],
    pub origin0: [f64; 3],
    /// The origins of the last steps, O(k0) at `k0 mod len`.
    pub ring: &'a [[f64; 3]],
    pub messages: &'a [Message],
    /// Their index by sender position.
    pub reach: &'a crate::world::reach::Reach,
    /// Each UAV's environment (the position-fix bias), empty when the scenario has none.
    pub env: &'a [crate::world::environment::UavEnv],
    /// The warm-up: an ideal link (no dropout but the references' own, no loss).
    pub warm: bool,
    /// The controller's inputs are applied (`RunOptions::adjustment_enabled`).
    pub adjust: bool,
    /// The formation in force and every UAV's dependency table in it (a
    /// `[[formation.change]]`'s from its time on).
    pub formation: &'a std::sync::Arc<proxform_core::Formation>,
    pub dependencies: &'a [proxform_core::DependencySet],
}

impl View<'_> {
    /// How old a radio message is on arrival (s): the radio's delay in flight, none in the
    /// warm-up.
    #[inline]
    pub fn radio_delay_s(&self) -> f64 {
        if self.warm {
            0.0
        } else {
            self.c.radio_delay_steps as f64 * self.c.dt
        }
    }

    /// `O(k0) − O(k)`: how far the reference points of recent step `k0` lie from this step's.
    #[inline]
    pub fn shift(&self, k0: i32) -> [f64; 3] {
        let o = self.ring[ring_index(k0, self.ring.len())];
        [o[0] - self.origin[0], o[1] - self.origin[1], o[2] - self.origin[2]]
    }
}

/// Where step `k` goes in a ring of `len` origins (a power of two).
#[inline]
pub fn ring_index(k: i32, len: usize) -> usize {
    (k as u32 as usize) & (len - 1)
}

/// Per-thread working memory, allocated once.
pub struct Scratch {
    sensor: SensorScratch,
    /// Observed onboard (areas, references), then close-range detections.
    picked: Vec<u32>,
    /// The messages heard, by index.
    heard: Vec<usize>,
    /// Relays of the navigator heard.
    relayed: Vec<Observation>,
    /// How many of `picked` were reported onboard (the rest are close-range detections).
    onboard: usize,
    normals: Vec<f32>,
    obs: Vec<Observation>,
    /// The controller step's working memory.
    step: StepScratch,
    avoid: Option<Avoidance>,
}

impl Scratch {
    pub fn new(c: &Consts, sc: &Scenario) -> Self {
        Self {
            sensor: SensorScratch::new(c.areas),
            picked: Vec::with_capacity(c.capacity + 8),
            heard: Vec::with_capacity(8),
            relayed: Vec::new(),
            onboard: 0,
            normals: Vec::with_capacity(9 * (c.capacity + 8)),
            obs: Vec::with_capacity(c.capacity + 8),
            step: StepScratch::new(sc.controller(), c.capacity),
            avoid: c.avoid.map(|(d, a)| Avoidance::new(d, a)),
        }
    }
}

/// UAV `i`'s own reading of its true state `truth` at step `draw_step`: the truth plus noise
/// from its own-state stream (what a sensor that sticks freezes at).
#[inline]
pub fn noisy_own(c: &Consts, run: &RunKey, draw_step: u64, truth: &State9, i: usize) -> State9 {
    let mut z = [0.0f32; 9];
    bulk::normals(bulk::key(run, i as u64, Source::OwnState, draw_step), 0, &mut z);
    perturbed(truth, &c.sigma, &z)
}

/// `truth` plus the deviates `z` scaled by the noise `sigma`, per parameter.
#[inline(always)]
fn perturbed(truth: &State9, sigma: &[f32; 9], z: &[f32]) -> State9 {
    let mut s = *truth;
    for k in 0..9 {
        s[k] += f64::from(sigma[k] * z[k]);
    }
    s
}

/// UAV `i`'s own measurement at this step (absolute): its noisy reading, and in flight its
/// position fix's bias and its sensor faults. Its broadcasts carry the same measurement.
// A phase of `proxform bench`'s instruction table: kept a function of its own.
#[inline(never)]
pub fn own_measurement(v: &View<'_>, i: usize) -> State9 {
    let mut s = noisy_own(v.c, &v.run, v.draw_step, &v.states[i], i);
    if !v.warm {
        if let Some(e) = v.env.get(i) {
            for k in 0..3 {
                s[X + k] += e.gnss_bias[k];
            }
        }
        v.faults.corrupt(i, &mut s);
    }
    s
}

/// UAV `i`'s reference point R_i(k) = O(k) + A_i, A_i = p_i(0) − O(0): its tracks' positions
/// are relative to it.
#[inline]
pub fn reference_point(v: &View<'_>, i: usize) -> [f64; 3] {
    let p0 = &v.sc.initial()[i];
    std::array::from_fn(|k| v.origin[k] + (p0[k] - v.origin0[k]))
}

/// A UAV's tracks (its records, its reference point at `r_i`) as the controller's store at
/// this step.
fn step_tracks<'a, 'v>(
    v: &'v View<'_>,
    tracks: Owner<'a>,
    r_i: [f64; 3],
) -> StepTracks<'a, 'v, impl Fn(i32) -> [f64; 3] + 'v> {
    StepTracks {
        owner: tracks,
        filter: &v.c.filter,
        carry: v.c.carry.as_deref(),
        k: v.k,
        shift: move |k0| v.shift(k0),
        at: r_i,
        fed: 0,
    }
}

/// The relay of follower `i` (`radio.relay_navigator`), from its tracks: what it knows of the
/// navigator ([`proxform_core::controller::navigator_track`], as the reference's agents
/// forward it), None when it does not track it.
pub fn relay(v: &View<'_>, i: usize, tracks: Owner<'_>, frame: Option<&Option<OwnFix>>) -> Option<Message> {
    let c = v.c;
    let r_i = reference_point(v, i);
    let store = step_tracks(v, tracks, r_i);
    let t = f64::from(v.k) * c.dt;
    let (mut state, age_s) = navigator_track(v.sc.controller(), &store, v.leader, t)?;
    for k in 0..3 {
        state[X + k] += r_i[k];
    }
    // Relative sensing: its tracks are in the frame of its own fix; the report is relative to
    // its own position now (none before a fix).
    let (state, relative) = match frame {
        Some(fix) => ((*fix)?.relative(t, state), true),
        None => (state, false),
    };
    let s = &v.states[i];
    Some(Message { sender: i as u32, about: v.leader.0, state, age_s, at: [s[X], s[X + 1], s[X + 2]], relative })
}

/// What UAV `i` decided and how: its input (applied) and its record.
pub struct Update {
    pub applied: [f32; 6],
    pub step: UavStep,
}

/// What a UAV's autopilot flies from one step to the next, kept per UAV only where the
/// vehicle needs it (a vehicle flown by setpoints; [`Consts::autopilot`]): the setpoint of its
/// last adjustment and the formation's turn trend its controller leads it by.
#[derive(Debug, Clone, Copy, Default)]
pub struct Autopilot {
    pub setpoint: Option<Setpoint>,
    pub trend: TurnTrend,
}

/// What follower `i` keeps from one step to the next: its tracks, its own estimate, its
/// autopilot's setpoint and turn trend (None where the vehicle keeps neither), its last own
/// position fix (relative sensing: the frame of its tracks; None without).
pub struct Kept<'k> {
    pub tracks: Owner<'k>,
    pub own: &'k mut OwnEstimate,
    pub frame: Option<&'k mut Option<OwnFix>>,
    pub autopilot: Option<&'k mut Autopilot>,
    pub avoid: &'k mut Option<AvoidanceMemory>,
}

/// The update of follower `i`.
pub fn update(v: &View<'_>, i: usize, s: &mut Scratch, kept: Kept<'_>) -> Update {
    let c = v.c;
    let sc = v.sc;
    let radio_used = perceive(v, i, s);
    let measured = own_measurement(v, i);
    // The own-sensor check and filter, as the reference's agents run them (on the absolute
    // reading; the warm-up's inputs are not applied, so what it expected is forgotten after).
    let setup = sc.agents().controller();
    let t = f64::from(v.k) * c.dt;
    let (own_abs, own_suspect) = match c.own_estimate {
        true => kept.own.estimate(setup.params(), t, &measured),
        false => (measured, false),
    };
    let r_i = reference_point(v, i);
    let mut own = own_abs;
    for k in 0..3 {
        own[k] -= r_i[k];
    }
    // Relative sensing: what it observes onboard carries its own measurement's error, and its
    // tracks follow its own position fix (as the reference's controller).
    let mut tracks = kept.tracks;
    let error = kept.frame.map(|frame| {
        let fix = OwnFix::new(t, &own_abs);
        match frame {
            Some(last) => {
                if let Some(d) = last.follow(fix, setup.params().track_timeout_s) {
                    tracks.shift(d);
                }
            }
            None => *frame = Some(fix),
        }
        proxform_core::state::difference(&measured, &v.states[i])
    });
    build_observations(v, i, s, &r_i, error.as_ref());
    let mut autopilot = kept.autopilot;
    let trend = autopilot.as_deref_mut().map(|a| &mut a.trend).filter(|_| setup.keeps_turn_trend());
    let mut d = decide(v, i, (&own, r_i), s, (tracks, trend), kept.avoid);
    // The autopilot of a vehicle flown by setpoints flies the last one it was given.
    if let Some(a) = autopilot {
        a.setpoint = d.take_setpoint(sc.vehicle(), &own_abs, c.dt, a.setpoint.as_ref());
    }
    if c.own_estimate {
        kept.own.expect(setup, t, (&own_abs, &measured), &d.flown_input(sc.vehicle(), &own_abs));
    }
    // The robust fusion's count of the neighbours it left out, as the reference records it.
    let mut step = UavStep {
        radio_used,
        isolated: d.isolated,
        own_suspect,
        outcome: Some(d.outcome.into()),
        effort: plant::effort(sc, &d.input),
        ..UavStep::default()
    };
    // The plant's input at the true state, with the actuation error drawn from the UAV's own
    // stream, and the model error that caused.
    let truth = &v.states[i];
    let commanded = plant::commanded(sc, truth, Some(&d), v.adjust);
    let key = bulk::key(&v.run, i as u64, Source::Actuation, v.draw_step);
    let mut a = 0;
    let draw = || {
        a += 1;
        2.0 * bulk::uniform(key, a - 1) - 1.0
    };
    let applied = plant::actuated(sc, commanded, Some(&d), v.adjust, draw);
    if applied != commanded {
        let e = v.env.get(i).copied().unwrap_or_default();
        let next = plant::next_state(sc, truth, &applied, &e);
        step.model_error = plant::model_error(sc, truth, (&applied, &commanded), &next, &e);
    }
    Update { applied: std::array::from_fn(|a| applied[a] as f32), step }
}

/// The fast engine's [`Picks`]: the sensor's picks noted for their noise to be drawn in bulk
/// afterwards ([`build_observations`]); dropout and radio losses drawn by counter from the
/// UAV's sensing and radio streams, so that no draw depends on another's order.
struct Noted<'a> {
    picked: &'a mut Vec<u32>,
    onboard: &'a mut usize,
    heard: &'a mut Vec<usize>,
    relayed: &'a mut Vec<Observation>,
    drop_key: u64,
    radio_key: u64,
    /// Dropout draws so far.
    draws: u64,
    /// The true states and the noise σ (where a relative relay's sender is placed).
    states: &'a [State9],
    sigma: &'a [f32; 9],
}

impl Picks for Noted<'_> {
    #[inline]
    fn kept(&mut self, p: f64) -> bool {
        if p <= 0.0 {
            return true;
        }
        self.draws += 1;
        bulk::uniform(self.drop_key, DROPOUT_DRAWS + self.draws) >= p
    }

    #[inline]
    fn delivered(&mut self, k: usize, radio: &RadioModel, bad: bool) -> bool {
        let k = k as u64;
        if radio.loss > 0.0 && bulk::uniform(self.radio_key, k) < radio.loss {
            return false;
        }
        // A receiver whose channel is in its bad state (bursty losses) loses each message with
        // `loss_bad` besides.
        match radio.burst {
            Some(ge) if bad && ge.loss_bad > 0.0 => bulk::uniform(self.radio_key, BURST_DRAWS + k) >= ge.loss_bad,
            _ => true,
        }
    }

    #[inline]
    fn onboard(&mut self, j: u32) {
        self.picked.push(j);
        *self.onboard += 1;
    }

    #[inline]
    fn heard(&mut self, k: usize, _m: &Message, _age_s: f64) {
        self.heard.push(k);
    }

    #[inline]
    fn relayed(&mut self, about: u32, state: State9, age_s: f64, source: ObservationSource) {
        self.relayed.push(Observation { id: UavId(about), state, age_s, source });
    }

    #[inline]
    fn close(&mut self, j: u32) {
        self.picked.push(j);
    }

    /// The noisy observation of `j` that [`build_observations`] draws afterwards (the same
    /// deviates of the UAV's sensing stream, drawn here for the one asked).
    #[inline]
    fn seen_onboard(&self, j: u32) -> Option<State9> {
        let n = self.picked[..*self.onboard].iter().position(|&p| p == j)?;
        Some(observed(&self.states[j as usize], self.sigma, self.drop_key, n))
    }
}

/// Fills `s.picked` (onboard, then close-range), `s.heard` (radio messages) and `s.relayed`
/// for UAV `i`, picked by the reference engine's sensor from the true geometry; returns the
/// radio reports it used.
// A phase of `proxform bench`'s instruction table: kept a function of its own.
#[inline(never)]
fn perceive(v: &View<'_>, i: usize, s: &mut Scratch) -> u16 {
    let sc = v.sc;
    let scene = Scene { states: v.states, grid: v.grid, search: NeighbourSearch::Grid, dependencies: v.dependencies };
    let channel_bad = !v.warm && v.env.get(i).is_some_and(|e| e.channel_bad);
    // The warm-up's ideal link, as the reference engine's.
    let (radio, dropout, reference_dropout) = match v.warm {
        true => (v.ideal, 0.0, sc.reference_dropout_set().unwrap_or(0.0)),
        false => (sc.radio(), sc.dropout(), sc.reference_dropout()),
    };
    let link = Link {
        active: v.active,
        dropout,
        reference_dropout,
        radio_up: v.warm || v.faults.radio_up,
        radio,
        messages: v.messages,
        reach: v.reach,
        delay_s: v.radio_delay_s(),
        channel_bad,
        onboard: true,
        fuse: false,
    };
    s.picked.clear();
    s.heard.clear();
    s.relayed.clear();
    s.onboard = 0;
    let mut noted = Noted {
        picked: &mut s.picked,
        onboard: &mut s.onboard,
        heard: &mut s.heard,
        relayed: &mut s.relayed,
        drop_key: bulk::key(&v.run, i as u64, Source::Sensing, v.draw_step),
        radio_key: bulk::key(&v.run, i as u64, Source::Radio, v.draw_step),
        draws: 0,
        states: v.states,
        sigma: &v.c.sigma,
    };
    v.sensor.pick(i, &scene, &link, &mut noted, &mut s.sensor);
    let radio_reports = s.heard.len() + s.relayed.iter().filter(|o| o.source == ObservationSource::Radio).count();
    if v.warm {
        0
    } else {
        radio_reports as u16
    }
}

/// The `n`-th noisy observation of a UAV's perception, of true state `truth`: deviates
/// `9n … 9n + 8` of its sensing stream `key`, as [`build_observations`] draws them in bulk.
fn observed(truth: &State9, sigma: &[f32; 9], key: u64, n: usize) -> State9 {
    let first = 9 * n;
    let mut z = [0.0f32; 10];
    bulk::normals(key, (first / 2) as u64, &mut z);
    perturbed(truth, sigma, &z[first % 2..first % 2 + 9])
}

// A phase of `proxform bench`'s instruction table: kept a function of its own.
#[inline(never)]
///
/// With relative sensing (`error`: the UAV's own measurement less its true state) what it
/// observes onboard is placed with its own measured state: the error moves every onboard and
/// close-range observation, and the position of a relay placed from its own view of the
/// sender (as the reference's sensing does).
fn build_observations(v: &View<'_>, i: usize, s: &mut Scratch, r_i: &[f64; 3], error: Option<&State9>) {
    let c = v.c;
    let onboard = s.onboard;
    let noisy = s.picked.len();
    s.normals.clear();
    s.normals.resize(9 * noisy, 0.0);
    bulk::normals(bulk::key(&v.run, i as u64, Source::Sensing, v.draw_step), 0, &mut s.normals);
    s.obs.clear();
    let observe = |j: u32, z: &[f32], source| {
        let mut st = perturbed(&v.states[j as usize], &c.sigma, z);
        for k in 0..3 {
            st[k] -= r_i[k];
        }
        Observation { id: UavId(j), state: st, age_s: 0.0, source }
    };
    for (n, &j) in s.picked[..onboard].iter().enumerate() {
        s.obs.push(observe(j, &s.normals[9 * n..9 * n + 9], ObservationSource::Onboard));
    }
    for &m in &s.heard {
        let msg = &v.messages[m];
        let mut st = msg.state;
        for k in 0..3 {
            st[k] -= r_i[k];
        }
        // Measured when it was sent: as old as the radio's delay on arrival.
        let age_s = msg.age_s + v.radio_delay_s();
        s.obs.push(Observation { id: UavId(msg.sender), state: st, age_s, source: ObservationSource::Radio });
    }
    for o in &s.relayed {
        let mut o = *o;
        for k in 0..3 {
            o.state[k] -= r_i[k];
        }
        s.obs.push(o);
    }
    for n in onboard..noisy {
        let j = s.picked[n];
        s.obs.push(observe(j, &s.normals[9 * n..9 * n + 9], ObservationSource::Close));
    }
    if let Some(e) = error {
        s.obs.iter_mut().for_each(|o| place_in_own_frame(o, e));
    }
}

/// The controller's step (METHOD §6) for UAV `i` at its own estimate `own` (relative to its
/// reference point, which lies at `r_i`), on its tracks: the reference controller's own step
/// ([`UavView::step`]) over the engine's records.
/// Its outcome is `Alone` when it perceives nothing (it flies on). Collision avoidance runs on
/// the thread's rule, with the UAV's memory (`kept`, only while it remembers a side) lent to
/// it.
fn decide(
    v: &View<'_>,
    i: usize,
    (own, r_i): (&State9, [f64; 3]),
    s: &mut Scratch,
    (tracks, trend): (Owner<'_>, Option<&mut TurnTrend>),
    kept: &mut Option<AvoidanceMemory>,
) -> Decision {
    let c = v.c;
    let sc = v.sc;
    let mut tracks = tracks;
    tracks.sweep(v.k, c.track_limit);
    let mut store = step_tracks(v, tracks, r_i);
    let Scratch { step, obs, avoid, .. } = s;
    // The thread's rule runs, with what this UAV remembers lent to it (it remembers nothing
    // between UAVs).
    if let (Some(av), Some(memory)) = (avoid.as_mut(), kept.as_mut()) {
        av.exchange_memory(memory);
    }
    let avoidance = avoid.as_mut();
    let uav = UavView {
        id: UavId(i as u32),
        setup: sc.agents().controller(),
        formation: v.formation,
        dependency: &v.dependencies[i],
        navigator: Some(v.leader),
        tracks: &mut store,
        avoidance,
        // Kept for a vehicle that lags its setpoints.
        trend,
    };
    let d = uav.step(step, f64::from(v.k) * c.dt, own, obs);
    // What it remembers now goes back to the UAV, kept while there is any (the rule is left
    // with the empty memory it lent, or none); nothing to do for a UAV that remembered
    // nothing and remembers nothing (most UAVs, most steps).
    if let Some(av) = avoid.as_mut().filter(|av| av.remembers() || kept.is_some()) {
        let mut memory = kept.take().unwrap_or_default();
        av.exchange_memory(&mut memory);
        *kept = memory.remembers().then_some(memory);
    }
    d
}
