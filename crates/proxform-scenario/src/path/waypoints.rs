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
/// at speed `v`, each blended in and out over `transition_s`;
/// returns the segments and the initial course. Each leg's height change is flown as a
/// constant climb over its straight part. [`waypoint_segments_at`] gives each leg its speed.
pub fn waypoint_segments(
    points: &[[f64; 3]],
    v: f64,
    r: f64,
    transition_s: f64,
) -> Result<(Vec<Segment>, f64), WaypointError> {
    waypoint_segments_at(points, v, None, r, transition_s)
}

/// [`waypoint_segments`] with a speed per leg: the path starts at `v0` and flies leg k at
/// `leg_speeds[k]` (all at `v0` when None). A leg's change of speed is a cosine ramp at the
/// start of its straight part, over `transition_s` (less when the straight is shorter); the
/// turn at the end of a leg is flown at that leg's speed (its rate `v/r`), so the turns keep
/// their radius.
///
/// A turn is a blend in, an arc of radius `r`, and a blend out, symmetric about the corner's
/// bisector. It is placed like a railway transition curve: it leaves the incoming leg and joins
/// the outgoing one exactly, so every leg is flown on its line and the path ends on the last
/// leg's course. Its chord `D` (from where the blend in starts to where the blend out ends) is
/// integrated from the curve's headings; the curve then starts `|D| / (2·cos(θ/2))` before the
/// corner, θ the course change. The path cuts the corner by `r·(1/cos(θ/2) − 1)` plus what the
/// blends add (a blend of W seconds flattens the curve by about `0.024·v²·W²/r`).
pub fn waypoint_segments_at(
    points: &[[f64; 3]],
    v0: f64,
    leg_speeds: Option<&[f64]>,
    r: f64,
    transition_s: f64,
) -> Result<(Vec<Segment>, f64), WaypointError> {
    if points.is_empty() {
        return Err(WaypointError { point: None, message: "needs at least one point".into() });
    }
    let mut all = vec![[0.0f64; 3]];
    // A list that starts with the start itself, [0, 0, 0], names it twice: it is left out,
    // and errors still count the points as written (`point` below).
    let skipped = usize::from(points.len() > 1 && points[0] == [0.0; 3]);
    all.extend_from_slice(&points[skipped..]);
    // The written number (from 1) of `all[j]`.
    let point = |j: usize| Some(j + skipped);
    let legs: Vec<(f64, f64, f64)> = all
        .windows(2)
        .map(|w| {
            let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            (dx.hypot(dy), dy.atan2(dx), w[1][2] - w[0][2])
        })
        .collect();
    if let Some(k) = legs.iter().position(|l| l.0 < 1e-6) {
        return Err(WaypointError {
            point: point(k + 1),
            message: "repeats the previous point (legs need a horizontal length)".into(),
        });
    }
    // Each leg's speed, and the speed before it.
    let speeds: Vec<f64> = match leg_speeds {
        None => vec![v0; legs.len()],
        Some(s) if s.len() == legs.len() => s.to_vec(),
        Some(s) => {
            return Err(WaypointError {
                point: None,
                message: format!("the path has {} legs but {} leg speeds", legs.len(), s.len()),
            })
        }
    };
    let before_leg = |k: usize| if k == 0 { v0 } else { speeds[k - 1] };
    // Each inner waypoint's turn, at the speed of the leg it ends: course change θ, arc time,
    // blend width, and the distance from the corner to where its curve starts (and, by
    // symmetry, ends).
    let mut turns: Vec<Turn> = legs
        .windows(2)
        .zip(&speeds)
        .map(|(w, &v)| Turn::new(proxform_core::angle::wrap_pi(w[1].1 - w[0].1), v, r, transition_s))
        .collect();
    // A waypoint that sends the course straight back has no corner for a turn to cut.
    if let Some(k) = turns.iter().position(|t| t.theta.abs() > std::f64::consts::PI - 1e-9) {
        // Turning around in two corners of 90°, on a side leg as long as their curves (at the
        // faster of the two legs' speeds: the side leg's own is the user's to choose).
        let v = speeds[k].max(speeds[k + 1]);
        let corner = Turn::new(std::f64::consts::FRAC_PI_2, v, r, transition_s);
        let side_m = (2.0 * corner.reach(v)).ceil();
        let w = k + 1 + skipped;
        return Err(WaypointError {
            point: point(k + 1),
            message: format!(
                "waypoint {w} reverses the course (leg {} goes straight back along leg {}): a turn of radius {r} m \
                 rounds a corner, and a reversal has none; fly the way back on a parallel line at least {side_m} m \
                 to one side (a waypoint that far beside waypoint {w}, and the way back from it), so that it turns \
                 around in two corners of 90° (a vehicle that can turn around)",
                k + 2,
                k + 1,
            ),
        });
    }
    for t in turns.iter_mut() {
        t.reach_m = t.reach(t.speed_mps);
    }
    let mut segments = Vec::new();
    for (k, leg) in legs.iter().enumerate() {
        let before = if k == 0 { None } else { turns.get(k - 1) };
        let after = turns.get(k);
        let reach = before.map_or(0.0, |t| t.reach_m) + after.map_or(0.0, |t| t.reach_m);
        if !reach.is_finite() || leg.0 - reach < -1e-6 {
            let needs = match reach.is_finite() {
                true => format!("{} m", reach.ceil()),
                false => "more than any".into(),
            };
            // A hairpin (the sharper of its turns): its curve reaches far along the legs.
            let sharp = [(k, before), (k + 1, after)]
                .into_iter()
                .filter_map(|(w, t)| t.map(|t| (w, t.theta.abs().to_degrees())))
                .filter(|(_, deg)| *deg > 150.0)
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(String::new(), |(w, deg)| {
                    format!(
                        "; waypoint {} turns the course by {deg:.0}°: a hairpin that sharp is flown in two corners, \
                         the way back on a parallel line to one side",
                        w + skipped
                    )
                });
            return Err(WaypointError {
                point: point(k + 1),
                message: format!(
                    "leg {} is {} m long, too short for its turns (radius {r} m, blended over {transition_s} s) at \
                     its ends, which need {needs}{sharp}",
                    k + 1,
                    leg.0.floor()
                ),
            });
        }
        // The leg's segment: its straight part (flown from the speed before it to its own,
        // at their mean over a cosine ramp) plus the halves of the blends that reach into it
        // (the curves of two turns never overlap: each fits its side of the leg), flown at
        // the speeds of their turns.
        let (v_in, v) = (before_leg(k), speeds[k]);
        let straight_m = (leg.0 - reach).max(0.0);
        let half_in = before.map_or(0.0, |t| 0.5 * t.blend_s);
        let half_out = after.map_or(0.0, |t| 0.5 * t.blend_s);
        let blend_in = before.map(|x| x.blend_s);
        if v_in == v {
            let halves = 0.5 * (before.map_or(0.0, |t| t.blend_s) + after.map_or(0.0, |t| t.blend_s));
            let t = straight_m / v + halves;
            if t > 1e-9 {
                segments.push(Segment {
                    duration_s: t,
                    turn_rate_radps: 0.0,
                    climb_mps: leg.2 / t,
                    end_speed_mps: v,
                    start_blend_s: blend_in,
                });
            } else if leg.2.abs() > 1e-9 {
                return Err(WaypointError { point: point(k + 1), message: "has no straight part to climb on".into() });
            }
        } else {
            if straight_m < 1e-6 {
                return Err(WaypointError {
                    point: point(k + 1),
                    message: format!("leg {} has no straight part to change its speed on", k + 1),
                });
            }
            // The blend out of the turn before at its speed, the ramp to the leg's speed over
            // the path's transition (shorter when the straight is), the rest of the straight
            // and the blend into the next turn at the leg's speed; one climb rate over all of
            // them (no rate changes between).
            let ramp_s = transition_s.min(2.0 * straight_m / (v_in + v));
            let rest_s = (straight_m - 0.5 * (v_in + v) * ramp_s).max(0.0) / v;
            let t = half_in + ramp_s + rest_s + half_out;
            let climb = leg.2 / t;
            let pieces = [(half_in, v_in, blend_in), (ramp_s, v, None), (rest_s + half_out, v, None)];
            for (d, end, blend) in pieces {
                if d > 1e-9 {
                    segments.push(Segment {
                        duration_s: d,
                        turn_rate_radps: 0.0,
                        climb_mps: climb,
                        end_speed_mps: end,
                        start_blend_s: blend,
                    });
                }
            }
        }
        if let Some(turn) = after {
            if turn.theta.abs() > 1e-9 {
                segments.push(Segment {
                    duration_s: turn.arc_s,
                    turn_rate_radps: turn.theta.signum() * turn.speed_mps / r,
                    climb_mps: 0.0,
                    end_speed_mps: turn.speed_mps,
                    start_blend_s: Some(turn.blend_s),
                });
            }
        }
    }
    Ok((segments, legs[0].1))
}

