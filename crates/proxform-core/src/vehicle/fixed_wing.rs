//! A fixed-wing vehicle (METHOD §5, model 2; the paper's eq. 8 inputs).
//!
//! Inputs `u = [δa, δr, δe, δp]` are normalised aileron, rudder, elevator and throttle
//! commands in [−1, 1]. Over one period: roll changes at `roll_rate_max·δa`; pitch at
//! `pitch_rate_max·δe`; yaw at `yaw_rate_max·δr` plus the coordinated-turn rate `g·tan γ / V`;
//! airspeed at `accel_max·δp − g·sin α` (δp = 0 is the level-flight trim). The velocity is the
//! airspeed along the attitude, `V·[cos α cos β, cos α sin β, sin α]` (α here is the pitch of
//! the flight path), and position advances by the mean of the old and new velocity. Wind is
//! added by the simulator; the model, like the controller, works with the air-relative state.
//!
//! Limits: stall and maximum speed, bank limited both by `bank_max` and by the structural load
//! factor (`cos γ ≥ 1/n_max`), and pitch. The controller's B is the Jacobian of one period at
//! the current state, by central differences.

use crate::angle::{deg, kmh, wrap_pi};
use crate::control::ControlMatrix;
use crate::error::{positive, ConfigError};
use crate::state::{Input, State9, ALPHA, BETA, GAMMA, VX, VY, VZ, X};

use super::G;

/// Parameters of the fixed-wing model. Defaults: a small fixed-wing UAV.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FixedWingModel {
    /// Stall speed (m/s). Default 90 km/h.
    pub stall_speed_mps: f64,
    /// Maximum airspeed (m/s). Default 300 km/h.
    pub max_speed_mps: f64,
    /// Bank limit (rad). Default 45°.
    pub bank_max_rad: f64,
    /// Structural load-factor limit n_max (≥ 1). Default 2.5.
    pub load_factor_max: f64,
    /// Pitch (flight-path angle) limit (rad). Default 20°.
    pub pitch_max_rad: f64,
    /// Roll rate at full aileron (rad/s). Default 45 °/s.
    pub roll_rate_max_radps: f64,
    /// Pitch rate at full elevator (rad/s). Default 15 °/s.
    pub pitch_rate_max_radps: f64,
    /// Yaw rate at full rudder, beyond the coordinated-turn rate (rad/s). Default 10 °/s.
    pub yaw_rate_max_radps: f64,
    /// Airspeed change at full throttle (m/s²). Default 3 m/s².
    pub accel_max_mps2: f64,
}

impl Default for FixedWingModel {
    fn default() -> Self {
        Self {
            stall_speed_mps: kmh(90.0),
            max_speed_mps: kmh(300.0),
            bank_max_rad: deg(45.0),
            load_factor_max: 2.5,
            pitch_max_rad: deg(20.0),
            roll_rate_max_radps: deg(45.0),
            pitch_rate_max_radps: deg(15.0),
            yaw_rate_max_radps: deg(10.0),
            accel_max_mps2: 3.0,
        }
    }
}

