//! A UAV's commands received on the own clock and not yet applied, in the order of the instants
//! they act at ([`Pending`]). An agent on a slow link decides for a later step than the update
//! it answered; a command for step k+1 may arrive while step k's is still waiting, and it waits
//! for its own step instead of replacing step k's (which left step k without a command: under
//! 40 ± 20 ms each way, a sixth of the steps).

use std::collections::VecDeque;

use proxform_net::wire::{CommandMsg, STALE_AFTER_PERIODS};

/// What became of a command offered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Offered {
    /// Waits for its step.
    Kept,
    /// Replaced one for the same instant (decided on an older update), or pushed out the oldest
    /// of a full queue: one command will not be applied.
    Replaced,
    /// For an instant whose command was applied already: not applied.
    Late,
}

/// One UAV's pending commands, by the instant they act at, at most `capacity`.
#[derive(Debug, Clone)]
pub struct Pending {
    queue: VecDeque<CommandMsg>,
    capacity: usize,
}

impl Default for Pending {
    /// As many as an agent may decide ahead: it never decides for an instant more than
    /// [`STALE_AFTER_PERIODS`] periods after its update.
    fn default() -> Self {
        Self::new(STALE_AFTER_PERIODS as usize + 1)
    }
}

impl Pending {
    /// At most `capacity` commands waiting (an agent decides at most a few periods ahead).
    pub fn new(capacity: usize) -> Self {
        Self { queue: VecDeque::new(), capacity: capacity.max(1) }
    }

    /// Takes `c`, unless the instant it acts at is not after `applied_t_s` (the instant of the
    /// last command applied).
    pub fn offer(&mut self, c: CommandMsg, applied_t_s: Option<f64>) -> Offered {
        if applied_t_s.is_some_and(|t| c.t_s <= t) {
            return Offered::Late;
        }
        let at = self.queue.partition_point(|p| p.t_s < c.t_s);
        if self.queue.get(at).is_some_and(|p| p.t_s == c.t_s) {
            self.queue[at] = c;
            return Offered::Replaced;
        }
        self.queue.insert(at, c);
        match self.queue.len() > self.capacity {
            true => {
                self.queue.pop_front();
                Offered::Replaced
            }
            false => Offered::Kept,
        }
    }

    /// The command to apply at the step of time `t_s` (period `dt_s`): the newest of those that
    /// act at or before it (nearest step), and how many older due ones it overtook.
    pub fn due(&mut self, t_s: f64, dt_s: f64) -> (Option<CommandMsg>, u64) {
        let (mut due, mut overtaken) = (None, 0);
        while self.queue.front().is_some_and(|c| c.t_s <= t_s + 0.5 * dt_s) {
            overtaken += u64::from(due.is_some());
            due = self.queue.pop_front();
        }
        (due, overtaken)
    }

    /// Whether a command for the step of time `t_s` is waiting.
    pub fn answers(&self, t_s: f64, dt_s: f64) -> bool {
        self.queue.iter().any(|c| c.t_s > t_s - 0.5 * dt_s && c.t_s <= t_s + 0.5 * dt_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_core::{Decision, Input, Outcome};

    fn command(t_s: f64, tag: f64) -> CommandMsg {
        let mut input = Input::zeros();
        input[0] = tag;
        let decision = Decision::without_areas(Outcome::Held, input);
        CommandMsg { uav: 3, run: 0, k: 0, t_s, age_s: 0.0, decision, digest: 0 }
    }

    #[test]
    fn a_command_for_a_later_step_waits_for_it_and_does_not_replace_this_steps() {
        let dt = 0.1;
        let mut p = Pending::new(6);
        assert_eq!(p.offer(command(1.0, 1.0), None), Offered::Kept);
        // Step 1.1's command arrives while step 1.0's waits: both are applied, each at its step.
        assert_eq!(p.offer(command(1.1, 2.0), None), Offered::Kept);
        assert!(p.answers(1.0, dt) && p.answers(1.1, dt) && !p.answers(1.2, dt));
        let (now, overtaken) = p.due(1.0, dt);
        assert_eq!((now.map(|c| c.decision.input[0]), overtaken), (Some(1.0), 0));
        assert_eq!(p.due(1.1, dt).0.map(|c| c.decision.input[0]), Some(2.0));
        assert_eq!(p.due(1.2, dt), (None, 0));
    }

    #[test]
    fn the_newest_due_is_applied_and_what_came_too_late_is_not() {
        let dt = 0.1;
        let mut p = Pending::new(3);
        // Decided for the same step on a newer update: it replaces the older.
        p.offer(command(2.0, 1.0), None);
        assert_eq!(p.offer(command(2.0, 2.0), None), Offered::Replaced);
        // Steps that passed without the world (a stall): the newest due one is applied.
        p.offer(command(2.1, 3.0), None);
        let (now, overtaken) = p.due(2.3, dt);
        assert_eq!((now.map(|c| c.decision.input[0]), overtaken), (Some(3.0), 1));
        // For a step applied already: late. A full queue drops its oldest.
        assert_eq!(p.offer(command(2.1, 4.0), Some(2.1)), Offered::Late);
        for (i, t) in [2.4, 2.5, 2.6].into_iter().enumerate() {
            assert_eq!(p.offer(command(t, i as f64), Some(2.1)), Offered::Kept);
        }
        assert_eq!(p.offer(command(2.7, 9.0), Some(2.1)), Offered::Replaced);
        assert_eq!(p.due(2.4, dt), (None, 0), "2.4 was pushed out");
        assert_eq!(p.due(2.5, dt).0.map(|c| c.t_s), Some(2.5));
    }
}
