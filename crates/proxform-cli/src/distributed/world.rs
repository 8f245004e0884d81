//! The world's side of a distributed flight: the engine's followers are agents reached over
//! Zenoh ([`NetAgents`] implements the simulator's `Agents`).
//!
//! - **Lockstep**: each update period the world sends every active follower what it sensed,
//!   waits for the decisions of the live agents until all have answered or the step's deadline
//!   passed (a late or missing answer counts as holding), publishes the navigator's state and
//!   its clock, and goes on. The flight is the in-process flight, bit for bit.
//! - **Real time** (the agents on their own clocks): step k begins at its wall-clock time; the
//!   world sends each follower what its sensors give (its own state and what it perceives
//!   onboard: the radio goes agent to agent), then applies, until the end of the period, each
//!   UAV's newest command due at the step (one decided for a later step waits for its step
//!   instead of replacing one for this step), whatever update it answered, if it is at most
//!   [`COMMAND_MAX_AGE_PERIODS`] periods old; while none comes the UAV holds (a multirotor
//!   keeps its last setpoint, as its autopilot would). A world that falls a period or more
//!   behind its clock (a stall of its machine) does not replay the missed steps: the flight's
//!   time pauses, the clock's epoch moves by the stall, and the agents read it from the clock.

use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{bail, Result};
use proxform_core::{Decision, ObservationSource, Setpoint};
use proxform_net::keys::Swarm;
use proxform_net::transport::{Inbox, LivelinessInbox, Publisher, Received, Session};
use proxform_net::wire::{self, ClockMode, ClockMsg, Message, Presence, SenseMsg, StateMsg};
use proxform_scenario::{NetworkFaults, Scenario};
use proxform_sim::world::remote::{holding, Agents, Phase, StepRequest};

use super::pending::{Offered, Pending};

/// How long an agent stays live without a word (its heartbeat comes every 0.5 s).
const LIVE_FOR: Duration = Duration::from_millis(2000);

/// Real time: a command older than this many periods when its step comes is not applied, and a
/// UAV without one for longer flies uncontrolled.
const COMMAND_MAX_AGE_PERIODS: f64 = wire::STALE_AFTER_PERIODS;

/// Real time: a UAV without a command for this long (s) is in its autopilot's failsafe (PX4's
/// offboard-loss timeout, `COM_OF_LOSS_T`, 1 s by default); uncontrolled before that, it holds
/// its course.
const FAILSAFE_AFTER_S: f64 = 1.0;

/// What the world measured of the network.
#[derive(Debug, Clone, Default)]
pub struct NetStats {
    /// Decisions received in time.
    pub answered: u64,
    /// Decisions that did not come in time (held instead).
    pub missing: u64,
    /// Answers that came after their step (discarded).
    pub late: u64,
    /// Undecodable messages.
    pub garbage: u64,
    /// Of those, messages not sealed with the flight's key ([`proxform_net::seal`]): from a
    /// process without it (an agent started without `--flight-key`, or an outsider).
    pub unsealed: u64,
    /// Messages on another UAV's key than their own (a Command for UAV 3 put on UAV 2's key):
    /// never taken.
    pub misplaced: u64,
    /// Decisions refused: a non-finite number (also counted as missing), far beyond what the
    /// vehicle can do in a period (the world's check, [`Agents::refused`]), or for an instant
    /// ahead of the flight. The UAV holds instead.
    pub refused: u64,
    /// Round trips (send of a step's first sense message to each answer), seconds.
    pub round_trips_s: Vec<f64>,
    /// How old each update was when its agent stepped (s; real time only).
    pub ages_s: Vec<f64>,
    /// Flight steps the world began later than their wall-clock time by more than a tenth of
    /// a period (real time only).
    pub late_steps: u64,
    /// Flight steps (real time only).
    pub steps: u64,
    /// Times the world fell a period or more behind its clock and paused the flight's time
    /// instead of replaying the missed steps, and the time paused (s; real time only).
    pub paused: (u64, f64),
    /// Real time: how old each applied command was when its step came (s).
    pub applied_ages_s: Vec<f64>,
    /// Messages lost to the scenario's `[network]` faults.
    pub dropped: u64,
    /// Announcements of agents that run another scenario than the world's (their UAVs are
    /// not theirs to fly).
    pub foreign: u64,
    /// Messages the world's inbox dropped, full (a flood).
    pub inbox_dropped: u64,
    /// UAVs (from 1) that more than one agent process announced itself for at once, with
    /// their process ids: their commands compete (each is applied when it is the newest).
    pub twins: BTreeMap<u32, BTreeSet<u32>>,
    /// The UAVs' MAVLink systems, when served.
    pub mavlink: Option<super::mavlink::MavlinkStats>,
    /// When each UAV's agent said it was rejoining (back after flying without decisions), by
    /// UAV (from 1): the flight times (s) it began and, once it was near its slot again, ended.
    pub rejoins: BTreeMap<u32, Vec<(f64, Option<f64>)>>,
}

