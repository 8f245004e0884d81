//! Formation parameters (METHOD §4, the paper's eq. 5-7).
//!
//! A formation is a slot per UAV: a position offset `d_i` in the formation frame (forward,
//! left, up; m) and an attitude offset `a_i` (rad, normally zero). The formation control
//! parameter vector of i with respect to j is `W_ij = [R_f(d_i − d_j); 0; a_i − a_j]`.

use nalgebra::Vector3;

use crate::error::ConfigError;
use crate::observation::UavId;
use crate::state::{self, State9};
use crate::vehicle::G;

/// One UAV's place in the formation.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FormationSlot {
    /// Offset d_i in the formation frame: forward, left, up (m).
    pub offset_m: Vector3<f64>,
    /// Attitude offset a_i: pitch, yaw, roll (rad). Default zero: one common attitude.
    pub attitude_offset_rad: Vector3<f64>,
}

impl FormationSlot {
    /// A slot at `offset_m` with no attitude offset.
    pub fn at(forward: f64, left: f64, up: f64) -> Self {
        Self { offset_m: Vector3::new(forward, left, up), attitude_offset_rad: Vector3::zeros() }
    }
}

/// How the formation frame is oriented in the world (METHOD §4 Choice).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FormationFrame {
    /// `R_f = I`: the formation frame is the world frame (the paper's straight flight).
    #[default]
    World,
    /// `R_f` is the yaw rotation by the formation's course, taken as the horizontal direction
    /// of travel of the reference UAV, so the formation turns with its course.
    Course,
    /// `R_f` is the yaw rotation by the reference UAV's heading (its nose, β): the formation
    /// turns with the noses, which stay parallel, and keeps its shape while hovering (a
    /// multirotor's frame: its nose need not follow its course).
    Heading,
}

impl FormationFrame {
    /// Cosine and sine of the frame's yaw: from the reference's horizontal velocity (no
    /// trigonometric call; a reference with no horizontal speed keeps the world frame) or from
    /// its heading.
    #[inline]
    pub fn course_cos_sin(self, reference: &State9) -> (f64, f64) {
        match self {
            FormationFrame::World => (1.0, 0.0),
            FormationFrame::Heading => {
                let (s, c) = reference[state::BETA].sin_cos();
                (c, s)
            }
            FormationFrame::Course => {
                let (vx, vy) = (reference[state::VX], reference[state::VY]);
                let h = vx.hypot(vy);
                if h > 1e-9 {
                    (vx / h, vy / h)
                } else {
                    (1.0, 0.0)
                }
            }
        }
    }
}

/// The whole formation: one slot per UAV, indexed by [`UavId`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Formation {
    /// Slots, `slots[id]`.
    pub slots: Vec<FormationSlot>,
    /// Orientation of the formation frame.
    pub frame: FormationFrame,
}

impl Formation {
    /// Builds a formation after checking every offset is finite.
    pub fn new(slots: Vec<FormationSlot>, frame: FormationFrame) -> Result<Self, ConfigError> {
        for s in &slots {
            for v in s.offset_m.iter().chain(s.attitude_offset_rad.iter()) {
                if !v.is_finite() {
                    return Err(ConfigError::OutOfRange {
                        field: "formation offset",
                        value: *v,
                        expected: "finite offsets",
                    });
                }
            }
        }
        Ok(Self { slots, frame })
    }

    /// Number of slots.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True when there are no slots.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The slot of `id`, if it is in the formation.
    pub fn slot(&self, id: UavId) -> Option<&FormationSlot> {
        self.slots.get(id.index())
    }

    /// Adds `W_ij` to `x` in place (the position and attitude rows; the velocity rows are 0).
    #[inline]
    pub fn add_w(&self, i: &FormationSlot, j: &FormationSlot, reference: &State9, x: &mut State9) {
        let (c, s) = self.frame.course_cos_sin(reference);
        add_w_rotated(i, j, c, s, x);
    }

