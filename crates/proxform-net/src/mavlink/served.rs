//! A vehicle's side of the MAVLink conversation, for a UAV whose dynamics someone else runs
//! (the simulated world's): what it says (HEARTBEAT with its mode and arming, LOCAL_POSITION_NED,
//! ATTITUDE, GLOBAL_POSITION_INT, HOME_POSITION and GPS_GLOBAL_ORIGIN from a state in NED) and
//! what it accepts: MAV_CMD_DO_SET_MODE and MAV_CMD_COMPONENT_ARM_DISARM addressed to it (each
//! answered by COMMAND_ACK), SET_POSITION_TARGET_LOCAL_NED velocity setpoints addressed to it
//! with finite values in the local NED frame, and SET_ATTITUDE_TARGET attitudes addressed to it
//! (a rotation; its roll and pitch go with the velocity setpoint while they are as fresh).
//! OFFBOARD is accepted only while setpoints stream
//! (as PX4 does), and falls back to HOLD when they stop for [`SETPOINT_LOSS_S`]. Anything
//! addressed to another system, or with values it cannot apply, is counted and never applied.

use mavlink::dialects::common::{
    AttitudeTargetTypemask, MavCmd, MavFrame, MavMessage, MavModeFlag, MavResult, MavState, MavType,
    PositionTargetTypemask, ATTITUDE_DATA, COMMAND_ACK_DATA, GLOBAL_POSITION_INT_DATA, GPS_GLOBAL_ORIGIN_DATA,
    HEARTBEAT_DATA, HOME_POSITION_DATA, LOCAL_POSITION_NED_DATA,
};
use mavlink::MavHeader;

use super::frame::{euler, GeoOrigin, Ned};
use super::modes::{Flavour, Mode};

/// Offboard setpoints older than this (s) put the vehicle in HOLD (PX4's COM_OF_LOSS_T is 1 s).
pub const SETPOINT_LOSS_S: f64 = 1.0;

/// A velocity setpoint in local NED.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    /// Velocity north, east, down (m/s).
    pub velocity_ned: [f64; 3],
    /// Yaw, clockwise from north (rad); None: keep the present one.
    pub yaw: Option<f64>,
    /// Roll and pitch (rad) of an attitude target heard within [`SETPOINT_LOSS_S`]; None: the
    /// ones the velocity brings.
    pub attitude: Option<[f64; 2]>,
    /// When it arrived (the vehicle's time, s).
    pub at_s: f64,
    /// Its sender's time stamp (`time_boot_ms`): a proxform agent flying on a world's sensing
    /// stamps the flight time of the update it decided at (ms), so the world can fly it from
    /// the same estimate.
    pub stamp_ms: u32,
}

/// Messages the vehicle refused, by reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Refused {
    /// Commands or setpoints addressed to another system.
    pub foreign: u64,
    /// Setpoints with a non-finite value, another frame, or no velocity; attitude targets that
    /// are no rotation.
    pub invalid: u64,
    /// Commands this vehicle does not carry out (answered UNSUPPORTED or DENIED).
    pub commands: u64,
}

/// One simulated UAV as a MAVLink system.
#[derive(Debug, Clone)]
pub struct Served {
    system_id: u8,
    flavour: Flavour,
    mav_type: MavType,
    armed: bool,
    mode: Mode,
    setpoint: Option<Setpoint>,
    /// The last attitude target's roll and pitch (rad) and when it arrived (s).
    attitude: Option<([f64; 2], f64)>,
    /// The last attitude target's sender's time stamp (`time_boot_ms`).
    attitude_stamp_ms: Option<u32>,
    /// Whether an outside controller may fly it (OFFBOARD).
    offboard: bool,
    /// What it refused.
    pub refused: Refused,
    /// Setpoints accepted.
    pub setpoints: u64,
    /// Attitude targets accepted.
    pub attitude_targets: u64,
}

