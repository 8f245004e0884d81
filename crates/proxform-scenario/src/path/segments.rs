//! A path of segments: turns, climbs and descents at constant rates, and speed changes.
//!
//! The nominal turn and climb rates are constant over each segment. Each change of rate, at a
//! segment boundary, is a cosine ramp *centred* on the boundary, of width `transition_s` (or
//! the segment's own `start_blend_s`; a ramp never starts before t = 0), and the rates are the
//! sum of these ramps. A centred ramp gives back on one side exactly what it takes on the other
//! (`S(u) + S(1 − u) = 1`), so once the ramps around a segment are over, the heading and the
//! height are the nominal ones: a turn segment of rate ω and duration d turns by exactly ω·d,
//! however short it is against the transition (a turn shorter than its ramps is flown more
//! gently, at a lower peak rate). The path starts with the first segment's rates; after the
//! last segment it blends back to straight and level flight and flies on. Speed changes by a
//! cosine ramp over its whole segment.
//!
//! The navigator's attitude follows the path: yaw along the course, pitch along the
//! flight-path angle, roll at the coordinated-turn bank `atan(v·ω/g)`. Heading and height are
//! exact integrals of the rates; horizontal positions are integrated once (Simpson's rule) at
//! knots over the segments' extent, at most [`MAX_KNOTS`] of them whatever the length of the
//! path, and interpolated with cubic Hermite polynomials on the exact velocities. Beyond the
//! last ramp the flight is a straight line in closed form, so memory does not grow with the
//! duration of the flight.

use std::f64::consts::PI;

use proxform_core::state::{self, State9};
use proxform_core::vehicle::G;

use super::Segment;

/// Finest spacing of the position knots (s).
pub const KNOT_STEP_S: f64 = 0.01;
/// Most position knots of a path: longer paths are tabulated more coarsely.
pub const MAX_KNOTS: usize = 1 << 20;

/// A path of segments (see the module's documentation).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SegmentsPath {
    /// Initial horizontal speed (m/s).
    pub start_speed_mps: f64,
    /// Initial course (rad).
    pub start_course_rad: f64,
    /// The segments.
    pub segments: Vec<Segment>,
    /// Longest blend of turn and climb rates at a segment boundary (s).
    pub transition_s: f64,
    #[serde(skip)]
    plan: Plan,
}

/// What is derived once from the segments.
#[derive(Debug, Clone, Default, PartialEq)]
struct Plan {
    /// Start time of each segment, and the end of the last one (s).
    starts: Vec<f64>,
    /// Speed at the start of each segment (m/s).
    speeds: Vec<f64>,
    /// The rate changes: at each segment boundary after t = 0 (and at the end of the last
    /// segment), its time, ramp width, and changes of turn rate and climb rate.
    changes: Vec<Change>,
    /// Prefix sums over the changes: Σ Δ and Σ Δ·T, for turn and climb.
    sums: Vec<[f64; 4]>,
    /// The widest ramp (s).
    widest: f64,
    /// Initial turn and climb rates.
    initial: [f64; 2],
    /// Position knots: time step (s) and horizontal positions (m).
    knot_step: f64,
    knots: Vec<[f64; 2]>,
}

/// One change of rates, centred at `t` over `width` seconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Change {
    t: f64,
    width: f64,
    turn: f64,
    climb: f64,
}

/// `S(u) = ½(1 − cos πu)` on [0, 1], 0 before, 1 after.
fn ramp(u: f64) -> f64 {
    if u <= 0.0 {
        0.0
    } else if u >= 1.0 {
        1.0
    } else {
        0.5 * (1.0 - (PI * u).cos())
    }
}

/// `∫₀^u S`: 0 before the ramp, `u − ½` after it.
fn ramp_integral(u: f64) -> f64 {
    if u <= 0.0 {
        0.0
    } else if u >= 1.0 {
        u - 0.5
    } else {
        0.5 * u - (PI * u).sin() / (2.0 * PI)
    }
}

impl SegmentsPath {
    /// A path from `start_speed_mps` on `start_course_rad` through `segments`, with rate
    /// changes blended over at most `transition_s`.
    pub fn new(start_speed_mps: f64, start_course_rad: f64, segments: Vec<Segment>, transition_s: f64) -> Self {
        let mut p = Self { start_speed_mps, start_course_rad, segments, transition_s, plan: Plan::default() };
        p.plan = p.planned();
        p
    }

