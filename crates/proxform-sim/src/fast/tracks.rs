//! The neighbour tracks of every UAV in one array: `capacity` records per UAV, contiguous, each
//! a neighbour's filtered state in 48 bytes, with the reference's α-β filter (METHOD §3,
//! `proxform_core::predictor`) run on them in f32.
//!
//! A record holds position and velocity in f32, attitude as 16-bit binary angles (2π/65 536
//! rad a unit: they wrap as angles do, and the filter's residuals are wrapped anyway) and the
//! six rates in 16 bits over a span set per scenario ([`Filter::rate_span`]): wide enough for
//! the vehicle's limits (with what the wind adds, [`super::setup::wind_acceleration`]) and for
//! the noise of a two-point start, so the quantum lies far below
//! the noise the filter smooths. Twelve tracks of a UAV take 576 bytes instead of 768 (a
//! 10^6-UAV swarm: 549 MiB instead of 732).
//!
//! Positions are kept relative to the owner's reference point at the track's time, `R_i(k) =
//! O(k) + A_i` ([`super::update::View::shift`]): tens of metres, so f32 resolves them to
//! micrometres however far the swarm flies. Times are step numbers (`t = k·Δt`), kept modulo
//! 128 beside the id: the step of the last measurement, and how many steps later it arrived
//! (a radio's delay), so that a delayed report is neither a missing one nor a fresh one.
//!
//! (Measured: a record per track and a scalar update cost fewer instructions than the same
//! filter over lanes of all of a UAV's tracks, whose fixed width and copies outweigh the
//! vector arithmetic at a dozen tracks a UAV on 4-wide vectors.)

use proxform_core::controller::Tracks;
use proxform_core::plan::Carry;
use proxform_core::predictor::SAME_INSTANT_S;
use proxform_core::state::{State9, VX};
use proxform_core::{Observation, ObservationSource, UavId};

/// Marks a free track.
pub const FREE: u32 = u32::MAX;
/// A track's word: the neighbour's id in the low 24 bits, the step of its last measurement
/// modulo 128 in the next 7, and whether it has absorbed a second measurement in the top bit.
const ID_MASK: u32 = (1 << 24) - 1;
const K_SHIFT: u32 = 24;
const K_MASK: u32 = 0x7f;
const SEEN_TWICE: u32 = 1 << 31;
/// Largest UAV id a track can hold.
pub const MAX_ID: u32 = ID_MASK - 1;
/// Longest a track may go unmeasured and still be used (steps): ages are kept modulo 128, and
/// every UAV frees its tracks older than its limit each step ([`Owner::sweep`]).
pub const MAX_AGE_STEPS: i64 = 120;

/// Radians per unit of a binary angle.
const ANGLE_QUANTUM: f32 = std::f32::consts::PI / 32768.0;

const _: () = assert!(std::mem::size_of::<Track>() == 48);

/// One neighbour's filtered state: 48 bytes, packed.
#[derive(Debug, Clone, Copy)]
#[repr(C, packed(2))]
pub struct Track {
    /// Id, step modulo 128 and second-measurement flag; [`FREE`] when unused.
    word: u32,
    /// Position relative to the owner's reference point at the track's step (m; 0-2) and
    /// velocity (m/s; 3-5).
    pv: [f32; 6],
    /// Attitude, binary angles ([`ANGLE_QUANTUM`]).
    att: [i16; 3],
    /// Rates of velocity (m/s²) and attitude (rad/s) in units of [`Filter::rate_quantum`].
    rate: [i16; 6],
    /// Steps from its last measurement to when that report arrived (the radio's delay; 0 for
    /// what is sensed onboard).
    lag: u8,
    /// [`ONBOARD`] when its last report came from the owner's own sensors.
    flags: u8,
}

/// [`Track::flags`]: the last report came from the owner's own sensors (not the radio).
const ONBOARD: u8 = 1;

impl Default for Track {
    fn default() -> Self {
        Self { word: FREE, pv: [0.0; 6], att: [0; 3], rate: [0; 6], lag: 0, flags: 0 }
    }
}

/// 1.5·2²³: a float in [2²³, 2²⁴) holds an integer in its low mantissa bits, so adding it
/// rounds `x` (|x| < 2²²) to the nearest integer (ties to even) and the bits read it off: three
/// instructions, where a float-to-integer cast checks its range.
const ROUNDER: f32 = 12_582_912.0;

