//! Classic formation controllers, for comparison with the proximity method on equal terms.
//!
//! Each baseline turns what its UAV hears or sees into a commanded acceleration and an
//! attitude target, and hands the resulting one-period target state to the same input step
//! as the proximity controller ([`crate::ControllerSetup::input_toward`]): the same vehicle
//! model, limits, predictor (α-β tracks of every neighbour, coasting through lost messages
//! for `coast_s` like the proximity controller) and noise. What differs is only the control
//! law and what it needs to perceive:
//! - [`LeaderFollower`]: the navigator's broadcast state (radio);
//! - [`Consensus`]: every UAV's broadcast state (radio graph), navigator as leader;
//! - [`Flocking`]: neighbours sensed onboard, navigator as virtual leader (radio).
//!
//! Unlike the proximity controller, the baselines act every period (no tolerance envelope).

mod consensus;
mod flocking;
mod leader_follower;

pub use consensus::{Consensus, ConsensusGains};
pub use flocking::{Flocking, FlockingGains};
pub use leader_follower::{LeaderFollower, LeaderFollowerGains};

use std::sync::Arc;

use crate::controller::{ControllerSetup, Decision, Outcome};
use crate::error::{positive, ConfigError};
use crate::formation::Formation;
use crate::observation::{Observation, UavId};
use crate::predictor::NeighbourTracks;
use crate::state::{self, State9, ALPHA, VX, X};

/// A neighbour as a baseline uses it: its predicted state now and one period ahead, and the
/// weight of the estimate (1 when measured this period, fading while it coasts).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Heard {
    pub id: UavId,
    pub now: State9,
    pub next: State9,
    pub weight: f64,
}

/// Position and velocity gains of a PD law (critically damped when `kv² = 4·kp`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PdGains {
    /// Position gain (1/s²).
    pub kp: f64,
    /// Velocity gain (1/s).
    pub kv: f64,
}

impl Default for PdGains {
    /// Critically damped at 1 rad/s: kp 1/s², kv 2/s.
    fn default() -> Self {
        Self::critical(1.0)
    }
}

impl PdGains {
    /// Critically damped gains with natural frequency `omega` (rad/s).
    pub fn critical(omega: f64) -> Self {
        Self { kp: omega * omega, kv: 2.0 * omega }
    }

    pub(crate) fn validate(&self, kp: &'static str, kv: &'static str) -> Result<(), ConfigError> {
        positive(kp, self.kp)?;
        positive(kv, self.kv)
    }
}

/// What every baseline keeps: its UAV, the leader, the shared setup and formation, the tracks
/// of the UAVs it hears, and those known this period (working memory, allocated once).
#[derive(Debug, Clone)]
pub(crate) struct Hearing {
    pub id: UavId,
    pub leader: UavId,
    pub setup: Arc<ControllerSetup>,
    pub formation: Arc<Formation>,
    tracks: NeighbourTracks,
    pub heard: Vec<Heard>,
}

impl Hearing {
    /// For UAV `id` following `leader`, tracking at most `capacity` UAVs.
    pub fn new(
        id: UavId,
        leader: UavId,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
        capacity: usize,
    ) -> Result<Self, ConfigError> {
        for u in [id, leader] {
            if formation.slot(u).is_none() {
                return Err(ConfigError::UnknownUav { id: u, size: formation.len() });
            }
        }
        let p = setup.params();
        let tracks = NeighbourTracks::new(p.predictor, capacity, p.track_timeout_s, p.coast_accel_s);
        Ok(Self { id, leader, setup, formation, tracks, heard: Vec::with_capacity(capacity) })
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.tracks.heap_bytes() + self.heard.capacity() * std::mem::size_of::<Heard>()
    }

