//! A multirotor flown through velocity and yaw setpoints (METHOD §5, model 3), as a companion
//! computer flies one through PX4's offboard or ArduPilot's guided mode.
//!
//! Inputs `u = [Δvx, Δvy, Δvz, Δψ]`: over one update period the autopilot is given the
//! velocity setpoint `v_sp = v(t) + u_v` (world frame, over the ground, m/s) and the yaw
//! setpoint `ψ_sp = ψ(t) + u_ψ` (rad), `v(t)` and `ψ(t)` those of the state the model is
//! given. The agent chooses `u` at the state it believes it has and flies the absolute
//! setpoint that makes ([`super::Setpoint`], `Decision::setpoint`); the plant takes it as the
//! input at the true state ([`super::VehicleModel::input_flying`]). The autopilot's inner loop
//! tracks the setpoints through the air, integrated in sub-steps of at most [`SUBSTEP_S`]:
//!
//! - desired acceleration `a_d = (v_sp − v)/τ_v`, its horizontal part at most `a_max`, its
//!   vertical part at most `a_z,max`;
//! - drag per unit mass `D = −k₁·v_a − k₂·|v_a|·v_a` on the air-relative velocity `v_a = v − w`;
//!   the inner loop's velocity integrator is taken as settled, so it asks for the specific force
//!   `f_d = a_d + g·ẑ − D`, with the horizontal part cut to the tilt limit and to what the
//!   thrust-to-weight ratio leaves beside the vertical part;
//! - the thrust's direction (in the world frame) follows the direction of `f_d` with a
//!   first-order lag `τ_att`; pitch α and roll γ are that direction seen from the nose
//!   (nose-up pitch brakes, right roll pushes right); the thrust settles within a sub-step
//!   (motors respond in tens of milliseconds) to the vertical force asked for, at most `T/W·g`;
//! - yaw ψ (β) follows its setpoint with the first-order lag `τ_ψ`, at most at the yaw-rate
//!   limit;
//! - the acceleration is the thrust along the attitude, less gravity, plus the drag; velocity
//!   and position are integrated by the trapezoid rule.
//!
//! So a gust moves the vehicle through the attitude lag and its limits, a steady wind tilts it
//! (and leaves less tilt for manoeuvres), and it hovers, climbs and flies any heading with its
//! nose independent of its course.
//!
//! The controller's view (`F`, `B`): `F·X` keeps position moving at the present velocity
//! (velocity and attitude kept); `B` takes the velocity setpoint as reached within the period
//! and the yaw through its lag ([`MultirotorModel::control_matrix`]). Pitch and roll are the
//! inner loop's: B has no rows for them, and the controller does not steer them. The loop's
//! lag τ_v is led instead: the controller asks for the velocity its slot will have τ_v later
//! ([`super::VehicleModel::setpoint_lag_s`]).

use crate::angle::{deg, kmh, wrap_pi};
use crate::control::ControlMatrix;
use crate::error::{positive, ConfigError};
use crate::state::{Input, State9, ALPHA, BETA, GAMMA, VX, VZ, X, Z};

use super::G;

/// Longest sub-step of the plant's integration (s); never more than a quarter of the velocity
/// loop's time constant (the attitude and yaw lags are integrated exactly).
pub const SUBSTEP_S: f64 = 0.02;

/// Shortest velocity-loop time constant (s): a faster loop is no multirotor's, and the plant's
/// sub-steps (a quarter of it) stay at most 80 a period of 1 s.
pub const MIN_VELOCITY_TIME_CONSTANT_S: f64 = 0.05;

/// The slowest lag of a multirotor's loops (velocity, attitude, yaw; s). Its loops answer within
/// a second or two; a lag of minutes is not a multirotor (its nose would never follow a turn of
/// its path, nor its velocity a change of its slot's).
pub const MAX_TIME_CONSTANT_S: f64 = 5.0;