/// `x` rounded to the nearest integer, for |x| < 2²².
#[inline]
fn round_small(x: f32) -> i32 {
    ((x + ROUNDER).to_bits() as i32).wrapping_sub(ROUNDER.to_bits() as i32)
}

/// `x` to the nearest whole number as a 16-bit integer within ±32 767 (a clamp and the
/// rounder: vector instructions for the six rates at once). Finite inputs only: NaN, which the
/// filter never produces from finite measurements, gives an unspecified value.
#[inline]
fn to_i16(x: f32) -> i16 {
    round_small(x.clamp(-32767.0, 32767.0)) as i16
}

/// An angle (rad, any turn) as a binary angle: wraps modulo 2π.
#[inline]
fn to_angle(a: f32) -> i16 {
    let u = a * (1.0 / ANGLE_QUANTUM);
    if u.abs() < 4_194_304.0 {
        round_small(u) as i16
    } else {
        // Beyond 400 rad (64 turns): wrapped in f64 first.
        let w = f64::from(a).rem_euclid(std::f64::consts::TAU) / f64::from(ANGLE_QUANTUM);
        (w.round() as i64) as i16
    }
}

impl Track {
    /// The neighbour, None when free.
    #[inline]
    pub fn id(&self) -> Option<u32> {
        (self.word != FREE).then_some(self.word & ID_MASK)
    }

    /// Whether the track has been measured more than once since it started.
    #[cfg(test)]
    pub fn seen_twice(&self) -> bool {
        self.word != FREE && self.word & SEEN_TWICE != 0
    }

    /// Whether the track is `id`'s (an id is at most [`MAX_ID`], so never a free track's).
    #[inline]
    fn is(&self, id: u32) -> bool {
        self.word & ID_MASK == id
    }

    /// Steps since its last measurement at step `k` (a free track: older than any).
    #[inline]
    fn age(&self, k: i32) -> i64 {
        if self.word == FREE {
            return i64::MAX;
        }
        i64::from((k as u32).wrapping_sub(self.word >> K_SHIFT) & K_MASK)
    }

    /// The word of neighbour `id` measured at step `k`.
    #[inline]
    fn word(id: u32, k: i32, twice: bool) -> u32 {
        id | ((k as u32 & K_MASK) << K_SHIFT) | if twice { SEEN_TWICE } else { 0 }
    }
}

/// The α-β filter's constants.
#[derive(Debug, Clone, Copy)]
pub struct Filter {
    /// No tracks (the constant-velocity predictor): each observation is predicted by the
    /// plain transition F, and nothing is kept.
    pub plain: bool,
    pub alpha: f64,
    pub beta: f64,
    /// Update period (s).
    pub dt: f64,
    /// A track not updated for this many steps restarts.
    pub timeout_steps: i64,
    /// A coasting track extrapolates its acceleration for at most this long (s).
    pub coast_accel_s: f64,
    /// β/Δt (a track measured every period).
    pub beta_dt: f32,
    /// Units per rate (1 / quantum) of the six rates (velocity m/s², attitude rad/s).
    pub rate_units: [f32; 6],
    /// The quantum of each rate.
    pub rate_quantum: [f32; 6],
}

impl Filter {
    /// The α-β filter with update period `dt` (s), a track restarting after `timeout_steps`,
    /// accelerations extrapolated for `coast_accel_s`, and rates kept over ±`span` (per rate).
    pub fn new(alpha: f64, beta: f64, dt: f64, timeout_steps: i64, coast_accel_s: f64, span: [f64; 6]) -> Self {
        let quantum = span.map(|s| (s.max(1e-6) / f64::from(i16::MAX)) as f32);
        Self {
            plain: false,
            alpha,
            beta,
            dt,
            timeout_steps,
            coast_accel_s,
            beta_dt: (beta / dt) as f32,
            rate_units: quantum.map(|q| 1.0 / q),
            rate_quantum: quantum,
        }
    }

    /// Keeps no tracks when `plain` (the constant-velocity predictor).
    pub fn plain(self, plain: bool) -> Self {
        Self { plain, ..self }
    }