    fn planned(&self) -> Plan {
        let mut plan = Plan::default();
        let (mut t, mut v) = (0.0, self.start_speed_mps);
        for s in &self.segments {
            plan.starts.push(t);
            plan.speeds.push(v);
            t += s.duration_s;
            v = s.end_speed_mps;
        }
        plan.starts.push(t);
        plan.speeds.push(v);
        let rates = |k: usize| self.segments.get(k).map_or([0.0, 0.0], |s| [s.turn_rate_radps, s.climb_mps]);
        plan.initial = rates(0);
        for k in 1..=self.segments.len() {
            let (before, after) = (rates(k - 1), rates(k));
            let tk = plan.starts[k];
            let blend = self.segments.get(k).and_then(|s| s.start_blend_s).unwrap_or(self.transition_s);
            // A ramp never starts before the path does.
            let width = blend.clamp(0.0, 2.0 * tk);
            plan.changes.push(Change { t: tk, width, turn: after[0] - before[0], climb: after[1] - before[1] });
        }
        let mut acc = [0.0f64; 4];
        for c in &plan.changes {
            acc = [acc[0] + c.turn, acc[1] + c.turn * c.t, acc[2] + c.climb, acc[3] + c.climb * c.t];
            plan.sums.push(acc);
            plan.widest = plan.widest.max(c.width);
        }
        // Knots over the segments and the last ramps: straight and level beyond.
        let end = plan.changes.iter().map(|c| c.t + 0.5 * c.width).fold(t, f64::max);
        plan.knot_step = KNOT_STEP_S.max(end / (MAX_KNOTS - 3) as f64);
        let count = (end / plan.knot_step).ceil() as usize + 2;
        let mut pos = [0.0f64; 2];
        let h = plan.knot_step;
        let mut this = self.clone();
        this.plan = plan;
        let mut knots = Vec::with_capacity(count);
        knots.push(pos);
        for k in 1..count {
            let t0 = (k - 1) as f64 * h;
            let (a, m, b) = (this.velocity(t0), this.velocity(t0 + 0.5 * h), this.velocity(t0 + h));
            for i in 0..2 {
                pos[i] += h / 6.0 * (a[i] + 4.0 * m[i] + b[i]);
            }
            knots.push(pos);
        }
        this.plan.knots = knots;
        this.plan
    }

    /// The turn rate (`turn`) or climb rate at `t ≥ 0`, and its integral from 0: the initial
    /// rate plus every change's ramp. Changes whose ramps are over contribute `Δ·(t − T)`,
    /// summed by prefix sums; only those within the widest ramp of `t` are evaluated.
    fn rate_and_integral(&self, t: f64, turn: bool) -> (f64, f64) {
        let p = &self.plan;
        let (r0, d, dt) = if turn { (p.initial[0], 0, 1) } else { (p.initial[1], 2, 3) };
        let delta = |c: &Change| if turn { c.turn } else { c.climb };
        // Changes centred before this are over.
        let done = p.changes.partition_point(|c| c.t < t - 0.5 * p.widest);
        let (mut rate, mut integral) = (r0, r0 * t);
        if done > 0 {
            let s = &p.sums[done - 1];
            rate += s[d];
            integral += t * s[d] - s[dt];
        }
        for c in p.changes[done..].iter().take_while(|c| c.t <= t + 0.5 * p.widest) {
            if c.width <= 0.0 {
                if t >= c.t {
                    rate += delta(c);
                    integral += delta(c) * (t - c.t);
                }
                continue;
            }
            let u = (t - c.t + 0.5 * c.width) / c.width;
            rate += delta(c) * ramp(u);
            integral += delta(c) * c.width * ramp_integral(u);
        }
        (rate, integral)
    }

    /// Horizontal speed at `t ≥ 0`: a cosine ramp over each segment to its end speed.
    fn speed(&self, t: f64) -> f64 {
        let p = &self.plan;
        let k = p.starts.partition_point(|&s| s <= t).saturating_sub(1);
        match self.segments.get(k) {
            Some(s) => {
                let u = ((t - p.starts[k]) / s.duration_s).clamp(0.0, 1.0);
                p.speeds[k] + (s.end_speed_mps - p.speeds[k]) * ramp(u)
            }
            None => p.speeds[p.speeds.len() - 1],
        }
    }

    /// Horizontal velocity at `t ≥ 0`.
    fn velocity(&self, t: f64) -> [f64; 2] {
        let (v, (_, turned)) = (self.speed(t), self.rate_and_integral(t, true));
        let course = self.start_course_rad + turned;
        [v * course.cos(), v * course.sin()]
    }

    /// Horizontal position at `t ≥ 0` relative to the start.
    fn position(&self, t: f64) -> [f64; 2] {
        let p = &self.plan;
        let h = p.knot_step;
        let last = p.knots.len() - 1;
        let end = last as f64 * h;
        if t >= end {
            // Straight and level beyond the last ramp.
            let v = self.velocity(end);
            return [p.knots[last][0] + v[0] * (t - end), p.knots[last][1] + v[1] * (t - end)];
        }
        // Cubic Hermite between the knots, on the exact velocities.
        let k = ((t / h).floor() as usize).min(last - 1);
        let t0 = k as f64 * h;
        let s = (t - t0) / h;
        let (a, b) = (p.knots[k], p.knots[k + 1]);
        let (va, vb) = (self.velocity(t0), self.velocity(t0 + h));
        let (h00, h10, h01, h11) = (
            2.0 * s * s * s - 3.0 * s * s + 1.0,
            s * s * s - 2.0 * s * s + s,
            -2.0 * s * s * s + 3.0 * s * s,
            s * s * s - s * s,
        );
        std::array::from_fn(|i| h00 * a[i] + h10 * h * va[i] + h01 * b[i] + h11 * h * vb[i])
    }

