//! The pass criterion of a run: one rule, applied to the whole formation for the run's verdict
//! and to each follower for its own.
//!
//! What is judged depends on the scenario: a formation kept from the start stays within its
//! allowable errors for the whole flight; one that starts scattered must have formed by
//! `form_within_s` and stayed formed; with joiners, the followers that started in their slots
//! keep their errors and the joiners form; with changes of formation, the errors held before
//! the first change and every change was completed before the next. A follower is judged by the
//! same rule over its own errors; one that never flew as a follower has no verdict. (The
//! safety distance, which concerns pairs, is the run's alone: `RunMetrics::finish`.)

/// How a scenario's runs are judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Criterion {
    /// Scattered starts: formed by this time (s).
    pub form_within_s: Option<f64>,
    /// Some followers do not start in their slots (scattered starts, joiners).
    pub forming: bool,
}

/// What the criterion looks at, for the whole formation or for one follower.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Evidence {
    /// Follower steps judged (0: no follower flew).
    pub judged_steps: u64,
    /// Every error within its allowable error over the whole flight.
    pub within: bool,
    /// When the formation (or the follower) was formed, to the end or the first change (s; ∞:
    /// never).
    pub time_to_form_s: f64,
    /// Largest error over its allowable error of the followers judged from the start (those
    /// that started in their slots and do not join), before the first change.
    pub settled_ratio: f64,
    /// Largest error over its allowable error before the first change.
    pub before_ratio: f64,
    /// With changes of formation: whether every one was completed before the next.
    pub changes_completed: Option<bool>,
}

impl Criterion {
    /// Whether `e` passes.
    pub fn passes(&self, e: &Evidence) -> bool {
        e.judged_steps > 0
            && match (self.form_within_s, e.changes_completed) {
                // Formed in time, then every change completed.
                (Some(limit), changes) => e.time_to_form_s <= limit + 1e-9 && changes.unwrap_or(true),
                // Joiners: the others kept their errors and the joiners formed (before the
                // first change, then every change completed).
                (None, changes) if self.forming => {
                    e.settled_ratio <= 1.0 && e.time_to_form_s.is_finite() && changes.unwrap_or(true)
                }
                // Changes: the errors held before the first, and each was completed.
                (None, Some(completed)) => e.before_ratio <= 1.0 && completed,
                (None, None) => e.within,
            }
    }
}

/// A change of formation's window as a follower is judged in it: its first and last frames
/// (s), and whether a re-assignment cut it short.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    pub first: f64,
    pub last: f64,
    pub superseded: bool,
}

/// One follower's evidence as a run goes: its errors over their allowable errors before the
/// first change and when it was last outside them, then in each change of formation.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FollowerJudge {
    /// Judged from the start (started in its slot, does not join).
    pub settled: bool,
    /// Largest error ratio before the first change.
    pub before_ratio: f64,
    /// Last time (s) outside its allowable errors while the formation was forming (before the
    /// first change, or through a re-assignment made while it was still forming).
    pub last_out: f64,
    /// Per change of formation (in the run's order): the last time it was outside them.
    pub changes_last_out: Vec<f64>,
    /// The last time (s) it flew: its forming and its changes end there if it is removed
    /// before they do (out of its errors then, it neither formed nor completed them).
    pub last_seen: f64,
}

impl FollowerJudge {
    /// A follower judged from the start when `settled`, with `changes` changes known so far.
    pub fn new(settled: bool, changes: usize) -> Self {
        Self {
            settled,
            before_ratio: 0.0,
            last_out: f64::NEG_INFINITY,
            changes_last_out: vec![f64::NEG_INFINITY; changes],
            last_seen: f64::NEG_INFINITY,
        }
    }

    /// Its error ratio `ratio` at time `t`: before the first change when `before_change`,
    /// while the formation forms when `forming`, and in the changes whose windows hold `t`
    /// (`in_change(k)`).
    pub fn observe(
        &mut self,
        t: f64,
        ratio: f64,
        (before_change, forming): (bool, bool),
        in_change: impl Fn(usize) -> bool,
    ) {
        let out = ratio > 1.0;
        self.last_seen = t;
        if before_change {
            self.before_ratio = self.before_ratio.max(ratio);
        }
        if forming && out {
            self.last_out = t;
        }
        if out {
            for (k, last) in self.changes_last_out.iter_mut().enumerate() {
                if in_change(k) {
                    *last = t;
                }
            }
        }
    }

