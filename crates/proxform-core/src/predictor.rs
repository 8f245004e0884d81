//! Neighbour behaviour prediction (METHOD §3, the paper's eq. 2-4).
//!
//! A UAV predicts each neighbour's state at `t + Δt` from what it has observed of it up to `t`.
//! [`PredictorKind::ConstantVelocity`] is the plain transition F on the latest observation
//! (position advances by velocity, velocity and attitude carry over). It lags a neighbour that
//! turns or accelerates, so by default each neighbour is tracked with an α-β filter on velocity
//! and attitude (value and rate) and on position (advanced by the filtered velocity), and
//! predicted with the filtered rates. The filter only smooths and extrapolates what was
//! observed; it never differentiates raw observations, which is what makes mutual references
//! unstable (METHOD §3). A neighbour missing from one step's observations coasts on its track
//! until the track times out.

use crate::error::{unit_interval, ConfigError};
use crate::observation::{Observation, UavId};
use std::sync::Arc;

use crate::plan::Carry;
use crate::singer::{Axis, Singer, Step as SingerStep};
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
    /// A Kalman filter per axis on position, velocity and a Singer manoeuvre acceleration
    /// ([`crate::singer`]), fed by every observation of the neighbour with its measurement
    /// noise; the attitude on the α-β filter.
    Singer {
        /// Manoeuvre acceleration σ_a (m/s², > 0). Default 1.
        accel_sigma_mps2: f64,
        /// Its correlation time τ (s, > 0). Default 1.
        tau_s: f64,
        /// Measurement noise of an observed position (m, > 0), 1σ: the scenario's.
        position_sigma_m: f64,
        /// Measurement noise of an observed velocity (m/s, > 0), 1σ: the scenario's.
        velocity_sigma_mps: f64,
        /// α-β gains of the attitude.
        alpha: f64,
        /// See `alpha`.
        beta: f64,
    },
}

impl Default for PredictorKind {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl PredictorKind {
    /// α-β with α = 0.8 and the Benedict-Bordner β = α²/(2 − α).
    pub const DEFAULT: Self = PredictorKind::AlphaBeta { alpha: 0.8, beta: 0.8 * 0.8 / 1.2 };

    /// Default manoeuvre acceleration σ_a of the Singer filter (m/s²).
    pub const SINGER_ACCEL_SIGMA_MPS2: f64 = 1.0;
    /// Default correlation time τ of the Singer filter (s).
    pub const SINGER_TAU_S: f64 = 1.0;

    /// The Singer filter with its default manoeuvre model (σ_a, τ) and attitude gains (those of
    /// [`Self::DEFAULT`]), for sensors of the given noise.
    pub const fn singer(position_sigma_m: f64, velocity_sigma_mps: f64) -> Self {
        let PredictorKind::AlphaBeta { alpha, beta } = Self::DEFAULT else { unreachable!() };
        PredictorKind::Singer {
            accel_sigma_mps2: Self::SINGER_ACCEL_SIGMA_MPS2,
            tau_s: Self::SINGER_TAU_S,
            position_sigma_m,
            velocity_sigma_mps,
            alpha,
            beta,
        }
    }

