//! The 9-parameter behaviour state of METHOD.md §1 and the input vector of §5.
//!
//! `X = [x, y, z, vx, vy, vz, α, β, γ]`: position (m, world frame: x along the formation's
//! initial course, y left, z up), velocity (m/s) and attitude (rad): α pitch (nose up
//! positive), β yaw (counter-clockwise seen from above, from x toward y), γ roll (right wing
//! down positive).

use nalgebra::{SVector, Vector3};

use crate::angle::wrap_pi;

/// Number of behaviour parameters p.
pub const P: usize = 9;
/// Maximum number of control inputs of any vehicle model.
pub const MAX_INPUTS: usize = 6;

/// The behaviour state X (SI units, radians).
pub type State9 = SVector<f64, P>;
/// A control input Δu; a model with fewer inputs leaves the tail at zero.
pub type Input = SVector<f64, MAX_INPUTS>;

/// Index of x (m).
pub const X: usize = 0;
/// Index of y (m).
pub const Y: usize = 1;
/// Index of z (m).
pub const Z: usize = 2;
/// Index of vx (m/s).
pub const VX: usize = 3;
/// Index of vy (m/s).
pub const VY: usize = 4;
/// Index of vz (m/s).
pub const VZ: usize = 5;
/// Index of α, pitch (rad).
pub const ALPHA: usize = 6;
/// Index of β, yaw (rad).
pub const BETA: usize = 7;
/// Index of γ, roll (rad).
pub const GAMMA: usize = 8;

/// Short names of the nine parameters, in state order.
pub const NAMES: [&str; P] = ["x", "y", "z", "vx", "vy", "vz", "alpha", "beta", "gamma"];

/// Position part of a state.
#[inline]
pub fn position(s: &State9) -> Vector3<f64> {
    Vector3::new(s[X], s[Y], s[Z])
}

/// Velocity part of a state.
#[inline]
pub fn velocity(s: &State9) -> Vector3<f64> {
    Vector3::new(s[VX], s[VY], s[VZ])
}

/// `a − b` with the three attitude components wrapped to (−π, π].
#[inline]
pub fn difference(a: &State9, b: &State9) -> State9 {
    let mut d = a - b;
    for k in ALPHA..=GAMMA {
        d[k] = wrap_pi(d[k]);
    }
    d
}

/// Builds a state from its three parts.
#[inline]
pub fn from_parts(p: Vector3<f64>, v: Vector3<f64>, att: Vector3<f64>) -> State9 {
    State9::from_column_slice(&[p.x, p.y, p.z, v.x, v.y, v.z, att.x, att.y, att.z])
}

/// True when every component is finite.
#[inline]
pub fn is_finite(s: &State9) -> bool {
    s.iter().all(|v| v.is_finite())
}

/// Component `k` of `a − b`, wrapped to (−π, π] when it is an attitude angle.
#[inline]
pub fn difference_component(k: usize, a: f64, b: f64) -> f64 {
    if k >= ALPHA {
        wrap_pi(a - b)
    } else {
        a - b
    }
}
