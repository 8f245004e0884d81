//! The multi-level lattice of large swarms: rows of columns behind the navigator on several
//! levels, the navigator ahead of the front row's centre (the built-in `swarm` scenario's
//! layout, [`crate::builtin::swarm`]).

use proxform_core::FormationSlot;

/// Horizontal spacing of the lattice (m).
pub const SPACING_M: f64 = 50.0;
/// Vertical spacing of the levels (m).
pub const LEVEL_M: f64 = 20.0;

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
}
