//! Waypoints (relative to the start) turned into straight legs joined by turns of a radius.

use super::Segment;

/// A waypoint list that cannot be flown.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct WaypointError {
    /// The point (from 1) at fault, if one is.
    pub point: Option<usize>,
    /// What is wrong.
    pub message: String,
}

/// Turns waypoints (relative to the start) into straight legs joined by turns of radius `r`
/// at speed `v`; returns the segments and the initial course. Each leg's height change is
/// flown as a constant climb over its straight part. Turn rates blend in over `transition_s`,
/// which delays a turn by half of it; each turn therefore starts that much earlier.
pub fn waypoint_segments(
    points: &[[f64; 3]],
    v: f64,
    r: f64,
    transition_s: f64,
) -> Result<(Vec<Segment>, f64), WaypointError> {
    if points.is_empty() {
        return Err(WaypointError { point: None, message: "needs at least one point".into() });
    }
    let mut all = vec![[0.0f64; 3]];
    for (k, p) in points.iter().enumerate() {
        // A list that starts with the start itself, [0, 0, 0], names it twice.
        if k == 0 && *p == [0.0; 3] && points.len() > 1 {
            continue;
        }
        all.push(*p);
    }
    let legs: Vec<(f64, f64, f64)> = all
        .windows(2)
        .map(|w| {
            let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            (dx.hypot(dy), dy.atan2(dx), w[1][2] - w[0][2])
        })
        .collect();
    if let Some(k) = legs.iter().position(|l| l.0 < 1e-6) {
        return Err(WaypointError {
            point: Some(k + 1),
            message: "repeats the previous point (legs need a horizontal length)".into(),
        });
    }
    // Turn at each inner waypoint: course change, and the tangent length it takes off each leg.
    let turns: Vec<f64> = legs.windows(2).map(|w| proxform_core::angle::wrap_pi(w[1].1 - w[0].1)).collect();
    let cut = |k: usize| -> f64 { turns.get(k).map_or(0.0, |d| r * (d.abs() / 2.0).tan()) };
    let mut segments = Vec::new();
    let lead = 0.5 * transition_s * v;
    for (k, leg) in legs.iter().enumerate() {
        let before = if k == 0 { 0.0 } else { cut(k - 1) };
        let straight = leg.0 - before - cut(k);
        // Start the next turn early by the blend's delay, and end this leg's part late by it.
        let shift = |k: usize| if turns.get(k).is_some_and(|d| d.abs() > 1e-9) { lead } else { 0.0 };
        let straight = straight - shift(k) + if k == 0 { 0.0 } else { shift(k - 1) };
        if straight < -1e-6 {
            return Err(WaypointError {
                point: Some(k + 1),
                message: format!("leg {} is too short for turns of radius {r} m at its ends", k + 1),
            });
        }
        let t = straight.max(0.0) / v;
        if t > 1e-9 {
            segments.push(Segment { duration_s: t, turn_rate_radps: 0.0, climb_mps: leg.2 / t, end_speed_mps: v });
        } else if leg.2.abs() > 1e-9 {
            return Err(WaypointError { point: Some(k + 1), message: "has no straight part to climb on".into() });
        }
        if let Some(d) = turns.get(k) {
            if d.abs() > 1e-9 {
                let w = d.signum() * v / r;
                segments.push(Segment {
                    duration_s: d.abs() / (v / r),
                    turn_rate_radps: w,
                    climb_mps: 0.0,
                    end_speed_mps: v,
                });
            }
        }
    }
    Ok((segments, legs[0].1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::SegmentsPath;
    use proxform_core::angle::kmh;
    use proxform_core::state;

    #[test]
    fn waypoints_become_legs_and_turns_of_the_given_radius() {
        let v = kmh(200.0);
        let (segs, course) =
            waypoint_segments(&[[2000.0, 0.0, 0.0], [2000.0, 2000.0, 100.0]], v, 300.0, 2.0).expect("valid");
        assert_eq!(course, 0.0);
        // Straight 1700 m (less the blend's lead), a 90° left turn at v/300 rad/s, straight
        // 1700 m climbing 100 m.
        assert_eq!(segs.len(), 3);
        assert!((segs[0].duration_s - (1700.0 / v - 1.0)).abs() < 1e-9);
        assert!((segs[1].turn_rate_radps * segs[1].duration_s - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((segs[2].climb_mps * segs[2].duration_s - 100.0).abs() < 1e-9);
        let path = SegmentsPath::new(v, course, segs, 2.0, 200.0);
        let end = path.state_at(100.0, [0.0; 3]);
        assert!((end[state::BETA] - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((end[0] - 2000.0).abs() < 15.0, "x {}", end[0]);
        assert!(waypoint_segments(&[[100.0, 0.0, 0.0], [100.0, 100.0, 0.0]], v, 300.0, 2.0).is_err(), "legs too short");
        // The start may be listed as the first point.
        let with_start = [[0.0, 0.0, 0.0], [2000.0, 0.0, 0.0], [2000.0, 2000.0, 100.0]];
        assert_eq!(
            waypoint_segments(&with_start, v, 300.0, 2.0).expect("valid").0,
            waypoint_segments(&with_start[1..], v, 300.0, 2.0).expect("valid").0
        );
    }
}
