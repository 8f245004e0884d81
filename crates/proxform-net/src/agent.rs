//! The agent loop: the core's [`Agent`] of each UAV a process runs, over a [`Vehicle`].
//!
//! - **Lockstep** (and the warm-up of any flight): every update the vehicle delivers is
//!   stepped at once and answered, as the simulator steps it (a lockstep flight is the
//!   in-process flight, bit for bit).
//! - **Own clock** (a real-time flight): the agent never waits on a request. It keeps the
//!   latest update of its UAV (its own state and what it perceived onboard) and the latest
//!   report of every broadcaster ([`AgentRadio`]: agent to agent over the network, not through
//!   the world), and decides at its own period on the newest it has: when a new own update is
//!   there and at least nine tenths of a period passed since its last decision (once a
//!   period, whatever rate its updates come at: an autopilot reports at tens of hertz). Every
//!   observation is brought to the instant of the own state (its age from the times the
//!   messages carry), and when the command will act a period or more after its update, over
//!   that lead as the mission plan moves (`bridge_the_lead`: the network's latency, not the
//!   method's to predict); an own update older than [`STALE_AFTER_PERIODS`] periods on the
//!   shared clock is not stepped on (the UAV keeps its last command, which the world or the
//!   autopilot holds); a backlog (an agent that was stopped) is skipped to its newest. A
//!   neighbour whose agent has
//!   broadcast nothing for [`crate::watch::SILENT_AFTER_PERIODS`] periods flies uncontrolled
//!   ([`ControlWatch`]): it is avoided, not followed.
//!
//! A new run starts a fresh agent; the first flight update after a warm-up makes the agent
//! forget its own-state estimate (as the simulator does at t = 0). Whatever arrives is checked
//! first: an update with a non-finite own state is not stepped, observations of unknown UAVs,
//! of the UAV itself or with non-finite numbers are dropped.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use proxform_core::{Agent, Observation, UavId};
use proxform_scenario::Scenario;

use crate::link::LinkEstimate;
use crate::radio::AgentRadio;
use crate::transport::TransportError;
use crate::vehicle::{Answer, Event, Vehicle};
use crate::watch::ControlWatch;
use crate::wire::{
    ClockMode, CommandMsg, Phase, Presence, SenseMsg, StateMsg, COMMAND_WINDOW_PERIODS, STALE_AFTER_PERIODS,
};

/// A UAV that cannot be run from this scenario.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum HostError {
    /// Not in the formation.
    #[error("UAV {uav}: the scenario has UAVs 1 to {size}")]
    Unknown {
        /// The UAV (from 1).
        uav: u32,
        /// UAVs of the scenario.
        size: usize,
    },
    /// The navigator flies its path and runs no controller.
    #[error("UAV {0} is the navigator: it flies its path and runs no controller")]
    Navigator(u32),
}

/// On the own clock an agent decides at most once in this many periods (a little under one:
/// updates that come once a period with some jitter are each decided on).
pub const MIN_DECISION_PERIODS: f64 = 0.9;

/// An agent rejoining (back after more than [`STALE_AFTER_PERIODS`] periods without a decision:
/// stopped, cut off, restarted mid-flight) is back once a decision finds its course-keeping
/// state inside its envelope, or both its position within `Σ (g/Δ)² ≤` this of where its
/// neighbours place it ([`proxform_core::Decision::gap_sq`]) and its whole state (velocity
/// and attitude too) within `Σ ((X − O)/Δ)² ≤` this of its envelope's centre: one
/// permissible error. Until then its broadcasts say it is rejoining and the others do not
/// follow it (wherever its uncontrolled flight took it, they would be drawn there; followed
/// as soon as its position was back, its attitude, still pitched from the way back, pitched
/// them all 2-4° out of 0.4°; followed within three permissible errors, those leaning on it
/// took up what was left: the paper with one agent cut off 10 s, pitch 0.44° of 0.4° in 2 of
/// 5 runs, none of the same 5 within one).
pub const REJOINED_GAP_SQ: f64 = 1.0;

