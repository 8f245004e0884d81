//! The world's side of a distributed flight: the engine's followers are agents reached over
//! Zenoh ([`NetAgents`] implements the simulator's `Agents`). Each update period the world
//! sends every active follower what it sensed, waits for the decisions of the live agents (in
//! lockstep, until all have answered or the step's deadline passed; a late or missing answer
//! counts as holding), publishes the navigator's state and its clock, and goes on.

use std::collections::BTreeMap;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{bail, Result};
use proxform_core::Decision;
use proxform_net::keys::Swarm;
use proxform_net::transport::{Inbox, Publisher, Received, Session};
use proxform_net::wire::{self, ClockMode, ClockMsg, Message, Presence, SenseMsg, StateMsg};
use proxform_scenario::Scenario;
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
    /// Round trips (send of a step's first sense message to each answer), seconds.
    pub round_trips_s: Vec<f64>,
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
    /// When each agent last said anything.
    seen: BTreeMap<u32, Instant>,
    epoch_ns: u64,
    /// The network's numbers.
    pub stats: NetStats,
    answers: Vec<Option<Decision>>,
}

impl NetAgents {
    /// The world's end of `swarm` on `session` for `scenario`'s followers; `deadline` bounds
    /// one step's wait.
    pub fn new(session: Session, swarm: Swarm, scenario: &Scenario, deadline: Duration) -> Result<Self> {
        let navigator = scenario.navigator().0 + 1;
        let followers: Vec<u32> = (1..=scenario.len() as u32).filter(|u| *u != navigator).collect();
        let sense = followers.iter().map(|u| Ok((*u, session.publisher(&swarm.sense(*u))?))).collect::<Result<_>>()?;
        let inbox = session.inbox(&[swarm.all_commands(), swarm.all_members()])?;
        Ok(Self {
            clock: session.publisher(&swarm.clock())?,
            sense,
            inbox,
            session,
            swarm,
            dt_s: scenario.dt_s(),
            deadline,
            seen: BTreeMap::new(),
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
            while let Some(r) = self.inbox.try_recv() {
                self.note(r);
            }
            let missing: Vec<u32> = uavs.iter().copied().filter(|u| !self.seen.contains_key(u)).collect();
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
        }
    }

    fn live(&self, uav: u32) -> bool {
        self.seen.get(&uav).is_some_and(|t| t.elapsed() < LIVE_FOR)
    }

    /// Tells every agent that the batch is over.
    pub fn end(&self, run: u64) -> Result<()> {
        let clock = ClockMsg {
            mode: ClockMode::Lockstep,
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

fn now_ns() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64)
}

impl Agents for NetAgents {
    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        let s = request.sensed;
        let run = request.run as u32;
        let phase = match request.phase {
            Phase::Warm => wire::Phase::Warm,
            Phase::Fly => wire::Phase::Fly,
        };
        if request.phase == Phase::Fly && request.k == 0 {
            self.epoch_ns = now_ns();
        }
        let sent = Instant::now();
        self.answers.clear();
        self.answers.resize(s.len(), None);
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
            if let Some(p) = self.sense.get(&uav) {
                // A publication that fails is an answer that will not come.
                if p.send(&Message::Sense(m)).is_ok() && self.live(uav) {
                    waiting += 1;
                }
            }
        }
        let clock = ClockMsg {
            mode: ClockMode::Lockstep,
            run,
            k: request.k,
            t_s: request.t_s,
            dt_s: self.dt_s,
            epoch_ns: self.epoch_ns,
            end: false,
        };
        let _ = self.clock.send(&Message::Clock(clock));
        let deadline = sent + self.deadline;
        while waiting > 0 {
            let left = deadline.saturating_duration_since(Instant::now());
            let Some(r) = self.inbox.recv_timeout(left) else { break };
            match r {
                Received::Message(_, Message::Command(c))
                    if c.run == run && c.k == request.k && c.t_s.to_bits() == request.t_s.to_bits() =>
                {
                    self.seen.insert(c.uav, Instant::now());
                    if let Some(j) = s.uavs.iter().position(|u| u.0 + 1 == c.uav) {
                        if self.answers[j].is_none() {
                            self.answers[j] = Some(c.decision);
                            self.stats.answered += 1;
                            self.stats.round_trips_s.push(sent.elapsed().as_secs_f64());
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
