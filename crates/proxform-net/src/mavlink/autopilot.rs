//! The companion computer's side of the MAVLink conversation with its autopilot: which system
//! it flies (the first autopilot heard, or the one named), its state from LOCAL_POSITION_NED
//! and ATTITUDE (each with the time it arrived), where local NED is on the earth (HOME_POSITION
//! or GPS_GLOBAL_ORIGIN), its mode and arming from HEARTBEAT; and what it sends:
//! SET_POSITION_TARGET_LOCAL_NED velocity and yaw setpoints (and SET_ATTITUDE_TARGET attitudes for
//! the vehicle whose attitude is steered apart from its velocity), MAV_CMD_DO_SET_MODE for OFFBOARD
//! (PX4) or GUIDED (ArduPilot) and for HOLD/LOITER, and a HEARTBEAT of its own. It never arms
//! the vehicle. Messages from other systems, and its system id written from another address
//! than the autopilot's, are counted and left alone, and never move where a listening link
//! sends ([`super::link::PEER_SILENT`]).
//!
//! The safety policy ([`Safety`]) is apart from the link: given how old the own state and the
//! references are, fly the controller's setpoints or ask for HOLD.

use std::time::{Duration, Instant};

use mavlink::dialects::common::{
    AttitudeTargetTypemask, MavAutopilot, MavCmd, MavFrame, MavMessage, MavModeFlag, MavState, MavType,
    PositionTargetTypemask, COMMAND_LONG_DATA, HEARTBEAT_DATA, SET_ATTITUDE_TARGET_DATA,
    SET_POSITION_TARGET_LOCAL_NED_DATA,
};
use proxform_core::State9;

use super::frame::{quaternion, Frame, GeoOrigin, Ned};
use super::link::Link;
use super::modes::{Flavour, Mode};

/// The type mask of a velocity and yaw setpoint: position, acceleration and yaw rate ignored.
const VELOCITY_AND_YAW: u16 = 0b1001_1100_0111;

/// What the companion knows of its autopilot.
pub struct Autopilot {
    link: Link,
    target: Option<u8>,
    flavour: Option<Flavour>,
    position: Option<([f64; 6], Instant)>,
    attitude: Option<([f64; 3], Instant)>,
    origin: Option<GeoOrigin>,
    mode: Option<Mode>,
    armed: bool,
    /// Messages from systems other than the autopilot flown.
    pub foreign: u64,
    /// The last COMMAND_ACK: the command and whether it was accepted.
    pub last_ack: Option<(MavCmd, bool)>,
}

impl Autopilot {
    /// The autopilot over `link`; `target` names its system id (None: the first autopilot
    /// whose HEARTBEAT is heard).
    pub fn new(mut link: Link, target: Option<u8>) -> Self {
        // Only the autopilot's frames say where it is.
        link.answer_system(target);
        Self {
            link,
            target,
            flavour: None,
            position: None,
            attitude: None,
            origin: None,
            mode: None,
            armed: false,
            foreign: 0,
            last_ack: None,
        }
    }

    /// The link (its counters).
    pub fn link(&self) -> &Link {
        &self.link
    }

    /// The system flown, once known.
    pub fn target(&self) -> Option<u8> {
        self.target
    }

    /// Which autopilot it is (PX4, ArduPilot), as its HEARTBEAT says (None before one came).
    pub fn flavour(&self) -> Option<Flavour> {
        self.flavour
    }

    /// The mode the autopilot last reported.
    pub fn mode(&self) -> Option<Mode> {
        self.mode
    }

    /// Whether the autopilot last reported itself armed.
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// Where local NED is on the earth, once reported.
    pub fn origin(&self) -> Option<GeoOrigin> {
        self.origin
    }

