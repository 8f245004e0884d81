//! The built-in large-swarm scenario family.
//!
//! N UAVs in a multi-level lattice behind the navigator: rows of columns 50 m apart on up to
//! four levels 20 m apart, the navigator ahead of the front row's centre. Dependency tables
//! are derived from the geometry ([`crate::autodeps`]); the navigator flies the paper's lateral
//! and speed manoeuvres with gentler attitude sweeps; noise and vehicle are the paper's.

use std::sync::Arc;

use proxform_core::angle::deg;
use proxform_core::{AzimuthAreas, Formation, FormationFrame, FormationSlot, UavId};

use crate::path::{NavigatorPath, PaperPath};
use crate::scenario::{AllowableErrors, Scenario, ScenarioError};

/// Horizontal spacing of the lattice (m).
pub const SPACING_M: f64 = 50.0;
/// Vertical spacing of the levels (m).
pub const LEVEL_M: f64 = 20.0;

/// Dependency degree of every follower on the navigator, heard over the radio. Without it
/// errors grow along the reference chains of a deep lattice (see README, Large swarms).
pub const NAVIGATOR_DEGREE: f64 = 0.3;

/// Levels of the built-in swarm's lattice: 1 below 50 UAVs, 2 below 400, then 4.
pub fn default_levels(n: usize) -> usize {
    if n >= 400 {
        4
    } else if n >= 50 {
        2
    } else {
        1
    }
}

/// The built-in swarm's lattice slots for `n` UAVs; slot 0 is the navigator.
pub fn lattice(n: usize) -> Vec<FormationSlot> {
    lattice_with(n, default_levels(n), SPACING_M, -LEVEL_M)
}

/// `n` UAVs in a multi-level lattice: the navigator ahead of the front row's centre, then
/// rows of columns `spacing` apart behind it on `levels` levels `level_step` apart (negative:
/// lower), filled row by row with the levels innermost.
pub fn lattice_with(n: usize, levels: usize, spacing: f64, level_step: f64) -> Vec<FormationSlot> {
    let levels = levels.max(1);
    let followers = n.saturating_sub(1);
    let per_level = followers.div_ceil(levels);
    let cols = ((per_level as f64).sqrt().ceil() as usize).max(1);
    let mut slots = Vec::with_capacity(n);
    slots.push(FormationSlot::at(0.0, 0.0, 0.0));
    for idx in 0..followers {
        let level = idx % levels;
        let cell = idx / levels;
        let (row, col) = (cell / cols, cell % cols);
        let left = (col as f64 - (cols as f64 - 1.0) / 2.0) * spacing;
        slots.push(FormationSlot::at(-((row + 1) as f64) * spacing, left, level as f64 * level_step));
    }
    slots
}

/// The swarm scenario with `n ≥ 2` UAVs.
pub fn scenario(n: usize) -> Result<Scenario, ScenarioError> {
    if n < 2 {
        return Err(ScenarioError::Shape { what: "number of UAVs", expected: 2, found: n });
    }
    let mut s = Scenario::paper();
    let slots = lattice(n);
    let dependencies = crate::autodeps::derive(&slots, UavId(0), 3, 1.6 * SPACING_M, NAVIGATOR_DEGREE)?;
    let path = PaperPath {
        height_amplitude_m: 10.0,
        pitch_swing_rad: deg(10.0),
        yaw_amplitude_rad: deg(5.0),
        roll_amplitude_rad: deg(10.0),
        ..PaperPath::default()
    };
    let formation = Formation { slots, frame: FormationFrame::World };
    s.initial = crate::scenario::in_slots(&formation, UavId(0), &path.state_at(0.0, [0.0; 3]));
    s.name = "swarm".into();
    s.formation = Arc::new(formation);
    s.dependencies = dependencies;
    s.path = NavigatorPath::Paper(path);
    s.controller.areas = AzimuthAreas { areas: 8, sensing_range_m: 1.6 * SPACING_M };
    s.allowable = AllowableErrors { position_m: [5.0, 5.0, 5.0], attitude_rad: [deg(2.0), deg(2.0), deg(3.0)] };
    s.safety_distance_m = 10.0;
    s.beacons = vec![UavId(0)];
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_has_n_distinct_slots() {
        for n in [2usize, 7, 50, 401, 1000] {
            let l = lattice(n);
            assert_eq!(l.len(), n);
            let mut min = f64::INFINITY;
            for a in 0..n.min(200) {
                for b in a + 1..n {
                    min = min.min((l[a].offset_m - l[b].offset_m).norm());
                }
            }
            assert!(min >= LEVEL_M - 1e-9, "n {n}: slots {min} m apart");
        }
    }

    #[test]
    fn every_follower_has_references() {
        let s = scenario(500).expect("valid");
        s.validate().expect("valid");
        assert!(s.dependencies.iter().skip(1).all(|d| !d.is_empty()));
    }
}