/// Parameters of the multirotor and its autopilot's inner loop. Defaults: a 1-2 kg quadrotor
/// with PX4's default velocity-control limits.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MultirotorModel {
    /// Maximum horizontal speed over the ground (m/s). Default 54 km/h (15 m/s).
    pub max_speed_mps: f64,
    /// Maximum climb rate (m/s). Default 10.8 km/h (3 m/s).
    pub climb_max_mps: f64,
    /// Maximum descent rate (m/s). Default 7.2 km/h (2 m/s).
    pub descent_max_mps: f64,
    /// Maximum horizontal acceleration the inner loop asks for (m/s²). Default 5 m/s².
    pub accel_max_mps2: f64,
    /// Maximum vertical acceleration the inner loop asks for, up or down (m/s²). Default 3 m/s².
    pub vertical_accel_max_mps2: f64,
    /// Tilt limit (rad, below 90°). Default 35°.
    pub tilt_max_rad: f64,
    /// Thrust-to-weight ratio (> 1). Default 2.
    pub thrust_to_weight: f64,
    /// Yaw-rate limit (rad/s). Default 60 °/s.
    pub yaw_rate_max_radps: f64,
    /// Velocity-loop time constant τ_v (s): the desired acceleration is the velocity error over
    /// it. Default 0.5 s.
    pub velocity_time_constant_s: f64,
    /// Attitude lag τ_att (s): pitch and roll reach the commanded tilt as a first-order lag.
    /// Default 0.1 s.
    pub attitude_time_constant_s: f64,
    /// Yaw lag τ_ψ (s). Default 0.2 s.
    pub yaw_time_constant_s: f64,
    /// Linear drag per unit mass k₁ (1/s). Default 0.1 /s.
    pub drag_linear_per_s: f64,
    /// Quadratic drag per unit mass k₂ (1/m). Default 0.015 /m: with k₁, 4.9 m/s² at 15 m/s of
    /// airspeed (a 25° tilt), 1.4 m/s² in a 25 km/h wind.
    pub drag_quadratic_per_m: f64,
}

impl Default for MultirotorModel {
    fn default() -> Self {
        Self {
            max_speed_mps: kmh(54.0),
            climb_max_mps: kmh(10.8),
            descent_max_mps: kmh(7.2),
            accel_max_mps2: 5.0,
            vertical_accel_max_mps2: 3.0,
            tilt_max_rad: deg(35.0),
            thrust_to_weight: 2.0,
            yaw_rate_max_radps: deg(60.0),
            velocity_time_constant_s: 0.5,
            attitude_time_constant_s: 0.1,
            yaw_time_constant_s: 0.2,
            drag_linear_per_s: 0.1,
            drag_quadratic_per_m: 0.015,
        }
    }
}

/// The specific force the inner loop asks for, split into the vertical part and the
/// horizontal world-frame part (m/s²).
#[derive(Debug, Clone, Copy)]
struct Force {
    up: f64,
    east: f64,
    north: f64,
}

