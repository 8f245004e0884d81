//! The onboard proximity sensor: what one UAV perceives of the others at one instant.
//!
//! A UAV's sensors report, within the sensing range, the nearest UAV in each of its azimuth
//! areas (METHOD §2) and the main references it tracks, each with white measurement noise.
//! Areas are taken from the true relative geometry; the controller re-sorts the noisy reports
//! into its own areas. Candidates come from the neighbour grid, or from every UAV for the naive
//! all-pairs reference search.
//!
//! What is picked is decided once, for both engines ([`ProximitySensor::pick`]); what becomes of
//! a pick (an observation with its noise now, or a note whose noise is drawn in bulk later) and
//! where its chance comes from is the engine's ([`Picks`]).

use proxform_core::azimuth::AreaClassifier;
use proxform_core::controller::CloseWatch;
use proxform_core::grid::NeighbourGrid;
use proxform_core::state::{self, State9};
use proxform_core::{DependencySet, Observation, ObservationSource, UavId};
use proxform_scenario::radio::RadioModel;

use super::measurement::Message;
use super::options::NeighbourSearch;
use super::reach::Reach;
use crate::random::{StepRng, Ziggurat};

/// What every UAV's sensors look at in one step: the true states, the neighbour index over
/// them and how it is searched.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// True states, indexed by UAV.
    pub states: &'a [State9],
    /// The grid over the active UAVs' positions (used with [`NeighbourSearch::Grid`]).
    pub grid: &'a NeighbourGrid,
    /// How candidates are found.
    pub search: NeighbourSearch,
    /// Every UAV's dependency table: its sensor tracks its main references.
    pub dependencies: &'a [DependencySet],
}

/// The two random streams of one UAV's perception at one step.
#[derive(Debug, Clone)]
pub struct PerceptionDraws {
    /// Onboard noise and dropout.
    pub sensing: StepRng,
    /// Radio losses.
    pub radio: StepRng,
}

/// Per-thread working memory of the sensor.
#[derive(Debug, Clone)]
pub struct SensorScratch {
    /// Nearest candidate per area: squared distance (∞ when empty) and id.
    best_d2: Vec<f64>,
    best_id: Vec<u32>,
    /// Main references found in range.
    refs: Vec<u32>,
    /// UAVs within the watch radius (collision avoidance's close-range detections).
    close: Vec<u32>,
    /// Messages within radio range ([`Reach::for_each`]).
    heard: Vec<u32>,
    /// Per UAV, whether this perception already holds an observation of it (any, or onboard):
    /// equal to `stamp` when it does (a number per perception, so nothing is cleared).
    seen_any: Vec<u32>,
    seen_onboard: Vec<u32>,
    stamp: u32,
}

impl SensorScratch {
    /// A new perception's stamp, the per-UAV marks sized for `n` UAVs.
    #[inline]
    fn next_stamp(&mut self, n: usize) -> u32 {
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.seen_any.fill(0);
            self.seen_onboard.fill(0);
            self.stamp = 1;
        }
        if self.seen_any.len() < n {
            self.seen_any.resize(n, 0);
            self.seen_onboard.resize(n, 0);
        }
        self.stamp
    }

    /// Scratch for `m` areas.
    pub fn new(m: usize) -> Self {
        Self {
            best_d2: vec![f64::INFINITY; m],
            best_id: vec![0; m],
            refs: Vec::with_capacity(8),
            close: Vec::with_capacity(8),
            heard: Vec::new(),
            seen_any: Vec::new(),
            seen_onboard: Vec::new(),
            stamp: 0,
        }
    }
}

/// The sensor model shared by all UAVs of a scenario.
#[derive(Debug, Clone)]
pub struct ProximitySensor {
    classifier: AreaClassifier,
    range_m: f64,
    sigma: State9,
    /// Which UAVs are also reported as close-range detections for collision avoidance.
    watch: CloseWatch,
}

impl ProximitySensor {
    /// The sensor of scenario `sc`'s UAVs: its areas, range and noise, watching for collision
    /// avoidance where the method avoids.
    pub fn of(sc: &proxform_scenario::Scenario) -> Self {
        let areas = &sc.controller().areas;
        Self::new(areas.areas, areas.sensing_range_m, sc.noise().sigma()).with_watch(super::engine::close_watch(sc))
    }

