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

/// Assigns azimuth areas without trigonometry in the inner loop: the offset is turned into
/// the body frame with the yaw's sine and cosine (computed once per step), and its bearing is
/// compared as a pseudo-angle (a monotonic stand-in for the angle, see [`pseudo_angle`])
/// against the precomputed pseudo-angles of the area boundaries.
#[derive(Debug, Clone, PartialEq)]
pub struct AreaClassifier {
    /// Pseudo-angles of the boundaries between areas 0|1, 1|2, …, (m−2)|(m−1).
    bounds: Vec<f64>,
}

impl AreaClassifier {
    /// The classifier for `m` areas.
    pub fn new(m: usize) -> Self {
        let bounds = (1..m.max(1))
            .map(|k| {
                let (s, c) = (k as f64 * TAU / m as f64).sin_cos();
                pseudo_angle(c, s)
            })
            .collect();
        Self { bounds }
    }

    /// Number of areas m.
    pub fn areas(&self) -> usize {
        self.bounds.len() + 1
    }

    /// Area of a neighbour at horizontal offset `(dx, dy)` (world frame) from a UAV whose yaw
    /// has sine `sin_yaw` and cosine `cos_yaw`.
    #[inline]
    pub fn area(&self, sin_yaw: f64, cos_yaw: f64, dx: f64, dy: f64) -> usize {
        // Body frame: bx forward, by to the left. Clockwise bearing = angle of (bx, −by).
        let bx = cos_yaw * dx + sin_yaw * dy;
        let by = cos_yaw * dy - sin_yaw * dx;
        if self.bounds.len() == 7 {
            return octant(bx, -by);
        }
        let p = pseudo_angle(bx, -by);
        self.bounds.iter().take_while(|&&b| b <= p).count()
    }
}

/// The octant `⌊8θ/2π⌋` of the direction `(x, y)` (the m = 8 case of
/// [`AreaClassifier::area`]; a boundary belongs to the next octant). Branch-free: the
/// direction is turned by 180° and 90° as needed, each turn adding its octants, and the
/// last comparison splits the remaining quadrant.
#[inline]
fn octant(x: f64, y: f64) -> usize {
    let origin = x == 0.0 && y == 0.0;
    let lower = y < 0.0 || (y == 0.0 && x < 0.0); // θ ≥ 180°
    let (x1, y1) = if lower { (-x, -y) } else { (x, y) };
    let left = x1 <= 0.0 && !origin; // θ ≥ 90° in the upper half
    let (x2, y2) = if left { (y1, -x1) } else { (x1, y1) };
    let upper_octant = y2 >= x2 && !origin; // θ ≥ 45° in the quadrant
    4 * usize::from(lower) + 2 * usize::from(left) + usize::from(upper_octant)
}

/// A monotonic pseudo-angle of the direction `(x, y)` in `[0, 4)`: 0 along +x, 1 along +y,
/// 2 along −x, 3 along −y (the "diamond angle"). `(0, 0)` maps to 0.
#[inline]
pub fn pseudo_angle(x: f64, y: f64) -> f64 {
    let ax = x.abs();
    let ay = y.abs();
    if ax + ay == 0.0 {
        return 0.0;
    }
    if y >= 0.0 {
        if x >= 0.0 {
            y / (x + y)
        } else {
            1.0 + ax / (ax + y)
        }
    } else if x < 0.0 {
        2.0 + ay / (ax + ay)
    } else {
        3.0 + x / (x + ay)
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
    fn classifier_agrees_with_the_bearing_formula() {
        for m in [1usize, 3, 4, 6, 8, 12, 16] {
            let c = AreaClassifier::new(m);
            assert_eq!(c.areas(), m);
            let areas = AzimuthAreas { areas: m, sensing_range_m: 1.0 };
            for yaw_deg in [-170.0, -33.0, 0.0, 3.0, 47.5, 90.0, 179.0] {
                let (s, co) = deg(yaw_deg).sin_cos();
                for k in 0..720 {
                    let a = deg(k as f64 * 0.5 + 0.13);
                    let (dx, dy) = (120.0 * a.cos(), 120.0 * a.sin());
                    let theta = bearing_cw_from_nose(deg(yaw_deg), dx, dy);
                    // Skip bearings within 1e-9 rad of a boundary, where rounding may differ.
                    let edge = (m as f64 * theta / TAU).fract();
                    if !(1e-9..=1.0 - 1e-9).contains(&edge) {
                        continue;
                    }
                    assert_eq!(c.area(s, co, dx, dy), areas.area_of(deg(yaw_deg), dx, dy), "m {m} yaw {yaw_deg} k {k}");
                }
            }
        }
    }

    #[test]
    fn octants_follow_the_boundary_convention() {
        // Exact boundaries belong to the next octant; the origin is octant 0.
        let cases = [
            ((1.0, 0.0), 0),
            ((1.0, 1.0), 1),
            ((0.0, 1.0), 2),
            ((-1.0, 1.0), 3),
            ((-1.0, 0.0), 4),
            ((-1.0, -1.0), 5),
            ((0.0, -1.0), 6),
            ((1.0, -1.0), 7),
            ((0.0, 0.0), 0),
            ((1.0, -1e-12), 7),
            ((1.0, 1e-12), 0),
        ];
        for ((x, y), o) in cases {
            assert_eq!(octant(x, y), o, "({x}, {y})");
        }
    }

    #[test]
    fn pseudo_angle_is_monotonic() {
        let mut last = -1.0;
        for k in 0..3600 {
            let a = deg(k as f64 * 0.1);
            let p = pseudo_angle(a.cos(), a.sin());
            assert!(p > last && p < 4.0, "{k}: {p} after {last}");
            last = p;
        }
        assert_eq!(pseudo_angle(0.0, 0.0), 0.0);
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(AzimuthAreas { areas: 0, sensing_range_m: 1.0 }.validate().is_err());
        assert!(AzimuthAreas { areas: 8, sensing_range_m: f64::NAN }.validate().is_err());
        assert!(AzimuthAreas { areas: 8, sensing_range_m: -1.0 }.validate().is_err());
        assert!(AREAS.validate().is_ok());
    }
}