/// Real time: the wall-clock instant of the flight's t = 0 (moved by the world's pauses),
/// shared by the world's agents and its telemetry.
#[derive(Debug, Clone, Default)]
pub struct FlightClock(std::rc::Rc<std::cell::Cell<Option<Instant>>>);

impl FlightClock {
    fn get(&self) -> Option<Instant> {
        self.0.get()
    }

    fn set(&self, start: Instant) {
        self.0.set(Some(start));
    }

    /// Waits until the flight's time `t_s` (at most `limit`): a simulated UAV says where it is
    /// when it is there, not as soon as the world has computed it (its next state is ready
    /// most of a period early).
    pub fn wait_until(&self, t_s: f64, limit: Duration) {
        if let Some(start) = self.get() {
            let due = start + Duration::from_secs_f64(t_s.max(0.0));
            let wait = due.saturating_duration_since(Instant::now()).min(limit);
            if !wait.is_zero() {
                std::thread::sleep(wait);
            }
        }
    }
}

/// Followers whose agents answer over the network.
pub struct NetAgents {
    session: Session,
    swarm: Swarm,
    sense: BTreeMap<u32, Publisher>,
    clock: Publisher,
    inbox: Inbox,
    dt_s: f64,
    deadline: Duration,
    mode: ClockMode,
    /// Real time: the wall-clock instant of t = 0 (shared with the telemetry, which says where
    /// a UAV is only once it is there).
    start: FlightClock,
    /// The scenario's transport faults, and the seed their draws are keyed by.
    faults: (NetworkFaults, u64),
    /// Messages the transport faults dropped.
    pub dropped: u64,
    /// When each agent last said anything.
    seen: BTreeMap<u32, Instant>,
    /// The agents' liveliness tokens, and which are alive.
    tokens: LivelinessInbox,
    alive: BTreeSet<u32>,
    epoch_ns: u64,
    /// The network's numbers.
    pub stats: NetStats,
    answers: Vec<Option<Decision>>,
    /// Real time: per UAV (from 1) of the current run, the newest command received and not yet
    /// applied, the time of the update the last applied one answered, and the last setpoint
    /// applied.
    own_clock: BTreeMap<u32, OwnClock>,
    own_clock_run: u32,
    /// Real time: the time of the current flight step (s).
    own_clock_t_s: f64,
    /// When the last Clock before the flight went out ([`NetAgents::keep_alive`]).
    alive_sent: Option<Instant>,
    /// The digest of what each follower's agent must run (from the world's scenario), and the
    /// UAVs whose agent last announced another.
    digests: BTreeMap<u32, u64>,
    foreign: BTreeMap<u32, u64>,
    /// Per UAV, the agent processes (ids) that announced themselves alive, and when last.
    announced: BTreeMap<u32, BTreeMap<u32, Instant>>,
    /// Real time: updates and commands held by the scenario's `[network] delay_s`, due in order.
    in_transit: std::collections::VecDeque<(Instant, Message)>,
}

#[derive(Debug, Clone, Default)]
struct OwnClock {
    /// Commands received and not yet applied, by the instant they act at.
    pending: Pending,
    applied_t_s: Option<f64>,
    /// The flight time of the update the command applied this step was decided on (None:
    /// none applied).
    decided_on_t_s: Option<f64>,
    setpoint: Option<Setpoint>,
    /// Steps in a row without a command to apply.
    held_periods: u32,
}

