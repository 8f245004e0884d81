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

use proxform_core::state::{Input, State9};
use proxform_core::{Outcome, VehicleModel};

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
    /// The targets flown while the agent holds.
    kept: KeptTargets,
    /// Setpoints sent.
    pub setpoints: u64,
    /// Times HOLD was asked by the safety policy, and the last reason.
    pub holds: (u64, Option<&'static str>),
}

/// What an autopilot is asked to fly, in the method's frame: velocity (m/s), yaw β (rad) and,
/// for a vehicle whose inputs steer its attitude apart from its velocity, pitch α and roll γ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Targets {
    /// Velocity (m/s).
    pub velocity_mps: [f64; 3],
    /// Yaw β (rad).
    pub yaw_rad: f64,
    /// Pitch α and roll γ (rad), for the paper's kinematic vehicle.
    pub attitude: Option<[f64; 2]>,
    /// The instant of the update they were decided at (flight time, s); None for what the
    /// autopilot reported it had.
    pub decided_t_s: Option<f64>,
}

/// The targets an autopilot is asked to fly after each answer: an adjusted decision's (the
/// decision's setpoint, or the velocity, yaw and attitude its input reaches from the state it
/// was decided at: not the update's, which would undo the commands still on their way); while
/// the agent holds, the last adjusted targets again (an autopilot keeps flying its last
/// setpoint, as a held UAV keeps its course in process: targets re-derived from each update's
/// measured state would fly the sensor's noise every period); before its first adjustment, what
/// the autopilot reports it has. Each carries the instant of the update it was decided at
/// (kept targets, their adjusted decision's).
#[derive(Debug, Clone, Default)]
pub struct KeptTargets {
    last: Option<Targets>,
}

impl KeptTargets {
    /// The targets after `answer`, for `model` at period `dt_s`; `autopilot` is the state the
    /// autopilot reports, when it has reported one.
    pub fn next(&mut self, model: &VehicleModel, dt_s: f64, answer: &Answer, autopilot: Option<&State9>) -> Targets {
        let (decision, at) = (&answer.command.decision, &answer.decided_at);
        let adjusted = matches!(decision.outcome, Outcome::Adjusted { .. });
        let zero = Input::zeros();
        let (from, input, decided_t_s) = match (adjusted, self.last, autopilot) {
            // The decision's own setpoint says what it keeps (the multirotor's).
            (false, Some(last), _) if decision.setpoint.is_none() => return last,
            // Nothing adjusted yet: hold what the autopilot has.
            (false, None, Some(own)) => (own, &zero, None),
            _ => (at, &decision.input, Some(answer.state.t_s)),
        };
        let (velocity_mps, yaw_rad) = match decision.setpoint {
            Some(sp) => (sp.velocity_mps, sp.yaw_rad),
            None => model.velocity_setpoint(from, input, dt_s),
        };
        let attitude = model.attitude_setpoint(from, input, dt_s);
        let targets = Targets { velocity_mps, yaw_rad, attitude, decided_t_s };
        if adjusted {
            self.last = Some(targets);
        }
        targets
    }
}