    /// The span each rate is kept over: eight standard deviations of the rate a two-point start
    /// takes from two noisy measurements one period apart (`sigma`: the noise of velocity and
    /// attitude), and at least twice the vehicle's own limit (`limit`: m/s², rad/s).
    pub fn rate_span(sigma: [f64; 6], limit: [f64; 6], dt: f64) -> [f64; 6] {
        std::array::from_fn(|c| (8.0 * std::f64::consts::SQRT_2 * sigma[c] / dt).max(2.0 * limit[c]))
    }

    /// A record as f32: position, velocity, attitude (rad, in [−π, π)), then the six rates.
    #[inline]
    fn load(&self, tr: &Track) -> [f32; 15] {
        let (pv, att, rate) = (tr.pv, tr.att, tr.rate);
        let mut v = [0.0f32; 15];
        v[..6].copy_from_slice(&pv);
        for c in 0..3 {
            v[6 + c] = f32::from(att[c]) * ANGLE_QUANTUM;
        }
        for c in 0..6 {
            v[9 + c] = f32::from(rate[c]) * self.rate_quantum[c];
        }
        v
    }

    /// Stores `v` (as [`Self::load`] gives it) in a record, its word unchanged.
    #[inline(always)]
    fn store(&self, tr: &mut Track, v: &[f32; 15]) {
        tr.pv = [v[0], v[1], v[2], v[3], v[4], v[5]];
        tr.att = [to_angle(v[6]), to_angle(v[7]), to_angle(v[8])];
        let mut rate = [0i16; 6];
        for c in 0..6 {
            rate[c] = to_i16(v[9 + c] * self.rate_units[c]);
        }
        tr.rate = rate;
    }
}

/// The tracks of one UAV: its records and how many are in use.
pub struct Owner<'a> {
    pub tracks: &'a mut [Track],
    pub used: &'a mut u8,
}