impl NetAgents {
    /// The world's end of `swarm` on `session` for `scenario`'s followers; `deadline` bounds
    /// one step's wait in lockstep; in real time a step waits until the end of its period.
    pub fn new(
        session: Session,
        swarm: Swarm,
        scenario: &Scenario,
        (mode, deadline, seed): (ClockMode, Duration, u64),
    ) -> Result<Self> {
        let navigator = scenario.navigator().0 + 1;
        let followers: Vec<u32> = (1..=scenario.len() as u32).filter(|u| *u != navigator).collect();
        let sense = followers.iter().map(|u| Ok((*u, session.publisher(&swarm.sense(*u))?))).collect::<Result<_>>()?;
        // The agents' broadcasts too: they say when an agent is rejoining.
        let inbox = session.inbox(&[swarm.all_commands(), swarm.all_members(), swarm.all_states()])?;
        let tokens = session.liveliness(&swarm.all_alive())?;
        Ok(Self {
            clock: session.publisher(&swarm.clock())?,
            sense,
            inbox,
            session,
            swarm,
            dt_s: scenario.dt_s(),
            deadline,
            mode,
            start: FlightClock::default(),
            faults: (*scenario.network(), seed),
            dropped: 0,
            seen: BTreeMap::new(),
            tokens,
            alive: BTreeSet::new(),
            epoch_ns: 0,
            stats: NetStats::default(),
            answers: Vec::new(),
            own_clock: BTreeMap::new(),
            own_clock_run: 0,
            own_clock_t_s: 0.0,
            alive_sent: None,
            digests: followers.iter().map(|u| (*u, proxform_net::agent::setup_digest(scenario, *u))).collect(),
            foreign: BTreeMap::new(),
            announced: BTreeMap::new(),
            in_transit: std::collections::VecDeque::new(),
        })
    }

    /// Waits until every one of `uavs` has announced itself (at most `timeout`); `alive` is
    /// asked every 100 ms and may end the wait with an error (an agent process that exited).
    pub fn wait_for(&mut self, uavs: &[u32], timeout: Duration, alive: &mut dyn FnMut() -> Result<()>) -> Result<()> {
        let start = Instant::now();
        loop {
            self.drain();
            let missing: Vec<u32> = uavs.iter().copied().filter(|u| !self.live(*u)).collect();
            if missing.is_empty() {
                return Ok(());
            }
            alive()?;
            self.keep_alive();
            if start.elapsed() > timeout {
                let foreign: Vec<String> = missing
                    .iter()
                    .filter_map(|u| self.foreign.get(u).map(|d| format!("UAV {u}'s agent runs {d:016x}")))
                    .collect();
                if !foreign.is_empty() {
                    bail!(
                        "no agent announced UAV(s) {missing:?} within {:.0} s: agents of another scenario were \
                         refused ({}; this world's scenario needs {}): start them with the world's scenario file \
                         and settings",
                        timeout.as_secs_f64(),
                        foreign.join(", "),
                        missing
                            .iter()
                            .filter_map(|u| self.digests.get(u).map(|d| format!("UAV {u} {d:016x}")))
                            .collect::<Vec<_>>()
                            .join(", ")
                    );
                }
                if self.stats.unsealed > 0 {
                    bail!(
                        "no agent announced UAV(s) {missing:?} within {:.0} s; {} message(s) came not sealed with this \
                         flight's key: start the agents with the world's --flight-key FILE",
                        timeout.as_secs_f64(),
                        self.stats.unsealed
                    );
                }
                bail!("no agent announced UAV(s) {missing:?} within {:.0} s", timeout.as_secs_f64());
            }
            if let Some(r) = self.inbox.recv_timeout(Duration::from_millis(100)) {
                self.note(r);
            }
        }
    }