struct Hosted {
    agent: Agent,
    run: u32,
    flying: bool,
    /// Own clock: the newest update not stepped on yet.
    pending: Option<SenseMsg>,
    /// Own clock: when the agent last decided, and the run and time of the update it decided on.
    decided: Option<Instant>,
    last: Option<(u32, f64)>,
    /// The instant the agent last stepped at (s).
    stepped_t_s: Option<f64>,
    /// Lockstep: the newest update answered (run, in flight, step): each is stepped on once,
    /// in order (a replayed or older one would step the agent twice).
    answered: Option<(u32, bool, u64)>,
    /// Own clock: its latest decisions and the instants they act at (the commands on their way).
    in_flight: std::collections::VecDeque<(f64, proxform_core::Decision)>,
    /// What it runs ([`setup_digest`]), carried by its commands and announcements.
    digest: u64,
    /// Own clock: back after flying without decisions, and not yet near its slot
    /// ([`REJOINED_GAP_SQ`]).
    rejoining: bool,
}

/// What a process's agents refused, skipped and left out ([`Host::counts`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    /// Observations dropped as invalid.
    pub dropped: u64,
    /// Updates not stepped (invalid own state, unknown UAV).
    pub refused: u64,
    /// Own clock: updates replaced by a newer one before a decision.
    pub skipped: u64,
    /// Own clock: updates too old to step on.
    pub stale: u64,
    /// Own clock: observations of silent neighbours avoided but not followed.
    pub unfollowed: u64,
    /// Own clock: broadcasts kept by the radio, not taken, and lost to the scenario's radio
    /// loss.
    pub radio: (u64, u64, u64),
}

/// The agents of the UAVs one process runs.
pub struct Host {
    scenario: Arc<Scenario>,
    agents: BTreeMap<u32, Hosted>,
    heard: Vec<Observation>,
    /// The formation's radio, heard on the own clock.
    radio: AgentRadio,
    /// Which neighbours fly under their agents, from their broadcasts (own clock).
    watch: ControlWatch,
    /// Own clock: how long a command takes back to the world, from the updates' ages.
    link: LinkEstimate,
    radio_run: u32,
    /// Observations dropped as invalid.
    pub dropped: u64,
    /// Updates not stepped (invalid own state, unknown UAV).
    pub refused: u64,
    /// Own clock: updates replaced by a newer one before the agent decided (a backlog skipped).
    pub skipped: u64,
    /// Own clock: updates too old to step on ([`STALE_AFTER_PERIODS`]).
    pub stale: u64,
}

impl Host {
    /// Agents for `uavs` (from 1) of `scenario`.
    pub fn new(scenario: Arc<Scenario>, uavs: &[u32]) -> Result<Self, HostError> {
        let mut agents = BTreeMap::new();
        for &u in uavs {
            let id = Self::follower(&scenario, u)?;
            let digest = setup_digest(&scenario, u);
            let hosted = Hosted {
                agent: scenario.agent(id),
                run: 0,
                flying: false,
                pending: None,
                decided: None,
                last: None,
                stepped_t_s: None,
                answered: None,
                in_flight: Default::default(),
                digest,
                rejoining: false,
            };
            agents.insert(u, hosted);
        }
        let (radio, watch) = (AgentRadio::new(&scenario), ControlWatch::new(&scenario));
        Ok(Self {
            scenario,
            agents,
            heard: Vec::new(),
            radio,
            watch,
            link: LinkEstimate::default(),
            radio_run: 0,
            dropped: 0,
            refused: 0,
            skipped: 0,
            stale: 0,
        })
    }

    /// The UAVs whose broadcasts these agents hear on their own clock (from 1): every other
    /// follower's (whether its agent is there) and the broadcasters' (the radio).
    pub fn listens_to(&self) -> Vec<u32> {
        let nav = self.scenario.navigator().0 + 1;
        let broadcasters = self.radio.broadcasters();
        (1..=self.scenario.len() as u32)
            .filter(|u| (*u != nav || broadcasters.contains(u)) && !self.agents.contains_key(u))
            .collect()
    }

    /// A broadcast heard (own clock).
    pub fn hear(&mut self, m: &StateMsg) {
        self.watch.hear(m);
        // The scenario's radio loss is drawn per receiving process (its first UAV).
        let me = self.agents.keys().next().map_or(0, |u| *u as usize - 1);
        self.radio.hear(me, m);
    }

