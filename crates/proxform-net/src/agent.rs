//! The agent loop: the core's [`Agent`] of each UAV a process runs, stepped on every update
//! its [`Vehicle`] delivers, as the simulator steps it. A new run starts a fresh agent; the
//! first flight update after a warm-up makes the agent forget its own-state estimate (as the
//! simulator does at t = 0). Whatever arrives is checked first: an update with a non-finite
//! own state is not stepped, observations of unknown UAVs, of the UAV itself or with
//! non-finite numbers are dropped.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use proxform_core::{Agent, Observation, UavId};
use proxform_scenario::Scenario;

use crate::transport::TransportError;
use crate::vehicle::{Event, Vehicle};
use crate::wire::{ClockMode, CommandMsg, Phase, Presence, SenseMsg, StateMsg};

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

struct Hosted {
    agent: Agent,
    run: u32,
    flying: bool,
}

/// The agents of the UAVs one process runs.
pub struct Host {
    scenario: Arc<Scenario>,
    agents: BTreeMap<u32, Hosted>,
    heard: Vec<Observation>,
    /// Observations dropped as invalid.
    pub dropped: u64,
    /// Updates not stepped (invalid own state, unknown UAV).
    pub refused: u64,
}

impl Host {
    /// Agents for `uavs` (from 1) of `scenario`.
    pub fn new(scenario: Arc<Scenario>, uavs: &[u32]) -> Result<Self, HostError> {
        let mut agents = BTreeMap::new();
        for &u in uavs {
            let id = Self::follower(&scenario, u)?;
            agents.insert(u, Hosted { agent: scenario.agent(id), run: 0, flying: false });
        }
        Ok(Self { scenario, agents, heard: Vec::new(), dropped: 0, refused: 0 })
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

    /// Steps the agent of `s.uav` on the update, which reached it `latency_s` after it was
    /// measured (0 in lockstep); its command and the state it broadcasts, or None when the
    /// update is not for this host or not valid.
    ///
    /// The agent steps at the update's time t_s: its own state and its observations were
    /// measured together then, and their ages are relative to that instant (a neighbour
    /// predicted to a later instant than the own state would be compared with a state that
    /// is not there: at 70 m/s, 1 ms is 7 cm). The latency is reported with the command; what
    /// it costs is a decision that reaches the vehicle too late for its period.
    pub fn handle(&mut self, s: &SenseMsg, latency_s: f64) -> Option<(CommandMsg, StateMsg)> {
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
            (h.run, h.flying) = (s.run, false);
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
        let decision = h.agent.step(s.t_s, &s.own, &self.heard);
        let command = CommandMsg { uav: s.uav, run: s.run, k: s.k, t_s: s.t_s, age_s: latency_s, decision };
        Some((command, StateMsg { uav: s.uav, k: s.k, t_s: s.t_s, state: s.own }))
    }
}

fn unix_ns() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos() as u64)
}

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

/// Runs `host`'s agents over `vehicle` until the world ends the batch or goes silent.
pub fn serve(host: &mut Host, vehicle: &mut impl Vehicle, timing: Timing) -> Result<Ended, TransportError> {
    vehicle.announce(Presence::Alive)?;
    let (mut last_heard, mut last_announce) = (Instant::now(), Instant::now());
    // In real time, the wall-clock time of t = 0 (ns since the Unix epoch), from the clock.
    let mut epoch_ns: Option<u64> = None;
    loop {
        match vehicle.next(timing.announce_every)? {
            Event::Sense(s) => {
                last_heard = Instant::now();
                let latency = match (epoch_ns, s.phase) {
                    (Some(e), Phase::Fly) => (unix_ns() as f64 - e as f64) * 1e-9 - s.t_s,
                    _ => 0.0,
                };
                if let Some((command, state)) = host.handle(&s, latency) {
                    vehicle.command(&command, &state)?;
                }
            }
            Event::Clock(c) => {
                last_heard = Instant::now();
                epoch_ns = (c.mode == ClockMode::RealTime && c.epoch_ns > 0).then_some(c.epoch_ns);
                if c.end {
                    vehicle.announce(Presence::Leaving)?;
                    return Ok(Ended::Done);
                }
            }
            Event::Idle => {
                if last_heard.elapsed() >= timing.idle_exit {
                    return Ok(Ended::Idle);
                }
            }
        }
        if last_announce.elapsed() >= timing.announce_every {
            vehicle.announce(Presence::Alive)?;
            last_announce = Instant::now();
        }
    }
}