    /// A sensor with `m` areas, range `range_m` and noise σ per parameter.
    pub fn new(m: usize, range_m: f64, sigma: State9) -> Self {
        Self { classifier: AreaClassifier::new(m), range_m, sigma, watch: CloseWatch::default() }
    }

    /// The same sensor also reporting the UAVs `watch` sees (within its range) as close-range
    /// detections ([`ObservationSource::Close`]): collision avoidance must see a UAV hidden
    /// behind another in its azimuth area, and one closing fast from afar.
    pub fn with_watch(mut self, watch: CloseWatch) -> Self {
        self.watch = watch;
        self
    }

    /// For a step in which no two UAVs move relative to each other faster than
    /// `max_relative_mps` ([`CloseWatch::for_speeds`]).
    pub fn set_speeds(&mut self, max_relative_mps: f64) {
        self.watch = self.watch.for_speeds(max_relative_mps);
    }

    /// Appends to `out` what UAV `i` perceives of `scene` through `link`: each pick observed
    /// at once, with noise and chance from `draws` (the reference engine's perception).
    #[inline(never)] // a phase of `proxform bench`'s instruction table
    pub fn perceive(
        &self,
        i: usize,
        scene: &Scene<'_>,
        link: &Link<'_>,
        draws: &mut PerceptionDraws,
        scratch: &mut SensorScratch,
        out: &mut Vec<Observation>,
    ) {
        let start = out.len();
        let mut observe = Observe { sensor: self, states: scene.states, draws, out, start };
        self.pick(i, scene, link, &mut observe, scratch);
    }