/// A flight time (s) as a MAVLink `time_boot_ms` stamp.
pub fn stamp_ms(t_s: f64) -> u32 {
    (t_s.max(0.0) * 1e3).round() as u32
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
            kept: KeptTargets::default(),
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

    /// Asks for `mode` unless the autopilot is in it or it was asked lately; whether it asked.
    fn ask(&mut self, mode: Mode, now: Instant) -> Result<bool, TransportError> {
        let recent = self.asked.is_some_and(|(m, t)| m == mode && now.duration_since(t) < ASK_EVERY);
        if self.autopilot.mode() != Some(mode) && !recent {
            self.autopilot.request(mode).map_err(io)?;
            self.asked = Some((mode, now));
            return Ok(true);
        }
        Ok(false)
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
                // Counted as asked (the request goes out at most every `ASK_EVERY`).
                if self.ask(Mode::Hold, now)? {
                    self.holds = (self.holds.0 + 1, Some(why));
                }
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
            Event::Sense(s) => {
                // The world is the UAV's sensors: its own state is the world's measurement (as
                // in process), the estimate its simulated autopilot flies the targets from.
                self.last_update = Some(now);
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
        if self.sensing == Sensing::Autopilot && self.clock.is_none() {
            // Before the flight: nothing for the autopilot.
            return self.net.command(answer);
        }
        if self.verdict(now) == Verdict::Fly {
            // The agent's setpoint (absolute), or the velocity and yaw its input reaches from
            // the state it was decided at (not the update's: that would undo the commands
            // still on their way).
            let own = self.autopilot.state(&self.frame, now).map(|(s, _)| s);
            let targets = self.kept.next(&self.model, self.dt_s, answer, own.as_ref());
            let (v, yaw) = (self.frame.velocity_ned(targets.velocity_mps), self.frame.yaw(targets.yaw_rad));
            // Stamped with the flight time of the world's update they were decided at, which a
            // world's simulated autopilot flies them from (its estimate then was that update's
            // measurement); otherwise with the time since the agent started, as MAVLink's
            // `time_boot_ms` is.
            let ms = match (self.sensing, targets.decided_t_s) {
                (Sensing::World, Some(t_s)) => stamp_ms(t_s),
                _ => now.duration_since(self.boot).as_millis() as u32,
            };
            if self.autopilot.send_velocity(v, yaw, ms).map_err(io)? {
                self.setpoints += 1;
                // The attitude too, where the vehicle's inputs steer it apart from its velocity.
                if let Some([alpha, gamma]) = targets.attitude {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::{CommandMsg, StateMsg};
    use proxform_core::state::{ALPHA, BETA, VX, VY};
    use proxform_core::vehicle::{KinematicModel, MultirotorModel, Setpoint};
    use proxform_core::Decision;

    fn answer(outcome: Outcome, input: Input, at: State9, setpoint: Option<Setpoint>) -> Answer {
        let mut decision = Decision::without_areas(outcome, input);
        decision.setpoint = setpoint;
        let command = CommandMsg { uav: 2, run: 0, k: 1, t_s: 0.1, age_s: 0.0, decision, digest: 0 };
        Answer { command, state: StateMsg { uav: 2, k: 1, t_s: 0.1, state: at, rejoining: false }, decided_at: at }
    }

    fn state(vx: f64, vy: f64, alpha: f64, beta: f64) -> State9 {
        let mut s = State9::zeros();
        (s[VX], s[VY], s[ALPHA], s[BETA]) = (vx, vy, alpha, beta);
        s
    }

    #[test]
    fn an_autopilot_keeps_flying_the_last_adjusted_targets_while_its_agent_holds() {
        let (model, dt) = (VehicleModel::Kinematic(KinematicModel::default()), 0.1);
        let held = |at| answer(Outcome::Held, Input::zeros(), at, None);
        let mut kept = KeptTargets::default();
        // Before any adjustment: what the autopilot reports it has, not the measured state.
        let truth = state(20.0, 0.0, 0.0, 0.0);
        let measured = state(20.3, -0.2, 0.01, 0.02);
        let first = kept.next(&model, dt, &held(measured), Some(&truth));
        assert_eq!((first.velocity_mps, first.yaw_rad, first.attitude), ([20.0, 0.0, 0.0], 0.0, Some([0.0, 0.0])));
        // An adjustment: the input's targets from the state it was decided at.
        let mut u = Input::zeros();
        (u[0], u[1], u[3]) = (0.5, -0.4, 0.02);
        let adjusted =
            kept.next(&model, dt, &answer(Outcome::Adjusted { normalised_sq: 2.0 }, u, measured, None), Some(&truth));
        let (v, beta) = model.velocity_setpoint(&measured, &u, dt);
        assert_eq!((adjusted.velocity_mps, adjusted.yaw_rad), (v, beta));
        assert_eq!(adjusted.attitude, model.attitude_setpoint(&measured, &u, dt));
        assert!((adjusted.velocity_mps[0] - 20.8).abs() < 1e-9, "{adjusted:?}");
        // Stamped with the update they were decided at; the autopilot's own state with none.
        assert_eq!((first.decided_t_s, adjusted.decided_t_s), (None, Some(0.1)));
        // Held at other measured states (the sensor's noise): the same targets, every time.
        for noisy in [state(20.6, 0.3, -0.02, 0.05), state(19.9, -0.5, 0.03, -0.01)] {
            // (Later updates: the stamp stays the adjusted decision's.)
            let mut later = held(noisy);
            later.state.t_s = 0.5;
            assert_eq!(kept.next(&model, dt, &later, Some(&truth)), adjusted);
            let alone = answer(Outcome::Alone, Input::zeros(), noisy, None);
            assert_eq!(kept.next(&model, dt, &alone, Some(&truth)), adjusted);
        }
    }

    #[test]
    fn a_decisions_own_setpoint_is_flown_as_it_is() {
        // The multirotor's decisions carry the setpoint they keep while holding.
        let (model, dt) = (VehicleModel::Multirotor(MultirotorModel::default()), 0.1);
        let mut kept = KeptTargets::default();
        let at = state(5.0, 0.0, 0.0, 0.0);
        let sp = Setpoint { velocity_mps: [5.5, 1.0, 0.0], yaw_rad: 0.2 };
        let mut u = Input::zeros();
        u[0] = 0.5;
        let a = kept.next(&model, dt, &answer(Outcome::Adjusted { normalised_sq: 2.0 }, u, at, Some(sp)), None);
        assert_eq!((a.velocity_mps, a.yaw_rad, a.attitude), (sp.velocity_mps, sp.yaw_rad, None));
        let later = Setpoint { velocity_mps: [5.0, 0.5, 0.0], yaw_rad: 0.1 };
        let h =
            kept.next(&model, dt, &answer(Outcome::Held, Input::zeros(), state(6.0, 0.0, 0.0, 0.0), Some(later)), None);
        assert_eq!((h.velocity_mps, h.yaw_rad), (later.velocity_mps, later.yaw_rad));
    }
}