    /// What the agents refused, skipped and left out.
    pub fn counts(&self) -> Counts {
        Counts {
            dropped: self.dropped,
            refused: self.refused,
            skipped: self.skipped,
            stale: self.stale,
            unfollowed: self.watch.unfollowed,
            radio: (self.radio.heard, self.radio.ignored, self.radio.lost),
        }
    }

    /// Own clock: keeps `s` as its UAV's newest update (an older one not yet stepped on is
    /// skipped; one older than the last stepped on is ignored).
    pub fn keep(&mut self, s: SenseMsg) {
        let Some(h) = self.agents.get_mut(&s.uav) else {
            self.refused += 1;
            return;
        };
        let older = |run: u32, t_s: f64| run == s.run && t_s >= s.t_s;
        if h.last.is_some_and(|(run, t)| older(run, t)) {
            self.skipped += 1;
            return;
        }
        match &h.pending {
            Some(p) if older(p.run, p.t_s) => self.skipped += 1,
            Some(_) => {
                self.skipped += 1;
                h.pending = Some(s);
            }
            None => h.pending = Some(s),
        }
    }

    /// Own clock: the decisions due at `now` (a hosted UAV with a new update and at least
    /// [`MIN_DECISION_PERIODS`] of a period since its last decision), each with the state it broadcasts; `age_of` gives an
    /// update's age on the shared clock (s).
    pub fn decide_due(&mut self, now: Instant, age_of: impl Fn(&SenseMsg) -> f64) -> Vec<Answer> {
        let half = Duration::from_secs_f64(MIN_DECISION_PERIODS * self.scenario.dt_s());
        let due: Vec<u32> = self
            .agents
            .iter()
            .filter(|(_, h)| h.pending.is_some() && h.decided.is_none_or(|d| now.duration_since(d) >= half))
            .map(|(u, _)| *u)
            .collect();
        let mut out = Vec::new();
        for u in due {
            let Some(s) = self.agents.get_mut(&u).and_then(|h| h.pending.take()) else { continue };
            let age = age_of(&s);
            if age > STALE_AFTER_PERIODS * self.scenario.dt_s() {
                self.stale += 1;
                continue;
            }
            self.link.observe(age);
            let way_back = self.link.way_back_s();
            if s.run != self.radio_run {
                self.radio.clear();
                self.watch.clear();
                self.radio_run = s.run;
            }
            if let Some(answer) = self.step(&s, age, Some(way_back)) {
                if let Some(h) = self.agents.get_mut(&u) {
                    (h.decided, h.last) = (Some(now), Some((s.run, s.t_s)));
                }
                out.push(answer);
            }
        }
        out
    }

    fn follower(sc: &Scenario, uav: u32) -> Result<UavId, HostError> {
        if uav == 0 || uav as usize > sc.len() {
            return Err(HostError::Unknown { uav, size: sc.len() });
        }
        let id = UavId(uav - 1);
        if id == sc.navigator() {
            return Err(HostError::Navigator(uav));
        }
        Ok(id)
    }

    /// The UAVs run, from 1.
    pub fn uavs(&self) -> Vec<u32> {
        self.agents.keys().copied().collect()
    }

    /// The UAVs run (from 1), each with the digest of what its agent runs, as announced.
    pub fn members(&self) -> Vec<(u32, u64)> {
        self.agents.iter().map(|(u, h)| (*u, h.digest)).collect()
    }

    /// Steps the agent of `s.uav` on the update, which reached it `latency_s` after it was
    /// measured (0 in lockstep); its command and the state it broadcasts, or None when the
    /// update is not for this host or not valid.
    ///
    /// Each update is answered once, in order: one not newer than the last answered (in run,
    /// warm-up before flight, and step) is skipped.
    ///
    /// The agent steps at the update's time t_s: its own state and its observations were
    /// measured together then, and their ages are relative to that instant (a neighbour
    /// predicted to a later instant than the own state would be compared with a state that
    /// is not there: at 70 m/s, 1 ms is 7 cm). The latency is reported with the command; what
    /// it costs is a decision that reaches the vehicle too late for its period.
    pub fn handle(&mut self, s: &SenseMsg, latency_s: f64) -> Option<Answer> {
        if let Some(h) = self.agents.get_mut(&s.uav) {
            let at = (s.run, s.phase == Phase::Fly, s.k);
            if h.answered.is_some_and(|last| at <= last) {
                // Stepped on already (a replay), or older than one that was.
                self.skipped += 1;
                return None;
            }
            h.answered = Some(at);
        }
        self.step(s, latency_s, None)
    }

