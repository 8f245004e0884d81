//! An agent's UAV behind a MAVLink autopilot ([`MavlinkVehicle`], `proxform-agent --mavlink`):
//! its own state comes from the autopilot (LOCAL_POSITION_NED and ATTITUDE in the method's
//! frame), what it perceived and heard from its sensing over the network as before, and each
//! decision goes to the autopilot as its velocity and yaw setpoint (the decision's
//! [`proxform_core::Setpoint`], absolute, chosen at the state the agent believed it had;
//! SET_POSITION_TARGET_LOCAL_NED; for the paper's kinematic vehicle, whose inputs steer its
//! attitude apart from its velocity, also the attitude it reaches, SET_ATTITUDE_TARGET), with
//! OFFBOARD asked
//! while it is not in it.
//! The safety policy ([`Safety`]) asks for HOLD instead when the autopilot's position is stale
//! or no update came for its timeout; the decision also goes to the world as before (a world
//! flies a UAV on its MAVLink setpoints while it is in OFFBOARD).
//!
//! With [`Sensing::Autopilot`] no world's sensing is used at all: in the flight (once the
//! swarm's clock says when t = 0 is) each new state the autopilot reports is the agent's update,
//! and its neighbours are what it hears of the other agents over the radio (the scenario must
//! have every UAV broadcast); the references the safety policy watches are those reports.

use std::time::{Duration, Instant};

use proxform_core::VehicleModel;

use super::autopilot::{Autopilot, Safety, Verdict};
use super::frame::Frame;
use super::modes::Mode;
use crate::transport::TransportError;
use crate::vehicle::{Answer, Event, NetVehicle, Vehicle};
use crate::wire::{ClockMode, Phase, Presence, SenseMsg};

/// How often a mode is asked for again while the autopilot is not in it.
const ASK_EVERY: Duration = Duration::from_millis(500);

/// Where an agent over MAVLink takes its updates from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensing {
    /// A world's sensing over the network (its own state replaced by the autopilot's).
    World,
    /// The autopilot's state alone, neighbours by radio: no world needed.
    Autopilot,
}

/// A UAV whose sensing arrives over the network and whose own state and commands go through
/// its autopilot.
pub struct MavlinkVehicle {
    sensing: Sensing,
    /// The swarm's clock, when known: run, t = 0 (ns since the Unix epoch), period.
    clock: Option<(u32, u64)>,
    /// When the last autopilot state given as an update was measured.
    last_sample: Option<Instant>,
    /// World updates not used ([`Sensing::Autopilot`]).
    pub ignored: u64,
    net: NetVehicle,
    autopilot: Autopilot,
    frame: Frame,
    model: VehicleModel,
    dt_s: f64,
    safety: Safety,
    last_update: Option<Instant>,
    asked: Option<(Mode, Instant)>,
    beat: Option<Instant>,
    boot: Instant,
    /// Setpoints sent.
    pub setpoints: u64,
    /// Times HOLD was asked by the safety policy, and the last reason.
    pub holds: (u64, Option<&'static str>),
}

fn io(e: std::io::Error) -> TransportError {
    TransportError::Io(format!("MAVLink: {e}"))
}

impl MavlinkVehicle {
    /// The UAV of `net` (one) behind `autopilot`, in `frame`, flying `model` at period `dt_s`.
    pub fn new(net: NetVehicle, autopilot: Autopilot, frame: Frame, (model, dt_s): (VehicleModel, f64)) -> Self {
        Self {
            sensing: Sensing::World,
            clock: None,
            last_sample: None,
            ignored: 0,
            net,
            autopilot,
            frame,
            model,
            dt_s,
            safety: Safety::default(),
            last_update: None,
            asked: None,
            beat: None,
            boot: Instant::now(),
            setpoints: 0,
            holds: (0, None),
        }
    }

    /// The same vehicle taking its updates from `sensing`.
    pub fn with_sensing(mut self, sensing: Sensing) -> Self {
        self.sensing = sensing;
        self
    }

    /// The autopilot (its link's counters, its mode).
    pub fn autopilot(&self) -> &Autopilot {
        &self.autopilot
    }

    /// [`Sensing::Autopilot`]: the autopilot's newest state as the agent's update, once the
    /// swarm's clock runs and when it is newer than the last one given.
    fn autopilot_update(&mut self, now: Instant) -> Option<SenseMsg> {
        let (run, epoch_ns) = self.clock?;
        let (own, age) = self.autopilot.state(&self.frame, now)?;
        // A new position is a new sample (its attitude comes in a message of its own).
        let sampled = self.autopilot.position_at()?;
        if self.last_sample.is_some_and(|l| sampled <= l) {
            return None;
        }
        let unix_s = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).ok()?.as_secs_f64();
        let t_s = unix_s - epoch_ns as f64 * 1e-9 - age.as_secs_f64();
        if !t_s.is_finite() || t_s < 0.0 {
            return None;
        }
        self.last_sample = Some(sampled);
        let uav = self.net.uavs().first().copied()?;
        let k = (t_s / self.dt_s).round() as u64;
        Some(SenseMsg { uav, run, phase: Phase::Fly, k, t_s, own, heard: Vec::new() })
    }

    /// The safety policy's verdict now.
    fn verdict(&self, now: Instant) -> Verdict {
        let own = self.autopilot.ned(now).map(|(_, age)| age.as_secs_f64());
        let update = self.last_update.map(|t| now.duration_since(t).as_secs_f64());
        self.safety.verdict(own, update)
    }