    /// Its evidence: `judged_steps` and `within` from its accumulated errors; formed from its
    /// last time out when that was before `form_end`'s frame; each change completed when it
    /// was last out before the window's last frame (`window(k)`). A follower removed
    /// earlier is judged up to the last frame it flew: removed out of its errors, it did not
    /// form, nor complete the change it was in (one it flew a step in: at a change's first
    /// frame nobody has moved yet). A change cut short by a re-assignment is judged by the
    /// re-assignment's window, but for a follower that left in it.
    pub fn evidence(
        &self,
        judged_steps: u64,
        within: bool,
        (form_end, dt): (f64, f64),
        window: impl Fn(usize) -> Window,
    ) -> Evidence {
        Evidence {
            judged_steps,
            within,
            time_to_form_s: formed_at(self.last_out, form_end.min(self.last_seen), dt),
            settled_ratio: if self.settled { self.before_ratio } else { 0.0 },
            before_ratio: self.before_ratio,
            changes_completed: (!self.changes_last_out.is_empty()).then(|| {
                self.changes_last_out.iter().enumerate().all(|(k, &l)| {
                    let w = window(k);
                    (w.superseded && self.last_seen > w.last + 1e-9)
                        || self.last_seen <= w.first + 1e-9
                        || l < w.last.min(self.last_seen) - 1e-9
                })
            }),
        }
    }
}

