//! An agent's UAV behind a MAVLink autopilot ([`MavlinkVehicle`], `proxform-agent --mavlink`):
//! with a world's sensing ([`Sensing::World`]) its update is the world's as before (the world
//! is the UAV's sensors: its own state is the world's measurement, which the world's simulated
//! autopilot also flies from, as a real one flies from its estimator's state); without
//! ([`Sensing::Autopilot`]) its own state is the autopilot's (LOCAL_POSITION_NED and ATTITUDE in
//! the method's frame). Each
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
use crate::wire::{ClockMode, Phase, Presence, SenseMsg, STALE_AFTER_PERIODS};

/// How often a mode is asked for again while the autopilot is not in it.
const ASK_EVERY: Duration = Duration::from_millis(500);

/// Where an agent over MAVLink takes its updates from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensing {
    /// A world's sensing over the network, own state included (the world's measurement, from
    /// which the world's simulated autopilot flies the targets).
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
    /// The flight clock's t = 0 (ns since the Unix epoch), once a real-time Clock said it.
    epoch_ns: Option<u64>,
    /// A decision for a later step than the present one, held until its instant.
    queued: Option<(Instant, Answer)>,
    /// Targets held until their instant, so far.
    pub held_for_their_instant: u64,
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
            epoch_ns: None,
            queued: None,
            held_for_their_instant: 0,
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
    /// The flight clock's t = 0, from a real-time Clock.
    fn note_clock(&mut self, c: &crate::wire::ClockMsg) {
        if c.mode == ClockMode::RealTime && c.epoch_ns > 0 {
            self.epoch_ns = Some(c.epoch_ns);
        }
    }

    /// When the targets of `answer` are to be sent, if later than now: a decision for a later
    /// step than the present one (its update came late, and the agent decided for the step its
    /// command reaches) waits for that step, a little before it (the autopilot flies a target
    /// when it arrives: sent now, it would act a period early). At most
    /// [`STALE_AFTER_PERIODS`] periods ahead (a clock that disagrees holds nothing longer).
    fn due(&self, answer: &Answer) -> Option<Instant> {
        let epoch_ns = self.epoch_ns?;
        let unix_s = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).ok()?.as_secs_f64();
        let wait_s = wait_for_instant(answer.command.t_s, unix_s - epoch_ns as f64 * 1e-9, self.dt_s)?;
        Some(Instant::now() + Duration::from_secs_f64(wait_s))
    }

    /// Sends the held targets whose instant has come.
    fn release(&mut self, now: Instant) -> Result<(), TransportError> {
        if let Some((due, answer)) = self.queued {
            if now >= due {
                self.queued = None;
                self.fly(&answer, now)?;
            }
        }
        Ok(())
    }

    /// The targets of `answer` to the autopilot now (or HOLD, if the safety policy says so).
    fn fly(&mut self, answer: &Answer, now: Instant) -> Result<(), TransportError> {
        let command = &answer.command;
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
            Ok(())
        } else {
            self.guard(now)
        }
    }
}

/// How long targets for the flight instant `t_s` wait at flight time `now_s` (periods of
/// `dt_s`): until a little before `t_s` (5 ms, or a twentieth of a period if shorter), so they
/// reach the autopilot after the present step and before theirs; None to send them now (their
/// instant has come, or is beyond [`STALE_AFTER_PERIODS`] periods: a clock that disagrees
/// holds nothing).
pub fn wait_for_instant(t_s: f64, now_s: f64, dt_s: f64) -> Option<f64> {
    let lead_s = (0.05 * dt_s).min(0.005);
    let wait_s = t_s - lead_s - now_s;
    (wait_s > 0.001 && wait_s <= STALE_AFTER_PERIODS * dt_s).then_some(wait_s)
}

impl Vehicle for MavlinkVehicle {
    fn next(&mut self, timeout: Duration) -> Result<Event, TransportError> {
        self.autopilot.poll(Duration::ZERO).map_err(io)?;
        self.release(Instant::now())?;
        // Back in time for held targets.
        let timeout = match self.queued {
            Some((due, _)) => timeout.min(due.saturating_duration_since(Instant::now())),
            None => timeout,
        };
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
                    self.note_clock(&c);
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
            Event::Sense(s) => {
                // The world is the UAV's sensors: its own state is the world's measurement (as
                // in process), the estimate its simulated autopilot flies the targets from.
                self.last_update = Some(now);
                Ok(Event::Sense(s))
            }
            other => {
                if let Event::Clock(c) = &other {
                    self.note_clock(c);
                }
                self.guard(now)?;
                Ok(other)
            }
        }
    }

    fn command(&mut self, answer: &Answer) -> Result<(), TransportError> {
        let now = Instant::now();
        if self.sensing == Sensing::Autopilot && self.clock.is_none() {
            // Before the flight: nothing for the autopilot.
            return self.net.command(answer);
        }
        match self.due(answer) {
            // For a later step: held until its instant (a newer decision replaces it).
            Some(due) => {
                self.queued = Some((due, *answer));
                self.held_for_their_instant += 1;
            }
            None => {
                self.queued = None;
                self.fly(answer, now)?;
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_for_a_later_step_wait_for_it_and_none_else() {
        let dt = 0.1;
        // Decided at 1.027 s for the step of 1.1 s: sent at 1.095 s, after the present step's.
        let wait = wait_for_instant(1.1, 1.027, dt).expect("held");
        assert!((wait - 0.068).abs() < 1e-9, "{wait}");
        // For the present step (or one past): at once.
        assert_eq!(wait_for_instant(1.0, 1.027, dt), None);
        assert_eq!(wait_for_instant(1.03, 1.027, dt), None);
        // Beyond what an agent decides for: a clock that disagrees, sent at once.
        assert_eq!(wait_for_instant(9.0, 1.0, dt), None);
    }
}
