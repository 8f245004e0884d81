//! Separation: the smallest distance between any two flying UAVs, from their true positions,
//! and the pairs closer than the safety distance, whatever the sensing range.
//!
//! Each step only pairs closer than `max(smallest so far, safety distance)` can change the
//! result, so those are searched with a neighbour grid of that radius: O(N) a step at any swarm
//! size. The first step widens the radius until some pair is found.

use std::collections::BTreeSet;

use proxform_core::grid::NeighbourGrid;
use proxform_core::state::State9;

/// Separation over a run.
#[derive(Debug, Clone)]
pub struct Separation {
    safety_m: f64,
    min_m: f64,
    close: BTreeSet<(u32, u32)>,
    grid: NeighbourGrid,
}

impl Separation {
    /// For a safety distance of `safety_m`.
    pub fn new(safety_m: f64) -> Self {
        Self { safety_m, min_m: f64::INFINITY, close: BTreeSet::new(), grid: NeighbourGrid::new() }
    }

    /// Smallest distance between two flying UAVs so far (m; ∞ while fewer than two fly).
    pub fn min_m(&self) -> f64 {
        self.min_m
    }

    /// Distinct pairs ever closer than the safety distance.
    pub fn close_pairs(&self) -> usize {
        self.close.len()
    }

    /// The neighbour grid's buffers, lent to another search between snapshots (each snapshot
    /// rebuilds it): one grid's memory serves both.
    pub(crate) fn grid_mut(&mut self) -> &mut NeighbourGrid {
        &mut self.grid
    }

    /// Looks at one snapshot.
    pub fn observe(&mut self, states: &[State9], active: &[bool]) {
        let flying =
            || states.iter().enumerate().filter(|(i, _)| active[*i]).map(|(i, s)| (i as u32, [s[0], s[1], s[2]]));
        if flying().nth(1).is_none() {
            return;
        }
        let mut radius = self.min_m.max(self.safety_m);
        if !radius.is_finite() {
            radius = self.safety_m;
        }
        // No pair is farther apart than the box around the flying UAVs (needed only while no
        // pair has been measured).
        let extent = || {
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for (_, p) in flying() {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
        };
        loop {
            self.grid.rebuild_ids(flying(), radius);
            let mut found = f64::INFINITY;
            let s2 = self.safety_m * self.safety_m;
            let close = &mut self.close;
            self.grid.for_each_pair_within(radius, |a, b, d2| {
                found = found.min(d2);
                if d2 < s2 {
                    close.insert((a.min(b), a.max(b)));
                }
            });
            if found.is_finite() {
                self.min_m = self.min_m.min(found.sqrt());
                return;
            }
            if self.min_m.is_finite() || !radius.is_finite() || radius > extent() {
                // Nothing closer than the smallest so far (or nothing measurable at all).
                return;
            }
            // The first snapshot, and nobody within the radius: look farther.
            radius *= 4.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(x: f64, y: f64) -> State9 {
        let mut s = State9::zeros();
        s[0] = x;
        s[1] = y;
        s
    }

    #[test]
    fn it_finds_the_true_minimum_at_any_distance_and_counts_close_pairs_once() {
        let mut sep = Separation::new(50.0);
        // Widely spread: the closest pair is 3 km apart, far beyond any sensing range.
        let far = [at(0.0, 0.0), at(3000.0, 0.0), at(0.0, 9000.0)];
        sep.observe(&far, &[true; 3]);
        assert!((sep.min_m() - 3000.0).abs() < 1e-9, "{}", sep.min_m());
        assert_eq!(sep.close_pairs(), 0);
        // Two pairs come within the safety distance; one of them twice.
        let near = [at(0.0, 0.0), at(30.0, 0.0), at(1000.0, 0.0), at(1010.0, 0.0)];
        sep.observe(&near, &[true; 4]);
        sep.observe(&near, &[true; 4]);
        assert_eq!((sep.min_m(), sep.close_pairs()), (10.0, 2));
        // A removed UAV is not measured.
        let mut sep = Separation::new(50.0);
        sep.observe(&near, &[true, true, true, false]);
        assert_eq!((sep.min_m(), sep.close_pairs()), (30.0, 1));
        // A lone UAV has no separation.
        let mut lone = Separation::new(50.0);
        lone.observe(&near, &[true, false, false, false]);
        assert!(lone.min_m().is_infinite());
    }
}
