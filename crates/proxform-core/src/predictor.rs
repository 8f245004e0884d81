//! Neighbour behaviour prediction (METHOD §3, the paper's eq. 2-4).
//!
//! A UAV predicts each neighbour's state at `t + Δt` from what it has observed of it up to `t`.
//! [`PredictorKind::ConstantVelocity`] is the plain transition F on the latest observation
//! (position advances by velocity, velocity and attitude carry over). It lags a neighbour that
//! turns or accelerates, so by default each neighbour is tracked with an α-β filter on velocity
//! and attitude (value and rate) and on position (advanced by the filtered velocity), and
//! predicted with the filtered rates. The filter only smooths and extrapolates what was
//! observed; it never differentiates raw observations, which is what makes mutual references
//! unstable (METHOD §3).

use nalgebra::SVector;

use crate::error::{unit_interval, ConfigError};
use crate::observation::{Observation, UavId};
use crate::state::{State9, VX, X};

/// How neighbours are predicted one step ahead.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PredictorKind {
    /// The plain F of METHOD §3 applied to the latest observation.
    ConstantVelocity,
    /// α-β tracking filter per neighbour (dimensionless gains).
    AlphaBeta {
        /// Value gain α ∈ (0, 1]. Default 0.8.
        alpha: f64,
        /// Rate gain β ∈ [0, 1]. Default 0.5333…, the Benedict-Bordner value α²/(2 − α).
        beta: f64,
    },
}

impl Default for PredictorKind {
    fn default() -> Self {
        PredictorKind::AlphaBeta { alpha: 0.8, beta: 0.8 * 0.8 / 1.2 }
    }
}

impl PredictorKind {
    /// Checks the gains.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let PredictorKind::AlphaBeta { alpha, beta } = *self {
            unit_interval("predictor alpha", alpha)?;
            if alpha == 0.0 {
                return Err(ConfigError::OutOfRange {
                    field: "predictor alpha",
                    value: alpha,
                    expected: "α in (0, 1]",
                });
            }
            unit_interval("predictor beta", beta)?;
        }
        Ok(())
    }
}

/// Rates of the six filtered components with a rate: acceleration (m/s²) and attitude rate (rad/s).
type Rates = SVector<f64, 6>;

#[derive(Debug, Clone, Copy)]
struct Track {
    id: UavId,
    /// Time of the measurement behind `est` (s).
    t: f64,
    est: State9,
    rate: Rates,
    /// Number of measurements absorbed (saturates at 2).
    seen: u8,
}

/// Per-neighbour tracks of one UAV. Capacity is fixed at construction: no allocation per step.
#[derive(Debug, Clone)]
pub struct NeighbourTracks {
    kind: PredictorKind,
    timeout_s: f64,
    tracks: Vec<Track>,
    capacity: usize,
}

impl NeighbourTracks {
    /// Tracks for at most `capacity` neighbours; a track not updated for `timeout_s` restarts.
    pub fn new(kind: PredictorKind, capacity: usize, timeout_s: f64) -> Self {
        let capacity = capacity.max(1);
        Self { kind, timeout_s, tracks: Vec::with_capacity(capacity), capacity }
    }

    /// Feeds observation `obs` (taken at `now − obs.age_s`) and returns the neighbour's
    /// predicted state at `now + horizon_s`.
    pub fn predict(&mut self, obs: &Observation, now: f64, horizon_s: f64) -> State9 {
        let t_obs = now - obs.age_s;
        let track = match self.kind {
            PredictorKind::ConstantVelocity => {
                Track { id: obs.id, t: t_obs, est: obs.state, rate: Rates::zeros(), seen: 1 }
            }
            PredictorKind::AlphaBeta { alpha, beta } => {
                let slot = self.slot_for(obs.id, t_obs);
                let tr = &mut self.tracks[slot];
                let dt = t_obs - tr.t;
                let fresh = dt <= self.timeout_s; // false for NaN too
                if tr.id != obs.id || !fresh {
                    *tr = Track { id: obs.id, t: t_obs, est: obs.state, rate: Rates::zeros(), seen: 1 };
                } else if dt > 0.0 && tr.seen < 2 {
                    two_point_start(tr, &obs.state, dt);
                } else if dt > 0.0 {
                    alpha_beta_update(tr, &obs.state, dt, alpha, beta);
                }
                *tr
            }
        };
        extrapolate(&track, now + horizon_s - track.t)
    }

