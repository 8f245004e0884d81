//! Which neighbours fly under their agents, as an agent on its own clock can tell: a
//! follower's agent broadcasts its state with every decision, so a follower whose agent has
//! broadcast nothing measured within [`SILENT_AFTER_PERIODS`] periods of the instant an agent
//! steps at (stopped, cut off, crashed) flies uncontrolled, holding what it had: it is still
//! seen and avoided, but not followed (its onboard observations are passed as close-range
//! detections, for collision avoidance only; its radio reports are dropped). Nor is one whose
//! agent is back but says it is rejoining (its newest broadcast's `rejoining`: not yet near
//! its slot again, wherever its uncontrolled flight took it), and it is left to avoid the
//! others: it is the one out of its place, closing fast, and its own avoidance brakes for them
//! (UAVs in their places that fled it were pushed 10 m out of theirs). Only a UAV rejoining
//! too avoids it. A follower never heard is taken as flying under control (a world may run
//! agents that do not broadcast); the navigator flies its path and is always followed.

use proxform_core::{Observation, ObservationSource};
use proxform_scenario::Scenario;

use crate::wire::StateMsg;

/// On the own clock, a follower whose agent has broadcast nothing measured within this many
/// periods of the instant an agent steps at flies uncontrolled as far as its neighbours can
/// tell: it is avoided, not followed ([`ControlWatch`]). Sooner than a command
/// goes stale, because until then a neighbour leaning on it follows the course it holds
/// (measured with one agent of the paper's stopped for 5 s: after 5 periods the others' pitch
/// erred by up to 0.54° of the 0.4° allowed, 5 runs of 5 failing; after 3, by 0.36° at most,
/// 5 of 5 passing). The newest broadcast is normally at most a period old, so 3 periods leave
/// two for a late or lost one.
pub const SILENT_AFTER_PERIODS: f64 = 3.0;

/// The time of the newest broadcast heard of every follower.
#[derive(Debug, Clone)]
pub struct ControlWatch {
    newest: Vec<Option<f64>>,
    /// Whether the newest broadcast of each follower said it is rejoining.
    rejoining: Vec<bool>,
    navigator: usize,
    silent_after_s: f64,
    /// Observations of silent neighbours passed for avoidance only or dropped.
    pub unfollowed: u64,
}

impl ControlWatch {
    /// The watch over `scenario`'s followers.
    pub fn new(scenario: &Scenario) -> Self {
        Self {
            newest: vec![None; scenario.len()],
            rejoining: vec![false; scenario.len()],
            navigator: scenario.navigator().index(),
            silent_after_s: SILENT_AFTER_PERIODS * scenario.dt_s(),
            unfollowed: 0,
        }
    }

    /// A broadcast heard.
    pub fn hear(&mut self, m: &StateMsg) {
        let j = (m.uav as usize).wrapping_sub(1);
        if let Some(t) = self.newest.get_mut(j).filter(|_| m.t_s.is_finite()) {
            if t.is_none_or(|t| m.t_s >= t) {
                self.rejoining[j] = m.rejoining;
            }
            *t = Some(t.map_or(m.t_s, |t| t.max(m.t_s)));
        }
    }

    /// Forgets what was heard (a new run).
    pub fn clear(&mut self) {
        self.newest.iter_mut().for_each(|t| *t = None);
        self.rejoining.iter_mut().for_each(|r| *r = false);
    }

    /// Whether follower `j` (from 0) has been silent at `t_s` (uncontrolled).
    pub fn silent(&self, j: usize, t_s: f64) -> bool {
        j != self.navigator && self.newest.get(j).copied().flatten().is_some_and(|t| t_s - t > self.silent_after_s)
    }

    /// Whether follower `j` (from 0) says it is rejoining.
    pub fn rejoining(&self, j: usize) -> bool {
        j != self.navigator && self.rejoining.get(j).copied().unwrap_or(false)
    }