impl Owner<'_> {
    /// Frees the tracks not measured for more than `limit` steps (the longer of the timeout and
    /// the coasting time, at most [`MAX_AGE_STEPS`]): none of them would be used again, and
    /// ages modulo 128 stay exact.
    #[inline]
    pub fn sweep(&mut self, k: i32, limit: i64) {
        for t in self.tracks[..usize::from(*self.used)].iter_mut() {
            if t.word != FREE && t.age(k) - i64::from(t.lag) > limit {
                t.word = FREE;
            }
        }
    }

    /// The slot of `id`, or the one to (re)use for it: a new one while there is room, else the
    /// one measured longest ago (freed). `hint` is where to look first (neighbours are fed in
    /// the same order step after step, so the n-th fed is usually in slot n).
    #[inline(always)]
    fn slot_for(&mut self, id: u32, k: i32, hint: usize) -> usize {
        let n = usize::from(*self.used);
        if hint < n && self.tracks[hint].is(id) {
            return hint;
        }
        if let Some(s) = self.tracks[..n].iter().position(|t| t.is(id)) {
            return s;
        }
        if n < self.tracks.len() {
            self.tracks[n] = Track::default();
            *self.used += 1;
            return n;
        }
        let mut oldest = 0;
        for s in 1..n {
            if self.tracks[s].age(k) > self.tracks[oldest].age(k) {
                oldest = s;
            }
        }
        self.tracks[oldest].word = FREE;
        oldest
    }

    /// Moves every track's position by `d` (m): the frame its observations are given in moved
    /// (relative sensing: the owner's own position fix).
    pub fn shift(&mut self, d: [f64; 3]) {
        for t in self.tracks[..usize::from(*self.used)].iter_mut() {
            let mut pv = t.pv;
            for c in 0..3 {
                pv[c] += d[c] as f32;
            }
            t.pv = pv;
        }
    }

    /// The slot of `id`'s track, if it has one.
    #[inline]
    pub fn find(&self, id: u32) -> Option<usize> {
        self.tracks[..usize::from(*self.used)].iter().position(|t| t.is(id))
    }

    /// Feeds neighbour `id`'s observation `z` (looked for first in slot `hint`; relative to the
    /// owner's reference point at step `k`) and returns its slot and its predicted state `h`
    /// seconds after `k` (position, velocity, attitude). `shift(k0)` is how far the reference
    /// point of step `k0` lies from that of step `k` (m).
    pub fn predict(
        &mut self,
        f: &Filter,
        (id, hint, h): (u32, usize, f32),
        (k, lag): (i32, u8),
        z: &State9,
        shift: impl Fn(i32) -> [f64; 3],
    ) -> (usize, [f32; 9]) {
        // (A full set frees the track measured longest ago, seen from now.)
        let s = self.slot_for(id, k + i32::from(lag), hint);
        let tr = &mut self.tracks[s];
        tr.lag = lag;
        let steps = tr.age(k);
        let zf = to_f32(z);
        // The record as f32 (value 0-8, rates 9-14), filtered, then stored once.
        let mut v = [0.0f32; 15];
        if !tr.is(id) || steps > f.timeout_steps {
            // Start: the measurement, no rates.
            tr.word = Track::word(id, k, false);
            v[..9].copy_from_slice(&zf);
            f.store(tr, &v);
        } else if steps > 0 {
            v = f.load(tr);
            let dt = (steps as f64 * f.dt) as f32;
            if tr.word & SEEN_TWICE == 0 {
                // Two-point start: value from the measurement, rate from the difference.
                for c in 0..6 {
                    let diff = proxform_core::state::difference_component(VX + c, z[VX + c], f64::from(v[3 + c]));
                    v[9 + c] = (diff / f64::from(dt)) as f32;
                }
                v[..9].copy_from_slice(&zf);
            } else {
                // The α-β update.
                let d = shift(k - steps as i32);
                let alpha = f.alpha as f32;
                let beta_dt = if steps == 1 { f.beta_dt } else { (f.beta / f64::from(dt)) as f32 };
                for c in 0..3 {
                    let pred = v[c] + d[c] as f32 + dt * (v[3 + c] + 0.5 * dt * v[9 + c]);
                    v[c] = pred + alpha * (zf[c] - pred);
                }
                for c in 0..6 {
                    let pred = v[3 + c] + dt * v[9 + c];
                    let raw = zf[3 + c] - pred;
                    let res = if c >= 3 { wrap_pi(raw) } else { raw };
                    v[3 + c] = pred + alpha * res;
                    v[9 + c] += beta_dt * res;
                }
            }
            tr.word = Track::word(id, k, true);
            f.store(tr, &v);
        } else {
            v = f.load(tr);
        }
        (s, extrapolate(&v, h, [0.0; 3], f32::INFINITY))
    }

    /// The step slot `s` was last measured, seen from step `k`.
    #[inline]
    pub fn measured_at(&self, s: usize, k: i32) -> i32 {
        k - self.tracks[s].age(k) as i32
    }

    /// Slots in use.
    #[inline]
    pub fn used(&self) -> usize {
        usize::from(*self.used)
    }

    /// The state of slot `s` `h` seconds after its measurement (a coasting neighbour), relative
    /// to the reference point `d` metres from that of its measurement.
    pub fn state_at(&self, f: &Filter, s: usize, h: f64, d: [f64; 3]) -> [f32; 9] {
        extrapolate(&f.load(&self.tracks[s]), h as f32, d.map(|x| x as f32), f.coast_accel_s as f32)
    }

    /// The state of slot `s`, measured at `t0` (s), at `t0 + h` as the reference's tracks
    /// bring it forward with a plan: its own rates over one period (at most `coast_accel_s`),
    /// `carry` beyond (`proxform_core::plan`); relative to the reference point `d` metres from
    /// that of its measurement, which lies at `at` in the plan's frame. (The plan turns a report
    /// about the planned navigator, in absolute positions: a relative one would turn about
    /// the wrong point.)
    pub fn carried(
        &self,
        f: &Filter,
        carry: &proxform_core::plan::Carry,
        s: usize,
        (t0, h): (f64, f64),
        (d, at): ([f64; 3], [f64; 3]),
    ) -> [f32; 9] {
        let span = f.dt.min(f.coast_accel_s);
        let own = extrapolate(&f.load(&self.tracks[s]), span as f32, d.map(|x| x as f32), f32::INFINITY);
        let mut x = to_f64(&own);
        for k in 0..3 {
            x[k] += at[k];
        }
        let mut out = carry.carry(&x, t0 + span, t0 + h);
        for k in 0..3 {
            out[k] -= at[k];
        }
        to_f32(&out)
    }
}