    /// Index of the track of `id`, or the slot to (re)use for it.
    fn slot_for(&mut self, id: UavId, t_obs: f64) -> usize {
        if let Some(k) = self.tracks.iter().position(|t| t.id == id) {
            return k;
        }
        if self.tracks.len() < self.capacity {
            self.tracks.push(Track { id, t: t_obs, est: State9::zeros(), rate: Rates::zeros(), seen: 0 });
            // Marked as foreign so the caller initialises it.
            let k = self.tracks.len() - 1;
            self.tracks[k].id = UavId(u32::MAX);
            return k;
        }
        // Evict the track observed longest ago.
        let mut oldest = 0;
        for (k, t) in self.tracks.iter().enumerate() {
            if t.t < self.tracks[oldest].t {
                oldest = k;
            }
        }
        self.tracks[oldest].id = UavId(u32::MAX);
        oldest
    }
}

/// The standard start of an α-β track: the second measurement sets the value and the rates
/// from the difference of the first two.
#[inline]
fn two_point_start(tr: &mut Track, z: &State9, dt: f64) {
    for k in VX..9 {
        tr.rate[k - VX] = crate::state::difference_component(k, z[k], tr.est[k]) / dt;
    }
    tr.est = *z;
    tr.t += dt;
    tr.seen = 2;
}

/// One α-β update after `dt` seconds with measurement `z`.
#[inline]
fn alpha_beta_update(tr: &mut Track, z: &State9, dt: f64, alpha: f64, beta: f64) {
    // Position: advanced by the filtered velocity and acceleration, corrected by α.
    for k in X..VX {
        let pred = tr.est[k] + dt * (tr.est[k + 3] + 0.5 * dt * tr.rate[k]);
        tr.est[k] = pred + alpha * (z[k] - pred);
    }
    // Velocity and attitude: value and rate.
    for k in VX..9 {
        let r = k - VX;
        let pred = tr.est[k] + dt * tr.rate[r];
        let res = crate::state::difference_component(k, z[k], pred);
        tr.est[k] = pred + alpha * res;
        tr.rate[r] += beta / dt * res;
    }
    tr.t += dt;
}

/// The track's state `h` seconds after its measurement time.
#[inline]
fn extrapolate(tr: &Track, h: f64) -> State9 {
    let mut s = tr.est;
    for k in X..VX {
        s[k] += h * (tr.est[k + 3] + 0.5 * h * tr.rate[k]);
    }
    for k in VX..9 {
        s[k] += h * tr.rate[k - VX];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observation::ObservationSource;
    use approx::assert_relative_eq;

    fn obs(id: u32, s: State9) -> Observation {
        Observation { id: UavId(id), state: s, age_s: 0.0, source: ObservationSource::Onboard }
    }

    #[test]
    fn constant_velocity_advances_position_only() {
        let mut tracks = NeighbourTracks::new(PredictorKind::ConstantVelocity, 4, 1.0);
        let s = State9::from_column_slice(&[1.0, 2.0, 3.0, 10.0, -5.0, 1.0, 0.1, 0.2, 0.3]);
        let p = tracks.predict(&obs(1, s), 0.0, 0.1);
        assert_relative_eq!(
            p,
            State9::from_column_slice(&[2.0, 1.5, 3.1, 10.0, -5.0, 1.0, 0.1, 0.2, 0.3]),
            epsilon = 1e-12
        );
    }

    #[test]
    fn alpha_beta_learns_a_steady_turn_rate() {
        let mut tracks = NeighbourTracks::new(PredictorKind::default(), 4, 1.0);
        let rate = 0.02; // rad/s
        let dt = 0.1;
        let mut last = State9::zeros();
        for k in 0..300 {
            let t = k as f64 * dt;
            let mut s = State9::zeros();
            s[7] = rate * t;
            s[0] = 50.0 * t;
            s[3] = 50.0;
            last = tracks.predict(&obs(3, s), t, dt);
        }
        // Prediction for t = 30.0 s: yaw = rate·30, no lag once the rate is learnt.
        assert_relative_eq!(last[7], rate * 30.0, epsilon = 1e-6);
        assert_relative_eq!(last[0], 50.0 * 30.0, epsilon = 1e-6);
    }

    #[test]
    fn tracks_are_evicted_oldest_first_without_growing() {
        let mut tracks = NeighbourTracks::new(PredictorKind::default(), 2, 1.0);
        for (t, id) in [(0.0, 1), (0.1, 2), (0.2, 3)] {
            tracks.predict(&obs(id, State9::zeros()), t, 0.1);
        }
        assert_eq!(tracks.tracks.len(), 2);
        assert!(tracks.tracks.iter().all(|t| t.id != UavId(1)));
    }
}
