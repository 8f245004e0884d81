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
use proxform_scenario::Scenario;
use proxform_sim::world::remote::{Agents, StepRequest};

/// Where local NED's origin is on the earth (PX4 SITL's default home).
pub const ORIGIN: (f64, f64, f64) = (47.397742, 8.545594, 488.0);

/// One UAV's MAVLink system.
struct Vehicle {
    served: Served,
    link: Link,
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
                Ok(Vehicle { served, link })
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
                if let Some(reply) = v.served.handle(&h, &m, t) {
                    let _ = v.link.send(&reply);
                }
            }
        }
    }

    /// The decision that flies UAV `i` (from 0) at `own` toward its outside setpoint, if an
    /// outside controller flies it now.
    fn decision(&mut self, i: usize, own: &State9) -> Option<Decision> {
        let t = self.start.elapsed().as_secs_f64();
        let s = self.vehicles.get_mut(i)?.served.setpoint(t)?;
        let v = self.frame.velocity_xyz(s.velocity_ned);
        let beta = s.yaw.map(|y| self.frame.yaw(y));
        self.offboard_steps[i] += 1;
        // A vehicle flown by velocity setpoints (the multirotor) flies them as they are.
        if let Some(u) = self.setup.vehicle().input_for_setpoint(own, v, beta) {
            let yaw_rad = beta.unwrap_or(own[state::BETA]);
            let mut d = Decision::without_areas(Outcome::Adjusted { normalised_sq: 0.0 }, u);
            d.setpoint = Some(proxform_core::Setpoint { velocity_mps: v, yaw_rad });
            return Some(d);
        }
        let [vx, vy, vz] = v;
        let dt = self.setup.params().dt_s;
        let held = self.setup.vehicle().hold(own, dt);
        let mut target = held;
        (target[state::VX], target[state::VY], target[state::VZ]) = (vx, vy, vz);
        if let Some(beta) = beta {
            target[state::BETA] = beta;
        }
        // The attitude target, for the vehicle whose attitude is steered apart from its velocity.
        if let Some([roll, pitch]) = s.attitude {
            (target[state::GAMMA], target[state::ALPHA]) = (roll, pitch);
        }
        let r = state::difference(&held, &target);
        Some(Decision::without_areas(Outcome::Adjusted { normalised_sq: 0.0 }, self.setup.input_toward(own, &r)))
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

    fn navigator(&mut self, _: f64, truth: &State9) -> Option<Decision> {
        let mut swarm = self.swarm.borrow_mut();
        let nav = swarm.navigator;
        swarm.decision(nav, truth)
    }

    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        self.agents.decide(request, out);
        let mut swarm = self.swarm.borrow_mut();
        swarm.drain();
        if request.phase != proxform_sim::world::remote::Phase::Fly {
            return;
        }
        let s = request.sensed;
        for j in 0..s.len() {
            if let Some(d) = swarm.decision(s.uavs[j].index(), &s.own[j]) {
                out[j] = d;
            }
        }
    }
}
