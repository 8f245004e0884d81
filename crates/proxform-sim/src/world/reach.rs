//! Which radio messages can reach a receiver. With a finite radio range and many messages (a
//! large swarm in which every UAV broadcasts), scanning every message for every receiver costs
//! O(N²) a step; the messages are then indexed once a step by their senders' positions in a
//! [`NeighbourGrid`], and a receiver visits only those within range, in the order they are
//! heard. The receiver still applies its own range test (and draws its losses) exactly as
//! over the whole list, so the index changes what is scanned, never what is heard.

use proxform_core::grid::NeighbourGrid;

/// Messages from which on an index pays for itself.
const INDEX_FROM: usize = 64;

/// The index of one step's messages.
#[derive(Debug, Default)]
pub struct Reach {
    grid: NeighbourGrid,
    /// The radius the grid answers for (m), 0 when the messages are not indexed.
    radius: f64,
    /// How many messages are indexed.
    count: usize,
}

impl Reach {
    /// No index.
    pub fn new() -> Self {
        Self::default()
    }

    /// Indexes the messages sent from `senders` (their positions, in the order the messages
    /// are heard) for receivers whose radio reaches `range_m` (not when the range is unlimited
    /// or the messages few).
    pub fn rebuild(&mut self, senders: impl ExactSizeIterator<Item = [f64; 3]> + Clone, range_m: f64) {
        // A hair wider than the range: the grid's own distance test may round the other way
        // than the receiver's at the very edge.
        let radius = range_m * (1.0 + 1e-9) + 1e-9;
        let count = senders.len();
        if count < INDEX_FROM || !radius.is_finite() {
            self.radius = 0.0;
            return;
        }
        self.grid.rebuild_ids(senders.enumerate().map(|(k, at)| (k as u32, at)), radius);
        self.radius = radius;
        self.count = count;
    }

    /// Calls `f` with the index of every one of `count` messages (those indexed last) that a
    /// receiver at `at` with radio range `range_m` may hear, in the order they are heard: all
    /// of them when not indexed (or indexed for a shorter range or another list), else those
    /// within range. `scratch` holds the indices found.
    pub fn for_each(&self, count: usize, at: [f64; 3], range_m: f64, scratch: &mut Vec<u32>, mut f: impl FnMut(usize)) {
        let covered = range_m <= self.radius;
        if self.radius == 0.0 || !covered || self.count != count {
            (0..count).for_each(f);
            return;
        }
        scratch.clear();
        self.grid.for_each_within(at, self.radius, |k, _, _| scratch.push(k));
        scratch.sort_unstable();
        scratch.iter().for_each(|&k| f(k as usize));
    }

    /// Heap bytes of the index.
    pub fn heap_bytes(&self) -> usize {
        self.grid.heap_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::measurement::Message;
    use proxform_core::State9;

    #[test]
    fn a_receiver_visits_the_messages_within_range_in_their_order() {
        let mut seed = 17u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let messages: Vec<Message> = (0..2000)
            .map(|k| Message {
                sender: k,
                about: k,
                state: State9::zeros(),
                age_s: 0.0,
                at: [2000.0 * next(), 2000.0 * next(), 100.0 * next()],
                relative: false,
            })
            .collect();
        let range = 150.0;
        let mut reach = Reach::new();
        let senders = |ms: &[Message]| ms.iter().map(|m| m.at).collect::<Vec<_>>().into_iter();
        reach.rebuild(senders(&messages), range);
        assert!(reach.radius > 0.0, "indexed");
        let mut scratch = Vec::new();
        let mut total = 0;
        for r in 0..200 {
            let at = [2200.0 * next() - 100.0, 2200.0 * next() - 100.0, 100.0 * next()];
            let d2 = |m: &Message| (0..3).map(|a| (m.at[a] - at[a]).powi(2)).sum::<f64>();
            let want: Vec<usize> =
                messages.iter().enumerate().filter(|(_, m)| d2(m) <= range * range).map(|(k, _)| k).collect();
            let mut got = Vec::new();
            reach.for_each(messages.len(), at, range, &mut scratch, |k| {
                if d2(&messages[k]) <= range * range {
                    got.push(k);
                }
            });
            assert_eq!(got, want, "receiver {r}");
            // Only a neighbourhood is scanned.
            assert!(scratch.len() < messages.len() / 4, "{} scanned", scratch.len());
            total += want.len();
        }
        assert!(total > 1000, "receivers hear messages: {total}");
        // A longer range than the index's, or few messages: every message is visited.
        let mut all = 0;
        reach.for_each(messages.len(), [0.0; 3], 2.0 * range, &mut scratch, |_| all += 1);
        assert_eq!(all, messages.len());
        reach.rebuild(senders(&messages[..10]), range);
        let mut few = 0;
        reach.for_each(10, [0.0; 3], range, &mut scratch, |_| few += 1);
        assert_eq!(few, 10);
    }
}