/// One UAV's tracks at one update as the controller's step reads them
/// ([`proxform_core::controller::Tracks`]): the update is at step `k`, `t = k·Δt` on the
/// step's clock, and states come back in f64, relative to the owner's reference point at `k`.
/// A report heard over a delayed radio was measured before it arrived: the track is updated at
/// its measurement and counts as heard when it arrived (as the reference's tracks do). Its
/// records keep no source (the engine runs no relative sensing).
pub struct StepTracks<'a, 'v, S: Fn(i32) -> [f64; 3]> {
    pub owner: Owner<'a>,
    pub filter: &'v Filter,
    /// The mission plan's carry of old reports (as the reference tracks' `with_carry`).
    pub carry: Option<&'v Carry>,
    /// The update's step.
    pub k: i32,
    /// `shift(k0)`: how far the reference point of step `k0` lies from that of step `k` (m).
    pub shift: S,
    /// Where the owner's reference point of step `k` lies in the plan's frame (m): the
    /// absolute position the relative ones are taken from.
    pub at: [f64; 3],
    /// Tracks fed so far in this update (where the next is looked for first).
    pub fed: usize,
}

impl<S: Fn(i32) -> [f64; 3]> StepTracks<'_, '_, S> {
    /// Seconds from slot `s`'s last measurement to time `t`, and that measurement's step.
    #[inline]
    fn since(&self, s: usize, t: f64) -> (f64, i32) {
        let k0 = self.owner.measured_at(s, self.k);
        (t - f64::from(k0) * self.filter.dt, k0)
    }

    /// Seconds from slot `s`'s last measurement to time `t`, and from when that report
    /// arrived.
    #[inline]
    fn since_heard(&self, s: usize, t: f64) -> (f64, f64) {
        let age = self.since(s, t).0;
        let lag = self.owner.tracks[s].lag;
        (age, if lag == 0 { age } else { age - f64::from(lag) * self.filter.dt })
    }

    /// Whether slot `s`'s last report came from the owner's own sensors no longer than `max_s`
    /// before `now`, its measurement within the timeout (as the reference's tracks).
    #[inline]
    fn heard_onboard_in(&self, s: usize, now: f64, max_s: f64) -> bool {
        let (age, missing) = self.since_heard(s, now);
        let timeout = self.filter.timeout_steps as f64 * self.filter.dt;
        self.owner.tracks[s].flags & ONBOARD != 0
            && missing <= max_s + SAME_INSTANT_S
            && age <= timeout + SAME_INSTANT_S
    }

    /// Whether a state `h` seconds after its measurement is brought forward by the plan (past
    /// the track's own rates' span: a period, at most `coast_accel_s`).
    #[inline]
    fn carried(&self, h: f64) -> Option<&Carry> {
        let f = self.filter;
        self.carry.filter(|_| h > f.dt.min(f.coast_accel_s) + SAME_INSTANT_S)
    }

    /// Slot `s`'s state `h` seconds after its measurement at step `k0`.
    #[inline]
    fn state_after(&self, s: usize, k0: i32, h: f64) -> State9 {
        let (f, d) = (self.filter, (self.shift)(k0));
        let x = match self.carried(h) {
            Some(carry) => self.owner.carried(f, carry, s, (f64::from(k0) * f.dt, h), (d, self.at)),
            None => self.owner.state_at(f, s, h, d),
        };
        to_f64(&x)
    }
}