    /// What an agent stepping at `t_s` keeps of `heard`: a silent neighbour's onboard
    /// observations for avoidance only; a rejoining one's none, unless this agent is
    /// rejoining itself (`me_rejoining`: then for avoidance only); neither one's radio reports
    /// and relays.
    pub fn leave_out_the_unfollowed(&mut self, t_s: f64, heard: &mut Vec<Observation>, me_rejoining: bool) {
        let before = heard.len();
        heard.retain(|o| {
            let j = o.id.index();
            let onboard = matches!(o.source, ObservationSource::Onboard | ObservationSource::Close);
            match (self.silent(j, t_s), self.rejoining(j)) {
                (false, false) => true,
                (true, _) => onboard,
                (false, true) => onboard && me_rejoining,
            }
        });
        let mut unfollowed = (before - heard.len()) as u64;
        for o in heard.iter_mut() {
            let j = o.id.index();
            if o.source == ObservationSource::Onboard && (self.silent(j, t_s) || self.rejoining(j)) {
                o.source = ObservationSource::Close;
                unfollowed += 1;
            }
        }
        self.unfollowed += unfollowed;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proxform_core::state::State9;
    use proxform_core::UavId;

    #[test]
    fn a_silent_follower_is_avoided_not_followed() {
        let sc =
            proxform_scenario::load::parse("[formation.shape]\nkind = \"v\"\nuavs = 4\nspacing_m = 80.0\n", "w.toml")
                .expect("valid");
        let mut w = ControlWatch::new(&sc);
        let nav = sc.navigator().index();
        let (a, b) = ((nav + 1) % 4, (nav + 2) % 4);
        let msg = |j: usize, t_s| StateMsg { uav: j as u32 + 1, k: 0, t_s, state: State9::zeros(), rejoining: false };
        w.hear(&msg(a, 1.0));
        w.hear(&msg(b, 1.0));
        w.hear(&msg(b, 3.0));
        let obs = |j: usize, source| Observation { id: UavId(j as u32), state: State9::zeros(), age_s: 0.0, source };
        let mut heard = vec![
            obs(a, ObservationSource::Onboard),
            obs(a, ObservationSource::Radio),
            obs(b, ObservationSource::Onboard),
            obs(nav, ObservationSource::Onboard),
        ];
        // At 3 s, a was last heard 2 s ago (more than 3 periods of 0.1 s), b just now.
        assert!(!w.silent(a, 1.25) && w.silent(a, 1.35), "silent after 3 periods");
        w.leave_out_the_unfollowed(3.0, &mut heard, false);
        let got: Vec<(usize, ObservationSource)> = heard.iter().map(|o| (o.id.index(), o.source)).collect();
        assert_eq!(
            got,
            vec![(a, ObservationSource::Close), (b, ObservationSource::Onboard), (nav, ObservationSource::Onboard)]
        );
        assert_eq!(w.unfollowed, 2);
        // Heard again: followed again; never heard: followed.
        w.hear(&msg(a, 3.0));
        assert!(!w.silent(a, 3.2) && !w.silent((nav + 3) % 4, 100.0) && !w.silent(nav, 100.0));
        // Back but rejoining: neither followed nor avoided (it avoids the others), except by a
        // UAV rejoining too; until its newest broadcast says it is back (an older broadcast
        // arriving late changes nothing).
        w.hear(&StateMsg { rejoining: true, ..msg(a, 3.3) });
        let seen = || vec![obs(a, ObservationSource::Onboard), obs(a, ObservationSource::Radio)];
        let (mut mine, mut theirs) = (seen(), seen());
        w.leave_out_the_unfollowed(3.3, &mut mine, false);
        w.leave_out_the_unfollowed(3.3, &mut theirs, true);
        assert!(mine.is_empty(), "{mine:?}");
        assert_eq!(theirs.iter().map(|o| o.source).collect::<Vec<_>>(), [ObservationSource::Close]);
        w.hear(&msg(a, 3.1));
        assert!(w.rejoining(a), "a late older broadcast");
        w.hear(&msg(a, 3.5));
        assert!(!w.rejoining(a) && !w.silent(a, 3.5));
    }
}