    /// What UAV `i`'s sensors pick of `scene` through `link`, told to `picks` in the order of
    /// the reports (METHOD §2): the nearest UAV of each azimuth area, then its main references
    /// not among them, each surviving its dropout; the radio messages in range that survive
    /// the channel, from UAVs not perceived onboard (every one, where its tracks fuse), and the
    /// freshest relay of the navigator; then the close-range detections not reported onboard.
    /// Both engines' perception: `picks` observes each pick (with its own noise and chance).
    pub fn pick(
        &self,
        i: usize,
        scene: &Scene<'_>,
        link: &Link<'_>,
        picks: &mut impl Picks,
        scratch: &mut SensorScratch,
    ) {
        let states = scene.states;
        let deps = &scene.dependencies[i];
        let me = &states[i];
        let (sin_yaw, cos_yaw) = me[state::BETA].sin_cos();
        scratch.best_d2.iter_mut().for_each(|d| *d = f64::INFINITY);
        scratch.refs.clear();
        scratch.close.clear();
        let mut nearest = Nearest {
            sensor: self,
            i,
            states,
            sin_cos_yaw: (sin_yaw, cos_yaw),
            best_d2: &mut scratch.best_d2,
            best_id: &mut scratch.best_id,
            close: &mut scratch.close,
        };
        let p = [me[0], me[1], me[2]];
        match scene.search {
            // A method that reads the radio only scans no neighbours.
            _ if !link.onboard => {}
            NeighbourSearch::Grid => {
                scene.grid.for_each_within(p, self.range_m, |j, q, d2| nearest.consider(j, q, d2));
            }
            NeighbourSearch::AllPairs => {
                let r2 = self.range_m * self.range_m;
                for (j, s) in states.iter().enumerate() {
                    if !link.active[j] {
                        continue;
                    }
                    let q = [s[0], s[1], s[2]];
                    let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
                    if d2 <= r2 {
                        nearest.consider(j as u32, &q, d2);
                    }
                }
            }
        }
        // Main references within range (the sensor tracks them), when onboard sensing is used.
        let r2 = self.range_m * self.range_m;
        let tracked = if link.onboard { deps.refs() } else { &[] };
        for &(id, _) in tracked {
            let Some(q) = states.get(id.index()) else { continue };
            if !link.active[id.index()] {
                continue;
            }
            let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
            if id.index() != i && d2 <= r2 {
                scratch.refs.push(id.0);
            }
        }
        // Deterministic report order: areas in order, then references by id.
        scratch.refs.sort_unstable();
        // What this perception holds already, by UAV (a lookup per message and detection: a
        // search of the reports made broadcast to all cubic in the swarm's size).
        let n = states.len();
        let stamp = scratch.next_stamp(n);
        // Observations of main references are lost with their own probability.
        let loss = |j: u32| {
            if link.reference_dropout != link.dropout && deps.refs().iter().any(|r| r.0 .0 == j) {
                link.reference_dropout
            } else {
                link.dropout
            }
        };
        for a in 0..scratch.best_d2.len() {
            let j = scratch.best_id[a];
            if scratch.best_d2[a] < f64::INFINITY && picks.kept(loss(j)) {
                picks.onboard(j);
                scratch.seen_any[j as usize] = stamp;
                scratch.seen_onboard[j as usize] = stamp;
            }
        }
        for k in 0..scratch.refs.len() {
            let j = scratch.refs[k];
            let picked =
                (0..scratch.best_d2.len()).any(|a| scratch.best_d2[a] < f64::INFINITY && scratch.best_id[a] == j);
            if !picked && picks.kept(link.reference_dropout) {
                picks.onboard(j);
                scratch.seen_any[j as usize] = stamp;
                scratch.seen_onboard[j as usize] = stamp;
            }
        }
        // Messages heard over the radio (crate::radio), unless the sender is perceived onboard.
        // Of the relays (what others know of the navigator), the freshest heard counts, when
        // nothing fresher of the navigator came onboard or from the navigator itself.
        if link.radio_up {
            let radio = link.radio;
            let r2 = radio.range_m * radio.range_m;
            let mut relayed: Option<&Message> = None;
            let messages = link.messages;
            let (heard, seen_any, seen_onboard) = (&mut scratch.heard, &mut scratch.seen_any, &scratch.seen_onboard);
            link.reach.for_each(messages.len(), p, radio.range_m, heard, |k| {
                let m = &messages[k];
                let j = m.sender as usize;
                let about = m.about as usize;
                // (A relative relay is in the receiver's frame: only its own view of the UAV
                // makes it redundant, not a report in another's frame.)
                let seen = !link.fuse
                    && about < n
                    && match m.relative {
                        true => seen_onboard[about] == stamp,
                        false => seen_any[about] == stamp,
                    };
                if j == i || about == i || j >= n || about >= n || !link.active[j] || seen {
                    return;
                }
                let q = &m.at;
                let d2 = (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
                if d2 > r2 || !picks.delivered(k, radio, link.channel_bad) {
                    return;
                }
                if m.is_relay() {
                    // A relative relay can be placed only from the receiver's own view of its
                    // sender, in this period.
                    let placeable = !m.relative || picks.seen_onboard(m.sender).is_some();
                    if placeable && relayed.is_none_or(|r| m.age_s < r.age_s) {
                        relayed = Some(m);
                    }
                    return;
                }
                picks.heard(k, m, link.delay_s);
                seen_any[j] = stamp;
            });
            if let Some(m) = relayed {
                let age_s = link.delay_s + m.age_s;
                match picks.seen_onboard(m.sender).filter(|_| m.relative) {
                    // Relative: where the receiver sees the sender (moved back over the delay, to
                    // where it was when it sent), plus the relay's position relative to it then. In the receiver's frame, so
                    // the navigator's own broadcast (in its frame) neither stands for it nor
                    // hides it.
                    Some(seen) => {
                        let mut state = m.state;
                        for k in 0..3 {
                            state[state::X + k] += seen[state::X + k] - seen[state::VX + k] * link.delay_s;
                        }
                        picks.relayed(m.about, state, age_s, ObservationSource::Relayed);
                    }
                    // Unless something of the navigator came onboard or by radio already (its
                    // age is no more than the relay's).
                    None if scratch.seen_any[m.about as usize] != stamp => {
                        picks.relayed(m.about, m.state, age_s, ObservationSource::Radio);
                    }
                    None => {}
                }
            }
        }
        // Close-range detections for collision avoidance, after everything else (so that the
        // draws above are those of a sensor without them): every UAV within the watch radius
        // not already reported onboard, each with its own dropout and noise.
        if !scratch.close.is_empty() {
            scratch.close.sort_unstable();
            for k in 0..scratch.close.len() {
                let j = scratch.close[k];
                if scratch.seen_onboard[j as usize] != stamp && picks.kept(link.dropout) {
                    picks.close(j);
                }
            }
        }
    }
}

/// The scan of UAV `i`'s candidates: the nearest per azimuth area, and the ones the watch sees.
struct Nearest<'s> {
    sensor: &'s ProximitySensor,
    i: usize,
    states: &'s [State9],
    sin_cos_yaw: (f64, f64),
    best_d2: &'s mut [f64],
    best_id: &'s mut [u32],
    close: &'s mut Vec<u32>,
}

