//! The world's UAVs as MAVLink systems (`--mavlink-port BASE`): UAV i is system i, component 1,
//! a PX4 that sends to `127.0.0.1:BASE + i − 1` (as PX4 SITL's instances send to 14540 + i)
//! and answers whoever speaks to it there. Every flight step it says where its UAV truly is
//! (LOCAL_POSITION_NED, ATTITUDE, GLOBAL_POSITION_INT; HEARTBEAT, HOME_POSITION and
//! GPS_GLOBAL_ORIGIN each second), in local NED whose origin is the method's and whose north is
//! the method's x (the formation's initial course). A follower whose MAVLink controller has
//! switched it to OFFBOARD and streams velocity setpoints flies them (the decision is the input
//! toward the setpoint, within the vehicle's limits; with the roll and pitch of its attitude
//! target where the vehicle's attitude is steered apart from its velocity) instead of its
//! proxform agent's; without
//! setpoints for a second it falls back to HOLD, and its agent's decisions again. The navigator
//! likewise flies an outside controller's setpoints instead of its path while in OFFBOARD (the
//! followers keep their places around it as it flies), and its path again after.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use proxform_core::controller::ControllerSetup;
use proxform_core::{state, Decision, Outcome, State9};
use proxform_net::mavlink::frame::{Frame, GeoOrigin};
use proxform_net::mavlink::link::{Endpoint, Link, LinkStats};
use proxform_net::mavlink::modes::{Flavour, Mode};
use proxform_net::mavlink::served::{Refused, Served};
use proxform_net::mavlink::vehicle::stamp_ms;
use proxform_scenario::Scenario;
use proxform_sim::world::remote::{Agents, StepRequest};

/// Where local NED's origin is on the earth (PX4 SITL's default home).
pub const ORIGIN: (f64, f64, f64) = (47.397742, 8.545594, 488.0);

/// How long a step's flight waits for the setpoints of the followers flown in OFFBOARD that
/// have not sent one since the last step (a MAVLink link's latency: a router, a relay, a serial
/// bridge). A setpoint later than that flies from the next step on. Without it a setpoint that
/// arrived a millisecond after the agents' answers over Zenoh was flown a whole period late,
/// every step (measured: the paper's followers through a relay, roll 6.4° against 0.12°).
pub const SETPOINT_ALLOWANCE: Duration = Duration::from_millis(20);

/// How many of a UAV's last measurements the world keeps the errors of, for the setpoints
/// decided at them (3.2 s at the paper's period; a setpoint is flown for at most
/// [`proxform_net::mavlink::served::SETPOINT_LOSS_S`]).
const MEASUREMENTS_KEPT: usize = 32;

/// One UAV's MAVLink system.
struct Vehicle {
    served: Served,
    link: Link,
    /// Setpoints and attitude targets it had been sent when its last step was flown.
    flown_setpoints: (u64, u64),
    /// The errors (measured − true) of the measurements its agent was sent, by their instant
    /// as a stamp (ms of flight time).
    measured: VecDeque<(u32, State9)>,
    /// The error of the estimate the setpoint being flown was decided at, by its stamp (kept
    /// while the agent re-sends the same targets, however long it holds).
    flown_error: Option<(u32, State9)>,
    /// Whether the last setpoint came from the offboard port the vehicle sends to (where a
    /// proxform agent over MAVLink listens), not from a program elsewhere.
    setpoint_from_port: bool,
}

impl Vehicle {
    /// The error of the measurement stamped `stamp` (what the autopilot's estimate was when
    /// the setpoint was decided), if its agent decided it on one the world sent.
    fn estimate_error(&mut self, stamp: u32) -> Option<State9> {
        if let Some((_, e)) = self.flown_error.filter(|(s, _)| *s == stamp) {
            return Some(e);
        }
        let e = self.measured.iter().rev().find(|(s, _)| *s == stamp).map(|(_, e)| *e)?;
        self.flown_error = Some((stamp, e));
        Some(e)
    }
}