impl Served {
    /// System `system_id` (component 1) of `flavour`, armed (it is flying), in HOLD.
    pub fn new(system_id: u8, flavour: Flavour, mav_type: MavType) -> Self {
        Self {
            system_id,
            flavour,
            mav_type,
            armed: true,
            mode: Mode::Hold,
            setpoint: None,
            attitude: None,
            attitude_stamp_ms: None,
            offboard: true,
            refused: Refused::default(),
            setpoints: 0,
            attitude_targets: 0,
        }
    }

    /// A vehicle that never takes OFFBOARD (asked, it answers DENIED): one whose flight
    /// someone else decides (the navigator flies its mission).
    pub fn without_offboard(mut self) -> Self {
        self.offboard = false;
        self
    }

    /// The mode it flies in.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The sender's time stamps (`time_boot_ms`) of the last setpoint and the last attitude
    /// target it accepted.
    pub fn stamps(&self) -> (Option<u32>, Option<u32>) {
        (self.setpoint.map(|s| s.stamp_ms), self.attitude_stamp_ms)
    }

    /// The setpoint to fly at `now_s`: in OFFBOARD, the last one; None in HOLD. Setpoints that
    /// stopped for [`SETPOINT_LOSS_S`] switch it to HOLD.
    pub fn setpoint(&mut self, now_s: f64) -> Option<Setpoint> {
        if self.mode == Mode::Offboard && self.setpoint.is_none_or(|s| now_s - s.at_s > SETPOINT_LOSS_S) {
            self.mode = Mode::Hold;
        }
        let attitude = self.attitude.filter(|(_, at)| now_s - at <= SETPOINT_LOSS_S).map(|(a, _)| a);
        (self.mode == Mode::Offboard).then_some(self.setpoint).flatten().map(|s| Setpoint { attitude, ..s })
    }

    /// Takes message `m` from `from` at `now_s`; the answer to send back, if any.
    pub fn handle(&mut self, from: &MavHeader, m: &MavMessage, now_s: f64) -> Option<MavMessage> {
        let _ = from;
        match m {
            MavMessage::SET_POSITION_TARGET_LOCAL_NED(s) => {
                if s.target_system != self.system_id {
                    self.refused.foreign += 1;
                    return None;
                }
                let ignore = |f: PositionTargetTypemask| s.type_mask.contains(f);
                let velocity = !ignore(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VX_IGNORE)
                    && !ignore(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VY_IGNORE)
                    && !ignore(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_VZ_IGNORE);
                let yaw =
                    (!ignore(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE)).then_some(f64::from(s.yaw));
                let v = [f64::from(s.vx), f64::from(s.vy), f64::from(s.vz)];
                if s.coordinate_frame != MavFrame::MAV_FRAME_LOCAL_NED
                    || !velocity
                    || !v.iter().all(|x| x.is_finite())
                    || yaw.is_some_and(|y| !y.is_finite())
                {
                    self.refused.invalid += 1;
                    return None;
                }
                self.setpoint =
                    Some(Setpoint { velocity_ned: v, yaw, attitude: None, at_s: now_s, stamp_ms: s.time_boot_ms });
                self.setpoints += 1;
                None
            }
            MavMessage::SET_ATTITUDE_TARGET(a) => {
                if a.target_system != self.system_id {
                    self.refused.foreign += 1;
                    return None;
                }
                let rotation = euler(a.q.map(f64::from)).filter(|_| {
                    !a.type_mask.contains(AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE)
                });
                match rotation {
                    Some([roll, pitch, _]) => {
                        self.attitude = Some(([roll, pitch], now_s));
                        self.attitude_stamp_ms = Some(a.time_boot_ms);
                        self.attitude_targets += 1;
                    }
                    None => self.refused.invalid += 1,
                }
                None
            }
            MavMessage::COMMAND_LONG(c) => {
                if c.target_system != self.system_id {
                    self.refused.foreign += 1;
                    return None;
                }
                let result = match c.command {
                    MavCmd::MAV_CMD_DO_SET_MODE => match self.flavour.mode_of_params(c.param2, c.param3) {
                        // OFFBOARD only with a setpoint stream running (as PX4 requires).
                        Some(Mode::Offboard)
                            if !self.offboard || self.setpoint.is_none_or(|s| now_s - s.at_s > SETPOINT_LOSS_S) =>
                        {
                            MavResult::MAV_RESULT_DENIED
                        }
                        Some(mode) => {
                            self.mode = mode;
                            MavResult::MAV_RESULT_ACCEPTED
                        }
                        None => MavResult::MAV_RESULT_UNSUPPORTED,
                    },
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => {
                        // A flying simulated UAV cannot be disarmed: it would fall out of the run.
                        if c.param1 == 1.0 {
                            self.armed = true;
                            MavResult::MAV_RESULT_ACCEPTED
                        } else {
                            MavResult::MAV_RESULT_DENIED
                        }
                    }
                    _ => MavResult::MAV_RESULT_UNSUPPORTED,
                };
                if result != MavResult::MAV_RESULT_ACCEPTED {
                    self.refused.commands += 1;
                }
                Some(MavMessage::COMMAND_ACK(COMMAND_ACK_DATA { command: c.command, result }))
            }
            _ => None,
        }
    }