    /// Asks for `mode` unless the autopilot is in it or it was asked lately.
    fn ask(&mut self, mode: Mode, now: Instant) -> Result<(), TransportError> {
        let recent = self.asked.is_some_and(|(m, t)| m == mode && now.duration_since(t) < ASK_EVERY);
        if self.autopilot.mode() != Some(mode) && !recent {
            self.autopilot.request(mode).map_err(io)?;
            self.asked = Some((mode, now));
        }
        Ok(())
    }

    /// The companion's heartbeat, once a second.
    fn beat(&mut self, now: Instant) -> Result<(), TransportError> {
        if self.beat.is_none_or(|b| now.duration_since(b) >= Duration::from_secs(1)) {
            self.autopilot.heartbeat().map_err(io)?;
            self.beat = Some(now);
        }
        Ok(())
    }

    /// HOLD when the policy says so (once it has flown: a UAV never put in OFFBOARD is left as
    /// it is).
    fn guard(&mut self, now: Instant) -> Result<(), TransportError> {
        if let Verdict::Hold(why) = self.verdict(now) {
            if self.autopilot.mode() == Some(Mode::Offboard) || self.asked.is_some_and(|a| a.0 == Mode::Offboard) {
                if self.autopilot.mode() != Some(Mode::Hold) {
                    self.holds = (self.holds.0 + 1, Some(why));
                }
                self.ask(Mode::Hold, now)?;
            }
        }
        Ok(())
    }
}

impl Vehicle for MavlinkVehicle {
    fn next(&mut self, timeout: Duration) -> Result<Event, TransportError> {
        self.autopilot.poll(Duration::ZERO).map_err(io)?;
        if self.sensing == Sensing::Autopilot {
            let now = Instant::now();
            if let Some(s) = self.autopilot_update(now) {
                return Ok(Event::Sense(s));
            }
            // The autopilot reports far more often than the period: look again soon.
            let event = self.net.next(timeout.min(Duration::from_millis(10)))?;
            self.autopilot.poll(Duration::ZERO).map_err(io)?;
            let now = Instant::now();
            self.beat(now)?;
            return match event {
                // A world's warm-up is answered as it asks (nothing reaches the autopilot
                // before the flight's clock runs: see `command`).
                Event::Sense(s) if s.phase == Phase::Warm => Ok(Event::Sense(s)),
                Event::Sense(_) => {
                    self.ignored += 1;
                    Ok(Event::Idle)
                }
                Event::Clock(c) => {
                    self.clock = (c.mode == ClockMode::RealTime && c.epoch_ns > 0).then_some((c.run, c.epoch_ns));
                    self.guard(now)?;
                    Ok(Event::Clock(c))
                }
                Event::State(m) => {
                    // A neighbour's report: the references the safety policy watches.
                    self.last_update = Some(now);
                    Ok(Event::State(m))
                }
                Event::Idle => {
                    self.guard(now)?;
                    Ok(Event::Idle)
                }
            };
        }
        let event = self.net.next(timeout)?;
        self.autopilot.poll(Duration::ZERO).map_err(io)?;
        let now = Instant::now();
        self.beat(now)?;
        match event {
            Event::Sense(mut s) => {
                self.last_update = Some(now);
                // The own state is the autopilot's, when it is fresh.
                if let Some((own, age)) = self.autopilot.state(&self.frame, now) {
                    if age.as_secs_f64() <= self.safety.position_timeout_s {
                        s.own = own;
                    }
                }
                Ok(Event::Sense(s))
            }
            other => {
                self.guard(now)?;
                Ok(other)
            }
        }
    }

    fn command(&mut self, answer: &Answer) -> Result<(), TransportError> {
        let now = Instant::now();
        let command = &answer.command;
        if self.sensing == Sensing::Autopilot && self.clock.is_none() {
            // Before the flight: nothing for the autopilot.
            return self.net.command(answer);
        }
        if self.verdict(now) == Verdict::Fly {
            // The agent's setpoint (absolute), or the velocity and yaw its input reaches from
            // the state it was decided at (not the update's: that would undo the commands
            // still on their way).
            let at = &answer.decided_at;
            let (v, beta) = match command.decision.setpoint {
                Some(sp) => (sp.velocity_mps, sp.yaw_rad),
                None => self.model.velocity_setpoint(at, &command.decision.input, self.dt_s),
            };
            let (v, yaw) = (self.frame.velocity_ned(v), self.frame.yaw(beta));
            let ms = now.duration_since(self.boot).as_millis() as u32;
            if self.autopilot.send_velocity(v, yaw, ms).map_err(io)? {
                self.setpoints += 1;
                // The attitude too, where the vehicle's inputs steer it apart from its velocity.
                if let Some([alpha, gamma]) = self.model.attitude_setpoint(at, &command.decision.input, self.dt_s) {
                    self.autopilot.send_attitude([gamma, alpha, yaw], ms).map_err(io)?;
                }
                self.ask(Mode::Offboard, now)?;
            }
        } else {
            self.guard(now)?;
        }
        self.net.command(answer)
    }

    fn announce(&mut self, presence: Presence) -> Result<(), TransportError> {
        self.net.announce(presence)
    }

    fn listen(&mut self, uavs: &[u32]) -> Result<(), TransportError> {
        self.net.listen(uavs)
    }
}
