//! Formation generators: the usual shapes as slot offsets (forward, left, up; m).
//!
//! UAV 1 (index 0) leads at the origin and the others follow in a fixed order, so that a
//! generated formation numbers its UAVs predictably: arms alternate left then right, rows run
//! from left to right.

use std::f64::consts::{FRAC_1_SQRT_2, TAU};

use proxform_core::FormationSlot;

/// A formation shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// The paper's multi-level triangle: row r holds r + 1 UAVs `spacing` apart, rows
    /// `spacing·cos 30°` apart, each `level_step` higher than the one before.
    Triangle {
        /// Rows (row 0 is the leader).
        rows: usize,
        /// Spacing within a row (m).
        spacing: f64,
        /// Height step per row (m).
        level_step: f64,
    },
    /// A V: two arms at `angle` from the course, alternately left and right.
    V {
        /// UAVs.
        uavs: usize,
        /// Spacing along an arm (m).
        spacing: f64,
        /// Half-angle (rad).
        angle: f64,
        /// Height step per rank (m).
        level_step: f64,
    },
    /// An echelon: one arm at `angle` from the course, on the right or the left.
    Echelon {
        /// UAVs.
        uavs: usize,
        /// Spacing (m).
        spacing: f64,
        /// Angle (rad).
        angle: f64,
        /// True for the left side.
        left: bool,
        /// Height step per rank (m).
        level_step: f64,
    },
    /// Side by side, alternately left and right of the leader.
    LineAbreast {
        /// UAVs.
        uavs: usize,
        /// Spacing (m).
        spacing: f64,
        /// Height step per rank (m).
        level_step: f64,
    },
    /// One behind the other.
    Column {
        /// UAVs.
        uavs: usize,
        /// Spacing (m).
        spacing: f64,
        /// Height step per rank (m).
        level_step: f64,
    },
    /// Rows of width 1, 2, …, w, …, 2, 1 on diagonals `spacing` apart.
    Diamond {
        /// UAVs.
        uavs: usize,
        /// Spacing along the diagonals (m).
        spacing: f64,
    },
    /// Rows behind the leader, as square as possible, centred on its track.
    Grid {
        /// UAVs.
        uavs: usize,
        /// Spacing (m).
        spacing: f64,
    },
    /// A multi-level lattice behind the leader (the large-swarm layout, see
    /// [`crate::formation::lattice::lattice_with`]).
    Lattice {
        /// UAVs.
        uavs: usize,
        /// Spacing of rows and columns (m).
        spacing: f64,
        /// Levels.
        levels: usize,
        /// Height step between levels (m).
        level_step: f64,
    },
    /// Evenly on a circle whose front point is the leader.
    Circle {
        /// UAVs.
        uavs: usize,
        /// Radius (m).
        radius: f64,
    },
}