    /// HEARTBEAT.
    pub fn heartbeat(&self) -> MavMessage {
        let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        if self.armed {
            base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: self.flavour.custom_mode(self.mode),
            mavtype: self.mav_type,
            autopilot: self.flavour.autopilot(),
            base_mode: base,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        })
    }

    /// Where local NED's origin is: HOME_POSITION and GPS_GLOBAL_ORIGIN.
    pub fn origin(&self, origin: &GeoOrigin) -> [MavMessage; 2] {
        let (lat, lon, alt) = geo_int(origin.lat_rad, origin.lon_rad, origin.alt_m);
        [
            MavMessage::HOME_POSITION(HOME_POSITION_DATA {
                latitude: lat,
                longitude: lon,
                altitude: alt,
                q: [1.0, 0.0, 0.0, 0.0],
                ..Default::default()
            }),
            MavMessage::GPS_GLOBAL_ORIGIN(GPS_GLOBAL_ORIGIN_DATA { latitude: lat, longitude: lon, altitude: alt }),
        ]
    }

    /// The state messages of `ned` at `now_s` (the vehicle's time since boot).
    pub fn telemetry(&self, now_s: f64, ned: &Ned, origin: &GeoOrigin) -> [MavMessage; 3] {
        let t = (now_s.max(0.0) * 1e3) as u32;
        let [n, e, d] = ned.position;
        let [vn, ve, vd] = ned.velocity;
        let [roll, pitch, yaw] = ned.attitude;
        let g = origin.geo(ned.position);
        let (lat, lon, alt) = geo_int(g.lat_rad, g.lon_rad, g.alt_m);
        let cm = |v: f64| (v * 100.0).round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
        let hdg = (yaw.to_degrees().rem_euclid(360.0) * 100.0).round() as u16 % 36_000;
        [
            MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                time_boot_ms: t,
                x: n as f32,
                y: e as f32,
                z: d as f32,
                vx: vn as f32,
                vy: ve as f32,
                vz: vd as f32,
            }),
            MavMessage::ATTITUDE(ATTITUDE_DATA {
                time_boot_ms: t,
                roll: roll as f32,
                pitch: pitch as f32,
                yaw: yaw as f32,
                ..Default::default()
            }),
            MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                time_boot_ms: t,
                lat,
                lon,
                alt,
                relative_alt: (-d * 1e3).round() as i32,
                vx: cm(vn),
                vy: cm(ve),
                vz: cm(vd),
                hdg,
            }),
        ]
    }
}

