//! Vehicle models (METHOD §5): how a UAV's state responds to its inputs.
//!
//! Every model gives the controller the same three things: the course-keeping prediction
//! `F·X`, the control matrix B at the current state, and the per-step input bounds that keep
//! the vehicle inside its limits. The simulator uses [`VehicleModel::propagate`] as the plant.

mod fixed_wing;
mod kinematic;
mod multirotor;

pub use fixed_wing::FixedWingModel;
pub use kinematic::{KinematicLimits, KinematicModel};
pub use multirotor::{MultirotorModel, MAX_TIME_CONSTANT_S, MIN_VELOCITY_TIME_CONSTANT_S};

use crate::control::ControlMatrix;
use crate::error::ConfigError;
use crate::state::{Input, State9};

/// Standard gravity (m/s²).
pub const G: f64 = 9.80665;

/// What an autopilot flown by velocity and yaw setpoints is told to fly (a MAVLink velocity
/// setpoint): absolute, so that it means the same whatever the autopilot's own estimate of its
/// state, and whatever the companion believed when it chose it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setpoint {
    /// Velocity over the ground (world frame, m/s).
    pub velocity_mps: [f64; 3],
    /// Yaw β (rad, within ±π).
    pub yaw_rad: f64,
}

/// The vehicle models proxform knows. An enum rather than a trait object: the controller's
/// inner loop stays monomorphic and the models stay plain data.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum VehicleModel {
    /// The paper's §4 simulation model (METHOD §5, model 1).
    Kinematic(KinematicModel),
    /// Aileron, rudder, elevator and throttle (METHOD §5, model 2).
    FixedWing(FixedWingModel),
    /// Velocity and yaw setpoints to an autopilot's inner loop (METHOD §5, model 3).
    Multirotor(MultirotorModel),
}

impl VehicleModel {
    /// Checks the model's parameters.
    pub fn validate(&self) -> Result<(), ConfigError> {
        match self {
            VehicleModel::Kinematic(m) => m.limits.validate(),
            VehicleModel::FixedWing(m) => m.validate(),
            VehicleModel::Multirotor(m) => m.validate(),
        }
    }

    /// Smallest and largest forward speed the vehicle can fly (m/s).
    pub fn forward_speed_range(&self) -> (f64, f64) {
        match self {
            VehicleModel::Kinematic(m) => (m.limits.vx_min_mps, m.limits.vx_max_mps),
            VehicleModel::FixedWing(m) => (m.stall_speed_mps, m.max_speed_mps),
            VehicleModel::Multirotor(m) => (0.0, m.max_speed_mps),
        }
    }

    /// The speed of state `x` that [`Self::forward_speed_range`] bounds (m/s): the world-frame
    /// vx for the kinematic vehicle (its limits are per axis), the airspeed for the fixed wing,
    /// the horizontal speed over the ground for the multirotor.
    pub fn forward_speed(&self, x: &State9) -> f64 {
        match self {
            VehicleModel::Kinematic(_) => x[crate::state::VX],
            VehicleModel::FixedWing(_) => {
                (x[crate::state::VX].powi(2) + x[crate::state::VY].powi(2) + x[crate::state::VZ].powi(2)).sqrt()
            }
            VehicleModel::Multirotor(_) => MultirotorModel::horizontal_speed(x),
        }
    }