    /// Books a message that is not an answer to the current step.
    fn note(&mut self, r: Received) {
        match r {
            Received::Message(_, Message::Member(m)) if self.digests.get(&m.uav) != Some(&m.digest) => {
                // Another scenario's agent (or not a follower): its UAV is not its to fly, and it
                // says nothing of the agent that flies it.
                self.stats.foreign += 1;
                self.foreign.insert(m.uav, m.digest);
            }
            Received::Message(_, Message::Member(m)) => {
                let now = Instant::now();
                let pids = self.announced.entry(m.uav).or_default();
                match m.presence {
                    Presence::Alive => {
                        self.seen.insert(m.uav, now);
                        pids.insert(m.pid, now);
                    }
                    Presence::Leaving => {
                        self.seen.remove(&m.uav);
                        pids.remove(&m.pid);
                    }
                };
                // Another process alive for the same UAV (each announces every 0.5 s).
                pids.retain(|_, t| now.duration_since(*t) <= LIVE_FOR);
                if pids.len() > 1 {
                    self.stats.twins.entry(m.uav).or_default().extend(pids.keys());
                }
            }
            Received::Message(_, Message::Command(c)) if self.digests.get(&c.uav) != Some(&c.digest) => {
                self.stats.foreign += 1;
            }
            Received::Message(_, Message::Command(c))
                if self.mode == ClockMode::RealTime && self.start.get().is_some() =>
            {
                self.seen.insert(c.uav, Instant::now());
                // Whatever its way in, a command comes after the transport's delay.
                let delay = Duration::from_secs_f64(self.faults.0.delay_s);
                match delay.is_zero() {
                    true => self.offer(c),
                    false => self.in_transit.push_back((Instant::now() + delay, Message::Command(c))),
                }
            }
            Received::Message(_, Message::Command(c)) => {
                // Late, or an old one again: no sign of an agent flying now.
                let _ = c;
                self.stats.late += 1;
            }
            Received::Message(_, Message::State(m)) if self.digests.contains_key(&m.uav) => self.rejoining(&m),
            Received::Message(..) => {}
            Received::Garbage(_, e) => {
                self.stats.garbage += 1;
                self.stats.unsealed += u64::from(e == proxform_net::wire::codec::DecodeError::Unsealed);
            }
            Received::Misplaced(..) => self.stats.misplaced += 1,
        }
    }

    /// Whether the transport loses the message of step `request` to (direction 0) or from
    /// (1) UAV `uav`'s agent.
    fn lost(&mut self, request: &StepRequest<'_>, uav: u32, direction: u64) -> bool {
        let (faults, seed) = self.faults;
        if faults.loss <= 0.0 {
            return false;
        }
        let phase = u64::from(request.phase == Phase::Fly);
        let lost = uniform([seed, request.run, request.k * 2 + phase, u64::from(uav), direction]) < faults.loss;
        self.dropped += u64::from(lost);
        lost
    }

    fn drain(&mut self) {
        while let Some(r) = self.inbox.try_recv() {
            self.note(r);
        }
        while let Some(l) = self.tokens.try_recv() {
            if let Some(uav) = l.key.rsplit('/').next().and_then(|n| n.parse::<u32>().ok()) {
                match l.alive {
                    true => self.alive.insert(uav),
                    false => {
                        // Its process is gone: what it announced no longer counts (a restarted
                        // agent is not a second one).
                        self.announced.remove(&uav);
                        self.alive.remove(&uav)
                    }
                };
            }
        }
    }

    /// Notes when UAV `m.uav`'s broadcasts begin and stop saying it is rejoining.
    fn rejoining(&mut self, m: &StateMsg) {
        let spans = self.stats.rejoins.entry(m.uav).or_default();
        let open = spans.last().is_some_and(|(_, end)| end.is_none());
        match (m.rejoining, open) {
            (true, false) => spans.push((m.t_s, None)),
            (false, true) => {
                if let Some(last) = spans.last_mut() {
                    last.1 = Some(m.t_s);
                }
            }
            _ => {}
        }
        if spans.is_empty() {
            self.stats.rejoins.remove(&m.uav);
        }
    }

    /// An agent is live while its liveliness token is (gone at once when its process dies)
    /// and it has said something lately (a hung agent goes silent).
    fn live(&self, uav: u32) -> bool {
        self.alive.contains(&uav) && self.seen.get(&uav).is_some_and(|t| t.elapsed() < LIVE_FOR)
    }

    /// Before the flight, a Clock once a second (no time yet): the agents that came early hear
    /// the world is there, and do not leave as if it were gone (`--idle-exit-s`).
    pub fn keep_alive(&mut self) {
        if self.alive_sent.is_some_and(|t| t.elapsed() < Duration::from_secs(1)) {
            return;
        }
        self.alive_sent = Some(Instant::now());
        let clock = ClockMsg { mode: self.mode, run: 0, k: 0, t_s: 0.0, dt_s: self.dt_s, epoch_ns: 0, end: false };
        let _ = self.clock.send(&Message::Clock(clock));
    }

