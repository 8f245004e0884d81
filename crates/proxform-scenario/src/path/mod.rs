//! Scripted navigator paths.
//!
//! [`PaperPath`] is METHOD §9's profile of the paper's experiment: forward speed with two
//! smooth rises, lateral displacement with cosine ramps, a sinusoidal height, and attitude
//! profiles kept inside the vehicle's stated limits. Positions are the exact integrals of the
//! velocities, so the navigator's state is consistent at every instant.

use std::f64::consts::{PI, TAU};

use proxform_core::angle::{deg, kmh};
use proxform_core::state::{self, State9};

pub mod segments;
pub mod waypoints;

/// A cosine ramp from `from` to `to` over `[t0, t1]` (s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ramp {
    /// Start time (s).
    pub t0: f64,
    /// End time (s).
    pub t1: f64,
    /// Value change over the ramp.
    pub delta: f64,
}

impl Ramp {
    #[inline]
    fn phase(&self, t: f64) -> f64 {
        ((t - self.t0) / (self.t1 - self.t0)).clamp(0.0, 1.0)
    }

    /// Contribution to the value at t: `delta·(1 − cos πs)/2`.
    #[inline]
    fn value(&self, t: f64) -> f64 {
        self.delta * 0.5 * (1.0 - (PI * self.phase(t)).cos())
    }

    /// Its time derivative.
    #[inline]
    fn rate(&self, t: f64) -> f64 {
        if t <= self.t0 || t >= self.t1 {
            return 0.0;
        }
        let tt = self.t1 - self.t0;
        self.delta * 0.5 * PI / tt * (PI * self.phase(t)).sin()
    }

    /// Its integral from 0 to t.
    #[inline]
    fn integral(&self, t: f64) -> f64 {
        if t <= self.t0 {
            return 0.0;
        }
        let tt = self.t1 - self.t0;
        let tau = (t - self.t0).min(tt);
        let inside = 0.5 * self.delta * (tau - tt / PI * (PI * tau / tt).sin());
        inside + if t > self.t1 { self.delta * (t - self.t1) } else { 0.0 }
    }
}

/// METHOD §9's navigator profile. All fields SI / radians.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PaperPath {
    /// Initial forward speed (m/s). 250 km/h.
    pub vx0_mps: f64,
    /// Forward speed changes: 250 → 288 km/h over 30-40 s, → 324 km/h over 70-80 s.
    pub speed_ramps: Vec<Ramp>,
    /// Lateral displacement: 0 → 200 m (10-30 s) → −200 m (40-75 s) → 0 (80-100 s).
    pub lateral_ramps: Vec<Ramp>,
    /// Height oscillation amplitude (m) and period (s): 20 m, 50 s.
    pub height_amplitude_m: f64,
    /// Height oscillation period (s).
    pub height_period_s: f64,
    /// α = α0 + Δα·(1 − cos 2πt/T)/2: α0 = 5°, Δα = 40°, T = 100 s.
    pub pitch_base_rad: f64,
    /// Δα (rad).
    pub pitch_swing_rad: f64,
    /// β = β_amp·sin(2πt/T + φ): 15°, φ = asin 0.2 (so β(0) = 3°).
    pub yaw_amplitude_rad: f64,
    /// φ (rad).
    pub yaw_phase_rad: f64,
    /// γ = γ_amp·sin(2πt/T): 30°.
    pub roll_amplitude_rad: f64,
    /// T of the attitude profiles (s): 100 s.
    pub attitude_period_s: f64,
    /// Time flown before the profile's t = 0 (s, ≥ 0): the profile continued backward (steady
    /// speed and side position, the height and attitude oscillations going on), so that a
    /// formation can gather before the experiment proper starts. Default 0.
    #[serde(default)]
    pub lead_in_s: f64,
}

impl Default for PaperPath {
    fn default() -> Self {
        Self {
            vx0_mps: kmh(250.0),
            speed_ramps: vec![
                Ramp { t0: 30.0, t1: 40.0, delta: kmh(38.0) },
                Ramp { t0: 70.0, t1: 80.0, delta: kmh(36.0) },
            ],
            lateral_ramps: vec![
                Ramp { t0: 10.0, t1: 30.0, delta: 200.0 },
                Ramp { t0: 40.0, t1: 75.0, delta: -400.0 },
                Ramp { t0: 80.0, t1: 100.0, delta: 200.0 },
            ],
            height_amplitude_m: 20.0,
            height_period_s: 50.0,
            pitch_base_rad: deg(5.0),
            pitch_swing_rad: deg(40.0),
            yaw_amplitude_rad: deg(15.0),
            yaw_phase_rad: 0.2f64.asin(),
            roll_amplitude_rad: deg(30.0),
            attitude_period_s: 100.0,
            lead_in_s: 0.0,
        }
    }
}

impl PaperPath {
    /// The navigator's state at time `t` (s), starting from position `start` (m).
    pub fn state_at(&self, t: f64, start: [f64; 3]) -> State9 {
        if self.lead_in_s > 0.0 {
            // The profile at t − lead-in, moved so that the flight still starts at `start`.
            let first = self.profile_at(-self.lead_in_s, [0.0; 3]);
            let from = [start[0] - first[state::X], start[1] - first[state::Y], start[2] - first[state::Z]];
            return self.profile_at(t - self.lead_in_s, from);
        }
        self.profile_at(t, start)
    }