    /// Feeds this period's observations accepted by `accept` to the tracks and fills `heard`
    /// with every UAV known now: measured ones, then missing ones coasting on their tracks
    /// (weight `exp(−age / coast_decay_s)`, at most `coast_s` old), each id once.
    pub fn hear(&mut self, now: f64, observations: &[Observation], accept: impl Fn(&Observation) -> bool) {
        let Self { id: me, setup, tracks, heard, .. } = self;
        let p = setup.params();
        let dt = p.dt_s;
        heard.clear();
        for o in observations {
            if o.id == *me || !accept(o) || heard.iter().any(|h| h.id == o.id) {
                continue;
            }
            let now_state = tracks.predict(o, now, 0.0);
            // The observation is already in the track: this only extrapolates it.
            let next = tracks.predict(o, now, dt);
            heard.push(Heard { id: o.id, now: now_state, next, weight: 1.0 });
        }
        for s in 0..tracks.slots() {
            let Some(id) = tracks.coasting(s, now, p.coast_s, p.track_timeout_s) else { continue };
            if id == *me || heard.iter().any(|h| h.id == id) {
                continue;
            }
            let weight = p.coasting_weight(tracks.missing(s, now));
            heard.push(Heard { id, now: tracks.state_at(s, now), next: tracks.state_at(s, now + dt), weight });
        }
    }

    /// Where `h` says this UAV should be, now and one period ahead: `X_j + W_ij`, with the
    /// proximity controller's W (the formation's rigid-body turn at j's turn rate when
    /// `turn_feedforward` is on), so that every method flies the same formation.
    pub fn slot_from(&self, h: &Heard) -> Option<(State9, State9)> {
        let f = &self.formation;
        let (si, sj) = (f.slot(self.id)?, f.slot(h.id)?);
        let p = self.setup.params();
        let turn = p.turn_feedforward.then(|| self.setup.vehicle().turn_rate(&h.now, &h.next, p.dt_s));
        let (mut now, mut next) = (h.now, h.next);
        f.add_w_with(turn, si, sj, &h.now, &mut now);
        f.add_w_with(turn, si, sj, &h.next, &mut next);
        Some((now, next))
    }
}

/// The PD acceleration toward a desired trajectory known now and one period ahead:
/// `a = (v_d(t+Δt) − v_d(t))/Δt − kp·(p − p_d) − kv·(v − v_d)` (m/s²).
pub(crate) fn pd_acceleration(own: &State9, d_now: &State9, d_next: &State9, dt: f64, g: &PdGains) -> [f64; 3] {
    std::array::from_fn(|k| {
        let ff = (d_next[VX + k] - d_now[VX + k]) / dt;
        ff - g.kp * (own[X + k] - d_now[X + k]) - g.kv * (own[VX + k] - d_now[VX + k])
    })
}

/// Turns a commanded acceleration `a` (m/s², world axes) and attitude target into the input:
/// the target state after one period is `p + vΔt + ½aΔt²`, `v + aΔt`, `attitude`, reached as
/// closely as the vehicle's limits allow.
pub(crate) fn act(setup: &ControllerSetup, own: &State9, a: [f64; 3], attitude: [f64; 3]) -> Decision {
    let dt = setup.params().dt_s;
    let mut target = *own;
    for k in 0..3 {
        target[X + k] = own[X + k] + own[VX + k] * dt + 0.5 * a[k] * dt * dt;
        target[VX + k] = own[VX + k] + a[k] * dt;
        target[ALPHA + k] = attitude[k];
    }
    let hold = setup.vehicle().hold(own, dt);
    let r = state::difference(&hold, &target);
    let input = setup.input_toward(own, &r);
    let normalised_sq = setup.params().envelope.normalised_sq(&r);
    Decision::without_areas(Outcome::Adjusted { normalised_sq }, input)
}

/// Weighted mean attitude (wrapped around `base`) of desired states.
pub(crate) fn mean_attitude(base: &State9, desired: impl Iterator<Item = (State9, f64)>) -> Option<[f64; 3]> {
    let mut sum = [0.0; 3];
    let mut w = 0.0;
    for (d, c) in desired {
        for k in 0..3 {
            sum[k] += c * crate::angle::wrap_pi(d[ALPHA + k] - base[ALPHA + k]);
        }
        w += c;
    }
    (w > 0.0).then(|| std::array::from_fn(|k| base[ALPHA + k] + sum[k] / w))
}