/// One turn of a waypoint path.
#[derive(Debug, Clone, Copy)]
struct Turn {
    /// Course change (rad, counter-clockwise positive).
    theta: f64,
    /// Time on the arc at the full turn rate (s).
    arc_s: f64,
    /// Width of the blends in and out (s).
    blend_s: f64,
    /// Distance from the corner to where the curve starts and ends (m).
    reach_m: f64,
    /// Speed through the turn (m/s).
    speed_mps: f64,
}

impl Turn {
    /// A course change `theta` (rad) at speed `v` (m/s) on radius `r` (m), blended over
    /// `blend_s` (s); its reach not yet computed.
    fn new(theta: f64, v: f64, r: f64, blend_s: f64) -> Self {
        Self { theta, arc_s: theta.abs() / (v / r), blend_s, reach_m: 0.0, speed_mps: v }
    }

    /// `|D| / (2·cos(θ/2))`, with D the chord of the blended curve at speed `v`.
    fn reach(&self, v: f64) -> f64 {
        let (w, d) = (self.blend_s, self.arc_s);
        let omega = self.theta / d.max(f64::MIN_POSITIVE);
        // Heading along the curve, τ from the start of the blend in (the blends overlap when
        // the arc is shorter than they are): the rate is
        // ω·S(τ/w) − ω·S((τ − d)/w), its integral ω·w·(I(τ/w) − I((τ − d)/w)) with
        // I(u) = ∫₀^u S, which is u − ½ once the blend is over.
        let integral = |u: f64| {
            if u <= 0.0 {
                0.0
            } else if u >= 1.0 {
                u - 0.5
            } else {
                0.5 * u - (std::f64::consts::PI * u).sin() / (2.0 * std::f64::consts::PI)
            }
        };
        let heading = |tau: f64| {
            if w <= 0.0 {
                omega * tau.clamp(0.0, d)
            } else {
                omega * w * (integral(tau / w) - integral((tau - d) / w))
            }
        };
        // Simpson's rule on a smooth heading: 256 intervals put the chord within micrometres.
        let n = 256;
        let total = d + w;
        let h = total / n as f64;
        let (mut x, mut y) = (0.0, 0.0);
        for k in 0..n {
            let t0 = k as f64 * h;
            let (a, m, b) = (heading(t0), heading(t0 + 0.5 * h), heading(t0 + h));
            x += h / 6.0 * (a.cos() + 4.0 * m.cos() + b.cos());
            y += h / 6.0 * (a.sin() + 4.0 * m.sin() + b.sin());
        }
        v * x.hypot(y) / (2.0 * (self.theta / 2.0).cos())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::SegmentsPath;
    use proxform_core::angle::{kmh, wrap_pi};
    use proxform_core::state;

    #[test]
    fn a_reversal_is_refused_with_a_side_step_that_flies() {
        // Out and back along one line: refused as a reversal, naming the point as written
        // (a leading [0, 0, 0] counted), with the side step that loads; a little less does not.
        for (v_kmh, r, blend) in [(18.0, 30.0, 8.0), (150.0, 300.0, 8.0), (250.0, 800.0, 15.0), (36.0, 20.0, 2.0)] {
            let v = kmh(v_kmh);
            for lead in [false, true] {
                let mut pts = vec![[3000.0, 0.0, 0.0], [0.0, 0.0, 0.0]];
                if lead {
                    pts.insert(0, [0.0; 3]);
                }
                let e = waypoint_segments_at(&pts, v, None, r, blend).expect_err("a reversal");
                assert_eq!(e.point, Some(1 + usize::from(lead)), "{}", e.message);
                assert!(e.message.contains("reverses the course"), "{}", e.message);
                let side: f64 = e
                    .message
                    .split("at least ")
                    .nth(1)
                    .and_then(|m| m.split(' ').next())
                    .and_then(|x| x.parse().ok())
                    .expect("a distance");
                let stepped = |d: f64| {
                    waypoint_segments_at(&[[3000.0, 0.0, 0.0], [3000.0, d, 0.0], [0.0, d, 0.0]], v, None, r, blend)
                };
                assert!(stepped(side).is_ok(), "{side} m at {v_kmh} km/h, r {r} m");
                assert!(stepped(side - 2.0).is_err(), "{side} m at {v_kmh} km/h, r {r} m");
            }
        }
    }

    #[test]
    fn waypoints_become_legs_and_turns_of_the_given_radius() {
        let v = kmh(200.0);
        let (segs, course) =
            waypoint_segments(&[[2000.0, 0.0, 0.0], [2000.0, 2000.0, 100.0]], v, 300.0, 1e-9).expect("valid");
        assert_eq!(course, 0.0);
        // Straight 1700 m, a 90° left turn at v/300 rad/s, straight 1700 m climbing 100 m.
        assert_eq!(segs.len(), 3);
        assert!((segs[0].duration_s - 1700.0 / v).abs() < 1e-9);
        assert!((segs[1].turn_rate_radps * segs[1].duration_s - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((segs[2].climb_mps * segs[2].duration_s - 100.0).abs() < 1e-9);
        let path = SegmentsPath::new(v, course, segs, 2.0);
        let end = path.state_at(100.0, [0.0; 3]);
        assert!((end[state::BETA] - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((end[0] - 2000.0).abs() < 2.0, "x {}", end[0]);
        assert!(waypoint_segments(&[[100.0, 0.0, 0.0], [100.0, 100.0, 0.0]], v, 300.0, 2.0).is_err(), "legs too short");
        // The start may be listed as the first point.
        let with_start = [[0.0, 0.0, 0.0], [2000.0, 0.0, 0.0], [2000.0, 2000.0, 100.0]];
        assert_eq!(
            waypoint_segments(&with_start, v, 300.0, 2.0).expect("valid").0,
            waypoint_segments(&with_start[1..], v, 300.0, 2.0).expect("valid").0
        );
    }

    /// A small deterministic generator.
    struct Lcg(u64);

    impl Lcg {
        fn unit(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.unit()
        }
    }

    #[test]
    fn every_waypoint_is_met_and_the_last_course_is_exact_for_any_radius_and_transition() {
        let mut rng = Lcg(0x5EED_F00D);
        let mut flown = 0;
        let mut with_speeds = 0;
        for case in 0..600 {
            let v = kmh(rng.range(120.0, 330.0));
            let r = rng.range(80.0, 3000.0);
            let transition = rng.range(0.2, 25.0);
            // 2 to 5 legs of 0.5 to 8 km, turning by up to 170°; every other case gives each
            // leg its own speed.
            let mut points = Vec::new();
            let (mut x, mut y, mut course) = (0.0f64, 0.0f64, 0.0f64);
            for _ in 0..(2 + (rng.unit() * 4.0) as usize) {
                let len = rng.range(500.0, 8000.0);
                x += len * course.cos();
                y += len * course.sin();
                points.push([x, y, rng.range(-50.0, 50.0)]);
                course += rng.range(-170.0, 170.0).to_radians();
            }
            let speeds: Vec<f64> = points.iter().map(|_| kmh(rng.range(60.0, 330.0))).collect();
            let leg_speeds = (case % 2 == 1).then_some(&speeds[..]);
            let Ok((segs, c0)) = waypoint_segments_at(&points, v, leg_speeds, r, transition) else { continue };
            flown += 1;
            with_speeds += usize::from(leg_speeds.is_some());
            let path = SegmentsPath::new(v, c0, segs.clone(), transition);
            // The widest blend of the path flattens each curve by at most 0.024·v²·W²/r, v the
            // fastest turn's speed.
            let w = segs.iter().filter_map(|s| s.start_blend_s).fold(0.0, f64::max);
            let v_turns = leg_speeds.map_or(v, |s| s.iter().copied().fold(0.0, f64::max));
            let blend_shift = 0.024 * v_turns * v_turns * w * w / r;
            let end_t = path.settled_s();
            let samples: Vec<State9Pos> = (0..=((end_t + 60.0) / 0.05) as usize)
                .map(|k| {
                    let s = path.state_at(k as f64 * 0.05, [0.0; 3]);
                    [s[0], s[1]]
                })
                .collect();
            let mut all = vec![[0.0, 0.0, 0.0]];
            all.extend(points.iter().copied());
            for (k, p) in points.iter().enumerate() {
                let miss = samples.iter().map(|q| (q[0] - p[0]).hypot(q[1] - p[1])).fold(f64::INFINITY, f64::min);
                // The corner the radius cuts, r·(1/cos(θ/2) − 1) for a course change θ, and the
                // blends' flattening of the curve seen from the corner.
                let corner = if k + 1 < points.len() {
                    let (a, b, c) = (all[k], all[k + 1], all[k + 2]);
                    let theta = wrap_pi((c[1] - b[1]).atan2(c[0] - b[0]) - (b[1] - a[1]).atan2(b[0] - a[0]));
                    let sec = 1.0 / (theta.abs() / 2.0).cos();
                    r * (sec - 1.0) + blend_shift * sec
                } else {
                    0.0
                };
                assert!(
                    miss <= corner + 3.0,
                    "case {case}, waypoint {}: missed by {miss:.1} m, the turn's geometry allows {corner:.1} m",
                    k + 1
                );
            }
            let n = points.len();
            let (a, b) = (all[n - 1], all[n]);
            let last_course = (b[1] - a[1]).atan2(b[0] - a[0]);
            let end = path.state_at(end_t + 10.0, [0.0; 3]);
            assert!(wrap_pi(end[state::BETA] - last_course).abs() < 1e-9, "case {case}: ends on the wrong course");
            // The last leg ends at its own speed, and every turn is flown at its leg's speed
            // on the radius.
            let speed = |s: &proxform_core::state::State9| s[state::VX].hypot(s[state::VY]);
            let v_last = leg_speeds.map_or(v, |s| s[n - 1]);
            assert!((speed(&end) - v_last).abs() < 1e-9, "case {case}: ends at {} m/s, not {v_last}", speed(&end));
            for seg in segs.iter().filter(|s| s.turn_rate_radps != 0.0) {
                let radius = seg.end_speed_mps / seg.turn_rate_radps.abs();
                assert!((radius - r).abs() < 1e-6 * r, "case {case}: a turn of radius {radius} m, not {r}");
            }
        }
        assert!(flown > 200, "only {flown} flyable cases");
        assert!(with_speeds > 80, "only {with_speeds} flyable cases with leg speeds");
    }

    #[test]
    fn leg_speeds_ramp_on_each_straight_and_are_counted() {
        let pts = [[300.0, 0.0, 0.0], [300.0, 300.0, 20.0], [0.0, 300.0, 0.0]];
        let speeds = [5.0, 10.0, 2.5];
        let (segs, c) = waypoint_segments_at(&pts, 5.0, Some(&speeds), 40.0, 4.0).expect("flyable");
        let path = SegmentsPath::new(5.0, c, segs, 4.0);
        let speed_at = |t: f64| {
            let s = path.state_at(t, [0.0; 3]);
            s[state::VX].hypot(s[state::VY])
        };
        // Each leg's middle is flown at its speed or on the way to it, never beyond the two.
        let mut seen = [false; 3];
        for k in 0..4000 {
            let v = speed_at(k as f64 * 0.05);
            assert!((2.5 - 1e-9..=10.0 + 1e-9).contains(&v), "{v} m/s");
            for (a, s) in speeds.iter().enumerate() {
                seen[a] |= (v - s).abs() < 1e-9;
            }
        }
        assert_eq!(seen, [true; 3], "every leg's speed is reached");
        // ... over the transition at the start of the leg: the second leg (x = 300 m, y from
        // about 40 to 260 m) is at its 10 m/s from a transition (4 s, 30 m) after its start.
        let (segs2, c2) = waypoint_segments_at(&pts, 5.0, Some(&speeds), 40.0, 4.0).expect("flyable");
        let p2 = SegmentsPath::new(5.0, c2, segs2, 4.0);
        let mut first_at_speed = None;
        for k in 0..4000 {
            let s = p2.state_at(k as f64 * 0.05, [0.0; 3]);
            if (s[state::VX].hypot(s[state::VY]) - 10.0).abs() < 1e-9 {
                first_at_speed = Some(s[1]);
                break;
            }
        }
        let y = first_at_speed.expect("reached");
        assert!(y < 100.0, "10 m/s first reached at y = {y} m");
        // One speed per leg, or an error that says how many there are.
        let e = waypoint_segments_at(&pts, 5.0, Some(&[5.0, 10.0]), 40.0, 4.0).expect_err("two of three");
        assert!(e.message.contains("3 legs but 2 leg speeds"), "{}", e.message);
        // A leg whose turns leave it no straight part cannot change its speed.
        let tight_at = |l: f64| [[300.0, 0.0, 0.0], [300.0, l, 0.0], [0.0, l, 0.0]];
        // The shortest middle leg its two turns fit on, to within a nanometre.
        let (mut lo, mut hi) = (1.0, 300.0);
        while hi - lo > 1e-9 {
            let mid = 0.5 * (lo + hi);
            if waypoint_segments_at(&tight_at(mid), 5.0, None, 40.0, 4.0).is_ok() {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let tight = tight_at(hi + 2e-7);
        assert!(waypoint_segments_at(&tight, 5.0, None, 40.0, 4.0).is_ok());
        let e = waypoint_segments_at(&tight, 5.0, Some(&[5.0, 6.0, 6.0]), 40.0, 4.0).expect_err("no straight");
        assert_eq!(e.point, Some(2), "{}", e.message);
        // The same speed everywhere is the path without leg speeds, bit for bit.
        assert_eq!(
            waypoint_segments_at(&pts, 5.0, Some(&[5.0; 3]), 40.0, 4.0).expect("flyable"),
            waypoint_segments(&pts, 5.0, 40.0, 4.0).expect("flyable")
        );
    }

    type State9Pos = [f64; 2];
}
