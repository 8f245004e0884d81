//! Frames between an autopilot and the method: MAVLink's local NED (north, east, down; yaw
//! clockwise from north) and geodetic positions on one side, the method's world frame
//! (x along the formation's initial course, y to its left, z up; yaw β counter-clockwise from
//! x, METHOD §1) on the other.
//!
//! A [`Frame`] is where the method's origin is in the autopilot's local NED frame and which way
//! its x axis points (the course, clockwise from north). A [`GeoOrigin`] maps local NED to
//! latitude, longitude and altitude as PX4 does (an azimuthal equidistant projection on a
//! sphere of radius 6 371 km about the origin; the altitude is the origin's minus the down
//! coordinate), so that GLOBAL_POSITION_INT and LOCAL_POSITION_NED of one vehicle agree.

use proxform_core::angle::wrap_pi;
use proxform_core::state::{self, State9};

/// The sphere PX4's map projection uses (m).
pub const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// A position, velocity and attitude in MAVLink's local NED frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Ned {
    /// North, east, down (m).
    pub position: [f64; 3],
    /// Velocity north, east, down (m/s).
    pub velocity: [f64; 3],
    /// Roll (right wing down positive), pitch (nose up positive), yaw (clockwise from north),
    /// rad.
    pub attitude: [f64; 3],
}

/// The quaternion (w, x, y, z; local NED to body FRD, as MAVLink's attitude messages carry it)
/// of roll, pitch and yaw (rad).
pub fn quaternion([roll, pitch, yaw]: [f64; 3]) -> [f64; 4] {
    let (sr, cr) = (0.5 * roll).sin_cos();
    let (sp, cp) = (0.5 * pitch).sin_cos();
    let (sy, cy) = (0.5 * yaw).sin_cos();
    [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]
}

/// Roll, pitch and yaw (rad) of quaternion `q` (w, x, y, z), normalised first; None when it is
/// not a rotation (a non-finite or near-zero quaternion).
pub fn euler(q: [f64; 4]) -> Option<[f64; 3]> {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(n.is_finite() && n > 0.5) {
        return None;
    }
    let [w, x, y, z] = q.map(|v| v / n);
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    Some([roll, pitch, yaw])
}

/// The method's world frame in the autopilot's local NED frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Frame {
    /// The method's origin in local NED (m).
    pub origin_ned: [f64; 3],
    /// The direction of the method's x axis, clockwise from north (rad).
    pub course_rad: f64,
}

impl Frame {
    /// Horizontal NED components (north, east) of a vector with the method's (x, y).
    fn horizontal_ned(&self, x: f64, y: f64) -> (f64, f64) {
        let (s, c) = self.course_rad.sin_cos();
        // x along the course; y to its left (a quarter turn counter-clockwise seen from above).
        (c * x + s * y, s * x - c * y)
    }

    /// The method's (x, y) of a vector with NED components (north, east).
    fn horizontal_xy(&self, n: f64, e: f64) -> (f64, f64) {
        let (s, c) = self.course_rad.sin_cos();
        (c * n + s * e, s * n - c * e)
    }

    /// The method's state of a vehicle seen in local NED.
    pub fn state(&self, ned: &Ned) -> State9 {
        let [n, e, d] = ned.position;
        let (x, y) = self.horizontal_xy(n - self.origin_ned[0], e - self.origin_ned[1]);
        let [vn, ve, vd] = ned.velocity;
        let (vx, vy) = self.horizontal_xy(vn, ve);
        let [roll, pitch, yaw] = ned.attitude;
        let mut s = State9::zeros();
        (s[state::X], s[state::Y], s[state::Z]) = (x, y, self.origin_ned[2] - d);
        (s[state::VX], s[state::VY], s[state::VZ]) = (vx, vy, -vd);
        s[state::ALPHA] = wrap_pi(pitch);
        s[state::BETA] = wrap_pi(self.course_rad - yaw);
        s[state::GAMMA] = wrap_pi(roll);
        s
    }

    /// A state of the method in local NED.
    pub fn ned(&self, s: &State9) -> Ned {
        let (dn, de) = self.horizontal_ned(s[state::X], s[state::Y]);
        let (vn, ve) = self.horizontal_ned(s[state::VX], s[state::VY]);
        Ned {
            position: [self.origin_ned[0] + dn, self.origin_ned[1] + de, self.origin_ned[2] - s[state::Z]],
            velocity: [vn, ve, -s[state::VZ]],
            attitude: [s[state::GAMMA], s[state::ALPHA], wrap_pi(self.course_rad - s[state::BETA])],
        }
    }