    /// Steps on `s`, `latency_s` old on the shared clock: in lockstep (`way_back_s` None) at the
    /// update's instant; on the own clock, its command expected to take `way_back_s` to the
    /// world, at the instant it will act, with what it heard of the broadcasters.
    fn step(&mut self, s: &SenseMsg, latency_s: f64, way_back_s: Option<f64>) -> Option<Answer> {
        let own_clock = way_back_s.is_some();
        let n = self.scenario.len();
        let Some(h) = self.agents.get_mut(&s.uav) else {
            self.refused += 1;
            return None;
        };
        if !s.t_s.is_finite() || s.own.iter().any(|v| !v.is_finite()) {
            self.refused += 1;
            return None;
        }
        if s.run != h.run {
            h.agent = self.scenario.agent(UavId(s.uav - 1));
            (h.run, h.flying, h.stepped_t_s, h.rejoining) = (s.run, false, None, false);
            h.in_flight.clear();
        }
        if s.phase == Phase::Fly && !h.flying {
            h.flying = true;
            h.agent.forget_own_estimate();
        }
        self.heard.clear();
        for o in &s.heard {
            let valid = o.id.index() < n
                && o.id.0 != s.uav - 1
                && o.age_s.is_finite()
                && o.age_s >= 0.0
                && o.state.iter().all(|v| v.is_finite());
            match valid {
                true => self.heard.push(*o),
                false => self.dropped += 1,
            }
        }
        let latency_s = if latency_s.is_finite() { latency_s.max(0.0) } else { 0.0 };
        let (t_s, own) = match way_back_s {
            // In lockstep the agent steps at the update's instant, as the simulator does.
            None => (s.t_s, s.own),
            // On its own clock, for the instant its command will act ([`acts_at`]). The update
            // and what it perceived are brought forward to it, what it heard to the same instant.
            Some(way_back_s) => {
                let dt = self.scenario.dt_s();
                let t_s = acts_at(s.t_s, latency_s + way_back_s, dt);
                if t_s - s.t_s > STALE_AFTER_PERIODS * dt + 1e-9 {
                    // Its command would act on a state too old to act on.
                    self.stale += 1;
                    return None;
                }
                if h.stepped_t_s.is_some_and(|t| t_s <= t + 0.5 * dt) {
                    // A command for that period is already on its way.
                    self.skipped += 1;
                    return None;
                }
                // Back after flying without decisions (or started in the middle of a flight).
                let since = h.stepped_t_s.unwrap_or(0.0);
                if s.phase == Phase::Fly && s.t_s - since > STALE_AFTER_PERIODS * dt + 1e-9 {
                    h.rejoining = true;
                }
                // Through the commands that act before it (holding where none was sent).
                let periods = ((t_s - s.t_s) / dt).round() as usize;
                let mut own = s.own;
                for p in 0..periods {
                    let at = s.t_s + p as f64 * dt;
                    let d = h.in_flight.iter().find(|(t, _)| (t - at).abs() < 0.5 * dt).map(|(_, d)| d);
                    own = h.agent.predict_period(&own, d);
                }
                let age = t_s - s.t_s;
                for o in &mut self.heard {
                    o.age_s += age;
                }
                self.radio.observations(UavId(s.uav - 1), t_s, &own, &mut self.heard);
                bridge_the_lead(&self.scenario, &mut self.heard, t_s, age);
                // Silence is judged at the update's own instant (a neighbour's last broadcast
                // is of an update like this one), not at the instant the command will act.
                self.watch.leave_out_the_unfollowed(s.t_s, &mut self.heard, h.rejoining);
                (t_s, own)
            }
        };
        let decision = h.agent.step(t_s, &own, &self.heard);
        let back = match decision.outcome {
            proxform_core::Outcome::Held => true,
            proxform_core::Outcome::Adjusted { normalised_sq } => {
                decision.gap_sq <= REJOINED_GAP_SQ && normalised_sq <= REJOINED_GAP_SQ
            }
            proxform_core::Outcome::Alone => false,
        };
        h.rejoining &= !back;
        if own_clock {
            let dt = self.scenario.dt_s();
            h.in_flight.retain(|(t, _)| *t > s.t_s - 0.5 * dt);
            h.in_flight.push_back((t_s, decision));
            while h.in_flight.len() > STALE_AFTER_PERIODS as usize + 1 {
                h.in_flight.pop_front();
            }
        }
        h.stepped_t_s = Some(t_s);
        let command = CommandMsg { uav: s.uav, run: s.run, k: s.k, t_s, age_s: latency_s, decision, digest: h.digest };
        let state = StateMsg { uav: s.uav, k: s.k, t_s: s.t_s, state: s.own, rejoining: h.rejoining };
        Some(Answer { command, state, decided_at: own })
    }
}