    /// Tells every agent that the batch is over.
    pub fn end(&self, run: u64) -> Result<()> {
        let clock = ClockMsg {
            mode: self.mode,
            run: run as u32,
            k: 0,
            t_s: 0.0,
            dt_s: self.dt_s,
            epoch_ns: self.epoch_ns,
            end: true,
        };
        self.clock.send(&Message::Clock(clock))?;
        Ok(())
    }

    /// The session (for closing).
    pub fn into_session(self) -> Session {
        self.session
    }

    /// Messages dropped by the world's inbox, full.
    pub fn inbox_dropped(&self) -> u64 {
        self.inbox.dropped()
    }

    /// The flight's clock (real time).
    pub fn clock(&self) -> FlightClock {
        self.start.clone()
    }

    /// The swarm's name.
    pub fn swarm(&self) -> &Swarm {
        &self.swarm
    }
}

/// A uniform draw in [0, 1) keyed by the words of `key` (SplitMix64 over them): the transport
/// faults of a lockstep run are the same whatever the machine does.
fn uniform(key: [u64; 5]) -> f64 {
    let mut z = 0x9E37_79B9_7F4A_7C15u64;
    for w in key {
        z = z.wrapping_add(w).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    (z >> 11) as f64 / (1u64 << 53) as f64
}

fn now_ns() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64)
}

impl NetAgents {
    /// Real time: a command received; kept when it is the newest of its UAV for the current
    /// run and answers an update after the last applied one.
    fn offer(&mut self, c: wire::CommandMsg) {
        if c.run != self.own_clock_run {
            self.stats.late += 1;
            return;
        }
        // A command for an instant far ahead of the flight (or none) would stand as the newest
        // and keep every later one out: it is no command.
        if !(c.t_s.is_finite() && c.t_s <= self.own_clock_t_s + COMMAND_MAX_AGE_PERIODS * self.dt_s + 1e-9) {
            self.stats.refused += 1;
            return;
        }
        if !c.decision.is_finite() {
            self.stats.refused += 1;
            return;
        }
        let slot = self.own_clock.entry(c.uav).or_default();
        if slot.pending.offer(c, slot.applied_t_s) != Offered::Kept {
            self.stats.late += 1;
        }
    }