    /// `W_ij` in a formation that turns as one rigid body about the vertical at `omega` (rad/s,
    /// counter-clockwise positive; the reference's turn rate, [`crate::VehicleModel::turn_rate`]):
    /// adds to `x` the position, velocity and attitude parts. Relative to j, i's slot is at
    /// `R_f(d_i − d_j)` and moves at `ω × R_f(d_i − d_j)`.
    ///
    /// In a [`FormationFrame::Course`] frame (vehicles whose velocity follows their attitude,
    /// the fixed wing) j does not fly along the formation's course in the turn: its velocity is
    /// the course velocity plus `ω × d_j` (d_j from the formation's origin), so the course is
    /// j's heading turned back by the angle that adds; i heads along its own velocity and banks
    /// for the same ω at its own speed. In a [`FormationFrame::Heading`] frame the noses stay
    /// parallel (the attitude part is `a_i − a_j`). In a [`FormationFrame::World`] frame, or in
    /// a course frame behind a reference slower than 1 m/s, this is [`Self::add_w`].
    #[inline]
    pub fn add_w_turning(&self, i: &FormationSlot, j: &FormationSlot, reference: &State9, omega: f64, x: &mut State9) {
        let (vx, vy) = (reference[state::VX], reference[state::VY]);
        let v = vx.hypot(vy);
        match self.frame {
            FormationFrame::World => {
                self.add_w(i, j, reference, x);
                return;
            }
            FormationFrame::Heading => {
                let (c, s) = self.frame.course_cos_sin(reference);
                add_w_rotated(i, j, c, s, x);
                let d = i.offset_m - j.offset_m;
                let (rx, ry) = (c * d.x - s * d.y, s * d.x + c * d.y);
                x[state::VX] -= omega * ry;
                x[state::VY] += omega * rx;
                return;
            }
            FormationFrame::Course if v < 1.0 => {
                self.add_w(i, j, reference, x);
                return;
            }
            FormationFrame::Course => {}
        }
        // j's velocity in the formation frame is (√(v² − a²), a), a = ω·d_j,forward.
        let a = omega * j.offset_m.x;
        let (cphi, sphi) = if a.abs() < v { ((v * v - a * a).sqrt() / v, a / v) } else { (1.0, 0.0) };
        let (cpsi, spsi) = (vx / v, vy / v);
        let (c, s) = (cpsi * cphi + spsi * sphi, spsi * cphi - cpsi * sphi);
        add_w_rotated(i, j, c, s, x);
        let d = i.offset_m - j.offset_m;
        let (rx, ry) = (c * d.x - s * d.y, s * d.x + c * d.y);
        let (dvx, dvy) = (-omega * ry, omega * rx);
        x[state::VX] += dvx;
        x[state::VY] += dvy;
        // i's heading relative to j's, and the bank for ω at i's speed.
        let (wx, wy) = (vx + dvx, vy + dvy);
        let w = wx.hypot(wy);
        if w >= 1.0 {
            x[state::BETA] += (vx * wy - vy * wx).atan2(vx * wx + vy * wy);
            x[state::GAMMA] += (-omega * w / G).atan() - reference[state::GAMMA];
        }
    }

    /// Adds `W_ij` to `x`: [`Self::add_w_turning`] at the turn rate `turn` when there is one
    /// (the controllers' `turn_feedforward`), else [`Self::add_w`]. The controllers and the
    /// error metric choose here, so they use the same W.
    #[inline]
    pub fn add_w_with(
        &self,
        turn: Option<f64>,
        i: &FormationSlot,
        j: &FormationSlot,
        reference: &State9,
        x: &mut State9,
    ) {
        match turn {
            Some(omega) => self.add_w_turning(i, j, reference, omega, x),
            None => self.add_w(i, j, reference, x),
        }
    }

    /// `W_ij` (eq. 7) for slots i and j, with `R_f` from the reference state `reference`
    /// (the observed j for [`FormationFrame::Course`]).
    #[inline]
    pub fn w(&self, i: &FormationSlot, j: &FormationSlot, reference: &State9) -> State9 {
        let mut w = State9::zeros();
        self.add_w(i, j, reference, &mut w);
        w
    }
}