impl Shape {
    /// The slots of the shape.
    pub fn slots(&self) -> Vec<FormationSlot> {
        let mut out = Vec::new();
        let mut push = |x: f64, y: f64, z: f64| out.push(FormationSlot::at(x, y, z));
        match *self {
            Shape::Triangle { rows, spacing, level_step } => {
                let dx = spacing * 3f64.sqrt() / 2.0;
                for r in 0..rows {
                    for j in 0..=r {
                        push(-(r as f64) * dx, (r as f64 / 2.0 - j as f64) * spacing, r as f64 * level_step);
                    }
                }
            }
            Shape::V { uavs, spacing, angle, level_step } => {
                push(0.0, 0.0, 0.0);
                for k in 1..uavs {
                    let rank = k.div_ceil(2) as f64;
                    let side = if k % 2 == 1 { 1.0 } else { -1.0 };
                    push(-rank * spacing * angle.cos(), side * rank * spacing * angle.sin(), rank * level_step);
                }
            }
            Shape::Echelon { uavs, spacing, angle, left, level_step } => {
                let side = if left { 1.0 } else { -1.0 };
                for k in 0..uavs {
                    let rank = k as f64;
                    push(-rank * spacing * angle.cos(), side * rank * spacing * angle.sin(), rank * level_step);
                }
            }
            Shape::LineAbreast { uavs, spacing, level_step } => {
                push(0.0, 0.0, 0.0);
                for k in 1..uavs {
                    let rank = k.div_ceil(2) as f64;
                    let side = if k % 2 == 1 { 1.0 } else { -1.0 };
                    push(0.0, side * rank * spacing, rank * level_step);
                }
            }
            Shape::Column { uavs, spacing, level_step } => {
                for k in 0..uavs {
                    push(-(k as f64) * spacing, 0.0, k as f64 * level_step);
                }
            }
            Shape::Diamond { uavs, spacing } => {
                // Widest row w with w² ≥ uavs (a full diamond of width w holds w² UAVs).
                let w = (uavs as f64).sqrt().ceil() as usize;
                let dx = spacing * FRAC_1_SQRT_2;
                let dy = 2.0 * spacing * FRAC_1_SQRT_2;
                let mut placed = 0;
                for r in 0..(2 * w - 1) {
                    let width = if r < w { r + 1 } else { 2 * w - 1 - r };
                    for j in 0..width {
                        if placed == uavs {
                            break;
                        }
                        push(-(r as f64) * dx, ((width - 1) as f64 / 2.0 - j as f64) * dy, 0.0);
                        placed += 1;
                    }
                }
            }
            Shape::Grid { uavs, spacing } => {
                push(0.0, 0.0, 0.0);
                let cols = ((uavs.saturating_sub(1) as f64).sqrt().ceil() as usize).max(1);
                for k in 0..uavs.saturating_sub(1) {
                    let (r, c) = (k / cols, k % cols);
                    push(-((r + 1) as f64) * spacing, ((cols - 1) as f64 / 2.0 - c as f64) * spacing, 0.0);
                }
            }
            Shape::Lattice { uavs, spacing, levels, level_step } => {
                out = super::lattice::lattice_with(uavs, levels, spacing, level_step);
            }
            Shape::Circle { uavs, radius } => {
                for k in 0..uavs {
                    let a = TAU * k as f64 / uavs as f64;
                    push(radius * (a.cos() - 1.0), radius * a.sin(), 0.0);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn min_distance(s: &[FormationSlot]) -> f64 {
        let mut m = f64::INFINITY;
        for a in 0..s.len() {
            for b in a + 1..s.len() {
                m = m.min((s[a].offset_m - s[b].offset_m).norm());
            }
        }
        m
    }

    #[test]
    fn the_triangle_is_the_papers_layout() {
        let s = Shape::Triangle { rows: 3, spacing: 100.0, level_step: -10.0 }.slots();
        let paper = crate::builtin::paper();
        assert_eq!(s.len(), paper.formation().len());
        for (slot, want) in s.iter().zip(&paper.formation().slots) {
            // The paper rounds 100·cos 30° to 86.6.
            assert_relative_eq!(slot.offset_m.x, want.offset_m.x, epsilon = 0.03);
            assert_relative_eq!(slot.offset_m.y, want.offset_m.y, epsilon = 1e-9);
            assert_relative_eq!(slot.offset_m.z, want.offset_m.z, epsilon = 1e-9);
        }
    }

    #[test]
    fn every_shape_has_its_count_and_spacing() {
        let shapes = [
            Shape::V { uavs: 12, spacing: 60.0, angle: 0.6, level_step: 0.0 },
            Shape::Echelon { uavs: 7, spacing: 60.0, angle: 0.6, left: true, level_step: 0.0 },
            Shape::LineAbreast { uavs: 9, spacing: 60.0, level_step: 0.0 },
            Shape::Column { uavs: 5, spacing: 60.0, level_step: -5.0 },
            Shape::Diamond { uavs: 9, spacing: 60.0 },
            Shape::Diamond { uavs: 7, spacing: 60.0 },
            Shape::Grid { uavs: 10, spacing: 60.0 },
            Shape::Circle { uavs: 8, radius: 200.0 },
        ];
        let counts = [12, 7, 9, 5, 9, 7, 10, 8];
        for (shape, n) in shapes.iter().zip(counts) {
            let s = shape.slots();
            assert_eq!(s.len(), n, "{shape:?}");
            assert_eq!(s[0].offset_m, nalgebra::Vector3::zeros(), "{shape:?}: UAV 1 leads at the origin");
            assert!(
                min_distance(&s) >= 59.9 || matches!(shape, Shape::Circle { .. }),
                "{shape:?}: {}",
                min_distance(&s)
            );
        }
        // Circle: chord between neighbours = 2R sin(π/n).
        let c = Shape::Circle { uavs: 8, radius: 200.0 }.slots();
        assert_relative_eq!(min_distance(&c), 400.0 * (std::f64::consts::PI / 8.0).sin(), epsilon = 1e-9);
    }
}