/// The lead, from an update to the instant its command acts (`age`, s), is the network's,
/// not the method's to predict: what was heard is brought over it by the mission plan
/// ([`proxform_core::plan`]), and the method predicts from there as in process. With
/// `plan_forward` on, the tracks already carry every report beyond a period by the plan
/// (through its age) and nothing is done here; with the paper's prediction
/// (`plan_forward = false`) a report's tracked rates would otherwise carry it over the lead
/// too, and a rear rank falls behind the navigator's manoeuvres by a period per rank
/// (measured: 40 ± 20 ms each way failed the paper in 5 of 5 runs). Without a plan the
/// tracks carry the lead as they carry any age.
fn bridge_the_lead(scenario: &Scenario, heard: &mut [Observation], t_s: f64, age: f64) {
    let setup = scenario.agents().controller();
    let frame = scenario.formation_at(t_s).frame;
    if age <= 0.0 || setup.carry(frame).is_some() {
        return;
    }
    let Some(carry) = setup.carry_by_plan(frame) else { return };
    for o in heard {
        let bridge = o.age_s.min(age);
        let measured = t_s - o.age_s;
        o.state = carry.carry(&o.state, measured, measured + bridge);
        o.age_s -= bridge;
    }
}

/// A digest of what UAV `uav`'s (from 1) agent runs in `scenario`: everything its agent is
/// built from (its controller and vehicle, the formation and its tables, the plan, the
/// schedule), as this version of the library builds it. A world takes an agent only when the
/// digest it announces is the one of the world's own scenario for that UAV, so an agent that
/// read another file (or the same one with other settings) flies nothing. 64-bit FNV-1a over the
/// agent's full description (floats as written back exactly).
pub fn setup_digest(scenario: &Scenario, uav: u32) -> u64 {
    let description = match uav.checked_sub(1) {
        Some(i) if (i as usize) < scenario.len() => format!("{:?}", scenario.agent(UavId(i))),
        _ => String::new(),
    };
    description.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// The instant a command decided on an update measured at `t_s` (a step's time) will act at,
/// when the update's way out and the command's way back take `round_trip_s` together (the way
/// back as [`LinkEstimate`] expects it): the world applies it from the step whose window
/// ([`crate::wire::COMMAND_WINDOW_PERIODS`]) it reaches in: `t_s` itself while the round trip
/// fits in the window (the world waits for it: no lag at all), a later step's time otherwise.
pub fn acts_at(t_s: f64, round_trip_s: f64, dt_s: f64) -> f64 {
    let late = round_trip_s - COMMAND_WINDOW_PERIODS * dt_s;
    match late > 0.0 {
        true => t_s + (late / dt_s).ceil() * dt_s,
        false => t_s,
    }
}

fn unix_ns() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64)
}

/// A pass of the agent's loop this much longer than its longest wait
/// (`Timing::announce_every`) means its process was stopped, not that the world fell silent.
const STOPPED_AFTER: Duration = Duration::from_secs(2);

/// How long an agent waits.
#[derive(Debug, Clone, Copy)]
pub struct Timing {
    /// Exit when nothing arrived for this long (the world is gone): no orphan agent.
    pub idle_exit: Duration,
    /// Announce presence this often while idle.
    pub announce_every: Duration,
}

impl Default for Timing {
    fn default() -> Self {
        Self { idle_exit: Duration::from_secs(30), announce_every: Duration::from_millis(500) }
    }
}

/// Why the loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// The world said the batch is over.
    Done,
    /// Nothing arrived for [`Timing::idle_exit`].
    Idle,
}