    /// Real time, the flight: step k begins at its wall-clock time (or the flight's time
    /// pauses, when the world fell a period behind), the sensors' updates go out, and each
    /// UAV's newest command is applied when it comes within the period (see the module's text).
    /// The scenario's `[network] delay_s` holds each update and each command for that long on
    /// its way (queued, never slept: a delay longer than the period makes the commands older,
    /// not the world slower).
    fn decide_own_clock(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        let s = request.sensed;
        let run = request.run as u32;
        self.own_clock_t_s = request.t_s;
        if request.k == 0 {
            // t = 0 a little ahead, so that every agent has the clock before the first update.
            let lead = Duration::from_millis(200);
            self.start.set(Instant::now() + lead);
            self.epoch_ns = now_ns() + lead.as_nanos() as u64;
            self.own_clock.clear();
            self.own_clock_run = run;
            self.in_transit.clear();
        }
        let dt = Duration::from_secs_f64(self.dt_s);
        let start = self.start.get().unwrap_or_else(Instant::now);
        let mut begin = start + Duration::from_secs_f64(request.t_s.max(0.0));
        let now = Instant::now();
        if now < begin {
            std::thread::sleep(begin - now);
        } else if now - begin >= dt {
            // Behind by a period or more: the flight's time pauses for as long.
            let behind = now - begin;
            self.start.set(start + behind);
            self.epoch_ns += behind.as_nanos() as u64;
            // The world was not listening meanwhile: what it last heard of each agent is as
            // recent as it was before the pause.
            for t in self.seen.values_mut() {
                *t = (*t + behind).min(now);
            }
            self.stats.paused = (self.stats.paused.0 + 1, self.stats.paused.1 + behind.as_secs_f64());
            begin = now;
        } else if now - begin > dt.mul_f64(0.1) {
            self.stats.late_steps += 1;
        }
        self.stats.steps += 1;
        let deadline = begin + dt.mul_f64(wire::COMMAND_WINDOW_PERIODS);
        let delay = Duration::from_secs_f64(self.faults.0.delay_s);
        self.drain();
        let clock = ClockMsg {
            mode: self.mode,
            run,
            k: request.k,
            t_s: request.t_s,
            dt_s: self.dt_s,
            epoch_ns: self.epoch_ns,
            end: false,
        };
        let _ = self.clock.send(&Message::Clock(clock));
        let sent = Instant::now();
        for j in 0..s.len() {
            let uav = s.uavs[j].0 + 1;
            // What its sensors give: the radio goes agent to agent.
            let heard = s
                .heard_of(j)
                .iter()
                .filter(|o| !matches!(o.source, ObservationSource::Radio | ObservationSource::Relayed))
                .copied()
                .collect();
            let m =
                SenseMsg { uav, run, phase: wire::Phase::Fly, k: request.k, t_s: request.t_s, own: s.own[j], heard };
            if !self.lost(request, uav, 0) {
                self.in_transit.push_back((sent + delay, Message::Sense(m)));
            }
        }
        // Until the end of the period, or until every live follower's newest command answers
        // this step: what is due goes out or comes in.
        let max_ahead = COMMAND_MAX_AGE_PERIODS * self.dt_s;
        let answered_now = |me: &Self| {
            s.uavs.iter().all(|u| {
                let uav = u.0 + 1;
                !me.live(uav) || me.own_clock.get(&uav).is_some_and(|o| o.pending.answers(request.t_s, me.dt_s))
            })
        };
        loop {
            self.deliver(Instant::now());
            let waiting = self.in_transit.front().is_some_and(|(due, _)| *due <= deadline);
            if answered_now(self) && !waiting {
                break;
            }
            let now = Instant::now();
            let next_due = self.in_transit.front().map_or(deadline, |(due, _)| (*due).min(deadline));
            if now >= deadline {
                break;
            }
            let Some(r) = self.inbox.recv_timeout(next_due.saturating_duration_since(now)) else { continue };
            match r {
                // (An agent decides for the instant its command will act: ahead of the step.)
                Received::Message(_, Message::Command(c))
                    if c.run == run
                        && c.t_s <= request.t_s + max_ahead
                        && self.digests.get(&c.uav) == Some(&c.digest) =>
                {
                    self.seen.insert(c.uav, Instant::now());
                    if self.lost(request, c.uav, 1) {
                        continue;
                    }
                    // From the moment the update it answers left (the step it was measured at,
                    // after the transport's delay), whichever step this is.
                    let left = start + Duration::from_secs_f64(c.k as f64 * self.dt_s) + delay;
                    self.stats.round_trips_s.push(Instant::now().saturating_duration_since(left).as_secs_f64());
                    self.stats.ages_s.push(c.age_s);
                    let due = Instant::now() + delay;
                    match delay.is_zero() {
                        true => self.offer(c),
                        false => self.in_transit.push_back((due, Message::Command(c))),
                    }
                }
                other => self.note(other),
            }
        }
        out.clear();
        let max_age = COMMAND_MAX_AGE_PERIODS * self.dt_s;
        for j in 0..s.len() {
            let uav = s.uavs[j].0 + 1;
            let slot = self.own_clock.entry(uav).or_default();
            // A command acts at the step nearest the instant it was decided for (a later one
            // waits for its step).
            // The newest of those due; older due ones were overtaken.
            let (due, overtaken) = slot.pending.due(request.t_s, self.dt_s);
            self.stats.late += overtaken;
            let fresh = due.filter(|c| request.t_s - c.t_s <= max_age + 1e-9);
            let decision = match fresh {
                Some(c) => {
                    slot.applied_t_s = Some(c.t_s);
                    slot.decided_on_t_s = Some(c.k as f64 * self.dt_s);
                    slot.held_periods = 0;
                    if c.decision.setpoint.is_some() {
                        slot.setpoint = c.decision.setpoint;
                    }
                    self.stats.answered += 1;
                    self.stats.applied_ages_s.push(request.t_s - c.t_s);
                    c.decision
                }
                None => {
                    slot.decided_on_t_s = None;
                    slot.held_periods = slot.held_periods.saturating_add(1);
                    self.stats.missing += 1;
                    // A multirotor's autopilot keeps flying its last setpoint.
                    Decision { setpoint: slot.setpoint, ..holding() }
                }
            };
            out.push(decision);
        }
    }

