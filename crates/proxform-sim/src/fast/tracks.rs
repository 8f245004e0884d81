//! The neighbour tracks of every UAV in one array: `capacity` records per UAV, contiguous, each
//! a neighbour's filtered state in f32 (64 bytes), with the reference's α-β filter (METHOD §3,
//! `proxform_core::predictor`) run on them in f32.
//!
//! Positions are kept relative to the owner's reference point at the track's time, `R_i(k) =
//! O(k) + A_i` ([`super::update::View::shift`]): tens of metres, so f32 resolves them to
//! micrometres however far the swarm flies. Times are step numbers (`t = k·Δt`), kept modulo
//! 128 beside the id.
//!
//! (Measured: a record per track and a scalar update cost fewer instructions than the same
//! filter over lanes of all of a UAV's tracks, whose fixed width and copies outweigh the
//! vector arithmetic at a dozen tracks a UAV on 4-wide vectors.)

use proxform_core::state::{State9, VX};

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

/// One neighbour's filtered state: 64 bytes.
#[derive(Debug, Clone, Copy)]
pub struct Track {
    /// Id, step modulo 128 and second-measurement flag; [`FREE`] when unused.
    word: u32,
    /// Position relative to the owner's reference point at the track's step (m; 0-2),
    /// velocity and attitude (3-8), their rates (9-14).
    pub v: [f32; 15],
}

impl Default for Track {
    fn default() -> Self {
        Self { word: FREE, v: [0.0; 15] }
    }
}

impl Track {
    /// The neighbour, None when free.
    #[inline]
    pub fn id(&self) -> Option<u32> {
        (self.word != FREE).then_some(self.word & ID_MASK)
    }

    /// Whether the track is `id`'s.
    #[inline]
    fn is(&self, id: u32) -> bool {
        self.word != FREE && self.word & ID_MASK == id
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
    pub alpha: f64,
    pub beta: f64,
    /// Update period (s).
    pub dt: f64,
    /// A track not updated for this many steps restarts.
    pub timeout_steps: i64,
    /// A coasting track extrapolates its acceleration for at most this long (s).
    pub coast_accel_s: f64,
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
            if t.word != FREE && t.age(k) > limit {
                t.word = FREE;
            }
        }
    }

    /// The slot of `id`, or the one to (re)use for it: a new one while there is room, else the
    /// one measured longest ago (freed). `hint` is where to look first (neighbours are fed in
    /// the same order step after step, so the n-th fed is usually in slot n).
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

    /// Feeds neighbour `id`'s observation `z` (looked for first in slot `hint`; relative to the
    /// owner's reference point at step `k`) and returns its slot and its predicted state Δt
    /// after `k` (position, velocity, attitude). `shift(k0)` is how far the reference point of
    /// step `k0` lies from that of step `k` (m).
    pub fn predict(
        &mut self,
        f: &Filter,
        (id, hint): (u32, usize),
        k: i32,
        z: &State9,
        shift: impl Fn(i32) -> [f64; 3],
    ) -> (usize, [f32; 9]) {
        let s = self.slot_for(id, k, hint);
        let tr = &mut self.tracks[s];
        let steps = tr.age(k);
        let zf: [f32; 9] = std::array::from_fn(|c| z[c] as f32);
        if !tr.is(id) || steps > f.timeout_steps {
            // Start: the measurement, no rates.
            tr.word = Track::word(id, k, false);
            tr.v[..9].copy_from_slice(&zf);
            tr.v[9..].fill(0.0);
        } else if steps > 0 {
            let dt = (steps as f64 * f.dt) as f32;
            if tr.word & SEEN_TWICE == 0 {
                // Two-point start: value from the measurement, rate from the difference.
                for c in 0..6 {
                    let diff = proxform_core::state::difference_component(VX + c, z[VX + c], f64::from(tr.v[3 + c]));
                    tr.v[9 + c] = (diff / f64::from(dt)) as f32;
                }
                tr.v[..9].copy_from_slice(&zf);
            } else {
                // The α-β update.
                let d = shift(k - steps as i32);
                let (alpha, beta_dt) = (f.alpha as f32, (f.beta / f64::from(dt)) as f32);
                for c in 0..3 {
                    let pred = tr.v[c] + d[c] as f32 + dt * (tr.v[3 + c] + 0.5 * dt * tr.v[9 + c]);
                    tr.v[c] = pred + alpha * (zf[c] - pred);
                }
                for c in 0..6 {
                    let pred = tr.v[3 + c] + dt * tr.v[9 + c];
                    let raw = zf[3 + c] - pred;
                    let res = if c >= 3 { wrap_pi(raw) } else { raw };
                    tr.v[3 + c] = pred + alpha * res;
                    tr.v[9 + c] += beta_dt * res;
                }
            }
            tr.word = Track::word(id, k, true);
        }
        (s, extrapolate(tr, f.dt as f32, [0.0; 3], f32::INFINITY))
    }

    /// The neighbour of slot `s` if its track can coast at step `k`: measured before, no longer
    /// ago than `max_steps`.
    #[inline]
    pub fn coasting(&self, s: usize, k: i32, max_steps: i64) -> Option<u32> {
        let tr = &self.tracks[s];
        let age = tr.age(k);
        tr.id().filter(|_| age >= 1 && age <= max_steps)
    }

    /// Steps since slot `s` was measured, at step `k`.
    #[inline]
    pub fn age_steps(&self, s: usize, k: i32) -> i64 {
        self.tracks[s].age(k)
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
        extrapolate(&self.tracks[s], h as f32, d.map(|x| x as f32), f.coast_accel_s as f32)
    }
}