    /// Number of inputs n_u.
    #[inline]
    pub fn n_inputs(&self) -> usize {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::N_INPUTS,
            VehicleModel::FixedWing(_) => FixedWingModel::N_INPUTS,
            VehicleModel::Multirotor(_) => MultirotorModel::N_INPUTS,
        }
    }

    /// The deceleration (m/s²) the collision avoidance counts on to stop closing on a
    /// neighbour: the kinematic vehicle's smallest adjusting rate of vx, vy, vz; for the fixed
    /// wing, half the lateral acceleration of its steepest allowed bank (it avoids by turning,
    /// and must roll into the turn first); for the multirotor, the smaller of its horizontal and
    /// vertical acceleration limits.
    pub fn braking_mps2(&self) -> f64 {
        match self {
            VehicleModel::Kinematic(m) => m.limits.accel_max_mps2.min(),
            VehicleModel::FixedWing(m) => {
                let bank = m.bank_max_rad.min((1.0 / m.load_factor_max).acos());
                0.5 * G * bank.tan()
            }
            VehicleModel::Multirotor(m) => m.accel_max_mps2.min(m.vertical_accel_max_mps2),
        }
    }

    /// The velocity nearest `v` (m/s, world frame) that the vehicle can fly: the kinematic
    /// vehicle's vx, |vy|, |vz| limits; for the fixed wing, `v` scaled into its speed range;
    /// for the multirotor, its horizontal speed, climb and descent limits.
    pub fn clamp_velocity(&self, v: [f64; 3]) -> [f64; 3] {
        match self {
            VehicleModel::Kinematic(m) => {
                let l = &m.limits;
                [
                    v[0].clamp(l.vx_min_mps, l.vx_max_mps),
                    v[1].clamp(-l.vy_max_mps, l.vy_max_mps),
                    v[2].clamp(-l.vz_max_mps, l.vz_max_mps),
                ]
            }
            VehicleModel::FixedWing(m) => {
                let speed = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if speed < 1e-9 {
                    return v;
                }
                let k = speed.clamp(m.stall_speed_mps, m.max_speed_mps) / speed;
                [v[0] * k, v[1] * k, v[2] * k]
            }
            VehicleModel::Multirotor(m) => m.clamp_velocity(v),
        }
    }

    /// `F·X`: the state after `dt` when no new input is given.
    #[inline]
    pub fn hold(&self, x: &State9, dt: f64) -> State9 {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::hold(x, dt),
            VehicleModel::FixedWing(m) => m.hold(x, dt),
            VehicleModel::Multirotor(_) => MultirotorModel::hold(x, dt),
        }
    }

    /// Control matrix B at state `x`.
    #[inline]
    pub fn control_matrix(&self, x: &State9, dt: f64) -> ControlMatrix {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::control_matrix(x, dt),
            VehicleModel::FixedWing(m) => m.control_matrix(x, dt),
            VehicleModel::Multirotor(m) => m.control_matrix(dt),
        }
    }

    /// True when B does not depend on the state (so its cost Hessian can be cached).
    #[inline]
    pub fn control_matrix_is_constant(&self) -> bool {
        match self {
            VehicleModel::Kinematic(_) | VehicleModel::Multirotor(_) => true,
            VehicleModel::FixedWing(_) => false,
        }
    }

    /// Per-step input bounds `(lo, hi)` at state `x`.
    #[inline]
    pub fn input_bounds(&self, x: &State9, dt: f64) -> (Input, Input) {
        match self {
            VehicleModel::Kinematic(m) => m.input_bounds(x, dt),
            VehicleModel::FixedWing(m) => m.input_bounds(x, dt),
            VehicleModel::Multirotor(m) => m.input_bounds(x),
        }
    }

    /// Bounds on the running sum of the inputs over a horizon, when the vehicle's state limits
    /// are linear in it (the kinematic model: velocities and attitudes are the summed inputs);
    /// None when they are not, and only the per-step bounds apply.
    #[inline]
    pub fn cumulative_input_bounds(&self, x: &State9) -> Option<(Input, Input)> {
        match self {
            VehicleModel::Kinematic(m) => Some(m.cumulative_bounds(x)),
            VehicleModel::FixedWing(_) | VehicleModel::Multirotor(_) => None,
        }
    }

    /// The velocity (world frame, m/s) and yaw β (rad) an autopilot is given for input `u` at
    /// `x` over a period `dt` (a MAVLink velocity setpoint): the multirotor's are its setpoints
    /// (`v + u_v`, `β + u_ψ`); the other vehicles' are the velocity and yaw they reach with `u`
    /// after the period. [`Self::input_for_setpoint`] is its inverse for the multirotor.
    pub fn velocity_setpoint(&self, x: &State9, u: &Input, dt: f64) -> ([f64; 3], f64) {
        use crate::state::{BETA, VX};
        match self {
            VehicleModel::Multirotor(_) => {
                ([x[VX] + u[0], x[VX + 1] + u[1], x[VX + 2] + u[2]], crate::angle::wrap_pi(x[BETA] + u[3]))
            }
            _ => {
                let next = self.propagate(x, u, dt);
                ([next[VX], next[VX + 1], next[VX + 2]], next[BETA])
            }
        }
    }

    /// The attitude (α, γ; rad) an autopilot is given beside the velocity setpoint of input `u`
    /// at `x` over `dt` (a MAVLink attitude target), for the vehicle whose attitude its inputs
    /// steer apart from its velocity (the paper's kinematic vehicle): the one it reaches with `u`
    /// after the period. None for the others, whose attitude follows from their velocity.
    pub fn attitude_setpoint(&self, x: &State9, u: &Input, dt: f64) -> Option<[f64; 2]> {
        use crate::state::{ALPHA, GAMMA};
        match self {
            VehicleModel::Kinematic(_) => {
                let next = self.propagate(x, u, dt);
                Some([next[ALPHA], next[GAMMA]])
            }
            _ => None,
        }
    }

    /// How many times the width of the per-step input bounds an outside decision may lie beyond
    /// them ([`Self::plausible`]): an agent bounds its input at the state it believed, not at
    /// the true one, so its decisions lie near, not inside, the bounds at the true state.
    pub const PLAUSIBLE_SLACK: f64 = 10.0;

    /// Whether input `u` and setpoint `sp` are ones this vehicle could have been asked at its
    /// true state `x` over `dt` (a decision from outside the process, which may be broken or
    /// hostile): `u` within the per-step bounds at `x` widened on each side by
    /// [`Self::PLAUSIBLE_SLACK`] times their width; a setpoint only for a vehicle flown by
    /// setpoints, its speed within twice the vehicle's (horizontal, climb and descent) and its
    /// yaw an angle. Finite numbers are assumed (checked before).
    pub fn plausible(&self, x: &State9, u: &Input, sp: Option<&Setpoint>, dt: f64) -> bool {
        let (lo, hi) = self.input_bounds(x, dt);
        let inputs_ok = (0..u.len()).all(|j| {
            let w = (hi[j] - lo[j]).max(1e-9) * Self::PLAUSIBLE_SLACK;
            u[j] >= lo[j] - w && u[j] <= hi[j] + w
        });
        let setpoint_ok = match (self, sp) {
            (_, None) => true,
            (VehicleModel::Multirotor(m), Some(sp)) => {
                let [vx, vy, vz] = sp.velocity_mps;
                vx.hypot(vy) <= 2.0 * m.max_speed_mps
                    && vz <= 2.0 * m.climb_max_mps
                    && vz >= -2.0 * m.descent_max_mps
                    && sp.yaw_rad.abs() <= 2.0 * std::f64::consts::PI
            }
            (_, Some(_)) => false,
        };
        inputs_ok && setpoint_ok
    }

    /// Whether the vehicle is flown by velocity and yaw setpoints (its inputs are nothing else):
    /// the multirotor.
    pub fn takes_velocity_setpoints(&self) -> bool {
        matches!(self, VehicleModel::Multirotor(_))
    }

    /// Whether an autopilot's targets carry everything the vehicle's inputs do, so that it can
    /// be flown over MAVLink: the multirotor's velocity and yaw setpoints; the kinematic
    /// vehicle's velocity and yaw with its attitude target ([`Self::attitude_setpoint`]). Not
    /// the fixed wing, whose bank and load factor a velocity target leaves to its autopilot.
    pub fn flown_by_autopilot_targets(&self) -> bool {
        !matches!(self, VehicleModel::FixedWing(_))
    }

    /// The setpoint that input `u` chosen at the believed state `x` asks for, where the vehicle
    /// is flown by setpoints (the multirotor; None for the others).
    pub fn setpoint(&self, x: &State9, u: &Input, dt: f64) -> Option<Setpoint> {
        self.takes_velocity_setpoints().then(|| {
            let (velocity_mps, yaw_rad) = self.velocity_setpoint(x, u, dt);
            Setpoint { velocity_mps, yaw_rad }
        })
    }

    /// The plant's input at the true state `x` that flies setpoint `sp` (the multirotor's
    /// inputs are increments on the state it has; None for the vehicles not flown by
    /// setpoints).
    pub fn input_flying(&self, x: &State9, sp: &Setpoint) -> Option<Input> {
        self.input_for_setpoint(x, sp.velocity_mps, Some(sp.yaw_rad))
    }

    /// What the autopilot of a vehicle flown by setpoints flies once its companion's setpoints
    /// stop (PX4's offboard-loss failsafe, HOLD): zero velocity over the ground, on the heading
    /// of `x` (a multirotor hovers where it is). None for the vehicles flown by inputs, which
    /// keep their course.
    pub fn failsafe_hold(&self, x: &State9) -> Option<Setpoint> {
        match self {
            VehicleModel::Multirotor(_) => Some(Setpoint { velocity_mps: [0.0; 3], yaw_rad: x[crate::state::BETA] }),
            _ => None,
        }
    }

    /// The input with which an autopilot at the true state `x` flies its targets: velocity `v`
    /// (world frame, m/s), yaw (β, rad; None: keep the present one) and, for the vehicle whose
    /// attitude its inputs steer apart from its velocity (the paper's kinematic vehicle), an
    /// attitude (pitch α, roll γ; rad; as [`Self::attitude_setpoint`] gives it; None: keep the
    /// present one). The multirotor's are its
    /// setpoints ([`Self::input_for_setpoint`]); the kinematic vehicle's reach the targets in
    /// one period as far as its per-step bounds at `x` allow (an agent's own input, given
    /// back, where it decided at `x`) over the period `dt`. None for the fixed wing, whose bank and load factor the
    /// targets do not say.
    pub fn input_for_targets(
        &self,
        x: &State9,
        v: [f64; 3],
        yaw: Option<f64>,
        attitude: Option<[f64; 2]>,
        dt: f64,
    ) -> Option<Input> {
        use crate::state::{ALPHA, BETA, GAMMA, VX};
        match self {
            VehicleModel::Multirotor(_) => self.input_for_setpoint(x, v, yaw),
            VehicleModel::Kinematic(m) => {
                let mut u = Input::zeros();
                for k in 0..3 {
                    u[k] = v[k] - x[VX + k];
                }
                if let Some([alpha, gamma]) = attitude {
                    (u[3], u[5]) = (alpha - x[ALPHA], gamma - x[GAMMA]);
                }
                u[4] = yaw.map_or(0.0, |y| crate::angle::wrap_pi(y - x[BETA]));
                let (lo, hi) = m.input_bounds(x, dt);
                Some(u.zip_map(&lo, f64::max).zip_map(&hi, f64::min))
            }
            VehicleModel::FixedWing(_) => None,
        }
    }

    /// The input that gives an autopilot the velocity setpoint `v` (world frame, m/s) and yaw
    /// `yaw` (β, rad; None: keep the present one) at `x`, where the vehicle is flown by such
    /// setpoints (the multirotor; None for the others, whose inputs steer their attitude too:
    /// a velocity and a yaw do not say what they do).
    pub fn input_for_setpoint(&self, x: &State9, v: [f64; 3], yaw: Option<f64>) -> Option<Input> {
        use crate::state::{BETA, VX};
        match self {
            VehicleModel::Multirotor(_) => {
                let mut u = Input::zeros();
                for k in 0..3 {
                    u[k] = v[k] - x[VX + k];
                }
                u[3] = yaw.map_or(0.0, |y| crate::angle::wrap_pi(y - x[BETA]));
                Some(u)
            }
            _ => None,
        }
    }

    /// The controller's view of one period under input `u` from a state over the ground (a
    /// UAV's prediction of itself): for the fixed wing, the plant carried by the wind across
    /// its nose that the state implies (a steady wind drifts it, and the prediction with it);
    /// the calm-air plant for the others, whose velocity over the ground is what they hold.
    #[inline]
    pub fn predict(&self, x: &State9, u: &Input, dt: f64) -> State9 {
        match self {
            VehicleModel::FixedWing(m) => m.predict(x, u, dt),
            _ => self.propagate(x, u, dt),
        }
    }

    /// The plant in calm air: the true state after `dt` under the (already perturbed) input `u`.
    #[inline]
    pub fn propagate(&self, x: &State9, u: &Input, dt: f64) -> State9 {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::propagate(x, u, dt),
            VehicleModel::FixedWing(m) => m.propagate(x, u, dt),
            VehicleModel::Multirotor(m) => m.propagate(x, u, dt),
        }
    }

    /// The plant in wind: the true state (velocity over the ground) after `dt` under input
    /// `u`, with the wind `w0` at the start of the period and `w1` at its end (world frame,
    /// m/s). The multirotor flies through the air (drag on its air-relative velocity, its
    /// inner loop holding its ground velocity against it). The kinematic vehicle and the fixed
    /// wing move through the air at their state's velocity less the wind and are carried by
    /// it: the fixed wing's airspeed is what it holds, so a steady wind drifts it; the
    /// kinematic vehicle's velocity is over the ground, so only a change of the wind moves it
    /// (METHOD §5; a steady wind does nothing to it, and a scenario that sets one says so).
    #[inline]
    pub fn propagate_in_wind(&self, x: &State9, u: &Input, dt: f64, w0: [f64; 3], w1: [f64; 3]) -> State9 {
        if let VehicleModel::Multirotor(m) = self {
            return m.propagate_in_wind(x, u, dt, w0, w1);
        }
        let mut air = *x;
        for k in 0..3 {
            air[crate::state::VX + k] -= w0[k];
        }
        let mut next = self.propagate(&air, u, dt);
        for k in 0..3 {
            next[crate::state::VX + k] += w1[k];
            next[crate::state::X + k] += 0.5 * dt * (w0[k] + w1[k]);
        }
        next
    }

    /// The turn rate (rad/s, counter-clockwise positive) of a UAV seen at `now` and predicted
    /// `dt` later at `next`, for the rigid-body turn of a formation
    /// ([`crate::Formation::add_w_turning`]): for the fixed wing, the coordinated-turn rate of
    /// its bank at `next`, `−g·tan γ / V` (measured far more finely than a rate could be
    /// estimated); for the others, the rate of its heading (a multirotor's bank also holds it
    /// against the wind, so it says nothing of its turn).
    #[inline]
    pub fn turn_rate(&self, now: &State9, next: &State9, dt: f64) -> f64 {
        use crate::state::{BETA, GAMMA, VX, VY};
        match self {
            VehicleModel::FixedWing(_) => {
                let v = next[VX].hypot(next[VY]);
                if v < 1.0 {
                    0.0
                } else {
                    -G * next[GAMMA].tan() / v
                }
            }
            VehicleModel::Kinematic(_) | VehicleModel::Multirotor(_) => {
                crate::angle::wrap_pi(next[BETA] - now[BETA]) / dt
            }
        }
    }

    /// A UAV of this vehicle set on its path at `x` (a scripted navigator) in the wind `w`
    /// (world frame, m/s): the fixed wing's nose points along its velocity through the air, so
    /// in a wind it crabs (yaw and pitch of `v − w`); the kinematic vehicle's attitude is its
    /// own (the paper's); the multirotor flies its path instead (it is not set on it).
    #[inline]
    pub fn on_path_in_wind(&self, x: &State9, w: [f64; 3]) -> State9 {
        use crate::state::{ALPHA, BETA, VX};
        let mut s = *x;
        if let VehicleModel::FixedWing(_) = self {
            let a = [x[VX] - w[0], x[VX + 1] - w[1], x[VX + 2] - w[2]];
            let h = a[0].hypot(a[1]);
            if h > 1e-9 {
                s[BETA] = a[1].atan2(a[0]);
                s[ALPHA] = a[2].atan2(h);
            }
        }
        s
    }

    /// How long the vehicle's velocity lags the setpoint it is given (s): the multirotor's
    /// velocity loop τ_v, whose steady lag behind a ramp of setpoints is τ_v times its slope; 0
    /// for the kinematic vehicle and the fixed wing, whose inputs act within the period. Its
    /// controller asks for the velocity its slot will have this much later.
    #[inline]
    pub fn setpoint_lag_s(&self) -> f64 {
        match self {
            VehicleModel::Multirotor(m) => m.velocity_time_constant_s,
            VehicleModel::Kinematic(_) | VehicleModel::FixedWing(_) => 0.0,
        }
    }

    /// The fastest the vehicle flies over the ground in calm air (m/s): the kinematic vehicle's
    /// per-axis limits together, the fixed wing's top airspeed, the multirotor's top horizontal
    /// speed with its faster vertical one.
    pub fn top_speed_mps(&self) -> f64 {
        match self {
            VehicleModel::Kinematic(m) => {
                let l = &m.limits;
                (l.vx_min_mps.abs().max(l.vx_max_mps).powi(2) + l.vy_max_mps.powi(2) + l.vz_max_mps.powi(2)).sqrt()
            }
            VehicleModel::FixedWing(m) => m.max_speed_mps,
            VehicleModel::Multirotor(m) => m.top_speed(),
        }
    }

    /// Bounds on how fast each velocity component (world frame, m/s², calm air) and each
    /// attitude angle (α, β, γ; rad/s) of the vehicle can change: the kinematic vehicle's rate
    /// limits; for the fixed wing, its top speed turned at its fastest (the coordinated turn
    /// of its steepest bank at stall speed, the rudder and the pitch rate together) plus its
    /// thrust and gravity, and its roll, yaw and pitch rates; for the multirotor, its thrust
    /// with the drag at its top speed, its tilt swung across in one attitude time constant
    /// and its yaw rate. Wider than any change the vehicle flies (a track's rates are kept
    /// within them).
    pub fn rate_limits(&self, dt: f64) -> [f64; 6] {
        match self {
            VehicleModel::Kinematic(m) => {
                let s = m.input_scale(dt);
                std::array::from_fn(|k| s[k] / dt)
            }
            VehicleModel::FixedWing(m) => {
                let bank = m.bank_max_rad.min((1.0 / m.load_factor_max).acos());
                let turn = G * bank.tan() / m.stall_speed_mps + m.yaw_rate_max_radps;
                let a = m.max_speed_mps * (turn + m.pitch_rate_max_radps) + m.accel_max_mps2 + G;
                [a, a, a, m.pitch_rate_max_radps, turn, m.roll_rate_max_radps]
            }
            VehicleModel::Multirotor(m) => {
                let v = m.top_speed();
                let a = m.thrust_to_weight * G + (m.drag_linear_per_s + m.drag_quadratic_per_m * v) * v;
                let tilt = 2.0 * m.tilt_max_rad / m.attitude_time_constant_s;
                [a, a, a, tilt, m.yaw_rate_max_radps, tilt]
            }
        }
    }

    /// Largest magnitude of each input in one step, used to normalise the input penalty.
    #[inline]
    pub fn input_scale(&self, dt: f64) -> Input {
        match self {
            VehicleModel::Kinematic(m) => m.input_scale(dt),
            VehicleModel::FixedWing(m) => m.input_scale(),
            VehicleModel::Multirotor(m) => m.input_scale(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_vehicle_changes_faster_than_its_rate_limits() {
        // From states across each vehicle's envelope, under inputs at and between its per-step
        // bounds: every velocity and attitude changes within `rate_limits` (which the fast
        // engine's tracks keep their rates within), and not by far less (they are bounds of
        // what the vehicle does, not numbers from elsewhere).
        use crate::state::{ALPHA, BETA, GAMMA, VX};
        let dt = 0.1;
        let vehicles = [
            VehicleModel::Kinematic(KinematicModel::default()),
            VehicleModel::FixedWing(FixedWingModel::default()),
            VehicleModel::Multirotor(MultirotorModel::default()),
        ];
        for v in vehicles {
            let limits = v.rate_limits(dt);
            let (slow, fast) = v.forward_speed_range();
            let mut most = [0.0f64; 6];
            for a in 0..5 {
                for b in 0..4 {
                    let mut x = State9::zeros();
                    let speed = slow + (fast - slow) * f64::from(a) / 4.0;
                    let heading = f64::from(b) * 1.3 - 2.0;
                    let tilt = 0.3 * (f64::from(b) - 1.5) / 1.5;
                    (x[VX], x[VX + 1]) = (speed * heading.cos(), speed * heading.sin());
                    (x[ALPHA], x[BETA], x[GAMMA]) = (0.5 * tilt, heading, tilt);
                    match v {
                        VehicleModel::Kinematic(_) => (x[VX], x[VX + 1]) = (speed, 0.0),
                        // Its velocity is its airspeed along its flight path.
                        VehicleModel::FixedWing(_) => {
                            let (sa, ca) = x[ALPHA].sin_cos();
                            (x[VX], x[VX + 1], x[VX + 2]) =
                                (speed * ca * heading.cos(), speed * ca * heading.sin(), speed * sa);
                        }
                        VehicleModel::Multirotor(_) => {}
                    }
                    let (lo, hi) = v.input_bounds(&x, dt);
                    for m in 0..16u32 {
                        let u = Input::from_fn(|j, _| if (m >> (j % 4)) & 1 == 1 { hi[j] } else { lo[j] });
                        let next = v.propagate(&x, &u, dt);
                        for k in 0..6 {
                            let change = crate::state::difference_component(VX + k, next[VX + k], x[VX + k]) / dt;
                            assert!(
                                change.abs() <= limits[k] * (1.0 + 1e-9),
                                "{v:?}: rate {k} {change} beyond {}",
                                limits[k]
                            );
                            most[k] = most[k].max(change.abs());
                        }
                    }
                }
            }
            // Velocities reach a tenth of their bound at least (the bounds are not loose by
            // orders of magnitude).
            for k in 0..3 {
                assert!(most[k] > 0.1 * limits[k] / 8.0, "{v:?}: rate {k} at most {} of {}", most[k], limits[k]);
            }
        }
    }

    #[test]
    fn only_decisions_near_what_the_vehicle_can_do_are_plausible() {
        let dt = 0.1;
        let k = VehicleModel::Kinematic(KinematicModel::default());
        let mut x = State9::zeros();
        x[crate::state::VX] = 70.0;
        let (lo, hi) = k.input_bounds(&x, dt);
        assert!(k.plausible(&x, &hi, None, dt) && k.plausible(&x, &lo, None, dt));
        let mut far = hi;
        far[1] = hi[1] + (VehicleModel::PLAUSIBLE_SLACK + 1.0) * (hi[1] - lo[1]);
        assert!(!k.plausible(&x, &far, None, dt), "beyond the slack");
        let sp = Setpoint { velocity_mps: [20.0, 0.0, 0.0], yaw_rad: 0.0 };
        assert!(!k.plausible(&x, &Input::zeros(), Some(&sp), dt), "a setpoint for a vehicle that takes none");
        let m = VehicleModel::Multirotor(MultirotorModel::default());
        let x = State9::zeros();
        assert!(m.plausible(&x, &Input::zeros(), Some(&sp), dt), "20 m/s for a 15 m/s multirotor: near enough");
        let fast = Setpoint { velocity_mps: [1e3, 0.0, 0.0], yaw_rad: 0.0 };
        assert!(!m.plausible(&x, &Input::zeros(), Some(&fast), dt), "1 km/s");
        let spin = Setpoint { velocity_mps: [1.0, 0.0, 0.0], yaw_rad: 1e9 };
        assert!(!m.plausible(&x, &Input::zeros(), Some(&spin), dt), "not an angle");
    }

    #[test]
    fn an_autopilot_given_the_targets_of_an_input_flies_that_input() {
        use crate::state::{ALPHA, BETA, GAMMA, VX};
        let dt = 0.1;
        let mut x = State9::zeros();
        (x[VX], x[VX + 1], x[ALPHA], x[BETA], x[GAMMA]) = (60.0, 0.4, 0.01, 3.1, -0.02);
        for v in
            [VehicleModel::Kinematic(KinematicModel::default()), VehicleModel::Multirotor(MultirotorModel::default())]
        {
            let (lo, hi) = v.input_bounds(&x, dt);
            let u = lo.zip_map(&hi, |l, h| l + 0.7 * (h - l));
            let (vel, yaw) = v.velocity_setpoint(&x, &u, dt);
            let back = v.input_for_targets(&x, vel, Some(yaw), v.attitude_setpoint(&x, &u, dt), dt).expect("targets");
            for j in 0..v.n_inputs() {
                assert!((back[j] - u[j]).abs() < 1e-12, "{v:?}: input {j}: {} for {}", back[j], u[j]);
            }
        }
        // Targets beyond what the kinematic vehicle does in a period are flown as far as it can;
        // a velocity target alone keeps the attitude.
        let k = VehicleModel::Kinematic(KinematicModel::default());
        let (lo, hi) = k.input_bounds(&x, dt);
        let far = k.input_for_targets(&x, [90.0, -50.0, 0.4], None, Some([-1.0, 1.0]), dt).expect("targets");
        assert_eq!((far[0], far[1], far[3], far[4], far[5]), (hi[0], lo[1], lo[3], 0.0, hi[5]));
        let level = k.input_for_targets(&x, [60.0, 0.4, 0.0], None, None, dt).expect("targets");
        assert_eq!((level[3], level[4], level[5]), (0.0, 0.0, 0.0));
        assert!(VehicleModel::FixedWing(FixedWingModel::default())
            .input_for_targets(&x, [19.0, 0.0, 0.0], None, None, dt)
            .is_none());
    }
}