    /// METHOD §9's profile at its own time `t` (s; before 0 it continues backward).
    fn profile_at(&self, t: f64, start: [f64; 3]) -> State9 {
        let mut s = State9::zeros();
        s[state::VX] = self.vx0_mps + self.speed_ramps.iter().map(|r| r.value(t)).sum::<f64>();
        s[state::X] = start[0] + self.vx0_mps * t + self.speed_ramps.iter().map(|r| r.integral(t)).sum::<f64>();
        s[state::Y] = start[1] + self.lateral_ramps.iter().map(|r| r.value(t)).sum::<f64>();
        s[state::VY] = self.lateral_ramps.iter().map(|r| r.rate(t)).sum();
        let wz = TAU / self.height_period_s;
        s[state::Z] = start[2] + self.height_amplitude_m * (wz * t).sin();
        s[state::VZ] = self.height_amplitude_m * wz * (wz * t).cos();
        let wa = TAU / self.attitude_period_s;
        s[state::ALPHA] = self.pitch_base_rad + self.pitch_swing_rad * 0.5 * (1.0 - (wa * t).cos());
        s[state::BETA] = self.yaw_amplitude_rad * (wa * t + self.yaw_phase_rad).sin();
        s[state::GAMMA] = self.roll_amplitude_rad * (wa * t).sin();
        s
    }
}

/// One piece of a [`SegmentsPath`]: constant turn and climb rates, a smooth speed change.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Segment {
    /// Duration (s).
    pub duration_s: f64,
    /// Turn rate (rad/s, counter-clockwise positive).
    pub turn_rate_radps: f64,
    /// Climb rate (m/s).
    pub climb_mps: f64,
    /// Horizontal speed at the end of the segment (m/s), reached by a cosine ramp.
    pub end_speed_mps: f64,
    /// Width of the rate blend centred on this segment's start (s); `None`: the path's
    /// transition, limited by this segment and the one before. Never wider than either.
    pub start_blend_s: Option<f64>,
}

pub use segments::SegmentsPath;

/// How the navigator flies.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum NavigatorPath {
    /// METHOD §9's scripted profile.
    Paper(PaperPath),
    /// Turns, climbs and speed changes.
    Segments(SegmentsPath),
}

impl NavigatorPath {
    /// The navigator's state at `t` from start position `start`.
    #[inline]
    pub fn state_at(&self, t: f64, start: [f64; 3]) -> State9 {
        match self {
            NavigatorPath::Paper(p) => p.state_at(t, start),
            NavigatorPath::Segments(p) => p.state_at(t, start),
        }
    }
}

/// The navigator's path from its start position (m), as every UAV knows it before the flight
/// ([`proxform_core::plan::Plan`]).
#[derive(Debug, Clone)]
pub struct MissionPlan(pub NavigatorPath, pub [f64; 3]);

impl proxform_core::plan::Plan for MissionPlan {
    fn state_at(&self, t_s: f64) -> State9 {
        self.0.state_at(t_s, self.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn matches_method_section_9() {
        let p = PaperPath::default();
        let s0 = p.state_at(0.0, [0.0; 3]);
        assert_relative_eq!(s0[state::VX], kmh(250.0));
        assert_relative_eq!(s0[state::ALPHA], deg(5.0), epsilon = 1e-12);
        assert_relative_eq!(s0[state::BETA], deg(3.0), epsilon = 1e-9);
        assert_relative_eq!(s0[state::GAMMA], 0.0);
        let s35 = p.state_at(35.0, [0.0; 3]);
        assert_relative_eq!(s35[state::VX], kmh(269.0), epsilon = 1e-9);
        assert_relative_eq!(p.state_at(30.0, [0.0; 3])[state::Y], 200.0, epsilon = 1e-9);
        assert_relative_eq!(p.state_at(77.0, [0.0; 3])[state::Y], -200.0, epsilon = 1e-9);
        let s100 = p.state_at(100.0, [0.0; 3]);
        assert_relative_eq!(s100[state::Y], 0.0, epsilon = 1e-9);
        assert_relative_eq!(s100[state::VX], kmh(324.0), epsilon = 1e-9);
        assert_relative_eq!(p.state_at(50.0, [0.0; 3])[state::ALPHA], deg(45.0), epsilon = 1e-12);
    }

    #[test]
    fn positions_integrate_velocities() {
        let p = PaperPath::default();
        let h = 1e-4;
        for &t in &[5.0, 20.0, 35.0, 57.5, 75.5, 92.0] {
            let a = p.state_at(t - h, [0.0; 3]);
            let b = p.state_at(t + h, [0.0; 3]);
            let s = p.state_at(t, [0.0; 3]);
            for k in 0..3 {
                assert_relative_eq!((b[k] - a[k]) / (2.0 * h), s[k + 3], epsilon = 1e-5);
            }
        }
    }

    #[test]
    fn stays_inside_the_kinematic_limits() {
        let p = PaperPath::default();
        let lim = proxform_core::KinematicLimits::default();
        for k in 0..=1000 {
            let s = p.state_at(k as f64 * 0.1, [0.0; 3]);
            assert!(s[state::VY].abs() <= lim.vy_max_mps);
            assert!(s[state::VZ].abs() <= lim.vz_max_mps);
            assert!(s[state::VX] >= lim.vx_min_mps && s[state::VX] <= lim.vx_max_mps);
            for j in 0..3 {
                assert!(s[state::ALPHA + j].abs() <= lim.attitude_max_rad[j] + 1e-12);
            }
        }
    }
}
