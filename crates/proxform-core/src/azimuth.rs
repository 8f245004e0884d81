//! Azimuth areas (METHOD §2, the paper's eq. 1).
//!
//! UAV i splits its horizontal surroundings into `m` equal sectors fixed to its body axes.
//! The bearing of neighbour j is measured clockwise from i's nose:
//! `θ_ij = wrap_[0,2π)(β_i − atan2(y_j − y_i, x_j − x_i))`, and its area is `⌊m·θ_ij/2π⌋`.

use std::f64::consts::TAU;

use crate::angle::wrap_2pi;
use crate::error::ConfigError;

/// How a UAV partitions and perceives its surroundings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AzimuthAreas {
    /// Number of azimuth areas m (≥ 1). Default 8 (METHOD §9).
    pub areas: usize,
    /// Onboard sensing range r_sense (m, > 0). Default 250 m (METHOD §9).
    pub sensing_range_m: f64,
}

impl Default for AzimuthAreas {
    fn default() -> Self {
        Self { areas: 8, sensing_range_m: 250.0 }
    }
}

impl AzimuthAreas {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.areas < 1 {
            return Err(ConfigError::OutOfRange { field: "areas", value: self.areas as f64, expected: "m ≥ 1" });
        }
        if !(self.sensing_range_m.is_finite() && self.sensing_range_m > 0.0) {
            return Err(ConfigError::OutOfRange {
                field: "sensing_range_m",
                value: self.sensing_range_m,
                expected: "a finite range > 0 m",
            });
        }
        Ok(())
    }

    /// Area index of a neighbour at horizontal offset `(dx, dy)` (m, world frame) from a UAV
    /// with yaw `yaw` (rad).
    #[inline]
    pub fn area_of(&self, yaw: f64, dx: f64, dy: f64) -> usize {
        area_index(self.areas, bearing_cw_from_nose(yaw, dx, dy))
    }
}

/// Bearing of a horizontal offset `(dx, dy)`, clockwise from the nose of a UAV with yaw `yaw`,
/// in `[0, 2π)`.
#[inline]
pub fn bearing_cw_from_nose(yaw: f64, dx: f64, dy: f64) -> f64 {
    wrap_2pi(yaw - dy.atan2(dx))
}

/// Area index `⌊m·θ/2π⌋` of a bearing θ in `[0, 2π)`, always `< m`.
#[inline]
pub fn area_index(m: usize, theta: f64) -> usize {
    let s = (m as f64 * theta / TAU) as usize;
    s.min(m - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::angle::deg;
    use approx::assert_relative_eq;

    const AREAS: AzimuthAreas = AzimuthAreas { areas: 8, sensing_range_m: 250.0 };

    #[test]
    fn bearing_is_clockwise_from_the_nose() {
        // Nose along +x: a neighbour straight ahead is at 0, one on the right (−y) at 90°.
        assert_relative_eq!(bearing_cw_from_nose(0.0, 10.0, 0.0), 0.0);
        assert_relative_eq!(bearing_cw_from_nose(0.0, 0.0, -10.0), deg(90.0), epsilon = 1e-12);
        assert_relative_eq!(bearing_cw_from_nose(0.0, -10.0, 0.0), deg(180.0), epsilon = 1e-12);
        // Left (+y) is 270° clockwise.
        assert_relative_eq!(bearing_cw_from_nose(0.0, 0.0, 10.0), deg(270.0), epsilon = 1e-12);
    }

    #[test]
    fn area_boundaries_belong_to_the_next_area() {
        assert_eq!(area_index(8, 0.0), 0);
        assert_eq!(area_index(8, deg(44.999)), 0);
        assert_eq!(area_index(8, deg(45.0) + 1e-12), 1);
        assert_eq!(area_index(8, deg(359.999)), 7);
        // A bearing that rounds up to 2π still maps to the last area.
        assert_eq!(area_index(8, TAU - 1e-17), 7);
        assert_eq!(area_index(1, deg(200.0)), 0);
    }

    #[test]
    fn wraps_at_zero() {
        // Slightly left of the nose is just below 2π: last area, not area 0.
        assert_eq!(AREAS.area_of(0.0, 100.0, 0.1), 7);
        // Slightly right of the nose: area 0.
        assert_eq!(AREAS.area_of(0.0, 100.0, -0.1), 0);
    }

    #[test]
    fn areas_turn_with_the_uav() {
        // A neighbour due north (+y) of a UAV yawed 90° (flying along +y) is dead ahead.
        assert_eq!(AREAS.area_of(deg(90.0), 0.0, 100.0), 0);
        // The same neighbour seen by a UAV flying along +x is on its left: area 6 (270°-315°).
        assert_eq!(AREAS.area_of(0.0, 0.0, 100.0), 6);
        // Yawed 30°: a neighbour at world bearing 0 is 30° to the right, area 0; at −20° it is
        // 50° right, area 1.
        assert_eq!(AREAS.area_of(deg(30.0), 100.0, 0.0), 0);
        let (s, c) = deg(-20.0).sin_cos();
        assert_eq!(AREAS.area_of(deg(30.0), 100.0 * c, 100.0 * s), 1);
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(AzimuthAreas { areas: 0, sensing_range_m: 1.0 }.validate().is_err());
        assert!(AzimuthAreas { areas: 8, sensing_range_m: f64::NAN }.validate().is_err());
        assert!(AzimuthAreas { areas: 8, sensing_range_m: -1.0 }.validate().is_err());
        assert!(AREAS.validate().is_ok());
    }
}