/// Every UAV of the world as a MAVLink system.
pub struct MavlinkSwarm {
    vehicles: Vec<Vehicle>,
    frame: Frame,
    origin: GeoOrigin,
    setup: Arc<ControllerSetup>,
    start: Instant,
    last_beat: Option<Instant>,
    /// Flight steps in which an outside controller flew a UAV, per UAV.
    pub offboard_steps: Vec<u64>,
    /// The navigator (from 0).
    navigator: usize,
}

/// What the MAVLink side saw, for the report.
#[derive(Debug, Clone, Default)]
pub struct MavlinkStats {
    /// Per UAV (from 1): flight steps flown on outside setpoints, what its link could not
    /// decode, what its vehicle refused.
    pub uavs: Vec<(u32, u64, LinkStats, Refused)>,
}

impl MavlinkSwarm {
    /// Systems for every UAV of `scenario`, sending to `base_port + i − 1` on loopback.
    pub fn new(scenario: &Scenario, base_port: u16) -> Result<Self> {
        let n = scenario.len();
        if usize::from(base_port) + n - 1 > usize::from(u16::MAX) || n > 255 {
            bail!(
                "--mavlink-port {base_port}: {n} UAVs need ports up to {} and system ids up to 255",
                usize::from(base_port) + n - 1
            );
        }
        let flavour = Flavour::Px4;
        let mav_type = match scenario.vehicle() {
            proxform_core::VehicleModel::FixedWing(_) => proxform_net::mavlink::messages::MavType::MAV_TYPE_FIXED_WING,
            _ => proxform_net::mavlink::messages::MavType::MAV_TYPE_QUADROTOR,
        };
        let navigator = scenario.navigator().index();
        let vehicles = (0..n)
            .map(|i| {
                let endpoint = Endpoint::Out(([127, 0, 0, 1], base_port + i as u16).into());
                let link = Link::open(endpoint, i as u8 + 1, 1).context("cannot open a MAVLink port")?;
                let served = Served::new(i as u8 + 1, flavour, mav_type);
                // The navigator too: it flies its path until an outside controller takes it
                // in OFFBOARD, and again once that controller stops.
                let measured = VecDeque::with_capacity(MEASUREMENTS_KEPT);
                Ok(Vehicle {
                    served,
                    link,
                    flown_setpoints: (0, 0),
                    measured,
                    flown_error: None,
                    setpoint_from_port: false,
                })
            })
            .collect::<Result<_>>()?;
        Ok(Self {
            vehicles,
            frame: Frame { origin_ned: [0.0; 3], course_rad: 0.0 },
            origin: GeoOrigin::from_degrees(ORIGIN.0, ORIGIN.1, ORIGIN.2),
            setup: scenario.agents().controller().clone(),
            start: Instant::now(),
            last_beat: None,
            offboard_steps: vec![0; n],
            navigator,
        })
    }

    /// Reads what every vehicle was sent, and answers.
    fn drain(&mut self) {
        let t = self.start.elapsed().as_secs_f64();
        for v in &mut self.vehicles {
            while let Ok(Some((h, m))) = v.link.recv(Duration::ZERO) {
                let setpoints = v.served.setpoints;
                if let Some(reply) = v.served.handle(&h, &m, t) {
                    let _ = v.link.send(&reply);
                }
                if v.served.setpoints != setpoints {
                    v.setpoint_from_port = v.link.from_peer();
                }
            }
        }
    }

