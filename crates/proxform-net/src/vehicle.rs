//! What an agent sees of the UAVs it runs: each update period, a UAV's own measured state and
//! what it perceived and heard ([`SenseMsg`]) in; its answer ([`Answer`]: the decision, its
//! broadcast and the state it was decided at) out. The
//! network world implements it here ([`NetVehicle`]); a MAVLink autopilot
//! ([`crate::mavlink::vehicle::MavlinkVehicle`]: the command as the autopilot's setpoint, the
//! own state a world's measurement or the autopilot's) implements the same trait.

use std::time::Duration;

use proxform_core::State9;

use crate::keys::Swarm;
use crate::transport::{Inbox, Publisher, Received, Session, Token, TransportError};
use crate::wire::{ClockMsg, CommandMsg, MemberMsg, Message, Presence, SenseMsg, StateMsg};

/// What happened while an agent waited for its next update.
#[derive(Debug)]
pub enum Event {
    /// A UAV's update.
    Sense(SenseMsg),
    /// The world's clock (with `end`, the batch is over).
    Clock(ClockMsg),
    /// Another UAV's broadcast (the formation's radio, heard on the own clock).
    State(StateMsg),
    /// Nothing within the wait.
    Idle,
}

/// What an agent answers an update with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Answer {
    /// The decision, for the instant it acts at (`command.t_s`).
    pub command: CommandMsg,
    /// The state its UAV broadcasts: the update's own state, at the update's instant.
    pub state: StateMsg,
    /// The own state the decision was made at: the update's, brought forward to the instant
    /// the command acts at (through the commands still on their way). An autopilot's absolute
    /// targets are this state after the decision's input; from the update's own state they
    /// would undo the commands on their way.
    pub decided_at: State9,
}

/// The UAVs an agent process runs, as it sees them.
pub trait Vehicle {
    /// The next event, waiting at most `timeout`.
    fn next(&mut self, timeout: Duration) -> Result<Event, TransportError>;
    /// The answer to an update of UAV `answer.command.uav`: its decision, and the state the UAV
    /// now believes it has (its broadcast).
    fn command(&mut self, answer: &Answer) -> Result<(), TransportError>;
    /// Says that the UAVs are alive (or leaving).
    fn announce(&mut self, presence: Presence) -> Result<(), TransportError>;
    /// From now on, also delivers the broadcasts of `uavs` (from 1) as [`Event::State`]: an
    /// agent on its own clock hears the formation's radio and who flies under control
    /// ([`crate::agent::Host::listens_to`]). In lockstep nobody listens (the world's updates
    /// carry the radio).
    fn listen(&mut self, uavs: &[u32]) -> Result<(), TransportError>;
}

/// UAVs whose sensors and actuators are a network world's ([`crate::keys`]).
pub struct NetVehicle {
    session: Session,
    swarm: Swarm,
    members: Vec<(u32, u64)>,
    uavs: Vec<u32>,
    inbox: Inbox,
    commands: Vec<(u32, Publisher, Publisher)>,
    /// One liveliness token per UAV: the world sees at once when this process is gone.
    _tokens: Vec<Token>,
    /// Undecodable messages seen (a foreign or broken sender).
    pub garbage: u64,
}

impl NetVehicle {
    /// Subscribes to the updates of the UAVs of `members` (from 1, each with the digest of what
    /// its agent runs: [`crate::agent::Host::members`]) of `swarm` and the clock.
    pub fn new(session: Session, swarm: Swarm, members: &[(u32, u64)]) -> Result<Self, TransportError> {
        let uavs: Vec<u32> = members.iter().map(|m| m.0).collect();
        let uavs = &uavs[..];
        let mut keys: Vec<String> = uavs.iter().map(|u| swarm.sense(*u)).collect();
        keys.push(swarm.clock());
        let inbox = session.inbox(&keys)?;
        let commands = uavs
            .iter()
            .map(|u| Ok((*u, session.publisher(&swarm.command(*u))?, session.telemetry(&swarm.state(*u))?)))
            .collect::<Result<_, TransportError>>()?;
        let tokens = uavs.iter().map(|u| session.liveliness_token(&swarm.alive(*u))).collect::<Result<_, _>>()?;
        Ok(Self {
            session,
            swarm,
            members: members.to_vec(),
            uavs: uavs.to_vec(),
            inbox,
            commands,
            _tokens: tokens,
            garbage: 0,
        })
    }
}

impl NetVehicle {
    /// The UAVs it runs (from 1).
    pub fn uavs(&self) -> &[u32] {
        &self.uavs
    }
}

impl Vehicle for NetVehicle {
    fn next(&mut self, timeout: Duration) -> Result<Event, TransportError> {
        let deadline = std::time::Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            match self.inbox.recv_timeout(left) {
                None => return Ok(Event::Idle),
                Some(Received::Message(_, Message::Sense(s))) if self.uavs.contains(&s.uav) => {
                    return Ok(Event::Sense(s))
                }
                Some(Received::Message(_, Message::Clock(c))) => return Ok(Event::Clock(c)),
                Some(Received::Message(_, Message::State(m))) if !self.uavs.contains(&m.uav) => {
                    return Ok(Event::State(m))
                }
                Some(Received::Message(..)) => {}
                Some(Received::Garbage(..) | Received::Misplaced(..)) => self.garbage += 1,
            }
        }
    }

    fn command(&mut self, answer: &Answer) -> Result<(), TransportError> {
        if let Some((_, cmd, st)) = self.commands.iter().find(|(u, _, _)| *u == answer.command.uav) {
            cmd.send(&Message::Command(answer.command))?;
            st.send(&Message::State(answer.state))?;
        }
        Ok(())
    }

    fn listen(&mut self, uavs: &[u32]) -> Result<(), TransportError> {
        let keys: Vec<String> = uavs.iter().map(|u| self.swarm.state(*u)).collect();
        self.session.subscribe(&mut self.inbox, &keys)
    }

    fn announce(&mut self, presence: Presence) -> Result<(), TransportError> {
        for &(uav, digest) in &self.members {
            let m = Message::Member(MemberMsg { uav, presence, pid: std::process::id(), digest });
            self.session.put(&self.swarm.member(uav), &m)?;
        }
        Ok(())
    }
}