impl Nearest<'_> {
    /// Candidate `j` at `q`, `d2` (m²) from UAV `i` (inlined into each scan: a call per
    /// candidate cost more than its work).
    #[inline(always)]
    fn consider(&mut self, j: u32, q: &[f64; 3], d2: f64) {
        if j as usize == self.i {
            return;
        }
        let me = &self.states[self.i];
        let watch = &self.sensor.watch;
        if watch.may_see(d2) {
            let o = &self.states[j as usize];
            let w = [o[state::VX] - me[state::VX], o[state::VY] - me[state::VY], o[state::VZ] - me[state::VZ]];
            if watch.sees(d2, [q[0] - me[0], q[1] - me[1], q[2] - me[2]], w) {
                self.close.push(j);
            }
        }
        let (sin_yaw, cos_yaw) = self.sin_cos_yaw;
        let a = self.sensor.classifier.area(sin_yaw, cos_yaw, q[0] - me[0], q[1] - me[1]);
        // Branch-free keep-the-nearest: which candidate wins is data, not control flow.
        let better = d2 < self.best_d2[a];
        self.best_id[a] = if better { j } else { self.best_id[a] };
        self.best_d2[a] = if better { d2 } else { self.best_d2[a] };
    }
}

/// What a perception does with what the sensor picks ([`ProximitySensor::pick`]), and where
/// its chance comes from. The reference engine observes each pick at once, with noise from the
/// same stream as its dropout ([`Observe`]); the fast engine notes its picks and draws their
/// noise in bulk afterwards, its chances by counter.
pub trait Picks {
    /// Whether an onboard report survives a dropout of probability `p`.
    fn kept(&mut self, p: f64) -> bool;
    /// Whether message `k` (in range) reaches the receiver over `radio`, its channel in its
    /// bad state or not.
    fn delivered(&mut self, k: usize, radio: &RadioModel, bad: bool) -> bool;
    /// An onboard report of UAV `j`.
    fn onboard(&mut self, j: u32);
    /// Message `k`, `m`, heard: its sender's own state, `age_s` old on arrival.
    fn heard(&mut self, k: usize, m: &Message, age_s: f64);
    /// A relay of UAV `about` at `state`, `age_s` old, from `source` (radio, or placed from
    /// the receiver's own view of the relay's sender).
    fn relayed(&mut self, about: u32, state: State9, age_s: f64, source: ObservationSource);
    /// A close-range detection of UAV `j`.
    fn close(&mut self, j: u32);
    /// The state at which UAV `j` was reported onboard in this perception, if it was (where
    /// a relative relay of it is placed).
    fn seen_onboard(&self, j: u32) -> Option<State9>;
}

/// The reference engine's [`Picks`]: every pick observed at once, with the sensor's noise drawn
/// from the same stream as the dropout (so that a report's noise follows its survival),
/// appended to `out` after `start`.
struct Observe<'s, 'o> {
    sensor: &'s ProximitySensor,
    states: &'s [State9],
    draws: &'s mut PerceptionDraws,
    out: &'o mut Vec<Observation>,
    start: usize,
}

impl Picks for Observe<'_, '_> {
    #[inline]
    fn kept(&mut self, p: f64) -> bool {
        kept(p, &mut self.draws.sensing)
    }