impl<S: Fn(i32) -> [f64; 3]> Tracks for StepTracks<'_, '_, S> {
    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    fn predict(&mut self, obs: &Observation, now: f64, horizon_s: f64) -> State9 {
        if self.filter.plain {
            // The constant-velocity predictor: the plain F on the observation, as the
            // reference's tracks give it (they keep none either).
            let h = now + horizon_s - (now - obs.age_s);
            let mut s = obs.state;
            for k in 0..3 {
                s[k] += h * obs.state[VX + k];
            }
            return s;
        }
        let h = horizon_s + obs.age_s;
        let hint = self.fed;
        self.fed += 1;
        // Measured `lag` steps ago (a delayed radio report): the track is updated at that step,
        // in the reference point's frame of then, unless it knows a later measurement (then it
        // only counts as heard now, as the reference's).
        let lag = match obs.age_s > 0.0 {
            true => (obs.age_s / self.filter.dt).round().clamp(0.0, 127.0) as i32,
            false => 0,
        };
        if lag > 0 {
            let k_obs = self.k - lag;
            if let Some(s) = self.owner.find(obs.id.0) {
                let k0 = self.owner.measured_at(s, self.k);
                // (However old the track: a later measurement is never replaced by an earlier
                // one, which the record could not even place in time, ages being modulo 128.)
                if k0 > k_obs {
                    self.owner.tracks[s].lag = (self.k - k0) as u8;
                    self.owner.tracks[s].flags = onboard_flag(obs);
                    return self.state_after(s, k0, horizon_s + f64::from(self.k - k0) * self.filter.dt);
                }
            }
            let d = (self.shift)(k_obs);
            let mut z = obs.state;
            for c in 0..3 {
                z[c] -= d[c];
            }
            let shift = |k0: i32| {
                let e = (self.shift)(k0);
                [e[0] - d[0], e[1] - d[1], e[2] - d[2]]
            };
            let (s, _) = self.owner.predict(self.filter, (obs.id.0, hint, h as f32), (k_obs, lag as u8), &z, shift);
            self.owner.tracks[s].flags = onboard_flag(obs);
            return self.state_after(s, k_obs, h);
        }
        let (s, x) = self.owner.predict(self.filter, (obs.id.0, hint, h as f32), (self.k, 0), &obs.state, &self.shift);
        self.fed = s + 1;
        self.owner.tracks[s].flags = onboard_flag(obs);
        match self.carried(h) {
            Some(carry) => {
                let t0 = f64::from(self.k) * self.filter.dt;
                to_f64(&self.owner.carried(self.filter, carry, s, (t0, h), ([0.0; 3], self.at)))
            }
            None => to_f64(&x),
        }
    }

    #[inline]
    fn slots(&self) -> usize {
        self.owner.used()
    }

    #[inline]
    fn slot_of(&self, id: UavId) -> Option<usize> {
        self.owner.find(id.0)
    }
    #[inline]
    fn coasting(&self, s: usize, now: f64, max_s: f64, max_age_s: f64) -> Option<UavId> {
        let (age, missing) = self.since_heard(s, now);
        let id = self.owner.tracks[s].id()?;
        (missing >= SAME_INSTANT_S && missing <= max_s + SAME_INSTANT_S && age <= max_age_s + SAME_INSTANT_S)
            .then_some(UavId(id))
    }

    #[inline]
    fn missing(&self, s: usize, now: f64) -> f64 {
        self.since_heard(s, now).1
    }

    // A phase of `proxform bench`'s instruction table: kept a function of its own.
    #[inline(never)]
    fn state_at(&self, s: usize, t: f64) -> State9 {
        let (h, k0) = self.since(s, t);
        self.state_after(s, k0, h)
    }

    #[inline]
    fn carries(&self) -> bool {
        self.carry.is_some()
    }

    fn report(&self, id: UavId, now: f64, max_age_s: f64) -> Option<(State9, f64)> {
        let s = self.owner.find(id.0)?;
        let (age, k0) = self.since(s, now);
        let timeout = self.filter.timeout_steps as f64 * self.filter.dt;
        let alive = self.since_heard(s, now).1 <= timeout + SAME_INSTANT_S;
        (alive && age <= max_age_s + SAME_INSTANT_S).then(|| (self.state_after(s, k0, 0.0), age.max(0.0)))
    }

    #[inline]
    fn heard_onboard(&self, id: UavId, now: f64, max_s: f64) -> bool {
        self.owner.find(id.0).is_some_and(|s| self.heard_onboard_in(s, now, max_s))
    }

    #[inline]
    fn any_heard_onboard(&self, now: f64, max_s: f64) -> bool {
        (0..self.owner.used()).any(|s| self.owner.tracks[s].word != FREE && self.heard_onboard_in(s, now, max_s))
    }
}

/// [`ONBOARD`] for a report of the owner's own sensors (onboard, a close-range detection, a
/// relay placed from its own view of the sender), nothing for the radio's.
#[inline]
fn onboard_flag(obs: &Observation) -> u8 {
    match obs.source {
        ObservationSource::Radio => 0,
        _ => ONBOARD,
    }
}

