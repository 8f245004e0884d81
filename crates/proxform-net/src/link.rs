//! What an agent on its own clock expects of its link to the world: the way back of a command
//! taken as long as the way out of the updates, judged over the last few of them rather than
//! the one at hand. On a jittery link one update's age says little about its command's way
//! back: a quick update followed by a slow command misses the step it was decided for (under
//! 40 ± 20 ms each way, a third of the commands did). The estimate is a high quantile of the
//! recent updates' ages, so that a command reaches the step it names nearly always, at the cost
//! of acting a step later when the link is slow.

use std::collections::VecDeque;

/// How many recent updates the estimate looks at (two seconds at 10 Hz).
pub const LINK_WINDOW: usize = 20;

/// The quantile of the recent ages the way back is taken as (the eighteenth of twenty, from the quickest).
pub const LINK_QUANTILE: f64 = 0.9;

/// The recent updates' ages on arrival (s), newest last.
#[derive(Debug, Clone, Default)]
pub struct LinkEstimate {
    ages: VecDeque<f64>,
    sorted: Vec<f64>,
}

impl LinkEstimate {
    /// Takes the age of an update just come (non-finite or negative ones are not ages).
    pub fn observe(&mut self, age_s: f64) {
        if !(age_s.is_finite() && age_s >= 0.0) {
            return;
        }
        if self.ages.len() == LINK_WINDOW {
            self.ages.pop_front();
        }
        self.ages.push_back(age_s);
    }

    /// How long a command is expected to take back (s): the [`LINK_QUANTILE`] of the recent
    /// ages, 0 before any.
    pub fn way_back_s(&mut self) -> f64 {
        self.sorted.clear();
        self.sorted.extend(self.ages.iter().copied());
        self.sorted.sort_by(f64::total_cmp);
        match self.sorted.len() {
            0 => 0.0,
            n => self.sorted[((LINK_QUANTILE * n as f64).ceil() as usize).clamp(1, n) - 1],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_way_back_is_a_high_quantile_of_the_recent_ages() {
        let mut l = LinkEstimate::default();
        assert_eq!(l.way_back_s(), 0.0);
        l.observe(0.03);
        assert_eq!(l.way_back_s(), 0.03);
        // Twenty ages from 10 to 200 ms: the eighteenth, 180 ms.
        for i in 1..=20 {
            l.observe(0.01 * i as f64);
        }
        assert!((l.way_back_s() - 0.18).abs() < 1e-12);
        // Only the last twenty count: fast ones push the slow ones out.
        for _ in 0..20 {
            l.observe(0.02);
        }
        assert_eq!(l.way_back_s(), 0.02);
        l.observe(f64::NAN);
        l.observe(-1.0);
        assert_eq!(l.way_back_s(), 0.02);
    }
}