    /// A velocity of the method's frame (x, y, z) in NED (north, east, down).
    pub fn velocity_ned(&self, v: [f64; 3]) -> [f64; 3] {
        let (n, e) = self.horizontal_ned(v[0], v[1]);
        [n, e, -v[2]]
    }

    /// A velocity in NED (north, east, down) in the method's frame (x, y, z).
    pub fn velocity_xyz(&self, v: [f64; 3]) -> [f64; 3] {
        let (x, y) = self.horizontal_xy(v[0], v[1]);
        [x, y, -v[2]]
    }

    /// The method's yaw β of a NED yaw (clockwise from north), and back (the map is its own
    /// inverse).
    pub fn yaw(&self, yaw: f64) -> f64 {
        wrap_pi(self.course_rad - yaw)
    }
}

/// Where local NED (0, 0, 0) is on the earth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeoOrigin {
    /// Latitude (rad).
    pub lat_rad: f64,
    /// Longitude (rad).
    pub lon_rad: f64,
    /// Altitude above mean sea level (m).
    pub alt_m: f64,
}

/// A geodetic position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geo {
    /// Latitude (rad).
    pub lat_rad: f64,
    /// Longitude (rad).
    pub lon_rad: f64,
    /// Altitude above mean sea level (m).
    pub alt_m: f64,
}

impl GeoOrigin {
    /// The origin at `lat_deg`, `lon_deg` (degrees) and `alt_m`.
    pub fn from_degrees(lat_deg: f64, lon_deg: f64, alt_m: f64) -> Self {
        Self { lat_rad: lat_deg.to_radians(), lon_rad: lon_deg.to_radians(), alt_m }
    }

    /// The geodetic position of local NED `p`.
    pub fn geo(&self, p: [f64; 3]) -> Geo {
        let (x, y) = (p[0] / EARTH_RADIUS_M, p[1] / EARTH_RADIUS_M);
        let c = x.hypot(y);
        let (sin_ref, cos_ref) = self.lat_rad.sin_cos();
        let (lat, lon) = if c > 0.0 {
            let (sin_c, cos_c) = c.sin_cos();
            let lat = (cos_c * sin_ref + x * sin_c * cos_ref / c).clamp(-1.0, 1.0).asin();
            let lon = self.lon_rad + (y * sin_c).atan2(c * cos_ref * cos_c - x * sin_ref * sin_c);
            (lat, lon)
        } else {
            (self.lat_rad, self.lon_rad)
        };
        Geo { lat_rad: lat, lon_rad: wrap_pi(lon), alt_m: self.alt_m - p[2] }
    }