    /// Real time: sends the updates and takes the commands whose delay is over at `now`.
    fn deliver(&mut self, now: Instant) {
        while self.in_transit.front().is_some_and(|(due, _)| *due <= now) {
            let Some((_, m)) = self.in_transit.pop_front() else { break };
            match m {
                Message::Sense(m) => {
                    if let Some(p) = self.sense.get(&m.uav) {
                        // A publication that fails is an update lost.
                        let _ = p.send(&Message::Sense(m));
                    }
                }
                Message::Command(c) => self.offer(c),
                _ => {}
            }
        }
    }
}

impl Agents for NetAgents {
    /// While the agent is live and its answers keep coming: a UAV that went more than
    /// [`COMMAND_MAX_AGE_PERIODS`] steps without one (in lockstep, its updates unanswered; on
    /// the own clock, no command to apply) flies uncontrolled until one comes again.
    fn present(&mut self, uav: proxform_core::UavId) -> bool {
        self.drain();
        let held = self.own_clock.get(&(uav.0 + 1)).map_or(0, |o| o.held_periods);
        self.live(uav.0 + 1) && f64::from(held) <= COMMAND_MAX_AGE_PERIODS
    }

    /// At once when its agent is gone; on the own clock once [`FAILSAFE_AFTER_S`] passed
    /// without a command.
    fn failsafe(&mut self, uav: proxform_core::UavId) -> bool {
        let held = self.own_clock.get(&(uav.0 + 1)).map_or(0, |o| o.held_periods);
        !self.live(uav.0 + 1) || f64::from(held) * self.dt_s >= FAILSAFE_AFTER_S - 1e-9
    }

    fn refused(&mut self, _: proxform_core::UavId) {
        self.stats.refused += 1;
    }

