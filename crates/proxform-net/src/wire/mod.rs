//! The wire messages of a distributed swarm (schema version [`VERSION`]), apart from any
//! transport: what a UAV broadcasts ([`StateMsg`]), what its sensors report to its agent each
//! period ([`SenseMsg`]), what its agent commands ([`CommandMsg`]), the world's clock
//! ([`ClockMsg`]) and membership ([`MemberMsg`]). [`codec`] turns them into bytes and back;
//! `docs/wire.md` is the byte-level reference for programs in other languages.
//!
//! Units are the library's: SI and radians, world frame x forward, y left, z up; times in
//! seconds of flight (t = 0 at the start of the flight, negative in the warm-up). UAVs are
//! numbered from 1 on the wire, as in scenario files.

pub mod codec;

use proxform_core::state::State9;
use proxform_core::{Decision, Observation, Outcome};

/// Schema version carried by every message; a reader refuses other versions.
pub const VERSION: u8 = 1;

/// On the own clock, what is older than this many update periods is stale: an own update is
/// not stepped on, a command is not applied.
pub const STALE_AFTER_PERIODS: f64 = 5.0;

/// A world on real time applies the commands that reach it within this many periods after a
/// step's time from that step on (it propagates the period once that window has passed); one
/// that comes later acts from the next step. An agent on its own clock decides for the step its
/// command will act at ([`crate::agent`]).
pub const COMMAND_WINDOW_PERIODS: f64 = 0.9;

/// Most observations one [`SenseMsg`] may carry (a sensor reports one UAV per azimuth area and
/// its main references; radio reports add more, but never this many).
pub const MAX_OBSERVATIONS: usize = 4096;

/// Which part of the flight a sense message belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Before t = 0: the agent steps, its command is not applied.
    Warm,
    /// The flight. At the first flight message the agent forgets its own-state estimate.
    Fly,
}

/// A UAV's broadcast of its own state (what it believes: its measurement).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateMsg {
    /// The UAV (from 1).
    pub uav: u32,
    /// Step of the flight it was measured at.
    pub k: u64,
    /// Time of the measurement (s).
    pub t_s: f64,
    /// The state.
    pub state: State9,
    /// Its agent is rejoining: it came back after flying without decisions (stopped, cut off,
    /// restarted) and is not yet back near its slot. Others avoid it but do not follow it
    /// ([`crate::watch::ControlWatch`]). Always false for the navigator.
    pub rejoining: bool,
}

/// What reached one UAV's agent in one update period: its own measured state, what it
/// perceived onboard and heard by radio. In lockstep the agent answers each with a
/// [`CommandMsg`] of the same `run` and `k`.
#[derive(Debug, Clone, PartialEq)]
pub struct SenseMsg {
    /// The UAV (from 1).
    pub uav: u32,
    /// Run of the batch: a new run starts a new agent.
    pub run: u32,
    /// Warm-up or flight.
    pub phase: Phase,
    /// Step (of the flight, or of the warm-up from its start).
    pub k: u64,
    /// Time of the update (s).
    pub t_s: f64,
    /// The UAV's measurement of its own state.
    pub own: State9,
    /// Observations of neighbours (ids from 0 inside, from 1 on the wire).
    pub heard: Vec<Observation>,
}

/// An agent's decision for one period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandMsg {
    /// The UAV (from 1).
    pub uav: u32,
    /// Run it answers.
    pub run: u32,
    /// Step it answers.
    pub k: u64,
    /// Time of the update it answers (s).
    pub t_s: f64,
    /// How old the update was when the agent stepped (s): the transport's latency (0 in
    /// lockstep, where time is the world's).
    pub age_s: f64,
    /// The decision.
    pub decision: Decision,
    /// What the agent that decided runs ([`crate::agent::setup_digest`]): a world applies only
    /// the commands of its own scenario's agent for the UAV.
    pub digest: u64,
}

/// How the world's clock advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClockMode {
    /// The world advances when every live agent has answered or a deadline passed.
    Lockstep,
    /// Every process on its own wall clock at the scenario's period.
    RealTime,
}

/// The world's clock: sent every period, and `end` once the flight is over.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockMsg {
    /// Lockstep or real time.
    pub mode: ClockMode,
    /// Run of the batch.
    pub run: u32,
    /// Step.
    pub k: u64,
    /// Time of flight (s).
    pub t_s: f64,
    /// Update period (s).
    pub dt_s: f64,
    /// Wall-clock time of t = 0 (ns since the Unix epoch): real-time agents compute ages from it.
    pub epoch_ns: u64,
    /// The batch is over: agents may exit.
    pub end: bool,
}

/// What an agent says of itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Presence {
    /// Running and ready for sense messages (sent at start and then periodically).
    Alive,
    /// Leaving (a clean exit).
    Leaving,
}

/// Membership: an agent process announcing a UAV it runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemberMsg {
    /// The UAV (from 1).
    pub uav: u32,
    /// Alive or leaving.
    pub presence: Presence,
    /// The agent's process id (for the launcher's records).
    pub pid: u32,
    /// What the agent runs for its UAV ([`crate::agent::setup_digest`]): a world takes an agent
    /// only when it is the digest of its own scenario's agent for that UAV.
    pub digest: u64,
}

/// Any message, as decoded.
#[derive(Debug, Clone, PartialEq)]
pub enum Message {
    /// A broadcast state.
    State(StateMsg),
    /// A sense message.
    Sense(SenseMsg),
    /// A command.
    Command(CommandMsg),
    /// The clock.
    Clock(ClockMsg),
    /// Membership.
    Member(MemberMsg),
}

/// The outcome's code on the wire.
pub(crate) fn outcome_code(o: &Outcome) -> u8 {
    match o {
        Outcome::Held => 0,
        Outcome::Adjusted { .. } => 1,
        Outcome::Alone => 2,
    }
}
