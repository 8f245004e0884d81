//! The kinematic vehicle of the paper's §4 simulation (METHOD §5, model 1).
//!
//! Inputs `u = [Δvx, Δvy, Δvz, Δα, Δβ, Δγ]` are the velocity change (m/s) and attitude change
//! (rad) made in one update period. Each axis is limited by its adjusting rate (acceleration in
//! m/s², attitude rate in rad/s) and by the vehicle's state limits. The velocity changes
//! uniformly over the period, so position advances by the mean of the old and new velocity
//! and `X(t+1) = F·X(t) + B·u` with `B = [Δt/2·I 0; I 0; 0 I]` exactly: no linearisation
//! residue.

use nalgebra::Vector3;

use crate::angle::{deg, kmh};
use crate::control::ControlMatrix;
use crate::error::{positive, ConfigError};
use crate::state::{Input, State9, ALPHA, VX, X};

/// Limits of the kinematic vehicle. Defaults are the paper's §4 values (METHOD §9).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KinematicLimits {
    /// Minimum forward speed vx (m/s, ≥ 0; 0 for a vehicle that can hover). Default 180 km/h.
    pub vx_min_mps: f64,
    /// Maximum forward speed vx (m/s). Default 360 km/h.
    pub vx_max_mps: f64,
    /// Maximum |vy| (m/s). Default 72 km/h.
    pub vy_max_mps: f64,
    /// Maximum |vz| (m/s). Default 54 km/h.
    pub vz_max_mps: f64,
    /// Maximum |α|, |β|, |γ| (rad). Default 45°, 15°, 30°.
    pub attitude_max_rad: Vector3<f64>,
    /// Adjusting rates of vx, vy, vz (m/s²). Default 18 km/h per second on each axis
    /// (the paper gives 18 km/h for y and z; x uses the same, a Choice).
    pub accel_max_mps2: Vector3<f64>,
    /// Adjusting rates of α, β, γ (rad/s). Default 3, 2, 2 °/s.
    pub attitude_rate_max_radps: Vector3<f64>,
}

impl Default for KinematicLimits {
    fn default() -> Self {
        Self {
            vx_min_mps: kmh(180.0),
            vx_max_mps: kmh(360.0),
            vy_max_mps: kmh(72.0),
            vz_max_mps: kmh(54.0),
            attitude_max_rad: Vector3::new(deg(45.0), deg(15.0), deg(30.0)),
            accel_max_mps2: Vector3::from_element(kmh(18.0)),
            attitude_rate_max_radps: Vector3::new(deg(3.0), deg(2.0), deg(2.0)),
        }
    }
}

impl KinematicLimits {
    /// Checks every limit is finite and positive (vx_min may be 0: a vehicle that hovers) and
    /// vx_min < vx_max.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if !(self.vx_min_mps.is_finite() && self.vx_min_mps >= 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "vx_min",
                value: self.vx_min_mps,
                expected: "a finite speed ≥ 0 m/s",
            });
        }
        positive("vx_max", self.vx_max_mps)?;
        if self.vx_min_mps >= self.vx_max_mps {
            return Err(ConfigError::OutOfRange {
                field: "vx_min",
                value: self.vx_min_mps,
                expected: "vx_min < vx_max",
            });
        }
        positive("vy_max", self.vy_max_mps)?;
        positive("vz_max", self.vz_max_mps)?;
        for k in 0..3 {
            positive("attitude_max", self.attitude_max_rad[k])?;
            positive("accel_max", self.accel_max_mps2[k])?;
            positive("attitude_rate_max", self.attitude_rate_max_radps[k])?;
        }
        Ok(())
    }

    /// Lower and upper bound of the six state components the inputs act on.
    fn state_box(&self) -> ([f64; 6], [f64; 6]) {
        let a = self.attitude_max_rad;
        (
            [self.vx_min_mps, -self.vy_max_mps, -self.vz_max_mps, -a.x, -a.y, -a.z],
            [self.vx_max_mps, self.vy_max_mps, self.vz_max_mps, a.x, a.y, a.z],
        )
    }
}

/// The kinematic vehicle model.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct KinematicModel {
    /// Its limits.
    pub limits: KinematicLimits,
}

impl KinematicModel {
    /// Number of inputs.
    pub const N_INPUTS: usize = 6;

    /// `F·X`: position advances by velocity, velocity and attitude carry over.
    #[inline]
    pub fn hold(x: &State9, dt: f64) -> State9 {
        let mut s = *x;
        for k in X..VX {
            s[k] += dt * x[k + 3];
        }
        s
    }