impl FixedWingModel {
    /// Number of inputs.
    pub const N_INPUTS: usize = 4;

    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), ConfigError> {
        positive("stall_speed", self.stall_speed_mps)?;
        positive("max_speed", self.max_speed_mps)?;
        if self.stall_speed_mps >= self.max_speed_mps {
            return Err(ConfigError::OutOfRange {
                field: "stall_speed",
                value: self.stall_speed_mps,
                expected: "below the maximum speed",
            });
        }
        positive("bank_max", self.bank_max_rad)?;
        positive("pitch_max", self.pitch_max_rad)?;
        if !(self.load_factor_max.is_finite() && self.load_factor_max >= 1.0) {
            return Err(ConfigError::OutOfRange {
                field: "load_factor_max",
                value: self.load_factor_max,
                expected: "n_max ≥ 1",
            });
        }
        positive("roll_rate_max", self.roll_rate_max_radps)?;
        positive("pitch_rate_max", self.pitch_rate_max_radps)?;
        positive("yaw_rate_max", self.yaw_rate_max_radps)?;
        positive("accel_max", self.accel_max_mps2)
    }

    /// The bank limit: the smaller of `bank_max` and the load-factor limit.
    pub fn bank_limit(&self) -> f64 {
        self.bank_max_rad.min((1.0 / self.load_factor_max).acos().max(0.0))
    }

    fn airspeed(x: &State9) -> f64 {
        (x[VX] * x[VX] + x[VY] * x[VY] + x[VZ] * x[VZ]).sqrt()
    }

    /// One period under input `u` (air-relative).
    pub fn propagate(&self, x: &State9, u: &Input, dt: f64) -> State9 {
        let v = Self::airspeed(x).max(1e-3);
        let (alpha, beta, gamma) = (x[ALPHA], x[BETA], x[GAMMA]);
        let mut s = *x;
        let gamma_new = gamma + dt * self.roll_rate_max_radps * u[0];
        // Coordinated turn: bank right (γ > 0) turns clockwise (β decreasing).
        let turn = -G * gamma.tan() / v;
        let beta_new = wrap_pi(beta + dt * (self.yaw_rate_max_radps * u[1] + turn));
        let alpha_new = alpha + dt * self.pitch_rate_max_radps * u[2];
        let v_new = (v + dt * (self.accel_max_mps2 * u[3] - G * alpha.sin())).max(1e-3);
        s[GAMMA] = gamma_new;
        s[BETA] = beta_new;
        s[ALPHA] = alpha_new;
        let (sa, ca) = alpha_new.sin_cos();
        let (sb, cb) = beta_new.sin_cos();
        s[VX] = v_new * ca * cb;
        s[VY] = v_new * ca * sb;
        s[VZ] = v_new * sa;
        for k in 0..3 {
            s[X + k] = x[X + k] + 0.5 * dt * (x[VX + k] + s[VX + k]);
        }
        s
    }

    /// The controller's view of one period from a state over the ground: the UAV flies through
    /// the air at its nose's airspeed (its velocity's component along its nose), and is carried
    /// by the rest of its velocity, the wind across its nose that its state implies (zero in
    /// calm air, up to the noise). So a UAV crabbing in a crosswind is predicted to keep its
    /// track, not to drift where its nose points.
    pub fn predict(&self, x: &State9, u: &Input, dt: f64) -> State9 {
        let (sa, ca) = x[ALPHA].sin_cos();
        let (sb, cb) = x[BETA].sin_cos();
        let nose = [ca * cb, ca * sb, sa];
        let along = x[VX] * nose[0] + x[VY] * nose[1] + x[VZ] * nose[2];
        let w = [x[VX] - along * nose[0], x[VY] - along * nose[1], x[VZ] - along * nose[2]];
        let mut air = *x;
        for k in 0..3 {
            air[VX + k] -= w[k];
        }
        let mut s = self.propagate(&air, u, dt);
        for k in 0..3 {
            s[VX + k] += w[k];
            s[X + k] += dt * w[k];
        }
        s
    }

    /// `F·X`: the period with no new input (the turn from the bank and the climb's
    /// deceleration go on), carried by the wind across the nose that the state implies.
    pub fn hold(&self, x: &State9, dt: f64) -> State9 {
        self.predict(x, &Input::zeros(), dt)
    }

    /// B: the Jacobian of one period with respect to the inputs at `x` (the controller's view,
    /// as [`Self::hold`]).
    pub fn control_matrix(&self, x: &State9, dt: f64) -> ControlMatrix {
        let mut b = ControlMatrix::zeros();
        let h = 1e-4;
        for j in 0..Self::N_INPUTS {
            let mut up = Input::zeros();
            up[j] = h;
            let plus = self.predict(x, &up, dt);
            let minus = self.predict(x, &(-up), dt);
            let mut d = plus - minus;
            d[BETA] = wrap_pi(d[BETA]);
            for k in 0..9 {
                b[(k, j)] = d[k] / (2.0 * h);
            }
        }
        b
    }

    /// Per-step input bounds: deflections in [−1, 1], narrowed so that bank, pitch and airspeed
    /// stay within their limits (a state already beyond one may only move back).
    pub fn input_bounds(&self, x: &State9, dt: f64) -> (Input, Input) {
        let mut lo = Input::zeros();
        let mut hi = Input::zeros();
        for j in 0..Self::N_INPUTS {
            lo[j] = -1.0;
            hi[j] = 1.0;
        }
        let clamp = |lo: &mut f64, hi: &mut f64, value: f64, min: f64, max: f64, per_unit: f64, drift: f64| {
            // value + drift + per_unit·u within [min, max]
            let l = (min - value - drift) / per_unit;
            let h = (max - value - drift) / per_unit;
            *lo = lo.max(l.min(0.0));
            *hi = hi.min(h.max(0.0));
        };
        let bank = self.bank_limit();
        clamp(&mut lo[0], &mut hi[0], x[GAMMA], -bank, bank, dt * self.roll_rate_max_radps, 0.0);
        clamp(
            &mut lo[2],
            &mut hi[2],
            x[ALPHA],
            -self.pitch_max_rad,
            self.pitch_max_rad,
            dt * self.pitch_rate_max_radps,
            0.0,
        );
        let v = Self::airspeed(x);
        clamp(
            &mut lo[3],
            &mut hi[3],
            v,
            self.stall_speed_mps,
            self.max_speed_mps,
            dt * self.accel_max_mps2,
            -dt * G * x[ALPHA].sin(),
        );
        (lo, hi)
    }

    /// Per-step magnitude of each input (the deflections are normalised).
    pub fn input_scale(&self) -> Input {
        let mut s = Input::zeros();
        for j in 0..Self::N_INPUTS {
            s[j] = 1.0;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn level(v: f64) -> State9 {
        State9::from_column_slice(&[0.0, 0.0, 100.0, v, 0.0, 0.0, 0.0, 0.0, 0.0])
    }

    #[test]
    fn a_banked_glide_turns_at_the_coordinated_rate() {
        let m = FixedWingModel::default();
        let mut x = level(50.0);
        x[GAMMA] = deg(30.0);
        let mut s = x;
        for _ in 0..100 {
            s = m.hold(&s, 0.01);
        }
        // 1 s at g·tan 30°/50 m/s = 0.1133 rad/s, clockwise.
        assert_relative_eq!(s[BETA], -G * deg(30.0).tan() / 50.0, epsilon = 1e-3);
        assert_relative_eq!((s[VX] * s[VX] + s[VY] * s[VY]).sqrt(), 50.0, epsilon = 1e-9);
    }

    #[test]
    fn b_matches_the_response_to_a_small_input() {
        let m = FixedWingModel::default();
        let mut x = level(60.0);
        x[GAMMA] = deg(10.0);
        x[ALPHA] = deg(3.0);
        // In calm air, its velocity along its nose.
        x[VX] = 60.0 * deg(3.0).cos();
        x[VZ] = 60.0 * deg(3.0).sin();
        let b = m.control_matrix(&x, 0.1);
        let mut u = Input::zeros();
        u[0] = 0.01;
        u[1] = -0.02;
        u[2] = 0.015;
        u[3] = 0.03;
        let lin = m.hold(&x, 0.1) + b * u;
        let exact = m.propagate(&x, &u, 0.1);
        for k in 0..9 {
            assert_relative_eq!(lin[k], exact[k], epsilon = 1e-5);
        }
        // The rudder turns the velocity: it has a velocity column, not only an attitude one.
        assert!(b[(VY, 1)].abs() > 0.1);
    }

    #[test]
    fn crabbing_in_a_crosswind_it_is_predicted_to_keep_its_track() {
        let m = FixedWingModel::default();
        // 25 m/s along x over the ground, nose 18.4° right into an 8.33 m/s wind from the right.
        let mut x = level(25.0);
        x[BETA] = -(8.33f64 / 25.0).atan();
        let held = m.hold(&x, 0.1);
        assert_relative_eq!(held[VX], 25.0, epsilon = 1e-9);
        assert_relative_eq!(held[VY], 0.0, epsilon = 1e-9);
        assert_relative_eq!(held[X + 1], 0.0, epsilon = 1e-9);
        // The plant, given the air-relative state, agrees once carried by that wind.
        let mut air = x;
        air[VY] -= 8.33;
        let mut flown = m.propagate(&air, &Input::zeros(), 0.1);
        flown[VY] += 8.33;
        assert_relative_eq!(flown[VY], held[VY], epsilon = 1e-2);
    }

    #[test]
    fn bounds_respect_stall_bank_and_load_factor() {
        let m = FixedWingModel { load_factor_max: 1.2, ..FixedWingModel::default() };
        assert!(m.bank_limit() < deg(34.0) && m.bank_limit() > deg(33.0));
        let mut x = level(m.stall_speed_mps + 0.05);
        x[GAMMA] = m.bank_limit();
        let (lo, hi) = m.input_bounds(&x, 0.1);
        assert_eq!(hi[0], 0.0, "no more bank");
        assert!(lo[3] > -0.2, "cannot slow below stall: {}", lo[3]);
        assert_eq!(hi[1], 1.0);
    }
}