    /// The navigator's state at `t` from `start`; before t = 0, straight on at the initial state.
    pub fn state_at(&self, t: f64, start: [f64; 3]) -> State9 {
        if t < 0.0 {
            let mut s = self.state_at(0.0, start);
            for k in 0..3 {
                s[k] += t * s[k + 3];
            }
            return s;
        }
        let v = self.speed(t);
        let (turn, turned) = self.rate_and_integral(t, true);
        let (climb, climbed) = self.rate_and_integral(t, false);
        let course = self.start_course_rad + turned;
        let xy = self.position(t);
        let mut s = State9::zeros();
        s[state::X] = start[0] + xy[0];
        s[state::Y] = start[1] + xy[1];
        s[state::Z] = start[2] + climbed;
        s[state::VX] = v * course.cos();
        s[state::VY] = v * course.sin();
        s[state::VZ] = climb;
        s[state::ALPHA] = climb.atan2(v);
        s[state::BETA] = proxform_core::angle::wrap_pi(course);
        s[state::GAMMA] = -(v * turn / G).atan(); // right wing down is positive: a left turn banks left
        s
    }

    /// Time when the path becomes straight and level for good (s).
    pub fn settled_s(&self) -> f64 {
        let p = &self.plan;
        p.changes.iter().map(|c| c.t + 0.5 * c.width).fold(p.starts[p.starts.len() - 1], f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn seg(d: f64, w_deg: f64, c: f64, v: f64) -> Segment {
        Segment {
            duration_s: d,
            turn_rate_radps: w_deg.to_radians(),
            climb_mps: c,
            end_speed_mps: v,
            start_blend_s: None,
        }
    }

    #[test]
    fn segments_turn_climb_and_change_speed() {
        // A 36 s turn at 5 °/s climbing 2 m/s: 180° and 72 m in all.
        let p = SegmentsPath::new(
            60.0,
            0.0,
            vec![seg(10.0, 0.0, 0.0, 60.0), seg(36.0, 5.0, 2.0, 70.0), seg(10.0, 0.0, 0.0, 70.0)],
            4.0,
        );
        // Straight until the turn's ramp starts at 8 s: 480 m along x.
        assert_relative_eq!(p.state_at(8.0, [0.0; 3])[0], 480.0, epsilon = 1e-6);
        // After the turn's exit ramp the course points along −x, 72 m up.
        let s = p.state_at(50.0, [0.0; 3]);
        assert_relative_eq!(s[state::VX], -70.0, epsilon = 1e-9);
        assert_relative_eq!(s[state::VZ], 0.0, epsilon = 1e-12);
        assert_relative_eq!(s[state::Z], 72.0, epsilon = 1e-9);
        // Positions integrate velocities, on the knots and between them.
        for &t in &[5.0, 9.0, 11.0, 17.3, 33.0, 45.004, 47.0, 80.0] {
            let h = 1e-3;
            let (a, b, s) = (p.state_at(t - h, [0.0; 3]), p.state_at(t + h, [0.0; 3]), p.state_at(t, [0.0; 3]));
            for k in 0..3 {
                assert_relative_eq!((b[k] - a[k]) / (2.0 * h), s[k + 3], epsilon = 1e-4);
            }
        }
        // Banked into the (left) turn.
        assert!(p.state_at(20.0, [0.0; 3])[state::GAMMA] < 0.0);
    }

    #[test]
    fn a_turn_shorter_than_the_transition_turns_by_its_nominal_angle() {
        // 4 s at 2.5 °/s (10°) with an 8 s transition: the ramps overlap, the turn is gentler.
        let p = SegmentsPath::new(70.0, 0.0, vec![seg(60.0, 0.0, 0.0, 70.0), seg(4.0, -2.5, 0.0, 70.0)], 8.0);
        let end = p.state_at(100.0, [0.0; 3]);
        assert_relative_eq!(end[state::BETA], (-10.0f64).to_radians(), epsilon = 1e-12);
        assert_relative_eq!(p.settled_s(), 68.0, epsilon = 1e-12);
        let peak =
            (0..200).map(|k| p.state_at(55.0 + 0.1 * k as f64, [0.0; 3])[state::GAMMA].abs()).fold(0.0, f64::max);
        let full_rate_bank = (70.0 * 2.5f64.to_radians() / G).atan();
        // The ramps centred 4 s apart reach S(¾) − S(¼) = 0.71 of the full rate at most.
        assert!((peak / full_rate_bank - 0.707).abs() < 0.02, "peak bank {peak} vs {full_rate_bank} at the full rate");
    }

    #[test]
    fn a_long_path_stays_small() {
        // Ten days of flight: the knots are capped and the straight end is in closed form.
        let p = SegmentsPath::new(70.0, 0.0, vec![seg(864_000.0, 0.0, 0.0, 70.0), seg(10.0, 9.0, 0.0, 70.0)], 8.0);
        assert!(p.plan.knots.len() <= MAX_KNOTS);
        let s = p.state_at(2e6, [0.0; 3]);
        assert_relative_eq!(s[state::BETA], 90f64.to_radians(), epsilon = 1e-9);
        assert!(s[state::Y] > 7.0e7, "{}", s[state::Y]);
    }
}