/// Latitude and longitude in 1e-7 degrees, altitude in mm.
fn geo_int(lat_rad: f64, lon_rad: f64, alt_m: f64) -> (i32, i32, i32) {
    (
        (lat_rad.to_degrees() * 1e7).round() as i32,
        (lon_rad.to_degrees() * 1e7).round() as i32,
        (alt_m * 1e3).round() as i32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{COMMAND_LONG_DATA, SET_POSITION_TARGET_LOCAL_NED_DATA};

    fn from() -> MavHeader {
        MavHeader { system_id: 255, component_id: 190, sequence: 0 }
    }

    fn velocity(target: u8, v: [f32; 3]) -> MavMessage {
        MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
            vx: v[0],
            vy: v[1],
            vz: v[2],
            type_mask: PositionTargetTypemask::from_bits_truncate(0b1101_1100_0111),
            target_system: target,
            target_component: 1,
            coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
            ..Default::default()
        })
    }

    fn set_mode(target: u8, mode: Mode) -> MavMessage {
        let (p2, p3) = Flavour::Px4.set_mode_params(mode);
        MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: 1.0,
            param2: p2,
            param3: p3,
            command: MavCmd::MAV_CMD_DO_SET_MODE,
            target_system: target,
            target_component: 1,
            ..Default::default()
        })
    }

    fn result(m: Option<MavMessage>) -> MavResult {
        match m {
            Some(MavMessage::COMMAND_ACK(a)) => a.result,
            other => panic!("no ack: {other:?}"),
        }
    }

    #[test]
    fn offboard_needs_a_setpoint_stream_and_falls_back_to_hold() {
        let mut v = Served::new(3, Flavour::Px4, MavType::MAV_TYPE_QUADROTOR);
        assert_eq!(result(v.handle(&from(), &set_mode(3, Mode::Offboard), 0.0)), MavResult::MAV_RESULT_DENIED);
        v.handle(&from(), &velocity(3, [1.0, 2.0, -0.5]), 0.1);
        assert_eq!(v.setpoint(0.1), None, "in HOLD until asked");
        assert_eq!(result(v.handle(&from(), &set_mode(3, Mode::Offboard), 0.2)), MavResult::MAV_RESULT_ACCEPTED);
        let s = v.setpoint(0.5).expect("offboard");
        assert_eq!(s.velocity_ned, [1.0, 2.0, -0.5]);
        assert_eq!(s.yaw, None);
        assert!(v.setpoint(1.2).is_none(), "1.1 s without a setpoint");
        assert_eq!(v.mode(), Mode::Hold);
    }

    #[test]
    fn foreign_and_invalid_input_is_counted_never_applied() {
        let mut v = Served::new(3, Flavour::Px4, MavType::MAV_TYPE_QUADROTOR);
        v.handle(&from(), &velocity(3, [1.0, 0.0, 0.0]), 0.0);
        v.handle(&from(), &set_mode(3, Mode::Offboard), 0.0);
        assert!(v.handle(&from(), &velocity(4, [9.0, 9.0, 9.0]), 0.1).is_none());
        assert!(v.handle(&from(), &set_mode(4, Mode::Hold), 0.1).is_none());
        v.handle(&from(), &velocity(3, [f32::NAN, 0.0, 0.0]), 0.1);
        v.handle(&from(), &velocity(3, [f32::INFINITY, 0.0, 0.0]), 0.1);
        let mut global = velocity(3, [5.0, 0.0, 0.0]);
        if let MavMessage::SET_POSITION_TARGET_LOCAL_NED(s) = &mut global {
            s.coordinate_frame = MavFrame::MAV_FRAME_BODY_FRD;
        }
        v.handle(&from(), &global, 0.1);
        assert_eq!(v.refused, Refused { foreign: 2, invalid: 3, commands: 0 });
        // A vehicle that flies its own mission refuses OFFBOARD even with setpoints streaming.
        let mut nav = Served::new(1, Flavour::Px4, MavType::MAV_TYPE_QUADROTOR).without_offboard();
        nav.handle(&from(), &velocity(1, [1.0, 0.0, 0.0]), 0.0);
        assert_eq!(result(nav.handle(&from(), &set_mode(1, Mode::Offboard), 0.0)), MavResult::MAV_RESULT_DENIED);
        assert_eq!(nav.setpoint(0.1), None);
        assert_eq!(v.setpoint(0.2).expect("still offboard").velocity_ned, [1.0, 0.0, 0.0]);
        assert_eq!(v.mode(), Mode::Offboard);
    }

    #[test]
    fn an_attitude_target_goes_with_the_setpoint_while_it_is_fresh() {
        use mavlink::dialects::common::SET_ATTITUDE_TARGET_DATA;
        let attitude = |target: u8, q: [f32; 4]| {
            MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA { q, target_system: target, ..Default::default() })
        };
        let mut v = Served::new(3, Flavour::Px4, MavType::MAV_TYPE_QUADROTOR);
        v.handle(&from(), &velocity(3, [1.0, 0.0, 0.0]), 0.0);
        v.handle(&from(), &set_mode(3, Mode::Offboard), 0.0);
        assert_eq!(v.setpoint(0.0).expect("offboard").attitude, None);
        let q = super::super::frame::quaternion([0.1, -0.2, 0.7]).map(|x| x as f32);
        v.handle(&from(), &attitude(3, q), 0.1);
        v.handle(&from(), &velocity(3, [1.0, 0.0, 0.0]), 0.9);
        let [roll, pitch] = v.setpoint(0.9).expect("offboard").attitude.expect("fresh");
        assert!((roll - 0.1).abs() < 1e-6 && (pitch + 0.2).abs() < 1e-6, "{roll} {pitch}");
        // Older than the setpoint loss time, it is not flown; another system's, or no rotation, never.
        v.handle(&from(), &velocity(3, [1.0, 0.0, 0.0]), 1.2);
        assert_eq!(v.setpoint(1.2).expect("offboard").attitude, None);
        v.handle(&from(), &attitude(4, q), 1.2);
        v.handle(&from(), &attitude(3, [0.0; 4]), 1.2);
        v.handle(&from(), &attitude(3, [f32::NAN, 0.0, 0.0, 1.0]), 1.2);
        assert_eq!(v.refused, Refused { foreign: 1, invalid: 2, commands: 0 });
        assert_eq!(v.setpoint(1.2).expect("offboard").attitude, None);
    }

    #[test]
    fn telemetry_says_where_the_state_is() {
        let v = Served::new(1, Flavour::Px4, MavType::MAV_TYPE_QUADROTOR);
        let origin = GeoOrigin::from_degrees(47.397742, 8.545594, 488.0);
        let ned = Ned { position: [100.0, -50.0, -20.0], velocity: [3.0, -4.0, 0.5], attitude: [0.1, -0.05, -1.0] };
        let [local, _, global] = v.telemetry(12.5, &ned, &origin);
        let MavMessage::LOCAL_POSITION_NED(l) = local else { panic!("{local:?}") };
        assert_eq!((l.time_boot_ms, l.x, l.y, l.z), (12_500, 100.0, -50.0, -20.0));
        let MavMessage::GLOBAL_POSITION_INT(g) = global else { panic!("{global:?}") };
        let back = origin.ned(&super::super::frame::Geo {
            lat_rad: (f64::from(g.lat) * 1e-7).to_radians(),
            lon_rad: (f64::from(g.lon) * 1e-7).to_radians(),
            alt_m: f64::from(g.alt) * 1e-3,
        });
        assert!(
            (back[0] - 100.0).abs() < 0.02 && (back[1] + 50.0).abs() < 0.02 && (back[2] + 20.0).abs() < 1e-3,
            "{back:?}"
        );
        assert_eq!((g.relative_alt, g.vx, g.vy, g.vz), (20_000, 300, -400, 50));
        assert_eq!(g.hdg, 30_270); // −1 rad is 302.7°
    }
}