/// The track's state `h` seconds after its measurement, its position shifted by `d`: the
/// acceleration is extrapolated for at most `ha` seconds (then the velocity reached carries
/// on), attitude rates carry on.
#[inline]
fn extrapolate(tr: &Track, h: f32, d: [f32; 3], ha: f32) -> [f32; 9] {
    let v = &tr.v;
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
        let f = Filter { alpha, beta, dt: 0.1, timeout_steps: 10, coast_accel_s: 0.2 };
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
            let (_, got) = owner.predict(&f, (7, 0), k, &z, |_| [0.0; 3]);
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
        let (_, age) = reference.report(UavId(7), 20.0).expect("tracked");
        assert!(age < 0.2);
        let want = reference.state_at(0, 19.9 + 0.5);
        let got = owner.state_at(&f, 0, 0.5 + (19.9 - 0.1 * f64::from(owner.measured_at(0, 199))), [0.0; 3]);
        for c in 0..3 {
            assert!((f64::from(got[c]) - want[c]).abs() < 2e-3, "{got:?} vs {want:?}");
        }
    }

    #[test]
    fn a_full_set_of_tracks_gives_the_oldest_to_a_new_neighbour() {
        let f = Filter { alpha: 0.8, beta: 0.5, dt: 0.1, timeout_steps: 10, coast_accel_s: 0.2 };
        let mut records = vec![Track::default(); 2];
        let mut used = 0u8;
        let mut owner = Owner { tracks: &mut records, used: &mut used };
        let z = neighbour(0);
        owner.predict(&f, (1, 0), 0, &z, |_| [0.0; 3]);
        owner.predict(&f, (2, 1), 1, &z, |_| [0.0; 3]);
        let (s, _) = owner.predict(&f, (3, 0), 2, &z, |_| [0.0; 3]);
        assert_eq!(s, 0, "the track of UAV 1, measured longest ago, is reused");
        assert_eq!(owner.tracks[0].id(), Some(3));
        assert_eq!(owner.tracks[1].id(), Some(2));
        // A wrong hint still finds the track.
        let (s, _) = owner.predict(&f, (2, 0), 3, &z, |_| [0.0; 3]);
        assert_eq!(s, 1);
        assert_eq!(wrap_pi(3.5), 3.5 - std::f32::consts::TAU);
        assert_eq!(wrap_pi(-10.0), -10.0 + 2.0 * std::f32::consts::TAU);
    }
}