/// Runs `host`'s agents over `vehicle` until the world ends the batch or goes silent: in
/// lockstep (and in any warm-up) each update is answered at once; in a real-time flight each
/// agent decides on its own clock (see the module's text).
pub fn serve(host: &mut Host, vehicle: &mut impl Vehicle, timing: Timing) -> Result<Ended, TransportError> {
    vehicle.announce(Presence::Alive)?;
    let (mut last_heard, mut last_announce) = (Instant::now(), Instant::now());
    // In real time, the wall-clock time of t = 0 (ns since the Unix epoch), from the clock.
    let mut epoch_ns: Option<u64> = None;
    let mut listening = false;
    // The own clock looks at what it has a few times a period.
    let tick = Duration::from_secs_f64(0.25 * host.scenario.dt_s()).min(timing.announce_every);
    let age = |epoch_ns: Option<u64>, s: &SenseMsg| match (epoch_ns, s.phase) {
        (Some(e), Phase::Fly) => (unix_ns() as f64 - e as f64) * 1e-9 - s.t_s,
        _ => 0.0,
    };
    let mut awake = Instant::now();
    loop {
        // A pass takes at most the wait below and its work; one that took seconds means this
        // process was stopped (or starved): that silence was its own, not the world's, and it
        // does not count toward leaving (a 10 s stop made it leave at once on resuming).
        let gap = awake.elapsed();
        if gap > timing.announce_every + STOPPED_AFTER {
            last_heard = (last_heard + gap).min(Instant::now());
        }
        awake = Instant::now();
        let own_clock = epoch_ns.is_some();
        let mut event = vehicle.next(if own_clock { tick } else { timing.announce_every })?;
        // Everything that is waiting, before deciding: the newest counts.
        loop {
            match event {
                Event::Idle => break,
                Event::Sense(s) => {
                    last_heard = Instant::now();
                    if epoch_ns.is_some() && s.phase == Phase::Fly {
                        host.keep(s);
                    } else if let Some(answer) = host.handle(&s, age(epoch_ns, &s)) {
                        vehicle.command(&answer)?;
                    }
                }
                Event::State(m) => host.hear(&m),
                Event::Clock(c) => {
                    last_heard = Instant::now();
                    if c.mode == ClockMode::RealTime && !listening {
                        // A real-time flight: its agents hear each other (in its warm-up).
                        vehicle.listen(&host.listens_to())?;
                        listening = true;
                    }
                    epoch_ns = (c.mode == ClockMode::RealTime && c.epoch_ns > 0).then_some(c.epoch_ns);
                    if c.end {
                        vehicle.announce(Presence::Leaving)?;
                        return Ok(Ended::Done);
                    }
                }
            }
            event = vehicle.next(Duration::ZERO)?;
        }
        for answer in host.decide_due(Instant::now(), |s| age(epoch_ns, s)) {
            vehicle.command(&answer)?;
        }
        if last_heard.elapsed() >= timing.idle_exit {
            return Ok(Ended::Idle);
        }
        if last_announce.elapsed() >= timing.announce_every {
            vehicle.announce(Presence::Alive)?;
            last_announce = Instant::now();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_core::state::{self, State9};

    #[test]
    fn a_command_acts_at_the_step_whose_window_it_reaches() {
        // Δt 0.1 s, window 0.09 s: a round trip within it acts at the update's own step.
        assert_eq!(acts_at(2.0, 0.0, 0.1), 2.0);
        assert_eq!(acts_at(2.0, 0.088, 0.1), 2.0);
        assert!((acts_at(2.0, 0.12, 0.1) - 2.1).abs() < 1e-12);
        assert!((acts_at(2.0, 0.4, 0.1) - 2.4).abs() < 1e-12);
    }

    fn paper() -> Arc<Scenario> {
        let spec = proxform_scenario::builtin::spec_by_name("paper", None).expect("built in");
        Arc::new(Scenario::try_from(spec).expect("valid"))
    }

    fn update(sc: &Scenario, uav: u32, k: u64) -> SenseMsg {
        let t_s = k as f64 * sc.dt_s();
        let nav =
            proxform_core::state::State9::from_column_slice(&[20.0 * t_s, 0.0, 100.0, 20.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
        SenseMsg { uav, run: 0, phase: Phase::Fly, k, t_s, own: sc.slot_state((uav - 1) as usize, &nav), heard: vec![] }
    }

    #[test]
    fn in_lockstep_each_update_is_answered_once_and_in_order() {
        let sc = paper();
        let mut host = Host::new(sc.clone(), &[2]).expect("a follower");
        let first = host.handle(&update(&sc, 2, 10), 0.0).expect("answered");
        // A replay of it, or an older one, steps nothing; the next one is answered.
        assert!(host.handle(&update(&sc, 2, 10), 0.0).is_none());
        assert!(host.handle(&update(&sc, 2, 9), 0.0).is_none());
        assert_eq!(host.counts().skipped, 2);
        let next = host.handle(&update(&sc, 2, 11), 0.0).expect("answered");
        assert_eq!((first.command.k, next.command.k), (10, 11));
        // A warm-up update of the next run comes after the flight's last.
        let warm = SenseMsg { run: 1, phase: Phase::Warm, k: 0, ..update(&sc, 2, 0) };
        assert!(host.handle(&warm, 0.0).is_some());
        assert!(host.handle(&update(&sc, 2, 12), 0.0).is_none(), "the earlier run's");
    }

    #[test]
    fn on_its_own_clock_it_decides_on_the_newest_once_a_period_and_never_on_stale_updates() {
        let sc = paper();
        let mut host = Host::new(sc.clone(), &[2]).expect("a follower");
        let now = Instant::now();
        // A backlog of three updates: the newest only is stepped on.
        for k in 10..13 {
            host.keep(update(&sc, 2, k));
        }
        let out = host.decide_due(now, |_| 0.0);
        assert_eq!(out.len(), 1);
        assert_eq!((out[0].command.k, host.counts().skipped), (12, 2));
        // An older update after it is not stepped on; nothing new, nothing decided.
        host.keep(update(&sc, 2, 11));
        assert!(host.decide_due(now + Duration::from_millis(100), |_| 0.0).is_empty());
        // The next one, within nine tenths of a period of the last decision: not yet; after: yes.
        host.keep(update(&sc, 2, 13));
        assert!(host.decide_due(now + Duration::from_millis(60), |_| 0.0).is_empty());
        assert_eq!(host.decide_due(now + Duration::from_millis(95), |_| 0.0).len(), 1);
        // An update older than five periods on the shared clock is not stepped on.
        host.keep(update(&sc, 2, 14));
        assert!(host.decide_due(now + Duration::from_millis(200), |_| 0.51).is_empty());
        assert_eq!(host.counts().stale, 1);
    }

    #[test]
    fn back_after_a_gap_an_agent_says_it_is_rejoining_until_it_is_near_its_slot_again() {
        let sc = paper();
        let mut host = Host::new(sc.clone(), &[2]).expect("a follower");
        // Its update at step k, `dy` m off its slot, with the navigator on its path and UAV 3
        // in its slot.
        let at = |k: u64, dy: f64| {
            let t_s = k as f64 * sc.dt_s();
            let s0 = sc.initial()[0];
            let nav = sc.path().state_at(t_s, [s0[0], s0[1], s0[2]]);
            let mut own = sc.slot_state(1, &nav);
            own[state::Y] += dy;
            let seen = |id: u32, state| Observation {
                id: UavId(id),
                state,
                age_s: 0.0,
                source: proxform_core::ObservationSource::Onboard,
            };
            let heard = vec![seen(0, nav), seen(2, sc.slot_state(2, &nav))];
            SenseMsg { uav: 2, run: 0, phase: Phase::Fly, k, t_s, own, heard }
        };
        let t0 = Instant::now();
        let mut decide = |k: u64, dy: f64, after_ms: u64| {
            host.keep(at(k, dy));
            let out = host.decide_due(t0 + Duration::from_millis(after_ms), |_| 0.0);
            out[0].state.rejoining
        };
        for k in 0..5 {
            assert!(!decide(k, 0.0, 100 * k), "in its slot from the start");
        }
        // Three seconds without a decision (its agent was stopped), 20 m off: rejoining.
        assert!(decide(35, 20.0, 600));
        assert!(decide(36, 15.0, 700), "still far");
        assert!(!decide(37, 0.0, 800), "back in its slot");
    }

    #[test]
    fn a_late_round_trip_decides_for_the_next_step_through_the_command_on_its_way() {
        let sc = paper();
        let dt = sc.dt_s();
        let mut host = Host::new(sc.clone(), &[2]).expect("a follower");
        let t0 = Instant::now();
        host.keep(update(&sc, 2, 10));
        let first = host.decide_due(t0, |_| 0.06);
        // 2 × 60 ms is past the 90 ms window: the command acts one step later, at 1.1 s.
        assert!((first[0].command.t_s - 1.1).abs() < 1e-9, "{:?}", first[0].command);
        // The next update's own state is brought through that command to 1.2 s.
        let mut u = update(&sc, 2, 11);
        u.own[state::VY] += 0.3;
        host.keep(u.clone());
        let second = host.decide_due(t0 + Duration::from_millis(100), |_| 0.06);
        assert!((second[0].command.t_s - (1.1 + dt)).abs() < 1e-9);
        // Decided at that state: what an autopilot's absolute targets start from.
        let through = sc.agent(UavId(1)).predict_period(&u.own, Some(&first[0].command.decision));
        assert_eq!(second[0].decided_at, through);
        assert_ne!(second[0].decided_at, u.own);
        // A quick update after slow ones: its command is expected back as slowly as they came
        // (40 ms out and 60 ms back is past the window), so it is decided for the next step, not
        // for one it would miss (taken as symmetric, 80 ms, it was decided for its own step).
        let mut quick = update(&sc, 2, 12);
        quick.own[state::VY] += 0.3;
        host.keep(quick);
        let third = host.decide_due(t0 + Duration::from_millis(200), |_| 0.04);
        assert!((third[0].command.t_s - (1.2 + dt)).abs() < 1e-9, "{:?}", third[0].command);
        // Lockstep steps on the update's own instant.
        let mut lock = Host::new(sc.clone(), &[2]).expect("a follower");
        let a = lock.handle(&u, 0.06).expect("stepped");
        assert_eq!((a.command.t_s, a.decided_at), (u.t_s, u.own));
    }

    #[test]
    fn with_the_papers_prediction_what_was_heard_is_brought_over_the_lead_by_the_plan() {
        let sc = paper();
        let (dt, nav) = (sc.dt_s(), sc.navigator());
        let plan = sc.agents().controller().plan().expect("the paper's UAVs know the plan").clone();
        // The navigator in its lateral manoeuvre, seen onboard at the update (10.5 s) and heard
        // over the radio 0.15 s before; the command acts a period later.
        let (t, lead) = (10.5, dt);
        let onboard = Observation {
            id: nav,
            state: plan.state_at(t),
            age_s: lead,
            source: proxform_core::ObservationSource::Onboard,
        };
        let radio = Observation { state: plan.state_at(t - 0.15), age_s: 0.15 + lead, ..onboard };
        let mut heard = vec![onboard, radio];
        bridge_the_lead(&sc, &mut heard, t + lead, lead);
        let near = |a: &State9, b: &State9| (a - b).amax() < 1e-9;
        assert!(near(&heard[0].state, &plan.state_at(t + lead)), "{:?}", heard[0].state);
        assert!(heard[0].age_s.abs() < 1e-12, "the lead is bridged, its age at the update is left");
        assert!(near(&heard[1].state, &plan.state_at(t - 0.15 + lead)));
        assert!((heard[1].age_s - 0.15).abs() < 1e-12);
        // Not the track's rates: the manoeuvre turns the velocity within the lead.
        let mut by_rates = onboard.state;
        for k in 0..3 {
            by_rates[state::X + k] += lead * by_rates[state::VX + k];
        }
        assert!(!near(&heard[0].state, &by_rates), "the plan accelerates at 10.5 s");
        // With plan_forward on, the tracks carry reports by the plan through their ages.
        let mut spec = proxform_scenario::builtin::spec_by_name("paper", None).expect("built in");
        spec.controller.plan_forward = Some(true);
        let planned = Scenario::try_from(spec).expect("valid");
        let mut same = vec![onboard, radio];
        bridge_the_lead(&planned, &mut same, t + lead, lead);
        assert_eq!(same, vec![onboard, radio]);
    }
}