    /// Reads what the vehicles were sent until each of `uavs` (from 0) in OFFBOARD has had what
    /// it is to fly this step, or [`SETPOINT_ALLOWANCE`] passed. With the instant `decided_on`
    /// of the update its agent's adjustment applied this step was decided on (the agent's
    /// answer over the network), that is the setpoint (and attitude target, if it was ever sent one)
    /// stamped with it or a later one; otherwise any setpoint since its last step was flown. A
    /// setpoint counted only by arrival would, once one came after its step was flown, be
    /// taken for the next step's, and every step after would fly the one before (measured: the
    /// paper through a serial line at 921 600 baud, roll 3.9° of 1°).
    fn await_setpoints(&mut self, uavs: impl Iterator<Item = (usize, Option<f64>)> + Clone) {
        let deadline = Instant::now() + SETPOINT_ALLOWANCE;
        loop {
            self.drain();
            let waiting = uavs.clone().any(|(i, decided_on)| {
                self.vehicles.get(i).is_some_and(|v| {
                    let (setpoints, attitudes) = v.flown_setpoints;
                    let older = |stamp: Option<u32>, want: u32| stamp.is_none_or(|s| s < want);
                    let missing = match decided_on.map(stamp_ms) {
                        // A vehicle sent attitude targets beside its setpoints waits for both.
                        Some(want) => {
                            let (setpoint, attitude) = v.served.stamps();
                            older(setpoint, want) || (v.served.attitude_targets > 0 && older(attitude, want))
                        }
                        None => {
                            v.served.setpoints == setpoints || (attitudes > 0 && v.served.attitude_targets == attitudes)
                        }
                    };
                    v.served.mode() == Mode::Offboard && missing
                })
            });
            if !waiting || Instant::now() >= deadline {
                break;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        for (i, _) in uavs {
            if let Some(v) = self.vehicles.get_mut(i) {
                v.flown_setpoints = (v.served.setpoints, v.served.attitude_targets);
            }
        }
    }

    /// Keeps the error of the measurement of UAV `i` (from 0) at `t_s` its agent is sent.
    fn measured(&mut self, i: usize, t_s: f64, measured: &State9, truth: &State9) {
        if let Some(v) = self.vehicles.get_mut(i) {
            if v.measured.len() == MEASUREMENTS_KEPT {
                v.measured.pop_front();
            }
            v.measured.push_back((stamp_ms(t_s), state::difference(measured, truth)));
        }
    }

    /// The decision that flies UAV `i` (from 0), truly at `own`, toward its outside targets, if
    /// an outside controller flies it now. The simulated autopilot flies them from its estimate:
    /// for a setpoint its agent decided at one of the world's measurements (sent from the
    /// vehicle's offboard port, where the agent listens, and stamped with the measurement's
    /// instant), the truth with that measurement's error, as in process the decision's input
    /// acts on the truth; for any other, the truth.
    fn decision(&mut self, i: usize, own: &State9) -> Option<Decision> {
        let t = self.start.elapsed().as_secs_f64();
        let vehicle = self.vehicles.get_mut(i)?;
        let s = vehicle.served.setpoint(t)?;
        let error = vehicle.setpoint_from_port.then(|| vehicle.estimate_error(s.stamp_ms)).flatten();
        let estimate = own + error.unwrap_or_else(State9::zeros);
        let own = &estimate;
        let v = self.frame.velocity_xyz(s.velocity_ned);
        let beta = s.yaw.map(|y| self.frame.yaw(y));
        self.offboard_steps[i] += 1;
        let dt = self.setup.params().dt_s;
        let vehicle = self.setup.vehicle();
        // The attitude target's roll and pitch, as the vehicle's (α, γ).
        let attitude = s.attitude.map(|[roll, pitch]| [pitch, roll]);
        let u = match vehicle.input_for_targets(own, v, beta, attitude, dt) {
            Some(u) => u,
            // Targets that do not say what the vehicle's inputs do (the fixed wing): the input
            // that brings it nearest to them.
            None => {
                let held = vehicle.hold(own, dt);
                let mut target = held;
                (target[state::VX], target[state::VY], target[state::VZ]) = (v[0], v[1], v[2]);
                if let Some(beta) = beta {
                    target[state::BETA] = beta;
                }
                self.setup.input_toward(own, &state::difference(&held, &target))
            }
        };
        let mut d = Decision::without_areas(Outcome::Adjusted { normalised_sq: 0.0 }, u);
        // A vehicle flown by velocity setpoints (the multirotor) flies them as they are (its
        // inner loop flies from the truth, as in process).
        if vehicle.takes_velocity_setpoints() {
            let yaw_rad = beta.unwrap_or(own[state::BETA]);
            d.setpoint = Some(proxform_core::Setpoint { velocity_mps: v, yaw_rad });
        }
        Some(d)
    }

    /// What the MAVLink side saw.
    pub fn stats(&self) -> MavlinkStats {
        MavlinkStats {
            uavs: self
                .vehicles
                .iter()
                .enumerate()
                .map(|(i, v)| (i as u32 + 1, self.offboard_steps[i], v.link.stats, v.served.refused))
                .collect(),
        }
    }

    /// Whether UAV `i` (from 0) flies in OFFBOARD now.
    pub fn offboard(&self, i: usize) -> bool {
        self.vehicles.get(i).is_some_and(|v| v.served.mode() == Mode::Offboard)
    }
}

/// Says where every UAV is, each step, at the step's time on the flight's clock.
pub struct MavlinkTelemetry(pub Rc<RefCell<MavlinkSwarm>>, pub super::world::FlightClock, pub f64);

impl proxform_sim::Observer for MavlinkTelemetry {
    fn on_step(&mut self, _: &Scenario, frame: &proxform_sim::StepFrame<'_>) {
        self.1.wait_until(frame.t, Duration::from_secs_f64(self.2));
        let mut s = self.0.borrow_mut();
        let s = &mut *s;
        let t = s.start.elapsed().as_secs_f64();
        let beat = s.last_beat.is_none_or(|b| b.elapsed() >= Duration::from_secs(1));
        if beat {
            s.last_beat = Some(Instant::now());
        }
        for (i, v) in s.vehicles.iter_mut().enumerate() {
            if !frame.active.get(i).copied().unwrap_or(false) {
                continue;
            }
            // Telemetry is best effort: a datagram that cannot go is one sample lost.
            if beat {
                let _ = v.link.send(&v.served.heartbeat());
                for m in v.served.origin(&s.origin) {
                    let _ = v.link.send(&m);
                }
            }
            for m in v.served.telemetry(t, &s.frame.ned(&frame.states[i]), &s.origin) {
                let _ = v.link.send(&m);
            }
        }
        s.drain();
    }
}

/// The followers' decisions: their agents', or their outside MAVLink controllers' while those
/// fly them in OFFBOARD.
pub struct WithMavlink<'a, A: Agents> {
    /// The agents.
    pub agents: &'a mut A,
    /// The MAVLink systems.
    pub swarm: Rc<RefCell<MavlinkSwarm>>,
}

impl<A: Agents> Agents for WithMavlink<'_, A> {
    fn present(&mut self, uav: proxform_core::UavId) -> bool {
        self.agents.present(uav) || self.swarm.borrow().offboard(uav.index())
    }