/// The track's state `h` seconds after its measurement, its position shifted by `d`: the
/// acceleration is extrapolated for at most `ha` seconds (then the velocity reached carries
/// on), attitude rates carry on.
#[inline]
fn extrapolate(v: &[f32; 15], h: f32, d: [f32; 3], ha: f32) -> [f32; 9] {
    let mut s = [0.0f32; 9];
    let ta = h.min(ha);
    for c in 0..3 {
        let (p, vel, a) = (v[c], v[3 + c], v[9 + c]);
        // p + h·v + a·ta·(h − ta/2): h·(v + h·a/2) while h ≤ ha.
        s[c] = p + d[c] + h * vel + a * ta * (h - 0.5 * ta);
        s[3 + c] = vel + ta * a;
    }
    for c in 6..9 {
        s[c] = v[c] + h * v[c + 6];
    }
    s
}

/// A state in f32 (a loop: the generic array constructors did not always inline).
#[inline]
pub fn to_f32(x: &State9) -> [f32; 9] {
    let x = x.as_slice();
    let mut out = [0.0f32; 9];
    for a in 0..9 {
        out[a] = x[a] as f32;
    }
    out
}

/// A state from f32.
#[inline]
pub fn to_f64(x: &[f32; 9]) -> State9 {
    State9::from_fn(|a, _| f64::from(x[a]))
}

