//! What an agent sees of the UAVs it runs: each update period, a UAV's own measured state and
//! what it perceived and heard ([`SenseMsg`]) in; its decision ([`CommandMsg`]) out. The
//! network world implements it here ([`NetVehicle`]); a MAVLink autopilot
//! ([`crate::mavlink::vehicle::MavlinkVehicle`]: own state from the autopilot, the command as a
//! setpoint) implements the same trait.

use std::time::Duration;

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
    /// Nothing within the wait.
    Idle,
}

/// The UAVs an agent process runs, as it sees them.
pub trait Vehicle {
    /// The next event, waiting at most `timeout`.
    fn next(&mut self, timeout: Duration) -> Result<Event, TransportError>;
    /// The decision for an update of UAV `command.uav`, and the state the UAV now believes it
    /// has (its broadcast).
    fn command(&mut self, command: &CommandMsg, state: &StateMsg) -> Result<(), TransportError>;
    /// Says that the UAVs are alive (or leaving).
    fn announce(&mut self, presence: Presence) -> Result<(), TransportError>;
}

/// UAVs whose sensors and actuators are a network world's ([`crate::keys`]).
pub struct NetVehicle {
    session: Session,
    swarm: Swarm,
    uavs: Vec<u32>,
    inbox: Inbox,
    commands: Vec<(u32, Publisher, Publisher)>,
    /// One liveliness token per UAV: the world sees at once when this process is gone.
    _tokens: Vec<Token>,
    /// Undecodable messages seen (a foreign or broken sender).
    pub garbage: u64,
}

impl NetVehicle {
    /// Subscribes to the updates of `uavs` (from 1) of `swarm` and the clock.
    pub fn new(session: Session, swarm: Swarm, uavs: &[u32]) -> Result<Self, TransportError> {
        let mut keys: Vec<String> = uavs.iter().map(|u| swarm.sense(*u)).collect();
        keys.push(swarm.clock());
        let inbox = session.inbox(&keys)?;
        let commands = uavs
            .iter()
            .map(|u| Ok((*u, session.publisher(&swarm.command(*u))?, session.publisher(&swarm.state(*u))?)))
            .collect::<Result<_, TransportError>>()?;
        let tokens = uavs.iter().map(|u| session.liveliness_token(&swarm.alive(*u))).collect::<Result<_, _>>()?;
        Ok(Self { session, swarm, uavs: uavs.to_vec(), inbox, commands, _tokens: tokens, garbage: 0 })
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
                Some(Received::Message(..)) => {}
                Some(Received::Garbage(..) | Received::Misplaced(..)) => self.garbage += 1,
            }
        }
    }

    fn command(&mut self, command: &CommandMsg, state: &StateMsg) -> Result<(), TransportError> {
        if let Some((_, cmd, st)) = self.commands.iter().find(|(u, _, _)| *u == command.uav) {
            cmd.send(&Message::Command(*command))?;
            st.send(&Message::State(*state))?;
        }
        Ok(())
    }

    fn announce(&mut self, presence: Presence) -> Result<(), TransportError> {
        for u in &self.uavs {
            let m = Message::Member(MemberMsg { uav: *u, presence, pid: std::process::id() });
            self.session.put(&self.swarm.member(*u), &m)?;
        }
        Ok(())
    }
}