    fn failsafe(&mut self, uav: proxform_core::UavId) -> bool {
        self.agents.failsafe(uav)
    }

    fn refused(&mut self, uav: proxform_core::UavId) {
        self.agents.refused(uav);
    }

    fn navigator(&mut self, _: f64, truth: &State9) -> Option<Decision> {
        let mut swarm = self.swarm.borrow_mut();
        let nav = swarm.navigator;
        swarm.decision(nav, truth)
    }

    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        if request.phase == proxform_sim::world::remote::Phase::Fly {
            // What each live agent is sent: the estimate its setpoints will be decided at.
            for (j, u) in request.sensed.uavs.iter().enumerate() {
                let (Some(own), Some(truth)) = (request.sensed.own.get(j), request.truth.get(u.index())) else {
                    continue;
                };
                if self.agents.present(*u) {
                    self.swarm.borrow_mut().measured(u.index(), request.t_s, own, truth);
                }
            }
        }
        self.agents.decide(request, out);
        let mut swarm = self.swarm.borrow_mut();
        if request.phase != proxform_sim::world::remote::Phase::Fly {
            swarm.drain();
            return;
        }
        // An agent that adjusted sends new targets stamped with the update it decided on; one
        // that holds sends its last ones again, with their first stamp.
        let adjusted = |d: Option<&Decision>| d.is_some_and(|d| matches!(d.outcome, Outcome::Adjusted { .. }));
        let decided_on: Vec<_> = (request.sensed.uavs.iter().enumerate())
            .map(|(j, u)| (u.index(), self.agents.decided_on(*u).filter(|_| adjusted(out.get(j)))))
            .collect();
        swarm.await_setpoints(decided_on.iter().copied());
        // The autopilot flies its targets from its estimate (see `MavlinkSwarm::decision`).
        for (j, u) in request.sensed.uavs.iter().enumerate() {
            let Some(truth) = request.truth.get(u.index()) else { continue };
            if let Some(flown) = swarm.decision(u.index(), truth) {
                // What the vehicle flies, with what its agent said of the step (held or adjusted,
                // its areas and references): a proxform agent over MAVLink answers the world
                // too, so the report's adjustments are its own.
                out[j] = Decision { input: flown.input, setpoint: flown.setpoint, ..out[j] };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_net::mavlink::messages::{
        AttitudeTargetTypemask, MavCmd, MavFrame, MavMessage, PositionTargetTypemask, COMMAND_LONG_DATA,
        SET_ATTITUDE_TARGET_DATA, SET_POSITION_TARGET_LOCAL_NED_DATA,
    };
    use proxform_net::mavlink::MavHeader;
    use proxform_sim::world::remote::{holding, Phase, Sensed};

    /// Agents that always hold.
    struct Holding;

    impl Agents for Holding {
        fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
            out.clear();
            out.resize(request.sensed.len(), holding());
        }
    }

    /// UAV 2's switch to OFFBOARD, as PX4 numbers it.
    fn offboard() -> MavMessage {
        MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: 1.0,
            param2: Flavour::Px4.set_mode_params(Mode::Offboard).0,
            param3: Flavour::Px4.set_mode_params(Mode::Offboard).1,
            command: MavCmd::MAV_CMD_DO_SET_MODE,
            target_system: 2,
            target_component: 1,
            ..Default::default()
        })
    }

    /// UAV 2's velocity and attitude targets of the paper for input `u` decided at
    /// `decided_at`, stamped `stamp`.
    fn targets(
        sc: &Scenario,
        frame: Frame,
        u: &proxform_core::Input,
        decided_at: &State9,
        stamp: u32,
    ) -> [MavMessage; 2] {
        let (vehicle, dt) = (sc.vehicle().clone(), sc.dt_s());
        let (v, beta) = vehicle.velocity_setpoint(decided_at, u, dt);
        let [alpha, gamma] = vehicle.attitude_setpoint(decided_at, u, dt).expect("the paper's vehicle");
        let vn = frame.velocity_ned(v);
        [
            MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
                time_boot_ms: stamp,
                vx: vn[0] as f32,
                vy: vn[1] as f32,
                vz: vn[2] as f32,
                yaw: frame.yaw(beta) as f32,
                type_mask: PositionTargetTypemask::from_bits_truncate(0b1001_1100_0111),
                target_system: 2,
                target_component: 1,
                coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
                ..Default::default()
            }),
            MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
                time_boot_ms: stamp,
                q: proxform_net::mavlink::frame::quaternion([gamma, alpha, frame.yaw(beta)]).map(|x| x as f32),
                type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE,
                target_system: 2,
                target_component: 1,
                ..Default::default()
            }),
        ]
    }

    /// Flies UAV 2 of the paper (in a swarm served at `port`) on the targets its input `u`
    /// reaches from `decided_at`, stamped `stamp`, in a step at t = 1 s where the world measured
    /// it at `measured` and it truly is at `truth`; the input flown.
    fn flown(
        port: u16,
        u: &proxform_core::Input,
        decided_at: &State9,
        (stamp, from_port): (u32, bool),
        measured: &State9,
    ) -> Vec<f64> {
        let sc = proxform_scenario::builtin::paper();
        let swarm = Rc::new(RefCell::new(MavlinkSwarm::new(&sc, port).expect("loopback ports")));
        let frame = swarm.borrow().frame;
        let from = MavHeader { system_id: 2, component_id: 191, sequence: 0 };
        let [setpoint, attitude] = targets(&sc, frame, u, decided_at, stamp);
        let offboard = offboard();
        let messages = [setpoint, offboard, attitude];
        {
            let mut s = swarm.borrow_mut();
            let t = s.start.elapsed().as_secs_f64();
            for m in &messages {
                s.vehicles[1].served.handle(&from, m, t);
            }
            s.vehicles[1].setpoint_from_port = from_port;
            assert!(s.offboard(1));
        }
        let nav = sc.path().state_at(1.0, [0.0; 3]);
        let truth: Vec<State9> = (0..sc.len()).map(|i| sc.slot_state(i, &nav)).collect();
        let mut sensed = Sensed::default();
        sensed.uavs.push(proxform_core::UavId(1));
        sensed.own.push(*measured);
        sensed.spans.push(0..0);
        let request = StepRequest { run: 0, k: 10, t_s: 1.0, phase: Phase::Fly, sensed: &sensed, truth: &truth };
        let mut out = Vec::new();
        WithMavlink { agents: &mut Holding, swarm: swarm.clone() }.decide(&request, &mut out);
        out[0].input.iter().copied().collect()
    }

    /// UAV 2 of the paper in its slot at t = 1 s.
    fn paper_truth() -> State9 {
        let sc = proxform_scenario::builtin::paper();
        sc.slot_state(1, &sc.path().state_at(1.0, [0.0; 3]))
    }

    /// An input within the paper's vehicle's bounds at `x`.
    fn paper_input(x: &State9) -> proxform_core::Input {
        let sc = proxform_scenario::builtin::paper();
        let (lo, hi) = sc.vehicle().input_bounds(x, sc.dt_s());
        lo.zip_map(&hi, |l, h| l + 0.8 * (h - l))
    }

    #[test]
    fn a_served_vehicle_flies_its_agents_targets_from_the_estimate_they_were_decided_at() {
        // Its agent was sent a measurement 0.3 m and 0.2 m/s off, 0.01 rad pitched, and decided
        // its targets there: the input flown is the agent's, acting on the truth, as in process
        // (from the truth the measurement's error would be flown with it).
        let truth = paper_truth();
        let mut measured = truth;
        (measured[state::Y], measured[state::VY], measured[state::ALPHA]) =
            (truth[state::Y] + 0.3, truth[state::VY] + 0.2, truth[state::ALPHA] + 0.01);
        let u = paper_input(&measured);
        let flown = flown(47_610, &u, &measured, (stamp_ms(1.0), true), &measured);
        for (j, f) in flown.iter().enumerate() {
            assert!((f - u[j]).abs() < 1e-5, "input {j}: {f} for {}", u[j]);
        }
    }

    #[test]
    fn a_served_vehicle_flies_other_controllers_targets_from_where_it_is() {
        // An outside controller that read the vehicle's telemetry (the truth) and stamps its
        // own time: its targets are flown from the truth, whatever the world measured.
        let truth = paper_truth();
        let mut measured = truth;
        (measured[state::VY], measured[state::ALPHA]) = (truth[state::VY] + 0.2, truth[state::ALPHA] + 0.01);
        let u = paper_input(&truth);
        for (stamp, from_port) in [(123_456, true), (stamp_ms(1.0), false)] {
            // (Stamped at the measurement's instant too, but from elsewhere than the port.)
            let flown = flown(47_620 + u16::from(from_port), &u, &truth, (stamp, from_port), &measured);
            for (j, f) in flown.iter().enumerate() {
                assert!((f - u[j]).abs() < 1e-5, "input {j}: {f} for {} (stamp {stamp}, {from_port})", u[j]);
            }
        }
    }

    /// Agents whose decision for UAV 2 adjusts, decided on the update at 1 s.
    struct AdjustedAt1s;

    impl Agents for AdjustedAt1s {
        fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
            out.clear();
            let adjusted = Decision { outcome: proxform_core::Outcome::Adjusted { normalised_sq: 2.0 }, ..holding() };
            out.resize(request.sensed.len(), adjusted);
        }

        fn decided_on(&mut self, _: proxform_core::UavId) -> Option<f64> {
            Some(1.0)
        }
    }

    #[test]
    fn a_step_flies_the_targets_of_the_update_its_agent_decided_on_not_the_last_to_arrive() {
        // The targets decided on the update at 0.9 s came after that step was flown (a slow
        // line): at the step of 1 s they are there, unflown, and those decided on 1 s come 5 ms
        // after the agent's answer. The step waits for them; counted by arrival, it took the
        // late ones, and so every step after.
        let sc = proxform_scenario::builtin::paper();
        let swarm = Rc::new(RefCell::new(MavlinkSwarm::new(&sc, 47_630).expect("loopback ports")));
        let truth_2 = paper_truth();
        let late = paper_input(&truth_2);
        let due = {
            let (lo, hi) = sc.vehicle().input_bounds(&truth_2, sc.dt_s());
            lo.zip_map(&hi, |l, h| l + 0.3 * (h - l))
        };
        let frame = swarm.borrow().frame;
        let from = MavHeader { system_id: 2, component_id: 191, sequence: 0 };
        let to_vehicle = {
            let mut s = swarm.borrow_mut();
            let t = s.start.elapsed().as_secs_f64();
            let offboard = offboard();
            let [setpoint, attitude] = targets(&sc, frame, &late, &truth_2, stamp_ms(0.9));
            for m in [&setpoint, &offboard, &attitude] {
                s.vehicles[1].served.handle(&from, m, t);
            }
            assert!(s.offboard(1));
            s.vehicles[1].link.local_addr().expect("bound")
        };
        let [setpoint, attitude] = targets(&sc, frame, &due, &truth_2, stamp_ms(1.0));
        let agent = std::thread::spawn(move || {
            let mut link = Link::open(Endpoint::Out(to_vehicle), 2, 191).expect("bound");
            std::thread::sleep(Duration::from_millis(5));
            link.send(&setpoint).expect("sent");
            link.send(&attitude).expect("sent");
        });
        let nav = sc.path().state_at(1.0, [0.0; 3]);
        let truth: Vec<State9> = (0..sc.len()).map(|i| sc.slot_state(i, &nav)).collect();
        let mut sensed = Sensed::default();
        sensed.uavs.push(proxform_core::UavId(1));
        sensed.own.push(truth_2);
        sensed.spans.push(0..0);
        let request = StepRequest { run: 0, k: 10, t_s: 1.0, phase: Phase::Fly, sensed: &sensed, truth: &truth };
        let mut out = Vec::new();
        WithMavlink { agents: &mut AdjustedAt1s, swarm: swarm.clone() }.decide(&request, &mut out);
        agent.join().expect("sent");
        for j in 0..due.len() {
            assert!(
                (out[0].input[j] - due[j]).abs() < 1e-5,
                "input {j}: {} for {} (late {})",
                out[0].input[j],
                due[j],
                late[j]
            );
        }
    }
}