    fn decided_on(&mut self, uav: proxform_core::UavId) -> Option<f64> {
        self.own_clock.get(&(uav.0 + 1)).and_then(|o| o.decided_on_t_s)
    }

    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        if self.mode == ClockMode::RealTime && request.phase == Phase::Fly {
            return self.decide_own_clock(request, out);
        }
        let s = request.sensed;
        let run = request.run as u32;
        let phase = match request.phase {
            Phase::Warm => wire::Phase::Warm,
            Phase::Fly => wire::Phase::Fly,
        };
        let real_time = self.mode == ClockMode::RealTime && request.phase == Phase::Fly;
        if request.phase == Phase::Fly && request.k == 0 {
            // Each run counts the steps its agents went without answering from its start.
            self.own_clock.clear();
            // t = 0 a little ahead, so that every agent has the clock before the first update.
            let lead = Duration::from_millis(200);
            self.start.set(Instant::now() + lead);
            self.epoch_ns = now_ns() + lead.as_nanos() as u64;
        }
        // In real time, step k begins at its wall-clock time and its answers are awaited until
        // the end of its period.
        let mut deadline = Instant::now() + self.deadline;
        if let (true, Some(start)) = (real_time, self.start.get()) {
            let begin = start + Duration::from_secs_f64(request.t_s.max(0.0));
            let now = Instant::now();
            if now < begin {
                std::thread::sleep(begin - now);
            } else if now - begin > Duration::from_secs_f64(0.1 * self.dt_s) {
                self.stats.late_steps += 1;
            }
            self.stats.steps += 1;
            deadline = begin + Duration::from_secs_f64(0.9 * self.dt_s);
        }
        // Delayed updates leave `delay_s` into the period (real time).
        if real_time && self.faults.0.delay_s > 0.0 {
            std::thread::sleep(Duration::from_secs_f64(self.faults.0.delay_s));
        }
        // What arrived since the last step (heartbeats, late answers) first: who is live now.
        self.drain();
        let sent = Instant::now();
        self.answers.clear();
        self.answers.resize(s.len(), None);
        // The clock first: a real-time agent needs t = 0's wall-clock time for the first update.
        let clock = ClockMsg {
            mode: self.mode,
            run,
            k: request.k,
            t_s: request.t_s,
            dt_s: self.dt_s,
            epoch_ns: self.epoch_ns,
            end: false,
        };
        let _ = self.clock.send(&Message::Clock(clock));
        let mut waiting = 0usize;
        for j in 0..s.len() {
            let uav = s.uavs[j].0 + 1;
            let m = SenseMsg {
                uav,
                run,
                phase,
                k: request.k,
                t_s: request.t_s,
                own: s.own[j],
                heard: s.heard_of(j).to_vec(),
            };
            let lost = self.lost(request, uav, 0);
            if let Some(p) = self.sense.get(&uav) {
                // A publication that fails, or is lost, is an answer that will not come.
                if !lost && p.send(&Message::Sense(m)).is_ok() && self.live(uav) {
                    waiting += 1;
                }
            }
        }
        while waiting > 0 {
            let left = deadline.saturating_duration_since(Instant::now());
            let Some(r) = self.inbox.recv_timeout(left) else { break };
            match r {
                Received::Message(_, Message::Command(c))
                    if c.run == run
                        && c.k == request.k
                        && c.t_s.to_bits() == request.t_s.to_bits()
                        && self.digests.get(&c.uav) == Some(&c.digest) =>
                {
                    self.seen.insert(c.uav, Instant::now());
                    // A delayed answer arrives `delay_s` later: too late if past the deadline.
                    let delayed =
                        real_time && Instant::now() + Duration::from_secs_f64(self.faults.0.delay_s) > deadline;
                    // A decision with a non-finite number is never applied: it is not an answer
                    // (the UAV holds unless a valid one comes in time).
                    if !c.decision.is_finite() {
                        self.stats.refused += 1;
                        continue;
                    }
                    let lost = self.lost(request, c.uav, 1) || delayed;
                    if lost {
                        waiting -= 1;
                    }
                    if let Some(j) = s.uavs.iter().position(|u| u.0 + 1 == c.uav).filter(|_| !lost) {
                        if self.answers[j].is_none() {
                            self.answers[j] = Some(c.decision);
                            self.stats.answered += 1;
                            self.stats.round_trips_s.push(sent.elapsed().as_secs_f64());
                            if real_time {
                                self.stats.ages_s.push(c.age_s);
                            }
                            waiting -= 1;
                        }
                    }
                }
                other => self.note(other),
            }
        }
        out.clear();
        for (j, a) in self.answers.iter().enumerate() {
            if a.is_none() {
                self.stats.missing += 1;
            }
            // Steps in a row without an answer, as on the own clock: a UAV whose agent has not
            // answered for longer than a command may be old flies uncontrolled, whatever else
            // is heard of it (a liveliness token, or its own sealed messages replayed, say
            // nothing of whether it is flown).
            if request.phase == Phase::Fly {
                if let Some(u) = s.uavs.get(j) {
                    let slot = self.own_clock.entry(u.0 + 1).or_default();
                    slot.held_periods = match a {
                        Some(_) => 0,
                        None => slot.held_periods.saturating_add(1),
                    };
                }
            }
            out.push(a.unwrap_or_else(holding));
        }
    }
}

/// Publishes the navigator's state every step (it runs no agent), so that outside programs
/// see every UAV: an observer of the flight.
pub struct NavigatorTelemetry {
    publisher: Publisher,
    navigator: usize,
    /// Real time: the flight's clock, to publish each state at its time.
    clock: Option<(FlightClock, f64)>,
}

impl NavigatorTelemetry {
    /// A publisher on the navigator's state key of `swarm`.
    pub fn new(session: &Session, swarm: &Swarm, scenario: &Scenario) -> Result<Self> {
        let navigator = scenario.navigator().index();
        Ok(Self { publisher: session.telemetry(&swarm.state(navigator as u32 + 1))?, navigator, clock: None })
    }

    /// Publishes each state at its time on `clock` (real time; the period `dt_s` bounds a wait).
    pub fn timed(mut self, clock: FlightClock, dt_s: f64) -> Self {
        self.clock = Some((clock, dt_s));
        self
    }
}

impl proxform_sim::Observer for NavigatorTelemetry {
    fn on_step(&mut self, _: &Scenario, frame: &proxform_sim::StepFrame<'_>) {
        if let Some((clock, dt_s)) = &self.clock {
            clock.wait_until(frame.t, Duration::from_secs_f64(*dt_s));
        }
        let m = StateMsg {
            uav: self.navigator as u32 + 1,
            k: frame.k,
            t_s: frame.t,
            state: frame.states[self.navigator],
            rejoining: false,
        };
        // Telemetry is best effort: a failed publication loses one sample.
        let _ = self.publisher.send(&Message::State(m));
    }
}