    /// The local NED position of `g`.
    pub fn ned(&self, g: &Geo) -> [f64; 3] {
        let (sin_ref, cos_ref) = self.lat_rad.sin_cos();
        let (sin_lat, cos_lat) = g.lat_rad.sin_cos();
        let d_lon = wrap_pi(g.lon_rad - self.lon_rad);
        let cos_d_lon = d_lon.cos();
        let arg = (sin_ref * sin_lat + cos_ref * cos_lat * cos_d_lon).clamp(-1.0, 1.0);
        let c = arg.acos();
        let k = if c > 0.0 { c / c.sin() } else { 1.0 };
        let n = k * (cos_ref * sin_lat - sin_ref * cos_lat * cos_d_lon) * EARTH_RADIUS_M;
        let e = k * cos_lat * d_lon.sin() * EARTH_RADIUS_M;
        [n, e, self.alt_m - g.alt_m]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn axes_map_as_written() {
        // x along a course due east: x is east, y (left) is north, z is up.
        let f = Frame { origin_ned: [10.0, 20.0, -100.0], course_rad: std::f64::consts::FRAC_PI_2 };
        let mut s = State9::zeros();
        (s[state::X], s[state::Y], s[state::Z]) = (1.0, 2.0, 3.0);
        (s[state::VX], s[state::VY], s[state::VZ]) = (4.0, 5.0, 6.0);
        s[state::BETA] = 0.1; // 0.1 rad to the left of east: yaw (from north, clockwise) π/2 − 0.1
        s[state::ALPHA] = 0.2;
        s[state::GAMMA] = -0.3;
        let n = f.ned(&s);
        let want = [10.0 + 2.0, 20.0 + 1.0, -100.0 - 3.0];
        for k in 0..3 {
            assert!(close(n.position[k], want[k], 1e-12), "{n:?}");
        }
        assert!(
            close(n.velocity[0], 5.0, 1e-12) && close(n.velocity[1], 4.0, 1e-12) && close(n.velocity[2], -6.0, 1e-12)
        );
        assert!(close(n.attitude[2], std::f64::consts::FRAC_PI_2 - 0.1, 1e-12));
        assert_eq!((n.attitude[0], n.attitude[1]), (-0.3, 0.2));
        // Due north: y (left) is west.
        let north = Frame::default();
        let n = north.ned(&s);
        assert!(close(n.position[0], 1.0, 1e-12) && close(n.position[1], -2.0, 1e-12));
    }

    #[test]
    fn both_ways_give_the_state_back() {
        for (i, course) in [0.0, 0.7, -2.9, 3.1].into_iter().enumerate() {
            let f = Frame { origin_ned: [-5.0 * i as f64, 3.0, -50.0], course_rad: course };
            let mut s = State9::zeros();
            for k in 0..9 {
                s[k] = ((k + 1) as f64 * 1.37 + i as f64).sin() * if k < 6 { 300.0 } else { 1.0 };
            }
            let back = f.state(&f.ned(&s));
            let d = state::difference(&back, &s);
            assert!(d.amax() < 1e-9, "course {course}: {d:?}");
            assert!(close(f.yaw(f.yaw(0.4)), 0.4, 1e-12));
            let v = f.velocity_xyz(f.velocity_ned([3.0, -4.0, 5.0]));
            assert!((0..3).all(|k| close(v[k], [3.0, -4.0, 5.0][k], 1e-12)), "{v:?}");
        }
    }

    #[test]
    fn geodetic_positions_round_trip_and_measure_true_distances() {
        let o = GeoOrigin::from_degrees(47.397742, 8.545594, 488.0);
        for p in [[0.0, 0.0, 0.0], [1000.0, -250.0, -80.0], [-7000.0, 3000.0, 20.0], [0.01, 0.01, 0.0]] {
            let g = o.geo(p);
            let back = o.ned(&g);
            for k in 0..3 {
                assert!(close(back[k], p[k], 1e-6), "{p:?} -> {back:?}");
            }
        }
        // 1000 m north is 1000 m along the meridian: Δlat = 1000 / R.
        let g = o.geo([1000.0, 0.0, 0.0]);
        assert!(close(g.lat_rad - o.lat_rad, 1000.0 / EARTH_RADIUS_M, 1e-12));
        assert!(close(g.lon_rad, o.lon_rad, 1e-15));
        // 1000 m east at 47.4° N: Δlon ≈ 1000 / (R cos lat).
        let g = o.geo([0.0, 1000.0, 0.0]);
        let want = 1000.0 / (EARTH_RADIUS_M * o.lat_rad.cos());
        assert!(close(g.lon_rad - o.lon_rad, want, want * 1e-6));
        assert!(close(o.geo([0.0, 0.0, -30.0]).alt_m, 518.0, 1e-12));
        // Across the antimeridian.
        let o = GeoOrigin::from_degrees(-16.5, 179.9995, 0.0);
        let p = [100.0, 200.0, -1.0];
        let back = o.ned(&o.geo(p));
        assert!((0..3).all(|k| close(back[k], p[k], 1e-6)), "{back:?}");
    }

    #[test]
    fn a_quaternion_carries_roll_pitch_and_yaw_both_ways() {
        for a in [[0.0, 0.0, 0.0], [0.2, -0.3, 1.0], [-0.5, 0.4, -2.5], [0.1, 0.05, 3.0]] {
            let back = euler(quaternion(a)).expect("a rotation");
            for k in 0..3 {
                assert!(wrap_pi(back[k] - a[k]).abs() < 1e-12, "{a:?} -> {back:?}");
            }
        }
        // Scaled, it is the same rotation; zero or NaN is none.
        let q = quaternion([0.2, -0.3, 1.0]).map(|v| 3.0 * v);
        assert!((euler(q).expect("a rotation")[1] + 0.3).abs() < 1e-12);
        assert!(euler([0.0; 4]).is_none() && euler([f64::NAN, 0.0, 0.0, 1.0]).is_none());
    }
}