    #[inline]
    fn delivered(&mut self, _k: usize, radio: &RadioModel, bad: bool) -> bool {
        super::radio::delivered(radio, bad, &mut self.draws.radio)
    }

    #[inline]
    fn onboard(&mut self, j: u32) {
        let o = self.sensor.observe(j, self.states, &mut self.draws.sensing);
        self.out.push(o);
    }

    #[inline]
    fn heard(&mut self, _k: usize, m: &Message, age_s: f64) {
        self.out.push(Observation { id: UavId(m.sender), state: m.state, age_s, source: ObservationSource::Radio });
    }

    #[inline]
    fn relayed(&mut self, about: u32, state: State9, age_s: f64, source: ObservationSource) {
        self.out.push(Observation { id: UavId(about), state, age_s, source });
    }

    #[inline]
    fn close(&mut self, j: u32) {
        let mut o = self.sensor.observe(j, self.states, &mut self.draws.sensing);
        o.source = ObservationSource::Close;
        self.out.push(o);
    }

    #[inline]
    fn seen_onboard(&self, j: u32) -> Option<State9> {
        onboard_of(&self.out[self.start..], j)
    }
}

impl ProximitySensor {
    // Kept a function of its own: `proxform bench`'s instruction table counts it as noise,
    // not perception.
    #[inline(never)]
    fn observe(&self, j: u32, states: &[State9], rng: &mut StepRng) -> Observation {
        Observation {
            id: UavId(j),
            state: noisy(&states[j as usize], &self.sigma, rng),
            age_s: 0.0,
            source: ObservationSource::Onboard,
        }
    }
}

/// What the links allow this step.
#[derive(Debug, Clone, Copy)]
pub struct Link<'a> {
    /// Which UAVs are flying (removed or not yet joined ones are not).
    pub active: &'a [bool],
    /// Probability that an onboard observation is lost.
    pub dropout: f64,
    /// Probability that an onboard observation of one of the receiver's main references is
    /// lost.
    pub reference_dropout: f64,
    /// False during a radio blackout.
    pub radio_up: bool,
    /// The radio model.
    pub radio: &'a RadioModel,

    /// The messages arriving now, in the order they are heard.
    pub messages: &'a [Message],
    /// Their index by sender position ([`super::reach`]).
    pub reach: &'a Reach,
    /// Age of a radio message on arrival (s).
    pub delay_s: f64,
    /// The receiver's Gilbert-Elliott channel is in its bad state.
    pub channel_bad: bool,
    /// Whether the receiver's tracks fuse every report of a UAV (a radio report beside its onboard
    /// detection is then passed too; otherwise the radio only fills in what onboard sensing
    /// missed).
    pub fuse: bool,
    /// Whether the receiver's controller uses onboard sensing (false: radio messages only;
    /// no neighbour is scanned).
    pub onboard: bool,
}

/// Draws whether an observation survives a dropout of probability `p`.
#[inline]
/// The state of UAV `sender` as `perceived` onboard in this period, if it was.
fn onboard_of(perceived: &[Observation], sender: u32) -> Option<State9> {
    perceived.iter().find(|o| o.id.0 == sender && o.source == ObservationSource::Onboard).map(|o| o.state)
}

fn kept(p: f64, rng: &mut StepRng) -> bool {
    p <= 0.0 || ((rng.next_u64() >> 11) as f64) / ((1u64 << 53) as f64) >= p
}

/// Relative sensing: what a UAV observed is placed in the world with its own measured state,
/// so its own measurement's `error` (measured less true state) moves every onboard and
/// close-range observation, and the position of a relay placed from its own view of the
/// relay's sender (its velocity and attitude are the relay's); radio reports are their
/// senders' own. Both engines' perception.
#[inline]
pub fn place_in_own_frame(o: &mut Observation, error: &State9) {
    match o.source {
        ObservationSource::Onboard | ObservationSource::Close => o.state += error,
        ObservationSource::Relayed => {
            for k in state::X..state::X + 3 {
                o.state[k] += error[k];
            }
        }
        ObservationSource::Radio => {}
    }
}