/// Adds the position and attitude rows of `W_ij` to `x`, with `R_f` the yaw rotation of
/// cosine `c` and sine `s`.
#[inline]
fn add_w_rotated(i: &FormationSlot, j: &FormationSlot, c: f64, s: f64, x: &mut State9) {
    let d = i.offset_m - j.offset_m;
    x[state::X] += c * d.x - s * d.y;
    x[state::Y] += s * d.x + c * d.y;
    x[state::Z] += d.z;
    let da = i.attitude_offset_rad - j.attitude_offset_rad;
    x[state::ALPHA] += da.x;
    x[state::BETA] += da.y;
    x[state::GAMMA] += da.z;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::angle::deg;
    use approx::assert_relative_eq;

    fn two() -> (FormationSlot, FormationSlot) {
        (FormationSlot::at(0.0, 0.0, 0.0), FormationSlot::at(-86.6, 50.0, -10.0))
    }

    #[test]
    fn w_is_the_offset_difference_in_the_world_frame() {
        let (a, b) = two();
        let f = Formation::new(vec![a, b], FormationFrame::World).expect("finite");
        let w = f.w(&b, &a, &State9::zeros());
        assert_relative_eq!(w, State9::from_column_slice(&[-86.6, 50.0, -10.0, 0., 0., 0., 0., 0., 0.]));
        // W_ji = −W_ij.
        assert_relative_eq!(f.w(&a, &b, &State9::zeros()), -w);
    }

    #[test]
    fn course_frame_rotates_offsets_with_the_course() {
        let (a, b) = two();
        let f = Formation::new(vec![a, b], FormationFrame::Course).expect("finite");
        let mut reference = State9::zeros();
        reference[state::VY] = 10.0; // flying along +y: course 90°
        let w = f.w(&b, &a, &reference);
        // forward −86.6 now points along −y, left 50 along −x.
        assert_relative_eq!(w[0], -50.0, epsilon = 1e-9);
        assert_relative_eq!(w[1], -86.6, epsilon = 1e-9);
        assert_relative_eq!(w[2], -10.0, epsilon = 1e-9);
    }

    /// The state of the slot at `d` (forward, left, up from the formation's origin) in a
    /// steady level coordinated turn at rate `omega` (rad/s, counter-clockwise > 0), with the
    /// formation's course `psi` and the origin at `(0, 0, 0)` flying at `v_f`.
    fn in_turn(d: Vector3<f64>, psi: f64, omega: f64, v_f: f64) -> State9 {
        let (s, c) = psi.sin_cos();
        let mut x = State9::zeros();
        x[0] = c * d.x - s * d.y;
        x[1] = s * d.x + c * d.y;
        x[2] = d.z;
        // Velocity: the course velocity plus ω × r.
        x[3] = v_f * c - omega * x[1];
        x[4] = v_f * s + omega * x[0];
        let speed = x[3].hypot(x[4]);
        x[state::BETA] = x[4].atan2(x[3]);
        x[state::GAMMA] = (-omega * speed / G).atan();
        x
    }

    #[test]
    fn a_turning_formation_gives_every_slot_its_state_in_the_turn() {
        let lead = FormationSlot::at(0.0, 0.0, 0.0);
        let left = FormationSlot::at(-80.0, 60.0, -5.0);
        let right = FormationSlot::at(-160.0, -120.0, 0.0);
        let f = Formation::new(vec![lead, left, right], FormationFrame::Course).expect("finite");
        let (psi, v_f) = (deg(40.0), 55.0);
        for omega in [0.1, -0.08, 0.0] {
            let truth: Vec<State9> = f.slots.iter().map(|s| in_turn(s.offset_m, psi, omega, v_f)).collect();
            for (i, si) in f.slots.iter().enumerate() {
                for (j, sj) in f.slots.iter().enumerate() {
                    // From j's true state, W gives i's true state: position, velocity, heading
                    // and bank, although j itself does not fly along the course.
                    let mut x = truth[j];
                    f.add_w_turning(si, sj, &truth[j], omega, &mut x);
                    for k in 0..9 {
                        assert_relative_eq!(x[k], truth[i][k], epsilon = 1e-9);
                    }
                }
            }
        }
        // A world-fixed formation does not turn: W is the plain offset.
        let fixed = Formation::new(f.slots.clone(), FormationFrame::World).expect("finite");
        let reference = in_turn(right.offset_m, psi, 0.1, v_f);
        let (mut x, mut y) = (State9::zeros(), State9::zeros());
        fixed.add_w_turning(&left, &right, &reference, 0.1, &mut x);
        fixed.add_w(&left, &right, &reference, &mut y);
        assert_eq!(x, y);
    }

    #[test]
    fn a_heading_frame_turns_with_parallel_noses_and_holds_its_shape_in_a_hover() {
        let lead = FormationSlot::at(0.0, 0.0, 0.0);
        let wing = FormationSlot::at(-10.0, 8.0, 0.0);
        let f = Formation::new(vec![lead, wing], FormationFrame::Heading).expect("finite");
        // The lead hovers with its nose at 90°: the wing's slot is 10 m along −y, 8 m along −x.
        let mut hover = State9::zeros();
        hover[state::BETA] = deg(90.0);
        let w = f.w(&wing, &lead, &hover);
        assert_relative_eq!(w[0], -8.0, epsilon = 1e-9);
        assert_relative_eq!(w[1], -10.0, epsilon = 1e-9);
        // Turning at ω about the lead, the wing's slot moves at ω × r; its nose stays parallel.
        let (omega, mut x) = (0.2, hover);
        x[state::VX] = -5.0;
        f.add_w_turning(&wing, &lead, &hover, omega, &mut x);
        assert_relative_eq!(x[state::VX], -5.0 - omega * -10.0, epsilon = 1e-9);
        assert_relative_eq!(x[state::VY], omega * -8.0, epsilon = 1e-9);
        assert_eq!(x[state::BETA], hover[state::BETA]);
        assert_eq!(x[state::GAMMA], 0.0);
    }

    #[test]
    fn attitude_offsets_enter_w() {
        let a = FormationSlot::at(0.0, 0.0, 0.0);
        let mut b = FormationSlot::at(0.0, 10.0, 0.0);
        b.attitude_offset_rad.y = deg(2.0);
        let f = Formation::new(vec![a, b], FormationFrame::World).expect("finite");
        assert_relative_eq!(f.w(&b, &a, &State9::zeros())[state::BETA], deg(2.0));
    }

    #[test]
    fn rejects_non_finite_offsets() {
        let err = Formation::new(vec![FormationSlot::at(f64::NAN, 0.0, 0.0)], FormationFrame::World);
        assert!(err.is_err());
    }
}
