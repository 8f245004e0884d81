//! Angle helpers: wrapping to a principal interval and degree/radian conversion.
//!
//! Inside proxform every angle is in radians; degrees appear only at file boundaries.

use std::f64::consts::{PI, TAU};

/// Wraps an angle to `[0, 2π)`.
#[inline]
pub fn wrap_2pi(a: f64) -> f64 {
    let w = a.rem_euclid(TAU);
    // rem_euclid can return TAU itself for tiny negative inputs through rounding.
    if w >= TAU {
        0.0
    } else {
        w
    }
}

/// Wraps an angle to `(-π, π]`.
#[inline]
pub fn wrap_pi(a: f64) -> f64 {
    if a > -PI && a <= PI {
        return a;
    }
    let w = wrap_2pi(a);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

/// Degrees to radians.
#[inline]
pub fn deg(d: f64) -> f64 {
    d.to_radians()
}

/// km/h to m/s.
#[inline]
pub fn kmh(v: f64) -> f64 {
    v / 3.6
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn wraps_into_principal_intervals() {
        assert_relative_eq!(wrap_2pi(-0.5 * PI), 1.5 * PI);
        assert_relative_eq!(wrap_2pi(2.0 * TAU + 0.25), 0.25, epsilon = 1e-12);
        assert!(wrap_2pi(-1e-18) < TAU);
        assert_relative_eq!(wrap_pi(1.5 * PI), -0.5 * PI);
        assert_relative_eq!(wrap_pi(PI), PI);
        assert_relative_eq!(wrap_pi(-PI), PI);
    }
}