/// `x` plus white Gaussian noise of standard deviation `sigma` per parameter (a function of its
/// own: the noise is a phase of `proxform bench`'s instruction table).
#[inline(never)]
pub fn noisy(x: &State9, sigma: &State9, rng: &mut StepRng) -> State9 {
    let z = Ziggurat::get();
    let mut s = *x;
    for k in (0..8).step_by(2) {
        let (a, b) = z.pair(rng);
        s[k] += sigma[k] * a;
        s[k + 1] += sigma[k + 1] * b;
    }
    s[8] += sigma[8] * z.sample(rng);
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_core::state::{BETA, VX};
    use proxform_core::UavId;
    use proxform_scenario::radio::RadioModel;

    /// UAV 0 at the origin flying along x; UAVs 1 and 2 ahead in the same area (1 nearer),
    /// UAV 3 behind, UAV 4 out of range ahead; UAV 0 leans on UAV 2.
    fn setup() -> (Vec<State9>, Vec<DependencySet>) {
        let at = |x: f64, y: f64| {
            let mut s = State9::zeros();
            s[0] = x;
            s[1] = y;
            s[VX] = 50.0;
            s
        };
        let states = vec![at(0.0, 0.0), at(100.0, 1.0), at(200.0, 2.0), at(-150.0, 0.0), at(400.0, 0.0)];
        let mut deps = vec![DependencySet::default(); 5];
        deps[0] = DependencySet::new(UavId(0), 5, vec![(UavId(2), 1.0)]).expect("valid");
        (states, deps)
    }

    /// UAV `j`'s broadcast of its own (true) state.
    fn broadcast(states: &[State9], j: usize) -> Message {
        Message {
            sender: j as u32,
            about: j as u32,
            state: states[j],
            age_s: 0.0,
            at: [states[j][0], states[j][1], 0.0],
            relative: false,
        }
    }

    fn perceive(states: &[State9], deps: &[DependencySet], dropout: f64, messages: &[Message]) -> Vec<Observation> {
        perceive_fusing(states, deps, dropout, messages, false)
    }

    fn perceive_fusing(
        states: &[State9],
        deps: &[DependencySet],
        dropout: f64,
        messages: &[Message],
        fuse: bool,
    ) -> Vec<Observation> {
        perceive_watching(states, deps, dropout, messages, fuse, CloseWatch::default())
    }

    fn perceive_watching(
        states: &[State9],
        deps: &[DependencySet],
        dropout: f64,
        messages: &[Message],
        fuse: bool,
        watch: CloseWatch,
    ) -> Vec<Observation> {
        let sensor = ProximitySensor::new(8, 250.0, State9::zeros()).with_watch(watch);
        let mut grid = NeighbourGrid::new();
        grid.rebuild(states.iter().map(|s| [s[0], s[1], s[2]]), 250.0);
        let scene = Scene { states, grid: &grid, search: NeighbourSearch::Grid, dependencies: deps };
        let radio = RadioModel::default();
        let active = vec![true; states.len()];
        let link = Link {
            active: &active,
            dropout,
            reference_dropout: dropout,
            radio_up: true,
            radio: &radio,
            messages,
            reach: &Reach::new(),
            delay_s: 0.0,
            channel_bad: false,
            onboard: true,
            fuse,
        };
        let key = crate::random::RunKey::new(1, 0).at(0);
        let mut draws = PerceptionDraws {
            sensing: key.rng(0, crate::random::Source::Sensing),
            radio: key.rng(0, crate::random::Source::Radio),
        };
        let mut out =
            vec![Observation { id: UavId(99), state: State9::zeros(), age_s: 0.0, source: ObservationSource::Onboard }];
        sensor.perceive(0, &scene, &link, &mut draws, &mut SensorScratch::new(8), &mut out);
        assert_eq!(out[0].id, UavId(99), "perception appends");
        out.split_off(1)
    }

    #[test]
    fn a_watching_sensor_also_reports_a_close_uav_hidden_in_an_area_after_the_others() {
        // UAV 5 sits 30 m ahead, just behind UAV 1's line of sight: UAV 1 (100 m) is no longer
        // the nearest of that area, so put UAV 5 in UAV 1's area but farther than a new UAV 6.
        let (mut states, deps) = setup();
        let mut close = states[1];
        close[0] = 30.0;
        close[1] = 0.5;
        let mut nearer = states[1];
        nearer[0] = 20.0;
        nearer[1] = 0.2;
        states.push(close);
        states.push(nearer);
        let deps = [deps, vec![DependencySet::default(); 2]].concat();
        let plain = perceive_watching(&states, &deps, 0.0, &[], false, CloseWatch::default());
        assert!(!plain.iter().any(|o| o.id.0 == 5), "hidden behind UAV 6 in its area");
        // Avoidance distance 25 m: every UAV within 50 m is reported.
        let watch = CloseWatch::new(25.0, 2.5, 0.1, 250.0);
        let watching = perceive_watching(&states, &deps, 0.0, &[], false, watch);
        // The same reports first (the same draws), then the close one.
        assert_eq!(&watching[..plain.len()], &plain[..]);
        let extra: Vec<_> = watching[plain.len()..].iter().map(|o| (o.id.0, o.source)).collect();
        assert_eq!(extra, vec![(5, ObservationSource::Close)]);
    }

    #[test]
    fn a_watching_sensor_reports_a_hidden_uav_closing_fast_from_afar() {
        // UAV 5, 200 m ahead behind UAV 6 in the same area: reported once it closes fast
        // enough for the avoidance to need it, not while it keeps its distance or flies away.
        let (mut states, deps) = setup();
        let mut far = states[1];
        far[0] = 200.0;
        far[1] = 1.0;
        let mut nearer = states[1];
        nearer[0] = 20.0;
        nearer[1] = 0.1;
        states.push(far);
        states.push(nearer);
        let deps = [deps, vec![DependencySet::default(); 2]].concat();
        let watch = CloseWatch::new(25.0, 2.5, 0.1, 250.0);
        let closing = |speed: f64| {
            let mut s = states.clone();
            s[5][state::VX] -= speed;
            perceive_watching(&s, &deps, 0.0, &[], false, watch).iter().any(|o| o.id.0 == 5)
        };
        // Doubled closing speed c: reported when c²/(2·2.5) exceeds the room 200 − 25 − c·0.1.
        assert!(closing(40.0), "80²/5 = 1280 m > 167 m");
        assert!(closing(20.0), "40²/5 = 320 m > 171 m");
        assert!(!closing(10.0), "20²/5 = 80 m < 173 m");
        assert!(!closing(2.0) && !closing(0.0) && !closing(-20.0), "slow, steady or opening");
    }

    #[test]
    fn it_sees_the_nearest_per_area_and_its_references_within_range() {
        let (states, deps) = setup();
        let seen = perceive(&states, &deps, 0.0, &[]);
        let ids: Vec<u32> = seen.iter().map(|o| o.id.0).collect();
        // Areas in order, counted clockwise from the nose (3 behind in area 4, 1 just left of
        // the nose in area 7), then the reference 2; never 4 (out of range).
        assert_eq!(ids, vec![3, 1, 2]);
        assert!(seen.iter().all(|o| o.source == ObservationSource::Onboard && o.state == states[o.id.index()]));
        // A radio message of a UAV seen onboard is not counted twice; one of a UAV out of
        // range is heard.
        let message = |j: usize| broadcast(&states, j);
        let heard = perceive(&states, &deps, 0.0, &[message(1), message(4)]);
        let radio: Vec<u32> = heard.iter().filter(|o| o.source == ObservationSource::Radio).map(|o| o.id.0).collect();
        assert_eq!(radio, vec![4]);
        // A tracker that fuses gets the radio report of a UAV it also detects onboard.
        let fused = perceive_fusing(&states, &deps, 0.0, &[message(1), message(4)], true);
        let radio: Vec<u32> = fused.iter().filter(|o| o.source == ObservationSource::Radio).map(|o| o.id.0).collect();
        assert_eq!(radio, vec![1, 4]);
        // Everything onboard lost: only the radio is left.
        assert!(perceive(&states, &deps, 1.0, &[]).is_empty());
        // Turned around, the same neighbours fall in other areas.
        let mut turned = states.clone();
        turned[0][BETA] = std::f64::consts::PI;
        assert_eq!(perceive(&turned, &deps, 0.0, &[]).len(), 3);
    }

    #[test]
    fn of_the_relays_the_freshest_counts_unless_something_fresher_came() {
        let (states, deps) = setup();
        // UAVs 1 and 3 forward what they know of UAV 4 (out of range of UAV 0's sensors).
        let relay = |sender: usize, about: usize, age_s: f64| {
            let mut state = states[about];
            state[1] += age_s; // tells the reports apart
            Message {
                sender: sender as u32,
                about: about as u32,
                state,
                age_s,
                at: [states[sender][0], states[sender][1], 0.0],
                relative: false,
            }
        };
        let of_4 = |heard: &[Observation]| -> Vec<(f64, f64)> {
            heard.iter().filter(|o| o.id.0 == 4).map(|o| (o.age_s, o.state[1] - states[4][1])).collect()
        };
        let heard = perceive(&states, &deps, 0.0, &[relay(1, 4, 0.3), relay(3, 4, 0.1)]);
        assert_eq!(of_4(&heard), vec![(0.1, 0.1)], "{heard:?}");
        assert!(heard.iter().filter(|o| o.id.0 == 4).all(|o| o.source == ObservationSource::Radio));
        // UAV 4's own message is fresher: the relays add nothing.
        let own = broadcast(&states, 4);
        assert_eq!(of_4(&perceive(&states, &deps, 0.0, &[own, relay(3, 4, 0.1)])), vec![(0.0, 0.0)]);
        // A relay about a UAV seen onboard, or about the receiver itself, adds nothing.
        let heard = perceive(&states, &deps, 0.0, &[relay(3, 1, 0.2), relay(3, 0, 0.2)]);
        assert_eq!(heard.len(), 3, "{heard:?}");
        assert!(heard.iter().all(|o| o.source == ObservationSource::Onboard));
    }

    #[test]
    fn a_relative_relay_is_placed_by_the_receivers_own_view_of_its_sender() {
        let (states, deps) = setup();
        // UAV 3 (seen onboard by UAV 0) says where UAV 4 is relative to itself, as it was
        // 0.1 s ago; UAV 4's own broadcast is in its own frame.
        let offset = [30.0, -5.0, 2.0];
        let mut relative = states[4];
        for k in 0..3 {
            relative[k] = offset[k];
        }
        let relay = |sender: usize, age_s: f64| Message {
            sender: sender as u32,
            about: 4,
            state: relative,
            age_s,
            at: [states[sender][0], states[sender][1], 0.0],
            relative: true,
        };
        let own = broadcast(&states, 4);
        let heard = perceive(&states, &deps, 0.0, &[own, relay(3, 0.1)]);
        let placed: Vec<&Observation> = heard.iter().filter(|o| o.source == ObservationSource::Relayed).collect();
        assert_eq!(placed.len(), 1, "{heard:?}");
        let (o, seen) = (placed[0], states[3]);
        assert_eq!((o.id, o.age_s), (UavId(4), 0.1));
        for k in 0..3 {
            // Where UAV 0 sees UAV 3 (moved back over the radio's delay, none here: the offset
            // is relative to the sender when it sent, not when the navigator was measured),
            // plus the offset.
            let want = seen[k] + offset[k];
            assert!((o.state[k] - want).abs() < 1e-9, "axis {k}: {} against {want}", o.state[k]);
        }
        // The broadcast is heard beside it (the controller leaves out what is not in its frame).
        assert!(heard.iter().any(|o| o.id.0 == 4 && o.source == ObservationSource::Radio));
        // From a sender the receiver does not see onboard (every detection lost), a relative
        // relay cannot be placed and is not heard.
        let unseen = perceive(&states, &deps, 1.0, &[relay(3, 0.1)]);
        assert!(unseen.is_empty(), "{unseen:?}");
    }
}
