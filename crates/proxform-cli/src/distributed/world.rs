//! The world's side of a distributed flight: the engine's followers are agents reached over
//! Zenoh ([`NetAgents`] implements the simulator's `Agents`). Each update period the world
//! sends every active follower what it sensed, waits for the decisions of the live agents (in
//! lockstep, until all have answered or the step's deadline passed; a late or missing answer
//! counts as holding), publishes the navigator's state and its clock, and goes on.

use std::collections::{BTreeMap, BTreeSet};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{bail, Result};
use proxform_core::Decision;
use proxform_net::keys::Swarm;
use proxform_net::transport::{Inbox, LivelinessInbox, Publisher, Received, Session};
use proxform_net::wire::{self, ClockMode, ClockMsg, Message, Presence, SenseMsg, StateMsg};
use proxform_scenario::{NetworkFaults, Scenario};
use proxform_sim::world::remote::{holding, Agents, Phase, StepRequest};

/// How long an agent stays live without a word (its heartbeat comes every 0.5 s).
const LIVE_FOR: Duration = Duration::from_millis(2000);

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
    /// Messages on another UAV's key than their own (a Command for UAV 3 put on UAV 2's key):
    /// never taken.
    pub misplaced: u64,
    /// Decisions refused for a non-finite number (held instead; also counted as missing).
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
    /// Messages lost to the scenario's `[network]` faults.
    pub dropped: u64,
    /// The UAVs' MAVLink systems, when served.
    pub mavlink: Option<super::mavlink::MavlinkStats>,
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
    /// Real time: the wall-clock instant of t = 0.
    start: Option<Instant>,
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
        let inbox = session.inbox(&[swarm.all_commands(), swarm.all_members()])?;
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
            start: None,
            faults: (*scenario.network(), seed),
            dropped: 0,
            seen: BTreeMap::new(),
            tokens,
            alive: BTreeSet::new(),
            epoch_ns: 0,
            stats: NetStats::default(),
            answers: Vec::new(),
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
            if start.elapsed() > timeout {
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
            Received::Message(_, Message::Member(m)) => {
                match m.presence {
                    Presence::Alive => self.seen.insert(m.uav, Instant::now()),
                    Presence::Leaving => self.seen.remove(&m.uav),
                };
            }
            Received::Message(_, Message::Command(c)) => {
                self.seen.insert(c.uav, Instant::now());
                self.stats.late += 1;
            }
            Received::Message(..) => {}
            Received::Garbage(..) => self.stats.garbage += 1,
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
                    false => self.alive.remove(&uav),
                };
            }
        }
    }

    /// An agent is live while its liveliness token is (gone at once when its process dies)
    /// and it has said something lately (a hung agent goes silent).
    fn live(&self, uav: u32) -> bool {
        self.alive.contains(&uav) && self.seen.get(&uav).is_some_and(|t| t.elapsed() < LIVE_FOR)
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

impl Agents for NetAgents {
    fn present(&mut self, uav: proxform_core::UavId) -> bool {
        self.drain();
        self.live(uav.0 + 1)
    }

    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        let s = request.sensed;
        let run = request.run as u32;
        let phase = match request.phase {
            Phase::Warm => wire::Phase::Warm,
            Phase::Fly => wire::Phase::Fly,
        };
        let real_time = self.mode == ClockMode::RealTime && request.phase == Phase::Fly;
        if request.phase == Phase::Fly && request.k == 0 {
            // t = 0 a little ahead, so that every agent has the clock before the first update.
            let lead = Duration::from_millis(200);
            self.start = Some(Instant::now() + lead);
            self.epoch_ns = now_ns() + lead.as_nanos() as u64;
        }
        // In real time, step k begins at its wall-clock time and its answers are awaited until
        // the end of its period.
        let mut deadline = Instant::now() + self.deadline;
        if let (true, Some(start)) = (real_time, self.start) {
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
                    if c.run == run && c.k == request.k && c.t_s.to_bits() == request.t_s.to_bits() =>
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
        for a in &self.answers {
            if a.is_none() {
                self.stats.missing += 1;
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
}

impl NavigatorTelemetry {
    /// A publisher on the navigator's state key of `swarm`.
    pub fn new(session: &Session, swarm: &Swarm, scenario: &Scenario) -> Result<Self> {
        let navigator = scenario.navigator().index();
        Ok(Self { publisher: session.publisher(&swarm.state(navigator as u32 + 1))?, navigator })
    }
}

impl proxform_sim::Observer for NavigatorTelemetry {
    fn on_step(&mut self, _: &Scenario, frame: &proxform_sim::StepFrame<'_>) {
        let m =
            StateMsg { uav: self.navigator as u32 + 1, k: frame.k, t_s: frame.t, state: frame.states[self.navigator] };
        // Telemetry is best effort: a failed publication loses one sample.
        let _ = self.publisher.send(&Message::State(m));
    }
}