impl MultirotorModel {
    /// Number of inputs.
    pub const N_INPUTS: usize = 4;

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), ConfigError> {
        positive("max_speed", self.max_speed_mps)?;
        positive("climb_max", self.climb_max_mps)?;
        positive("descent_max", self.descent_max_mps)?;
        positive("accel_max", self.accel_max_mps2)?;
        positive("vertical_accel_max", self.vertical_accel_max_mps2)?;
        positive("tilt_max", self.tilt_max_rad)?;
        if self.tilt_max_rad >= deg(90.0) {
            return Err(ConfigError::OutOfRange {
                field: "tilt_max",
                value: self.tilt_max_rad,
                expected: "a tilt below 90°",
            });
        }
        if !(self.thrust_to_weight.is_finite() && self.thrust_to_weight > 1.0) {
            return Err(ConfigError::OutOfRange {
                field: "thrust_to_weight",
                value: self.thrust_to_weight,
                expected: "a ratio above 1 (the vehicle must lift itself)",
            });
        }
        if self.vertical_accel_max_mps2 >= G * (self.thrust_to_weight - 1.0) {
            return Err(ConfigError::OutOfRange {
                field: "vertical_accel_max",
                value: self.vertical_accel_max_mps2,
                expected: "below g·(T/W − 1), what the thrust can give",
            });
        }
        positive("yaw_rate_max", self.yaw_rate_max_radps)?;
        positive("velocity_time_constant", self.velocity_time_constant_s)?;
        if self.velocity_time_constant_s < MIN_VELOCITY_TIME_CONSTANT_S {
            return Err(ConfigError::OutOfRange {
                field: "velocity_time_constant",
                value: self.velocity_time_constant_s,
                expected: "at least 0.05 s",
            });
        }
        positive("attitude_time_constant", self.attitude_time_constant_s)?;
        positive("yaw_time_constant", self.yaw_time_constant_s)?;
        for (field, tau) in [
            ("velocity_time_constant", self.velocity_time_constant_s),
            ("attitude_time_constant", self.attitude_time_constant_s),
            ("yaw_time_constant", self.yaw_time_constant_s),
        ] {
            if tau > MAX_TIME_CONSTANT_S {
                return Err(ConfigError::OutOfRange { field, value: tau, expected: "at most 5 s" });
            }
        }
        for (field, v) in [("drag_linear", self.drag_linear_per_s), ("drag_quadratic", self.drag_quadratic_per_m)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(ConfigError::OutOfRange { field, value: v, expected: "a finite drag ≥ 0" });
            }
        }
        Ok(())
    }

    /// Horizontal speed of `x` (m/s).
    #[inline]
    pub fn horizontal_speed(x: &State9) -> f64 {
        x[VX].hypot(x[VX + 1])
    }

    /// The velocity nearest `v` within the speed, climb and descent limits.
    pub fn clamp_velocity(&self, v: [f64; 3]) -> [f64; 3] {
        let h = v[0].hypot(v[1]);
        let k = if h > self.max_speed_mps { self.max_speed_mps / h } else { 1.0 };
        [v[0] * k, v[1] * k, v[2].clamp(-self.descent_max_mps, self.climb_max_mps)]
    }

    /// The specific force the inner loop asks for at velocity `v` with setpoint `sp` and drag
    /// `d`, within the acceleration, tilt (its tangent `tan_tilt`) and thrust limits.
    #[inline]
    fn force_wanted(&self, v: [f64; 3], sp: [f64; 3], d: [f64; 3], tan_tilt: f64) -> Force {
        let tau = self.velocity_time_constant_s;
        let (mut ax, mut ay) = ((sp[0] - v[0]) / tau, (sp[1] - v[1]) / tau);
        let ah = (ax * ax + ay * ay).sqrt();
        if ah > self.accel_max_mps2 {
            let k = self.accel_max_mps2 / ah;
            ax *= k;
            ay *= k;
        }
        let az = ((sp[2] - v[2]) / tau).clamp(-self.vertical_accel_max_mps2, self.vertical_accel_max_mps2);
        let t_max = self.thrust_to_weight * G;
        let up = (az + G - d[2]).clamp(0.0, t_max);
        let (mut east, mut north) = (ax - d[0], ay - d[1]);
        // Vertical first (PX4's priority): the horizontal force within the tilt and what the
        // thrust leaves.
        let h_max = (up * tan_tilt).min((t_max * t_max - up * up).max(0.0).sqrt());
        let h = (east * east + north * north).sqrt();
        if h > h_max {
            let k = h_max / h;
            east *= k;
            north *= k;
        }
        Force { up, east, north }
    }

    /// The plant: one period under input `u` with the wind `w0` at its start and `w1` at its
    /// end (world frame, m/s; linear in between). The state's velocity is over the ground.
    pub fn propagate_in_wind(&self, x: &State9, u: &Input, dt: f64, w0: [f64; 3], w1: [f64; 3]) -> State9 {
        let sp = self.clamp_velocity([x[VX] + u[0], x[VX + 1] + u[1], x[VZ] + u[2]]);
        let yaw_sp = x[BETA] + u[3];
        let n = (dt / SUBSTEP_S.min(0.25 * self.velocity_time_constant_s)).ceil().max(1.0);
        let h = dt / n;
        let lag = 1.0 - (-h / self.attitude_time_constant_s).exp();
        let yaw_lag = 1.0 - (-h / self.yaw_time_constant_s).exp();
        let yaw_step_max = h * self.yaw_rate_max_radps;
        let t_max = self.thrust_to_weight * G;
        let tan_tilt = self.tilt_max_rad.tan();
        // The thrust's direction in the world frame, from the attitude (nose-up pitch tilts it
        // back, right roll to the right); it lags the direction asked for, and becomes the
        // attitude again at the end (a yaw turns the nose, not the thrust).
        let (sa, ca) = x[ALPHA].sin_cos();
        let (sg, cg) = x[GAMMA].sin_cos();
        let (sn, cs) = x[BETA].sin_cos();
        let (bf, bl) = (-cg * sa, -sg);
        let mut dir = [cs * bf - sn * bl, sn * bf + cs * bl, cg * ca];
        let mut psi = x[BETA];
        let mut s = *x;
        for k in 0..n as usize {
            let f = (k as f64 + 0.5) / n;
            let w = [w0[0] + f * (w1[0] - w0[0]), w0[1] + f * (w1[1] - w0[1]), w0[2] + f * (w1[2] - w0[2])];
            let v = [s[VX], s[VX + 1], s[VZ]];
            let va = [v[0] - w[0], v[1] - w[1], v[2] - w[2]];
            // Drag −k·v_a, k = k₁ + k₂·|v_a| (per unit mass).
            let k_drag = self.drag_linear_per_s
                + self.drag_quadratic_per_m * (va[0] * va[0] + va[1] * va[1] + va[2] * va[2]).sqrt();
            let d = [-k_drag * va[0], -k_drag * va[1], -k_drag * va[2]];
            let want = self.force_wanted(v, sp, d, tan_tilt);
            // Yaw toward its setpoint: its lag, at most the rate limit.
            psi = wrap_pi(psi + (yaw_lag * wrap_pi(yaw_sp - psi)).clamp(-yaw_step_max, yaw_step_max));
            // The thrust's direction toward the wanted force's (both within the tilt limit).
            let m = (want.east * want.east + want.north * want.north + want.up * want.up).sqrt();
            let aim = if m > 1e-9 { [want.east / m, want.north / m, want.up / m] } else { [0.0, 0.0, 1.0] };
            for c in 0..3 {
                dir[c] += lag * (aim[c] - dir[c]);
            }
            let norm = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
            for c in &mut dir {
                *c /= norm;
            }
            // Thrust for the vertical force asked for, along the direction reached.
            let thrust = (want.up / dir[2].max(0.1)).clamp(0.0, t_max);
            // The thrust, gravity, and the drag taken at the sub-step's end (semi-implicit: stable
            // however strong the drag).
            let a =
                [thrust * dir[0] + k_drag * w[0], thrust * dir[1] + k_drag * w[1], thrust * dir[2] - G + k_drag * w[2]];
            for j in 0..3 {
                let v_new = (s[VX + j] + h * a[j]) / (1.0 + h * k_drag);
                s[X + j] += 0.5 * h * (s[VX + j] + v_new);
                s[VX + j] = v_new;
            }
        }
        // Back to the attitude, in the frame of the nose reached.
        let (sn, cs) = psi.sin_cos();
        let fwd = cs * dir[0] + sn * dir[1];
        let left = -sn * dir[0] + cs * dir[1];
        s[ALPHA] = (-fwd).atan2(dir[2]);
        s[BETA] = psi;
        s[GAMMA] = (-left).atan2(fwd.hypot(dir[2]));
        debug_assert!(s[Z].is_finite());
        s
    }

    /// The plant in calm air.
    #[inline]
    pub fn propagate(&self, x: &State9, u: &Input, dt: f64) -> State9 {
        self.propagate_in_wind(x, u, dt, [0.0; 3], [0.0; 3])
    }

    /// Its top speed over the ground in calm air (m/s): horizontal and vertical together.
    pub fn top_speed(&self) -> f64 {
        self.max_speed_mps.hypot(self.climb_max_mps.max(self.descent_max_mps))
    }

    /// `F·X`: position advances at the present velocity; velocity and attitude are kept.
    #[inline]
    pub fn hold(x: &State9, dt: f64) -> State9 {
        let mut s = *x;
        for k in X..VX {
            s[k] += dt * x[k + 3];
        }
        s
    }

    /// B: the controller's view of the setpoints, constant: the velocity setpoint is taken as
    /// reached within the period (velocity rows I, position rows Δt/2·I, the kinematic
    /// vehicle's B), the yaw's lag as `1 − e^(−Δt/τ_ψ)`; pitch and roll rows are zero. The
    /// inner loop reaches a new velocity setpoint only over τ_v: the next period's feedback asks
    /// again for what was not reached (so the setpoint it gives is the velocity it wants), and
    /// the controller leads ramps by τ_v ([`super::VehicleModel::setpoint_lag_s`]). B of the
    /// loop's own one-period response (about 0.14 of a step at Δt = 0.1 s) would make the
    /// one-step input a dead-beat command that the tilt still building at the period's end
    /// overshoots: measured on `scenarios/multirotor-v12-circuit.toml`, pitch and roll swung by
    /// up to ±45° and every run failed.
    pub fn control_matrix(&self, dt: f64) -> ControlMatrix {
        let mut b = ControlMatrix::zeros();
        for j in 0..3 {
            b[(X + j, j)] = 0.5 * dt;
            b[(VX + j, j)] = 1.0;
        }
        b[(BETA, 3)] = 1.0 - (-dt / self.yaw_time_constant_s).exp();
        b
    }

    /// Per-step magnitude of each input: the setpoint change that saturates the inner loop's
    /// acceleration (`a_max·τ_v`, `a_z,max·τ_v`) and its yaw rate (`ψ̇_max·τ_ψ`).
    pub fn input_scale(&self) -> Input {
        let tv = self.velocity_time_constant_s;
        let mut s = Input::zeros();
        s[0] = self.accel_max_mps2 * tv;
        s[1] = self.accel_max_mps2 * tv;
        s[2] = self.vertical_accel_max_mps2 * tv;
        s[3] = self.yaw_rate_max_radps * self.yaw_time_constant_s;
        s
    }

    /// Input bounds: at most [`Self::input_scale`] (beyond, the inner loop saturates and B no
    /// longer holds), and setpoints within the speed, climb and descent limits (a state already
    /// beyond one may only move back toward it).
    pub fn input_bounds(&self, x: &State9) -> (Input, Input) {
        let scale = self.input_scale();
        let mut lo = -scale;
        let mut hi = scale;
        let (vx, vy, vz) = (x[VX], x[VX + 1], x[VZ]);
        let vm = self.max_speed_mps;
        let box_x = (vm * vm - vy * vy).max(0.0).sqrt();
        let box_y = (vm * vm - vx * vx).max(0.0).sqrt();
        for (j, v, min, max) in
            [(0, vx, -box_x, box_x), (1, vy, -box_y, box_y), (2, vz, -self.descent_max_mps, self.climb_max_mps)]
        {
            lo[j] = lo[j].max((min - v).min(0.0));
            hi[j] = hi[j].min((max - v).max(0.0));
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn u4(v: [f64; 4]) -> Input {
        let mut u = Input::zeros();
        for k in 0..4 {
            u[k] = v[k];
        }
        u
    }

    fn hover() -> State9 {
        State9::from_column_slice(&[0.0, 0.0, 50.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    }

    #[test]
    fn a_velocity_setpoint_is_its_input_both_ways() {
        let v = crate::vehicle::VehicleModel::Multirotor(MultirotorModel::default());
        assert!(v.takes_velocity_setpoints());
        let mut x = hover();
        (x[VX], x[BETA]) = (3.0, 3.0);
        let u = u4([1.0, -2.0, 0.5, 0.4]);
        let (sp, yaw) = v.velocity_setpoint(&x, &u, 0.1);
        assert_eq!(sp, [4.0, -2.0, 0.5]);
        assert_relative_eq!(yaw, wrap_pi(3.4), epsilon = 1e-12);
        let back = v.input_for_setpoint(&x, sp, Some(yaw)).expect("a multirotor takes setpoints");
        assert_relative_eq!((back - u).amax(), 0.0, epsilon = 1e-12);
        // Without a yaw it keeps its heading.
        assert_eq!(v.input_for_setpoint(&x, sp, None).expect("setpoint")[3], 0.0);
        let kinematic = crate::vehicle::VehicleModel::Kinematic(Default::default());
        assert!(!kinematic.takes_velocity_setpoints() && kinematic.input_for_setpoint(&x, sp, None).is_none());
    }

    fn fly(m: &MultirotorModel, mut x: State9, u: Input, seconds: f64, w: [f64; 3]) -> State9 {
        let dt = 0.1;
        // The setpoint stays: each period asks for the same absolute velocity and yaw.
        let (sp, yaw) = ([x[VX] + u[0], x[VX + 1] + u[1], x[VZ] + u[2]], x[BETA] + u[3]);
        for _ in 0..(seconds / dt).round() as usize {
            let du = u4([sp[0] - x[VX], sp[1] - x[VX + 1], sp[2] - x[VZ], wrap_pi(yaw - x[BETA])]);
            x = m.propagate_in_wind(&x, &du, dt, w, w);
        }
        x
    }

    #[test]
    fn it_hovers_and_flies_any_heading_with_its_nose_elsewhere() {
        let m = MultirotorModel::default();
        let x = fly(&m, hover(), Input::zeros(), 5.0, [0.0; 3]);
        assert_relative_eq!(x, hover(), epsilon = 1e-9);
        // 10 m/s toward −y (course 270°) with the nose turned to +x.
        let x = fly(&m, hover(), u4([0.0, -10.0, 0.0, 0.0]), 10.0, [0.0; 3]);
        assert_relative_eq!(x[VX + 1], -10.0, epsilon = 1e-3);
        assert_relative_eq!(x[BETA], 0.0, epsilon = 1e-9);
        // Flying sideways to the right at a steady speed rolls it right against the drag.
        assert!(x[GAMMA] > deg(5.0), "roll {}", x[GAMMA]);
        // Yaw 90° at the rate limit: 1.5 s at 60 °/s and the lag's tail.
        let x = fly(&m, hover(), u4([0.0, 0.0, 0.0, deg(90.0)]), 2.5, [0.0; 3]);
        assert_relative_eq!(x[BETA], deg(90.0), epsilon = deg(0.5));
    }

    #[test]
    fn a_steady_wind_tilts_it_and_it_holds_its_ground_velocity() {
        let m = MultirotorModel::default();
        let wind = [0.0, kmh(25.0), 0.0];
        let x = fly(&m, hover(), Input::zeros(), 10.0, wind);
        // Held over the ground, rolled into the wind (wind from the right pushes left, toward
        // +y: it rolls right, γ > 0) by the drag's angle atan(D/g).
        assert!(x[VX].abs() < 1e-6 && x[VX + 1].abs() < 1e-6, "{x}");
        let v = kmh(25.0);
        let d = (0.1 + 0.015 * v) * v;
        assert_relative_eq!(x[GAMMA], (d / G).atan(), epsilon = 1e-4);
        // A sudden gust moves it before the attitude lag catches up.
        let mut y = x;
        y = m.propagate_in_wind(&y, &Input::zeros(), 0.1, [0.0, 2.0 * v, 0.0], [0.0, 2.0 * v, 0.0]);
        assert!(y[VX + 1] > 0.05, "the gust pushes it downwind: {}", y[VX + 1]);
    }

    #[test]
    fn a_setpoint_held_is_reached_over_the_velocity_loop_and_b_takes_it_as_reached() {
        let m = MultirotorModel::default();
        let b = m.control_matrix(0.1);
        assert_eq!((b[(VX, 0)], b[(X, 0)], b[(ALPHA, 0)], b[(GAMMA, 1)]), (1.0, 0.05, 0.0, 0.0));
        assert_relative_eq!(b[(BETA, 3)], 1.0 - (-0.5f64).exp(), epsilon = 1e-12);
        // A setpoint 1 m/s ahead, given again each period: after τ_v + τ_att it has closed
        // about 1 − 1/e of the gap (the second-order loop lags a first-order one by ~τ_att).
        let x = fly(&m, hover(), u4([1.0, 0.0, 0.0, 0.0]), 0.6, [0.0; 3]);
        assert!(x[VX] > 0.55 && x[VX] < 0.75, "{}", x[VX]);
        let x = fly(&m, hover(), u4([1.0, 0.0, 0.0, 0.0]), 5.0, [0.0; 3]);
        assert_relative_eq!(x[VX], 1.0, epsilon = 1e-3);
    }

    #[test]
    fn limits_hold_speed_climb_and_tilt() {
        let m = MultirotorModel::default();
        let x = fly(&m, hover(), u4([40.0, 0.0, 20.0, 0.0]), 20.0, [0.0; 3]);
        assert!(MultirotorModel::horizontal_speed(&x) <= m.max_speed_mps + 1e-9);
        assert!(x[VZ] <= m.climb_max_mps + 1e-9);
        let tilt = (x[ALPHA].cos() * x[GAMMA].cos()).acos();
        assert!(tilt <= m.tilt_max_rad + 1e-9);
        let (lo, hi) = m.input_bounds(&x);
        assert!(hi[0] < 1e-9, "no faster: {hi}");
        assert!(lo[0] < 0.0);
        let bad = MultirotorModel { thrust_to_weight: 1.2, ..MultirotorModel::default() };
        assert!(bad.validate().is_err(), "3 m/s² up needs T/W > 1.31");
    }
}