    /// B = [Δt/2·I 0; I 0; 0 I].
    #[inline]
    pub fn control_matrix(_x: &State9, dt: f64) -> ControlMatrix {
        let mut b = ControlMatrix::zeros();
        for j in 0..3 {
            b[(X + j, j)] = 0.5 * dt;
            b[(VX + j, j)] = 1.0;
            b[(ALPHA + j, 3 + j)] = 1.0;
        }
        b
    }

    /// Per-step rate limit of each input.
    #[inline]
    pub fn input_scale(&self, dt: f64) -> Input {
        let l = &self.limits;
        Input::from_column_slice(&[
            l.accel_max_mps2.x * dt,
            l.accel_max_mps2.y * dt,
            l.accel_max_mps2.z * dt,
            l.attitude_rate_max_radps.x * dt,
            l.attitude_rate_max_radps.y * dt,
            l.attitude_rate_max_radps.z * dt,
        ])
    }

    /// Input bounds: the rate limit, narrowed so the state stays in its box. A state already
    /// outside its box may move back toward it at the full rate, never further out.
    #[inline]
    pub fn input_bounds(&self, x: &State9, dt: f64) -> (Input, Input) {
        let rate = self.input_scale(dt);
        let (smin, smax) = self.limits.state_box();
        let mut lo = Input::zeros();
        let mut hi = Input::zeros();
        for j in 0..6 {
            let v = x[VX + j];
            lo[j] = (smin[j] - v).min(0.0).max(-rate[j]);
            hi[j] = (smax[j] - v).max(0.0).min(rate[j]);
        }
        (lo, hi)
    }

    /// Bounds on the sum of the inputs from now on, keeping the six input-driven state
    /// components in their box (never tighter than staying where they are).
    #[inline]
    pub fn cumulative_bounds(&self, x: &State9) -> (Input, Input) {
        let (smin, smax) = self.limits.state_box();
        let lo = Input::from_fn(|j, _| (smin[j] - x[VX + j]).min(0.0));
        let hi = Input::from_fn(|j, _| (smax[j] - x[VX + j]).max(0.0));
        (lo, hi)
    }

    /// The plant step under input `u`.
    #[inline]
    pub fn propagate(x: &State9, u: &Input, dt: f64) -> State9 {
        let mut s = *x;
        for j in 0..3 {
            s[X + j] += dt * (x[VX + j] + 0.5 * u[j]);
            s[VX + j] += u[j];
            s[ALPHA + j] += u[3 + j];
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn cruise() -> State9 {
        State9::from_column_slice(&[0.0, 0.0, 0.0, kmh(250.0), 0.0, 0.0, deg(5.0), deg(3.0), 0.0])
    }

    #[test]
    fn propagate_matches_f_plus_b_u() {
        let m = KinematicModel::default();
        let x = cruise();
        let u = Input::from_column_slice(&[0.3, -0.2, 0.1, 0.001, -0.002, 0.003]);
        let b = KinematicModel::control_matrix(&x, 0.1);
        let lin = KinematicModel::hold(&x, 0.1) + b * u;
        assert_relative_eq!(KinematicModel::propagate(&x, &u, 0.1), lin, epsilon = 1e-12);
        assert_eq!(m.limits, KinematicLimits::default());
    }

    #[test]
    fn bounds_are_the_rate_limits_inside_the_box() {
        let m = KinematicModel::default();
        let (lo, hi) = m.input_bounds(&cruise(), 0.1);
        assert_relative_eq!(hi[1], 0.5, epsilon = 1e-12); // 5 m/s² · 0.1 s
        assert_relative_eq!(lo[1], -0.5, epsilon = 1e-12);
        assert_relative_eq!(hi[3], deg(0.3), epsilon = 1e-12); // 3 °/s · 0.1 s
        assert_relative_eq!(hi[4], deg(0.2), epsilon = 1e-12);
    }

    #[test]
    fn bounds_stop_at_the_state_limits() {
        let m = KinematicModel::default();
        let mut x = cruise();
        x[VX] = kmh(360.0) - 0.1; // 0.1 m/s below vx_max
        x[ALPHA + 2] = deg(30.0); // at γ_max
        let (lo, hi) = m.input_bounds(&x, 0.1);
        assert_relative_eq!(hi[0], 0.1, epsilon = 1e-9);
        assert_relative_eq!(lo[0], -0.5, epsilon = 1e-9);
        assert_relative_eq!(hi[5], 0.0, epsilon = 1e-12);
        // Beyond the box: only back toward it.
        x[ALPHA + 1] = deg(16.0);
        let (lo, hi) = m.input_bounds(&x, 0.1);
        assert_relative_eq!(hi[4], 0.0);
        assert_relative_eq!(lo[4], -deg(0.2), epsilon = 1e-12);
    }
}