/// `a` wrapped into (−π, π] (attitude residuals and differences are small: the test is a
/// branch always taken the same way).
#[inline]
pub fn wrap_pi(a: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    if a > -PI && a <= PI {
        a
    } else {
        let w = a - TAU * (a / TAU).round();
        if w <= -PI {
            w + TAU
        } else {
            w
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_core::predictor::{NeighbourTracks, PredictorKind};
    use proxform_core::{Observation, ObservationSource, UavId};

    /// A neighbour turning, climbing and rolling, observed with a step of noise-like wobble.
    fn neighbour(k: i32) -> State9 {
        let t = f64::from(k) * 0.1;
        let mut s = State9::zeros();
        s[0] = 70.0 * t + 3.0 * (0.3 * t).sin();
        s[1] = -40.0 + 5.0 * (0.2 * t).cos() + 0.01 * f64::from(k % 3);
        s[2] = 100.0 + 0.5 * t;
        s[3] = 70.0 + 0.9 * (0.3 * t).cos();
        s[4] = -(0.2 * 5.0) * (0.2 * t).sin();
        s[5] = 0.5;
        s[6] = 0.01 * (0.5 * t).sin();
        s[7] = 3.1 + 0.02 * t; // crosses π: residuals wrap
        s[8] = -0.05 + 0.001 * f64::from(k % 2);
        s
    }

    #[test]
    fn the_tracks_predict_as_the_reference_tracks_do() {
        let (alpha, beta) = (0.8, 0.8 * 0.8 / 1.2);
        let span = Filter::rate_span([0.05, 0.05, 0.05, 0.002, 0.002, 0.002], [5.0, 5.0, 5.0, 0.5, 0.5, 0.5], 0.1);
        let f = Filter::new(alpha, beta, 0.1, 10, 0.2, span);
        let mut reference = NeighbourTracks::new(PredictorKind::AlphaBeta { alpha, beta }, 4, 1.0, 0.2);
        let mut records = vec![Track::default(); 4];
        let mut used = 0u8;
        let mut owner = Owner { tracks: &mut records, used: &mut used };
        let mut worst = [0.0f64; 9];
        for k in 0..200 {
            if k % 37 == 5 {
                continue; // a missed observation: the next update spans two periods
            }
            let z = neighbour(k);
            let obs = Observation { id: UavId(7), state: z, age_s: 0.0, source: ObservationSource::Onboard };
            let want = reference.predict(&obs, f64::from(k) * 0.1, 0.1);
            let (_, got) = owner.predict(&f, (7, 0, 0.1), (k, 0), &z, |_| [0.0; 3]);
            for c in 0..9 {
                let mut d = f64::from(got[c]) - want[c];
                if c >= 6 {
                    d = proxform_core::angle::wrap_pi(d);
                }
                worst[c] = worst[c].max(d.abs());
            }
        }
        // f32 against f64: positions to a millimetre, velocities and attitudes far finer.
        for c in 0..3 {
            assert!(worst[c] < 1e-3, "position {c}: {worst:?}");
        }
        for c in 3..9 {
            assert!(worst[c] < 1e-4, "component {c}: {worst:?}");
        }
        // Coasting: the same extrapolation with the acceleration capped.
        let (_, age) = reference.report(UavId(7), 20.0, 1.0).expect("tracked");
        assert!(age < 0.2);
        let want = reference.state_at(0, 19.9 + 0.5);
        let got = owner.state_at(&f, 0, 0.5 + (19.9 - 0.1 * f64::from(owner.measured_at(0, 199))), [0.0; 3]);
        for c in 0..3 {
            assert!((f64::from(got[c]) - want[c]).abs() < 2e-3, "{got:?} vs {want:?}");
        }
    }

    #[test]
    fn a_full_set_of_tracks_gives_the_oldest_to_a_new_neighbour() {
        let f = Filter::new(0.8, 0.5, 0.1, 10, 0.2, [10.0; 6]);
        let mut records = vec![Track::default(); 2];
        let mut used = 0u8;
        let mut owner = Owner { tracks: &mut records, used: &mut used };
        let z = neighbour(0);
        owner.predict(&f, (1, 0, 0.1), (0, 0), &z, |_| [0.0; 3]);
        owner.predict(&f, (2, 1, 0.1), (1, 0), &z, |_| [0.0; 3]);
        let (s, _) = owner.predict(&f, (3, 0, 0.1), (2, 0), &z, |_| [0.0; 3]);
        assert_eq!(s, 0, "the track of UAV 1, measured longest ago, is reused");
        assert_eq!(owner.tracks[0].id(), Some(3));
        assert_eq!(owner.tracks[1].id(), Some(2));
        // A wrong hint still finds the track.
        let (s, _) = owner.predict(&f, (2, 0, 0.1), (3, 0), &z, |_| [0.0; 3]);
        assert_eq!(s, 1);
        assert_eq!(wrap_pi(3.5), 3.5 - std::f32::consts::TAU);
    }

    #[test]
    fn angles_wrap_and_rates_saturate_in_sixteen_bits() {
        use std::f32::consts::PI;
        for a in [0.0f32, 1.0, -1.0, 3.1, -3.1, 3.2, 10.0, -100.0, 1e4] {
            let back = f32::from(to_angle(a)) * ANGLE_QUANTUM;
            let d = wrap_pi(back - a);
            assert!(d.abs() <= 0.5 * ANGLE_QUANTUM + 2.0 * a.abs() * f32::EPSILON, "{a}: {back}");
        }
        assert_eq!(to_angle(PI), i16::MIN, "π is −π");
        assert_eq!(to_angle(-PI), i16::MIN);
        assert_eq!(to_angle(2.5 * ANGLE_QUANTUM), 2, "ties to even");
        assert_eq!(to_angle(-3.5 * ANGLE_QUANTUM), -4);
        for a in [1000.0f32, -2000.0, 1e6] {
            let d = wrap_pi(
                f32::from(to_angle(a)) * ANGLE_QUANTUM - (f64::from(a).rem_euclid(std::f64::consts::TAU)) as f32,
            );
            assert!(d.abs() <= ANGLE_QUANTUM, "{a}: {d}");
        }
        let f = Filter::new(0.8, 0.5, 0.1, 10, 0.2, [1.0; 6]);
        let mut t = Track::default();
        let mut v = [0.0f32; 15];
        v[6] = 3.5;
        v[9] = 0.25;
        v[10] = -5.0;
        v[11] = f32::INFINITY;
        f.store(&mut t, &v);
        let back = f.load(&t);
        assert!((back[9] - 0.25).abs() <= 0.5 * f.rate_quantum[0]);
        assert!((back[6] - (3.5 - std::f32::consts::TAU)).abs() <= ANGLE_QUANTUM, "{}", back[6]);
        let rate = t.rate;
        assert_eq!(rate[1], -i16::MAX, "beyond the span: the span's end");
        assert_eq!(rate[2], i16::MAX);
        for x in [-32767.4f32, -1.5, -0.5, 0.49, 0.5, 1.5, 12.7, 32766.6] {
            assert_eq!(i32::from(to_i16(x)), x.round_ties_even() as i32, "{x}");
        }
        assert_eq!(wrap_pi(-10.0), -10.0 + 2.0 * std::f32::consts::TAU);
    }
}