/// When a formation (or a follower) last outside its allowable errors at `last_out` was formed,
/// judged up to the frame `form_end` of a flight in steps of `dt`: ∞ when it was still out then.
pub(crate) fn formed_at(last_out: f64, form_end: f64, dt: f64) -> f64 {
    if last_out >= form_end - 1e-9 {
        f64::INFINITY
    } else {
        (last_out + dt).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A follower in one change from 10 s, flown every 0.1 s to step `until`, out of its
    /// errors where `out(t)`.
    fn flown_to(until: usize, out: impl Fn(f64) -> bool) -> FollowerJudge {
        let mut j = FollowerJudge::new(false, 1);
        for k in 0..=until {
            let t = k as f64 * 0.1;
            j.observe(t, if out(t) { 2.0 } else { 0.5 }, (t < 10.0 - 1e-9, t < 10.0 - 1e-9), |_| t >= 10.0 - 1e-9);
        }
        j
    }

    /// A change's window from `first` to `last`, run to its end.
    fn w(first: f64, last: f64) -> Window {
        Window { first, last, superseded: false }
    }

    fn kept(within: bool) -> Evidence {
        Evidence {
            judged_steps: 10,
            within,
            time_to_form_s: 0.0,
            settled_ratio: 0.0,
            before_ratio: 0.0,
            changes_completed: None,
        }
    }

    #[test]
    fn each_kind_of_scenario_is_judged_by_its_own_rule() {
        let keeping = Criterion { form_within_s: None, forming: false };
        assert!(keeping.passes(&kept(true)));
        assert!(!keeping.passes(&kept(false)));
        assert!(!keeping.passes(&Evidence { judged_steps: 0, ..kept(true) }), "nothing flew");
        // Scattered: formed by 30 s, whatever the errors on the way.
        let scattered = Criterion { form_within_s: Some(30.0), forming: true };
        assert!(scattered.passes(&Evidence { time_to_form_s: 29.0, ..kept(false) }));
        assert!(!scattered.passes(&Evidence { time_to_form_s: 31.0, ..kept(true) }));
        // Joiners: formed at all, the settled ones within their errors.
        let joining = Criterion { form_within_s: None, forming: true };
        assert!(joining.passes(&Evidence { time_to_form_s: 80.0, settled_ratio: 0.9, ..kept(false) }));
        assert!(!joining.passes(&Evidence { time_to_form_s: 80.0, settled_ratio: 1.1, ..kept(true) }));
        assert!(!joining.passes(&Evidence { time_to_form_s: f64::INFINITY, ..kept(true) }));
        // Changes: held before the first, each completed.
        let change =
            |before_ratio: f64, done: bool| Evidence { before_ratio, changes_completed: Some(done), ..kept(false) };
        assert!(keeping.passes(&change(0.5, true)));
        assert!(!keeping.passes(&change(1.5, true)));
        assert!(!keeping.passes(&change(0.5, false)));
    }

    #[test]
    fn a_follower_is_formed_from_its_last_time_out_and_completes_a_change_before_the_next() {
        let mut j = FollowerJudge::new(false, 1);
        // Out until 4.9 s, then within; a change from 10 s, out until 12 s.
        for k in 0..200 {
            let t = k as f64 * 0.1;
            let ratio = if t < 4.95 || (10.0..12.05).contains(&t) { 2.0 } else { 0.5 };
            j.observe(t, ratio, (t < 10.0 - 1e-9, t < 10.0 - 1e-9), |_| t >= 10.0 - 1e-9);
        }
        let e = j.evidence(200, false, (9.9, 0.1), |_| w(10.0, 19.9));
        assert!((e.time_to_form_s - 5.0).abs() < 1e-9, "{}", e.time_to_form_s);
        assert_eq!(e.changes_completed, Some(true));
        assert_eq!(e.settled_ratio, 0.0, "not judged from the start");
        // Still out at the window's last frame: not completed.
        assert_eq!(j.evidence(200, false, (9.9, 0.1), |_| w(10.0, 12.0)).changes_completed, Some(false));
    }

    #[test]
    fn forming_carried_on_past_the_first_change_judges_forming_not_the_errors_before_it() {
        // Forming carried on through a re-assignment at 5 s to 20 s: out of its errors to
        // 12 s (after the re-assignment's start), within them after. It formed at 12.1 s; its
        // errors before the change are those before 5 s only.
        let mut j = FollowerJudge::new(true, 1);
        for k in 0..300 {
            let t = k as f64 * 0.1;
            let ratio = if t < 4.95 {
                0.5
            } else if t < 12.05 {
                3.0
            } else {
                0.5
            };
            j.observe(t, ratio, (t < 5.0 - 1e-9, t < 20.0 - 1e-9), |_| t >= 5.0 - 1e-9);
        }
        let e = j.evidence(300, false, (19.9, 0.1), |_| w(5.0, 29.9));
        assert!((e.time_to_form_s - 12.1).abs() < 1e-9, "{}", e.time_to_form_s);
        assert_eq!(e.before_ratio, 0.5);
        assert_eq!(e.changes_completed, Some(true));
    }

    #[test]
    fn a_follower_removed_out_of_its_errors_neither_formed_nor_completed_its_change() {
        // Out from 10 s (a change) and removed at 11 s, while the window lasts to 19.9 s.
        let j = flown_to(110, |t| t >= 9.95);
        assert_eq!(j.evidence(111, false, (19.9, 0.1), |_| w(10.0, 19.9)).changes_completed, Some(false));
        // A joiner removed while still forming did not form.
        let mut j = FollowerJudge::new(false, 0);
        for k in 0..=110 {
            j.observe(k as f64 * 0.1, 2.0, (true, true), |_| false);
        }
        assert_eq!(j.evidence(111, false, (19.9, 0.1), |_| w(10.0, 19.9)).time_to_form_s, f64::INFINITY);
        // Removed within its errors: formed, and the change completed.
        let j = flown_to(110, |t| (10.0..10.55).contains(&t));
        let e = j.evidence(111, false, (19.9, 0.1), |_| w(10.0, 19.9));
        assert_eq!(e.changes_completed, Some(true));
        assert!(e.time_to_form_s.is_finite());
    }

    #[test]
    fn a_follower_gone_at_a_changes_first_frame_or_past_a_change_cut_short_is_not_held_to_it() {
        // Removed as the change begins: its last frame is the change's first, where nobody has
        // moved yet (far from its new slot): not held to the change.
        let j = flown_to(100, |t| t >= 9.95);
        assert_eq!(j.evidence(101, false, (9.9, 0.1), |_| w(10.0, 19.9)).changes_completed, Some(true));
        // A change cut short at 12 s by a re-assignment (the second window, to the end): a
        // follower out until 11 s and within from then on completed; one out at 11.9 s that
        // flew on is judged by the re-assignment alone; one that left in it out of its errors
        // did not complete it.
        let cut = |k: usize| match k {
            0 => Window { first: 10.0, last: 11.9, superseded: true },
            _ => w(12.0, 19.9),
        };
        let judge = |out: &dyn Fn(f64) -> bool, until: usize| {
            let mut j = FollowerJudge::new(false, 2);
            for k in 0..=until {
                let t = k as f64 * 0.1;
                j.observe(t, if out(t) { 2.0 } else { 0.5 }, (t < 10.0 - 1e-9, t < 10.0 - 1e-9), |c| match c {
                    0 => (10.0 - 1e-9..12.0 - 1e-9).contains(&t),
                    _ => t >= 12.0 - 1e-9,
                });
            }
            j.evidence(until as u64 + 1, false, (9.9, 0.1), cut).changes_completed
        };
        assert_eq!(judge(&|t| (10.0..11.05).contains(&t), 199), Some(true));
        assert_eq!(judge(&|t| (10.0..12.5).contains(&t), 199), Some(true));
        assert_eq!(judge(&|t| t >= 10.0, 115), Some(false));
    }
}