    /// Reads what arrived, waiting at most `wait` for the first message.
    pub fn poll(&mut self, wait: Duration) -> std::io::Result<()> {
        let mut wait = wait;
        while let Some((h, m)) = self.link.recv(wait)? {
            wait = Duration::ZERO;
            let system = u8::try_from(h.system_id).ok();
            if let MavMessage::HEARTBEAT(b) = &m {
                if self.target.is_none() && h.component_id == 1 && b.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID {
                    self.target = system;
                    self.link.answer_system(system);
                }
            }
            // The autopilot's frames come from the address the link answers; its system id
            // written from elsewhere (unsigned MAVLink: anyone can) is another's.
            if system.is_none() || system != self.target || !self.link.from_peer() {
                self.foreign += 1;
                continue;
            }
            let now = Instant::now();
            match m {
                MavMessage::HEARTBEAT(b) => {
                    self.flavour = Flavour::of(b.autopilot).or(self.flavour);
                    self.mode = self.flavour.and_then(|f| f.mode_of(b.custom_mode));
                    self.armed = b.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                }
                MavMessage::LOCAL_POSITION_NED(p) => {
                    let v = [p.x, p.y, p.z, p.vx, p.vy, p.vz].map(f64::from);
                    if v.iter().all(|x| x.is_finite()) {
                        self.position = Some((v, now));
                    }
                }
                MavMessage::ATTITUDE(a) => {
                    let v = [a.roll, a.pitch, a.yaw].map(f64::from);
                    if v.iter().all(|x| x.is_finite()) {
                        self.attitude = Some((v, now));
                    }
                }
                MavMessage::HOME_POSITION(o) => {
                    self.origin = Some(origin_of(o.latitude, o.longitude, o.altitude));
                }
                MavMessage::GPS_GLOBAL_ORIGIN(o) => {
                    self.origin = Some(origin_of(o.latitude, o.longitude, o.altitude));
                }
                MavMessage::COMMAND_ACK(a) => {
                    self.last_ack =
                        Some((a.command, a.result == mavlink::dialects::common::MavResult::MAV_RESULT_ACCEPTED));
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The vehicle in local NED and how old its older part is (None before both position and
    /// attitude arrived).
    pub fn ned(&self, now: Instant) -> Option<(Ned, Duration)> {
        let ((p, tp), (a, ta)) = (self.position?, self.attitude?);
        let age = now.saturating_duration_since(tp.min(ta));
        Some((Ned { position: [p[0], p[1], p[2]], velocity: [p[3], p[4], p[5]], attitude: a }, age))
    }

    /// When the newest position arrived (each one is a new sample of the vehicle's state).
    pub fn position_at(&self) -> Option<Instant> {
        self.position.map(|(_, t)| t)
    }

    /// The vehicle's state in the method's frame `frame`, and its age.
    pub fn state(&self, frame: &Frame, now: Instant) -> Option<(State9, Duration)> {
        self.ned(now).map(|(n, age)| (frame.state(&n), age))
    }

    /// Sends an attitude target (roll, pitch, yaw; rad), body rates and thrust ignored; refuses
    /// non-finite values (nothing is sent).
    pub fn send_attitude(&mut self, attitude: [f64; 3], time_boot_ms: u32) -> std::io::Result<bool> {
        let Some(target) = self.target else { return Ok(false) };
        if !attitude.iter().all(|v| v.is_finite()) {
            return Ok(false);
        }
        let m = MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            time_boot_ms,
            q: quaternion(attitude).map(|v| v as f32),
            type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE
                | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE
                | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE
                | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE,
            target_system: target,
            target_component: 1,
            ..Default::default()
        });
        self.link.send(&m).map(|()| true)
    }

    /// Sends a velocity (NED, m/s) and yaw (clockwise from north, rad) setpoint; refuses
    /// non-finite values (nothing is sent).
    pub fn send_velocity(&mut self, velocity_ned: [f64; 3], yaw: f64, time_boot_ms: u32) -> std::io::Result<bool> {
        let Some(target) = self.target else { return Ok(false) };
        if !velocity_ned.iter().all(|v| v.is_finite()) || !yaw.is_finite() {
            return Ok(false);
        }
        let m = MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
            time_boot_ms,
            vx: velocity_ned[0] as f32,
            vy: velocity_ned[1] as f32,
            vz: velocity_ned[2] as f32,
            yaw: yaw as f32,
            type_mask: PositionTargetTypemask::from_bits_truncate(VELOCITY_AND_YAW),
            target_system: target,
            target_component: 1,
            coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
            ..Default::default()
        });
        self.link.send(&m).map(|()| true)
    }

    /// Asks the autopilot for `mode` (its flavour's numbers; PX4's until a HEARTBEAT said).
    pub fn request(&mut self, mode: Mode) -> std::io::Result<()> {
        let Some(target) = self.target else { return Ok(()) };
        let (p2, p3) = self.flavour.unwrap_or(Flavour::Px4).set_mode_params(mode);
        let m = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.bits() as f32,
            param2: p2,
            param3: p3,
            command: MavCmd::MAV_CMD_DO_SET_MODE,
            target_system: target,
            target_component: 1,
            ..Default::default()
        });
        self.link.send(&m)
    }

    /// The companion's own HEARTBEAT (an onboard controller).
    pub fn heartbeat(&mut self) -> std::io::Result<()> {
        self.link.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }))
    }
}

fn origin_of(lat: i32, lon: i32, alt_mm: i32) -> GeoOrigin {
    GeoOrigin::from_degrees(f64::from(lat) * 1e-7, f64::from(lon) * 1e-7, f64::from(alt_mm) * 1e-3)
}

/// When the companion stops flying its controller's setpoints and asks for HOLD.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Safety {
    /// The own state older than this: HOLD (s).
    pub position_timeout_s: f64,
    /// No reference (a neighbour's report, the mission) newer than this: HOLD (s).
    pub reference_timeout_s: f64,
}

impl Default for Safety {
    fn default() -> Self {
        Self { position_timeout_s: 0.5, reference_timeout_s: 2.0 }
    }
}

/// What the safety policy says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Fly the controller's setpoints.
    Fly,
    /// Ask the autopilot to hold, for this reason.
    Hold(&'static str),
}

impl Safety {
    /// The verdict for an own state `own_age_s` old (None: never received) and references
    /// last heard `reference_age_s` ago (None: never).
    pub fn verdict(&self, own_age_s: Option<f64>, reference_age_s: Option<f64>) -> Verdict {
        match (own_age_s, reference_age_s) {
            (None, _) => Verdict::Hold("no position from the autopilot"),
            (Some(a), _) if a.is_nan() || a > self.position_timeout_s => {
                Verdict::Hold("the autopilot's position is stale")
            }
            (_, None) => Verdict::Hold("no reference heard"),
            (_, Some(r)) if r.is_nan() || r > self.reference_timeout_s => Verdict::Hold("the references are lost"),
            _ => Verdict::Fly,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_safety_policy_holds_without_a_fresh_position_or_references() {
        let s = Safety::default();
        assert_eq!(s.verdict(Some(0.1), Some(0.5)), Verdict::Fly);
        assert!(matches!(s.verdict(None, Some(0.1)), Verdict::Hold(_)));
        assert!(matches!(s.verdict(Some(0.6), Some(0.1)), Verdict::Hold(_)));
        assert!(matches!(s.verdict(Some(f64::NAN), Some(0.1)), Verdict::Hold(_)));
        assert!(matches!(s.verdict(Some(0.1), None), Verdict::Hold(_)));
        assert!(matches!(s.verdict(Some(0.1), Some(2.5)), Verdict::Hold(_)));
    }
}