    /// Checks the gains.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if let PredictorKind::Singer { accel_sigma_mps2, tau_s, position_sigma_m, velocity_sigma_mps, .. } = *self {
            crate::error::positive("predictor accel_sigma_mps2", accel_sigma_mps2)?;
            crate::error::positive("predictor tau_s", tau_s)?;
            crate::error::positive("predictor position_sigma_m", position_sigma_m)?;
            crate::error::positive("predictor velocity_sigma_mps", velocity_sigma_mps)?;
        }
        if let PredictorKind::AlphaBeta { alpha, beta } | PredictorKind::Singer { alpha, beta, .. } = *self {
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

/// One neighbour's filtered state, stored compactly: positions in f64 (they are large),
/// velocities, attitudes and their rates in f32 (their resolution, 1e-5 m/s and 1e-7 rad,
/// is far below any sensor's noise). 88 bytes.
#[derive(Debug, Clone, Copy, Default)]
struct Track {
    /// Time of the measurement behind the estimate (s).
    t: f64,
    /// When a report of the neighbour last arrived (s): a delayed report is old when it
    /// arrives, but the neighbour is missing only from then on.
    heard: f64,
    pos: [f64; 3],
    /// vx, vy, vz, α, β, γ.
    va: [f32; 6],
    /// Acceleration (m/s²) and attitude rate (rad/s).
    rate: [f32; 6],
}

impl Track {
    fn start(t: f64, z: &State9) -> Self {
        let mut tr = Track { t, pos: [z[0], z[1], z[2]], ..Track::default() };
        for k in 0..6 {
            tr.va[k] = z[VX + k] as f32;
        }
        tr
    }
}

/// Per-neighbour tracks of one UAV, at most `capacity` of them, stored compactly and
/// allocated once: a step allocates nothing.
#[derive(Debug, Clone)]
pub struct NeighbourTracks {
    kind: Kind,
    timeout_s: f64,
    /// A coasting track extrapolates its acceleration for at most this long after its last
    /// measurement, then goes on at the velocity it has reached (s).
    coast_accel_s: f64,
    /// Neighbour id of each track (`u32::MAX` for a free slot) and how many measurements it
    /// has absorbed (saturating at 2). Kept apart from the data so the lookup scans 8 bytes a
    /// track.
    ids: Vec<(u32, u8)>,
    tracks: Vec<Track>,
    capacity: usize,
    /// Reports older than a period are brought forward beyond it by the plan
    /// ([`crate::plan`]); shared by the swarm.
    carry: Option<Arc<Carry>>,
}

/// The predictor as the tracks run it: the Kalman filter's state boxed, so that the α-β tracks
/// of a large swarm pay one word for it.
#[derive(Debug, Clone)]
enum Kind {
    ConstantVelocity,
    AlphaBeta { alpha: f64, beta: f64 },
    Singer(Box<SingerTracks>),
}

/// The Singer filter's model, the attitude's α-β gains, the Kalman axes of each track, and
/// `F` and `Q` of the last interval (the update period, nearly always).
#[derive(Debug, Clone)]
struct SingerTracks {
    model: Singer,
    alpha: f64,
    beta: f64,
    axes: Vec<[Axis; 3]>,
    step: Option<SingerStep>,
}

const FREE: u32 = u32::MAX;
/// The measurement count in a track's id entry (saturating at 2) ...
const SEEN: u8 = 0x7f;
/// ... and whether its last report came from the owner's own sensors.
const ONBOARD: u8 = 0x80;

/// [`ONBOARD`] for a report of the owner's own sensors.
#[inline]
fn onboard_flag(obs: &Observation) -> u8 {
    if obs.source == crate::ObservationSource::Radio {
        0
    } else {
        ONBOARD
    }
}

/// Observation times closer than this (s) are the same instant. Time stamps reached by
/// different sums (`now − age` of a delayed radio report against an earlier `now`) differ by
/// rounding; a rate taken over that difference would be noise divided by ~1e-17 s. Far below
/// the shortest update period (1 ms) and far above the rounding of any flight time.
pub const SAME_INSTANT_S: f64 = 1e-6;

/// Time from `t_track` to `t_obs`, zero when they are the same instant.
fn elapsed(t_obs: f64, t_track: f64) -> f64 {
    let dt = t_obs - t_track;
    if dt.abs() < SAME_INSTANT_S {
        0.0
    } else {
        dt
    }
}

impl NeighbourTracks {
    /// Tracks for at most `capacity` neighbours; a track not updated for `timeout_s` restarts.
    /// Coasting tracks extrapolate their acceleration for at most `coast_accel_s`.
    pub fn new(kind: PredictorKind, capacity: usize, timeout_s: f64, coast_accel_s: f64) -> Self {
        let capacity = capacity.max(1);
        // Allocated once at full capacity: growing per neighbour fragments the heap of a large
        // swarm (measured: +40 % resident memory at 10^5 UAVs).
        let kind = match kind {
            PredictorKind::ConstantVelocity => Kind::ConstantVelocity,
            PredictorKind::AlphaBeta { alpha, beta } => Kind::AlphaBeta { alpha, beta },
            PredictorKind::Singer { accel_sigma_mps2, tau_s, position_sigma_m, velocity_sigma_mps, alpha, beta } => {
                Kind::Singer(Box::new(SingerTracks {
                    model: Singer { accel_sigma_mps2, tau_s, position_sigma_m, velocity_sigma_mps },
                    alpha,
                    beta,
                    axes: Vec::with_capacity(capacity),
                    step: None,
                }))
            }
        };
        Self {
            kind,
            timeout_s,
            coast_accel_s,
            ids: Vec::with_capacity(capacity),
            tracks: Vec::with_capacity(capacity),
            capacity,
            carry: None,
        }
    }

    /// These tracks, bringing a report forward with its own rates over at most the carry's
    /// period (and `coast_accel_s`) after its measurement and with `carry` beyond
    /// ([`crate::plan`]): without it, a track's rates are extrapolated over the whole interval
    /// (a coasting track's acceleration over `coast_accel_s`).
    pub fn with_carry(mut self, carry: Option<Arc<Carry>>) -> Self {
        self.carry = carry;
        self
    }

    /// The track's state `h` seconds after its measurement, brought forward by the plan
    /// beyond its own rates' span (the period, at most `coast_accel_s`); None without a plan,
    /// or within that span.
    #[inline]
    fn carried(&self, tr: &Track, h: f64) -> Option<State9> {
        let carry = self.carry.as_deref()?;
        let own = carry.period_s().min(self.coast_accel_s);
        (h > own + SAME_INSTANT_S).then(|| carry.carry(&extrapolate(tr, own), tr.t + own, tr.t + h))
    }

    /// Room for at least `capacity` neighbours, the tracks kept (a table with more main
    /// references after a succession).
    pub fn grow_to(&mut self, capacity: usize) {
        if capacity > self.capacity {
            let more = capacity - self.ids.len();
            self.ids.reserve_exact(more);
            self.tracks.reserve_exact(more);
            if let Kind::Singer(k) = &mut self.kind {
                k.axes.reserve_exact(more);
            }
            self.capacity = capacity;
        }
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.ids.capacity() * std::mem::size_of::<(u32, u8)>()
            + self.tracks.capacity() * std::mem::size_of::<Track>()
            + match &self.kind {
                Kind::Singer(k) => {
                    std::mem::size_of::<SingerTracks>() + k.axes.capacity() * std::mem::size_of::<[Axis; 3]>()
                }
                _ => 0,
            }
    }

    /// Feeds observation `obs` (taken at `now − obs.age_s`) and returns the neighbour's
    /// predicted state at `now + horizon_s`.
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    pub fn predict(&mut self, obs: &Observation, now: f64, horizon_s: f64) -> State9 {
        let t_obs = now - obs.age_s;
        let track = match self.kind {
            Kind::ConstantVelocity => {
                // The plain F, exact in f64.
                let h = now + horizon_s - t_obs;
                let mut s = obs.state;
                for k in X..VX {
                    s[k] += h * obs.state[k + 3];
                }
                return s;
            }
            Kind::AlphaBeta { alpha, beta } => {
                let slot = self.slot_for(obs.id, t_obs);
                let (id, seen) = (self.ids[slot].0, self.ids[slot].1 & SEEN);
                let tr = &mut self.tracks[slot];
                let dt = elapsed(t_obs, tr.t);
                let fresh = dt <= self.timeout_s; // false for NaN too
                if id != obs.id.0 || !fresh {
                    *tr = Track::start(t_obs, &obs.state);
                    self.ids[slot] = (obs.id.0, 1);
                } else if dt > 0.0 && seen < 2 {
                    two_point_start(tr, &obs.state, dt);
                    self.ids[slot].1 = 2;
                } else if dt > 0.0 {
                    alpha_beta_update(tr, &obs.state, dt, alpha, beta);
                }
                tr.heard = now;
                self.ids[slot].1 = (self.ids[slot].1 & SEEN) | onboard_flag(obs);
                *tr
            }
            Kind::Singer(_) => {
                let slot = self.slot_for(obs.id, t_obs);
                let (id, seen) = (self.ids[slot].0, self.ids[slot].1 & SEEN);
                let Kind::Singer(k) = &mut self.kind else { unreachable!("matched above") };
                let SingerTracks { model: m, alpha, beta, axes, step } = &mut **k;
                let (tr, axes) = (&mut self.tracks[slot], &mut axes[slot]);
                let dt = elapsed(t_obs, tr.t);
                let z = &obs.state;
                let fresh = dt <= self.timeout_s; // false for NaN too
                if id != obs.id.0 || !fresh {
                    *tr = Track::start(t_obs, z);
                    *axes = std::array::from_fn(|k| m.start(z[X + k], z[VX + k]));
                    self.ids[slot] = (obs.id.0, 1);
                } else if dt >= 0.0 {
                    // Every observation updates the track, two at the same instant included.
                    if dt > 0.0 {
                        let f = match step {
                            Some(s) if s.t == dt => *s,
                            _ => *step.insert(m.step(dt)),
                        };
                        for axis in axes.iter_mut() {
                            Singer::predict_with(axis, &f);
                        }
                    }
                    for k in 0..3 {
                        m.update(&mut axes[k], z[X + k], z[VX + k]);
                    }
                    if dt > 0.0 && seen < 2 {
                        // The attitude alone: the Kalman axes carry position and velocity.
                        va_two_point_start(tr, z, dt, 3..6);
                        self.ids[slot].1 = 2;
                    } else if dt > 0.0 {
                        va_alpha_beta(tr, z, dt, *alpha, *beta, 3..6);
                    }
                    tr.t = t_obs;
                }
                tr.heard = now;
                self.ids[slot].1 = (self.ids[slot].1 & SEEN) | onboard_flag(obs);
                for k in 0..3 {
                    tr.pos[k] = axes[k].x[0];
                    tr.va[k] = axes[k].x[1] as f32;
                    tr.rate[k] = axes[k].x[2] as f32;
                }
                *tr
            }
        };
        let h = now + horizon_s - track.t;
        self.carried(&track, h).unwrap_or_else(|| extrapolate(&track, h))
    }

    /// Moves every track's position by `d` (m): the frame its observations are given in moved.
    pub fn shift(&mut self, d: [f64; 3]) {
        for tr in &mut self.tracks {
            for k in 0..3 {
                tr.pos[k] += d[k];
            }
        }
        if let Kind::Singer(k) = &mut self.kind {
            for axes in &mut k.axes {
                for c in 0..3 {
                    axes[c].x[0] += d[c];
                }
            }
        }
    }

    /// Whether UAV `id`'s last report came from the owner's own sensors, no longer than
    /// `max_s` before `now` (and its measurement within the timeout).
    pub fn heard_onboard(&self, id: UavId, now: f64, max_s: f64) -> bool {
        self.slot_of(id).is_some_and(|s| {
            let tr = &self.tracks[s];
            self.ids[s].1 & ONBOARD != 0 && now - tr.heard <= max_s + SAME_INSTANT_S && now - tr.t <= self.timeout_s
        })
    }

    /// Whether any neighbour's last report came from the owner's own sensors, no longer than
    /// `max_s` before `now` (and its measurement within the timeout).
    pub fn any_heard_onboard(&self, now: f64, max_s: f64) -> bool {
        self.ids.iter().zip(&self.tracks).any(|(&(id, flags), tr)| {
            id != FREE
                && flags & ONBOARD != 0
                && now - tr.heard <= max_s + SAME_INSTANT_S
                && now - tr.t <= self.timeout_s
        })
    }

    /// The slot of `id`'s track, if it has one (a UAV has at most one).
    pub fn slot_of(&self, id: UavId) -> Option<usize> {
        self.ids.iter().position(|t| t.0 == id.0 && t.0 != FREE)
    }

    /// Number of track slots in use.
    pub fn slots(&self) -> usize {
        self.ids.len()
    }

    /// The neighbour of track slot `s` if its track can coast at `now`: last heard before
    /// `now`, no longer ago than `max_s`, and measured no longer ago than `max_age_s` (the
    /// timeout; a relay's information, carried hop by hop, is older). A neighbour missing from
    /// this step's observations (a lost message, a dropped detection) is then predicted from
    /// its track.
    pub fn coasting(&self, s: usize, now: f64, max_s: f64, max_age_s: f64) -> Option<UavId> {
        let (id, _) = self.ids[s];
        let missing = self.missing(s, now);
        let age = now - self.tracks[s].t;
        (id != FREE && missing >= SAME_INSTANT_S && missing <= max_s + SAME_INSTANT_S && age <= max_age_s)
            .then_some(UavId(id))
    }

    /// Lets UAV `from`'s track stand for UAV `to`, moved by `shift(its state)` (added to its
    /// position, velocity and attitude), when there is no track of `to`: a lost leader's
    /// track, carried by the plan, moved by the formation's offset between the two slots, is
    /// where its successor flies until reports of it arrive. Nothing when `to` is tracked
    /// already (what the UAV knows first-hand wins) or `from` is not.
    pub fn relabel(&mut self, from: UavId, to: UavId, shift: impl Fn(&State9) -> State9) {
        if self.ids.iter().any(|t| t.0 == to.0) {
            return;
        }
        let Some(s) = self.ids.iter().position(|t| t.0 == from.0 && t.0 != FREE) else { return };
        let tr = &mut self.tracks[s];
        let d = shift(&extrapolate(tr, 0.0));
        if !d.iter().all(|v| v.is_finite()) {
            return;
        }
        for k in 0..3 {
            tr.pos[k] += d[X + k];
        }
        for k in 0..6 {
            tr.va[k] += d[VX + k] as f32;
        }
        if let Kind::Singer(k) = &mut self.kind {
            for (c, axis) in k.axes[s].iter_mut().enumerate() {
                axis.x[0] += d[X + c];
                axis.x[1] += d[VX + c];
            }
        }
        self.ids[s].0 = to.0;
    }

    /// Whether reports are brought forward by the plan beyond a period ([`Self::with_carry`]).
    pub fn carries(&self) -> bool {
        self.carry.is_some()
    }

    /// What the tracks know of UAV `id` at `now`: its filtered state at its last measurement
    /// and how long ago that was (s); None without a track, one not heard within the timeout,
    /// or one measured more than `max_age_s` ago (and always with the plain transition, which
    /// keeps no tracks). A track fed by relays keeps the time of the measurement they
    /// describe, so that age is how old the information is.
    pub fn report(&self, id: UavId, now: f64, max_age_s: f64) -> Option<(State9, f64)> {
        let s = self.slot_of(id)?;
        let tr = &self.tracks[s];
        let age = now - tr.t;
        let alive = now - tr.heard <= self.timeout_s && age <= max_age_s;
        (age >= -SAME_INSTANT_S && alive).then(|| (extrapolate(tr, 0.0), age.max(0.0)))
    }

    /// Seconds since a report of track slot `s` last arrived, at `now` (its age less the age
    /// it had when it arrived: a radio's delay is not a missing report).
    pub fn missing(&self, s: usize, now: f64) -> f64 {
        now - self.tracks[s].heard
    }

    /// The state of track slot `s` extrapolated to time `t` (a coasting neighbour): its
    /// acceleration is extrapolated for at most `coast_accel_s`, after which it goes on at the
    /// velocity reached; attitude rates carry on.
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    pub fn state_at(&self, s: usize, t: f64) -> State9 {
        let tr = &self.tracks[s];
        let h = t - tr.t;
        if let Some(st) = self.carried(tr, h) {
            return st;
        }
        let mut st = extrapolate(tr, h);
        let ha = self.coast_accel_s;
        if h > ha {
            for k in 0..3 {
                let v = f64::from(tr.va[k]);
                let a = f64::from(tr.rate[k]);
                st[X + k] = tr.pos[k] + h * v + a * ha * (h - 0.5 * ha);
                st[VX + k] = v + ha * a;
            }
        }
        st
    }

    /// Index of the track of `id`, or the slot to (re)use for it (marked free).
    fn slot_for(&mut self, id: UavId, t_obs: f64) -> usize {
        if let Some(k) = self.ids.iter().position(|t| t.0 == id.0) {
            return k;
        }
        if self.ids.len() < self.capacity {
            self.ids.push((FREE, 0));
            self.tracks.push(Track { t: t_obs, heard: t_obs, ..Track::default() });
            if let Kind::Singer(k) = &mut self.kind {
                k.axes.push([Axis::default(); 3]);
            }
            return self.ids.len() - 1;
        }
        // Evict the track observed longest ago.
        let mut oldest = 0;
        for (k, t) in self.tracks.iter().enumerate() {
            if t.t < self.tracks[oldest].t {
                oldest = k;
            }
        }
        self.ids[oldest] = (FREE, 0);
        oldest
    }
}

/// The standard start of an α-β track: the second measurement sets the value and the rates
/// from the difference of the first two.
#[inline]
fn two_point_start(tr: &mut Track, z: &State9, dt: f64) {
    va_two_point_start(tr, z, dt, 0..6);
    tr.pos = [z[0], z[1], z[2]];
    tr.t += dt;
}

/// The two-point start of the velocity and attitude components `ks` (0-2 velocity, 3-5
/// attitude): value from the measurement, rate from the difference with the first.
#[inline]
fn va_two_point_start(tr: &mut Track, z: &State9, dt: f64, ks: std::ops::Range<usize>) {
    for k in ks {
        let d = crate::state::difference_component(VX + k, z[VX + k], f64::from(tr.va[k]));
        tr.rate[k] = (d / dt) as f32;
        tr.va[k] = z[VX + k] as f32;
    }
}

/// One α-β update after `dt` seconds with measurement `z`.
#[inline]
fn alpha_beta_update(tr: &mut Track, z: &State9, dt: f64, alpha: f64, beta: f64) {
    // Position: advanced by the filtered velocity and acceleration, corrected by α.
    for k in 0..3 {
        let v = f64::from(tr.va[k]);
        let a = f64::from(tr.rate[k]);
        let pred = tr.pos[k] + dt * (v + 0.5 * dt * a);
        tr.pos[k] = pred + alpha * (z[X + k] - pred);
    }
    // Velocity and attitude: value and rate (attitude residuals wrapped).
    va_alpha_beta(tr, z, dt, alpha, beta, 0..6);
    tr.t += dt;
}

/// The α-β update of the velocity and attitude components `ks` (0-2 velocity, 3-5 attitude).
#[inline]
fn va_alpha_beta(tr: &mut Track, z: &State9, dt: f64, alpha: f64, beta: f64, ks: std::ops::Range<usize>) {
    let beta_dt = beta / dt;
    for k in ks {
        let rate = f64::from(tr.rate[k]);
        let pred = f64::from(tr.va[k]) + dt * rate;
        let raw = z[VX + k] - pred;
        let res = if k >= 3 { crate::angle::wrap_pi(raw) } else { raw };
        tr.va[k] = (pred + alpha * res) as f32;
        tr.rate[k] = (rate + beta_dt * res) as f32;
    }
}

/// The track's state `h` seconds after its measurement time.
#[inline]
fn extrapolate(tr: &Track, h: f64) -> State9 {
    let mut s = State9::zeros();
    for k in 0..3 {
        let v = f64::from(tr.va[k]);
        let a = f64::from(tr.rate[k]);
        s[X + k] = tr.pos[k] + h * (v + 0.5 * h * a);
    }
    for k in 0..6 {
        s[VX + k] = f64::from(tr.va[k]) + h * f64::from(tr.rate[k]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_delayed_report_is_old_but_not_missing_and_tracks_move_with_their_frame() {
        let mut tracks = NeighbourTracks::new(PredictorKind::default(), 4, 1.0, 0.2);
        let mut s = State9::zeros();
        s[VX] = 10.0;
        let radio = |s: State9, age_s: f64| Observation {
            id: UavId(3),
            state: s,
            age_s,
            source: crate::ObservationSource::Radio,
        };
        tracks.predict(&radio(s, 0.3), 1.0, 0.1);
        // Measured 0.3 s before it arrived, heard now: missing from the next period on only.
        assert!((tracks.missing(0, 1.0)).abs() < 1e-12);
        assert!((tracks.missing(0, 1.2) - 0.2).abs() < 1e-12);
        assert!(tracks.coasting(0, 1.2, 0.5, 1.0).is_some(), "0.2 s missing, 0.5 s old: coasts");
        assert!(tracks.coasting(0, 1.8, 0.5, 1.0).is_none(), "0.8 s missing: no longer");
        assert!(!tracks.heard_onboard(UavId(3), 1.2, 0.5), "heard by radio");
        let mut onboard = radio(s, 0.0);
        onboard.source = crate::ObservationSource::Onboard;
        tracks.predict(&onboard, 1.3, 0.1);
        assert!(tracks.heard_onboard(UavId(3), 1.5, 0.5) && !tracks.heard_onboard(UavId(3), 1.9, 0.5));
        // The frame the observations are given in moved by 0.4 m: so did the track.
        let before = tracks.state_at(0, 1.4);
        tracks.shift([0.0, 0.4, 0.0]);
        let after = tracks.state_at(0, 1.4);
        assert!((after[X + 1] - before[X + 1] - 0.4).abs() < 1e-12 && (after[X] - before[X]).abs() < 1e-12);
    }

    #[test]
    fn a_track_reports_its_last_measurement_and_its_age() {
        let mut tracks = NeighbourTracks::new(PredictorKind::default(), 4, 1.0, 0.2);
        let mut s = State9::zeros();
        s[VX] = 70.0;
        let obs =
            |s: State9| Observation { id: UavId(7), state: s, age_s: 0.0, source: crate::ObservationSource::Onboard };
        tracks.predict(&obs(s), 0.0, 0.1);
        s[X] = 7.0;
        tracks.predict(&obs(s), 0.1, 0.1);
        let (state, age) = tracks.report(UavId(7), 0.4, 1.0).expect("tracked");
        assert!((age - 0.3).abs() < 1e-12, "{age}");
        assert!((state[X] - 7.0).abs() < 1e-9 && (state[VX] - 70.0).abs() < 1e-9, "{state:?}");
        assert!(tracks.report(UavId(8), 0.4, 1.0).is_none(), "no track");
        assert!(tracks.report(UavId(7), 1.2, 1.0).is_none(), "older than the timeout");
        let plain = NeighbourTracks::new(PredictorKind::ConstantVelocity, 4, 1.0, 0.2);
        assert!(plain.report(UavId(7), 0.0, 1.0).is_none(), "the plain transition keeps no tracks");
    }
    use crate::observation::ObservationSource;
    use approx::assert_relative_eq;

    fn obs(id: u32, s: State9) -> Observation {
        Observation { id: UavId(id), state: s, age_s: 0.0, source: ObservationSource::Onboard }
    }

    #[test]
    fn constant_velocity_advances_position_only() {
        let mut tracks = NeighbourTracks::new(PredictorKind::ConstantVelocity, 4, 1.0, 0.2);
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
        let mut tracks = NeighbourTracks::new(PredictorKind::default(), 4, 1.0, 0.2);
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
    fn a_coasting_track_stops_accelerating_after_the_cap() {
        let mut tracks = NeighbourTracks::new(PredictorKind::AlphaBeta { alpha: 1.0, beta: 1.0 }, 4, 5.0, 0.2);
        // A neighbour accelerating at 2 m/s² along x, seen for 1 s.
        for k in 0..=10 {
            let t = k as f64 * 0.1;
            let mut s = State9::zeros();
            s[0] = 10.0 * t + t * t;
            s[3] = 10.0 + 2.0 * t;
            tracks.predict(&obs(7, s), t, 0.1);
        }
        // Coasting 1 s past its last measurement: 0.2 s more of acceleration, then 10.4 m/s… on.
        let x = tracks.state_at(0, 2.0);
        assert_relative_eq!(x[3], 12.0 + 2.0 * 0.2, epsilon = 1e-4);
        assert_relative_eq!(x[0], 11.0 + 12.0 * 1.0 + 2.0 * 0.2 * (1.0 - 0.1), epsilon = 1e-3);
    }

    #[test]
    fn a_singer_track_fuses_an_onboard_detection_and_a_radio_report_of_the_same_instant() {
        let kind = PredictorKind::singer(1.0, 0.5);
        let mut one = NeighbourTracks::new(kind, 4, 1.0, 0.2);
        let mut two = NeighbourTracks::new(kind, 4, 1.0, 0.2);
        let at = |y: f64| {
            let mut s = State9::zeros();
            s[1] = y;
            s[3] = 50.0;
            s
        };
        for k in 0..5 {
            let t = k as f64 * 0.1;
            let mut x = at(0.0);
            x[0] = 50.0 * t;
            one.predict(&obs(1, x), t, 0.1);
            two.predict(&obs(1, x), t, 0.1);
        }
        // At 0.5 s the onboard detection says y = +1 m and the radio report y = −1 m: alone,
        // the first pulls the track toward +1; fused, the two cancel.
        let (mut up, mut down) = (at(1.0), at(-1.0));
        up[0] = 25.0;
        down[0] = 25.0;
        let alone = one.predict(&obs(1, up), 0.5, 0.0);
        two.predict(&obs(1, up), 0.5, 0.0);
        let mut radio = obs(1, down);
        radio.source = ObservationSource::Radio;
        let fused = two.predict(&radio, 0.5, 0.0);
        assert!(alone[1] > 0.1, "{}", alone[1]);
        assert!(fused[1].abs() < 0.5 * alone[1], "{} vs {}", fused[1], alone[1]);
    }

    #[test]
    fn reports_of_one_instant_stamped_by_different_sums_give_no_rate() {
        // A neighbour flying 50 m/s along x, observed every 0.1 s; then the same instant again,
        // its stamp off by rounding (1e-14 s) and its position off by measurement noise (2 cm).
        for kind in [PredictorKind::default(), PredictorKind::singer(0.02, 0.05)] {
            let mut tracks = NeighbourTracks::new(kind, 4, 1.0, 0.2);
            let at = |t: f64, dy: f64| {
                let mut s = State9::zeros();
                s[0] = 50.0 * t;
                s[1] = dy;
                s[3] = 50.0;
                s[8] = dy;
                s
            };
            for k in 0..10 {
                let t = k as f64 * 0.1;
                tracks.predict(&obs(2, at(t, 0.0)), t, 0.1);
            }
            let t = 0.9 + 1e-14;
            let p = tracks.predict(&obs(2, at(t, 0.02)), t, 0.1);
            assert!((p[4]).abs() < 1.0, "{kind:?}: lateral velocity {}", p[4]);
            assert!((p[1]).abs() < 0.1, "{kind:?}: lateral position {}", p[1]);
            assert!((p[8]).abs() < 0.1, "{kind:?}: roll {}", p[8]);
        }
    }

    #[test]
    fn tracks_are_evicted_oldest_first_without_growing() {
        let mut tracks = NeighbourTracks::new(PredictorKind::default(), 2, 1.0, 0.2);
        for (t, id) in [(0.0, 1), (0.1, 2), (0.2, 3)] {
            tracks.predict(&obs(id, State9::zeros()), t, 0.1);
        }
        assert_eq!(tracks.tracks.len(), 2);
        assert!(tracks.ids.iter().all(|t| t.0 != 1));
    }

    #[test]
    fn a_lost_leaders_track_stands_for_its_successor_moved_by_their_offset() {
        for kind in [
            PredictorKind::default(),
            PredictorKind::Singer {
                accel_sigma_mps2: 1.0,
                tau_s: 1.0,
                position_sigma_m: 0.02,
                velocity_sigma_mps: 0.05,
                alpha: 0.8,
                beta: 0.47,
            },
        ] {
            let mut tracks = NeighbourTracks::new(kind, 4, 1.0, 0.2);
            let mut s = State9::zeros();
            s[VX] = 70.0;
            for k in 0..5 {
                s[X] = 7.0 * k as f64;
                tracks.predict(&obs(1, s), 0.1 * k as f64, 0.1);
            }
            let shift = |_: &State9| {
                let mut d = State9::zeros();
                d[X + 1] = 50.0;
                d
            };
            let (before, age) = tracks.report(UavId(1), 0.4, 1.0).expect("tracked");
            tracks.relabel(UavId(1), UavId(2), shift);
            assert!(tracks.report(UavId(1), 0.4, 1.0).is_none(), "{kind:?}: no longer UAV 1's");
            let (after, age2) = tracks.report(UavId(2), 0.4, 1.0).expect("UAV 2's now");
            assert_eq!(age, age2);
            assert!(
                (after[X + 1] - before[X + 1] - 50.0).abs() < 1e-9 && (after[X] - before[X]).abs() < 1e-9,
                "{kind:?}"
            );
            assert!((after[VX] - before[VX]).abs() < 1e-4, "{kind:?}");
            // A UAV tracked first-hand keeps its own track.
            tracks.predict(&obs(3, State9::zeros()), 0.4, 0.1);
            tracks.relabel(UavId(2), UavId(3), shift);
            assert!(tracks.report(UavId(2), 0.4, 1.0).is_some() && tracks.report(UavId(3), 0.4, 1.0).is_some());
        }
    }
}
