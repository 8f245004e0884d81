//! Vehicle models (METHOD §5): how a UAV's state responds to its inputs.
//!
//! Every model gives the controller the same three things: the course-keeping prediction
//! `F·X`, the control matrix B at the current state, and the per-step input bounds that keep
//! the vehicle inside its limits. The simulator uses [`VehicleModel::propagate`] as the plant.

mod fixed_wing;
mod kinematic;

pub use fixed_wing::FixedWingModel;
pub use kinematic::{KinematicLimits, KinematicModel};

use crate::control::ControlMatrix;
use crate::error::ConfigError;
use crate::state::{Input, State9};

/// Standard gravity (m/s²).
pub const G: f64 = 9.80665;

/// The vehicle models proxform knows. An enum rather than a trait object: the controller's
/// inner loop stays monomorphic and the models stay plain data.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum VehicleModel {
    /// The paper's §4 simulation model (METHOD §5, model 1).
    Kinematic(KinematicModel),
    /// Aileron, rudder, elevator and throttle (METHOD §5, model 2).
    FixedWing(FixedWingModel),
}

impl VehicleModel {
    /// Checks the model's parameters.
    pub fn validate(&self) -> Result<(), ConfigError> {
        match self {
            VehicleModel::Kinematic(m) => m.limits.validate(),
            VehicleModel::FixedWing(m) => m.validate(),
        }
    }

    /// Smallest and largest forward speed the vehicle can fly (m/s).
    pub fn forward_speed_range(&self) -> (f64, f64) {
        match self {
            VehicleModel::Kinematic(m) => (m.limits.vx_min_mps, m.limits.vx_max_mps),
            VehicleModel::FixedWing(m) => (m.stall_speed_mps, m.max_speed_mps),
        }
    }

    /// The speed of state `x` that [`Self::forward_speed_range`] bounds (m/s): the world-frame
    /// vx for the kinematic vehicle (its limits are per axis), the airspeed for the fixed wing.
    pub fn forward_speed(&self, x: &State9) -> f64 {
        match self {
            VehicleModel::Kinematic(_) => x[crate::state::VX],
            VehicleModel::FixedWing(_) => {
                (x[crate::state::VX].powi(2) + x[crate::state::VY].powi(2) + x[crate::state::VZ].powi(2)).sqrt()
            }
        }
    }

    /// Number of inputs n_u.
    #[inline]
    pub fn n_inputs(&self) -> usize {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::N_INPUTS,
            VehicleModel::FixedWing(_) => FixedWingModel::N_INPUTS,
        }
    }

    /// The deceleration (m/s²) the collision avoidance counts on to stop closing on a
    /// neighbour: the kinematic vehicle's smallest adjusting rate of vx, vy, vz; for the fixed
    /// wing, half the lateral acceleration of its steepest allowed bank (it avoids by turning,
    /// and must roll into the turn first).
    pub fn braking_mps2(&self) -> f64 {
        match self {
            VehicleModel::Kinematic(m) => m.limits.accel_max_mps2.min(),
            VehicleModel::FixedWing(m) => {
                let bank = m.bank_max_rad.min((1.0 / m.load_factor_max).acos());
                0.5 * G * bank.tan()
            }
        }
    }

    /// The velocity nearest `v` (m/s, world frame) that the vehicle can fly: the kinematic
    /// vehicle's vx, |vy|, |vz| limits; for the fixed wing, `v` scaled into its speed range.
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
        }
    }

    /// `F·X`: the state after `dt` when no new input is given.
    #[inline]
    pub fn hold(&self, x: &State9, dt: f64) -> State9 {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::hold(x, dt),
            VehicleModel::FixedWing(m) => m.hold(x, dt),
        }
    }

    /// Control matrix B at state `x`.
    #[inline]
    pub fn control_matrix(&self, x: &State9, dt: f64) -> ControlMatrix {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::control_matrix(x, dt),
            VehicleModel::FixedWing(m) => m.control_matrix(x, dt),
        }
    }

    /// True when B does not depend on the state (so its cost Hessian can be cached).
    #[inline]
    pub fn control_matrix_is_constant(&self) -> bool {
        match self {
            VehicleModel::Kinematic(_) => true,
            VehicleModel::FixedWing(_) => false,
        }
    }

    /// Per-step input bounds `(lo, hi)` at state `x`.
    #[inline]
    pub fn input_bounds(&self, x: &State9, dt: f64) -> (Input, Input) {
        match self {
            VehicleModel::Kinematic(m) => m.input_bounds(x, dt),
            VehicleModel::FixedWing(m) => m.input_bounds(x, dt),
        }
    }

    /// Bounds on the running sum of the inputs over a horizon, when the vehicle's state limits
    /// are linear in it (the kinematic model: velocities and attitudes are the summed inputs);
    /// None when they are not, and only the per-step bounds apply.
    #[inline]
    pub fn cumulative_input_bounds(&self, x: &State9) -> Option<(Input, Input)> {
        match self {
            VehicleModel::Kinematic(m) => Some(m.cumulative_bounds(x)),
            VehicleModel::FixedWing(_) => None,
        }
    }

    /// The plant: the true state after `dt` under the (already perturbed) input `u`.
    #[inline]
    pub fn propagate(&self, x: &State9, u: &Input, dt: f64) -> State9 {
        match self {
            VehicleModel::Kinematic(_) => KinematicModel::propagate(x, u, dt),
            VehicleModel::FixedWing(m) => m.propagate(x, u, dt),
        }
    }

    /// Largest magnitude of each input in one step, used to normalise the input penalty.
    #[inline]
    pub fn input_scale(&self, dt: f64) -> Input {
        match self {
            VehicleModel::Kinematic(m) => m.input_scale(dt),
            VehicleModel::FixedWing(m) => m.input_scale(),
        }
    }
}
