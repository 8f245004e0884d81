//! The formation's radio as an agent hears it on its own clock: every broadcaster's latest
//! [`StateMsg`] as it came from that UAV's agent over the network (agent to agent, not through
//! a world), turned into observations at the instant the agent steps, by the scenario's rules
//! (the same as the simulator's radio, `proxform_sim::world::sensing`): who broadcasts (the
//! beacons, or every UAV with `radio.broadcast_all`), the radio's range, and a report of a UAV
//! the agent perceives onboard left out unless its tracks fuse every report.
//!
//! Each report is brought to the agent's instant: its age is the time between its measurement
//! and that instant; one measured after it (its sender stepped on a later update) is moved back
//! along its velocity, so that every observation describes the same instant. A report older
//! than the controller's track timeout is dropped (its track would be gone anyway).
//!
//! The scenario's radio faults are applied on top of what the network does: each report is
//! lost with probability `radio.loss` (a draw keyed by receiver, sender and the report's time:
//! the same in every run of the same flight) and heard only `radio.delay_s` after it was
//! measured. Bursty loss (`radio.burst_*`) is the simulator's only.

use proxform_core::state::{self, State9};
use proxform_core::{Observation, ObservationSource, UavId};
use proxform_scenario::Scenario;

use crate::wire::StateMsg;

/// The latest report of every broadcaster, and the rules of the scenario's radio.
#[derive(Debug, Clone)]
pub struct AgentRadio {
    /// Latest report per UAV (index from 0), only for broadcasters.
    latest: Vec<Option<StateMsg>>,
    /// Reports on their way (the radio's delay), per UAV, oldest first.
    arriving: Vec<std::collections::VecDeque<StateMsg>>,
    loss: f64,
    delay_s: f64,
    broadcaster: Vec<bool>,
    range_m: f64,
    max_age_s: f64,
    fuse: bool,
    /// Reports kept (newer than the one held).
    pub heard: u64,
    /// Reports not taken: from a UAV that does not broadcast, not newer than the one held, or
    /// with a number that is not finite.
    pub ignored: u64,
    /// Reports lost to the scenario's radio loss.
    pub lost: u64,
}

/// A uniform draw in [0, 1) keyed by the words of `key` (SplitMix64 over them).
fn uniform(key: [u64; 3]) -> f64 {
    let mut z = 0x9E37_79B9_7F4A_7C15u64;
    for w in key {
        z = z.wrapping_add(w).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    (z >> 11) as f64 / (1u64 << 53) as f64
}

impl AgentRadio {
    /// The radio of `scenario`.
    pub fn new(scenario: &Scenario) -> Self {
        let n = scenario.len();
        let radio = scenario.radio();
        let mut broadcaster = vec![radio.broadcast_all; n];
        for b in scenario.beacons() {
            if let Some(x) = broadcaster.get_mut(b.index()) {
                *x = true;
            }
        }
        Self {
            latest: vec![None; n],
            arriving: vec![std::collections::VecDeque::new(); n],
            loss: radio.loss,
            delay_s: f64::from(radio.delay_steps) * scenario.dt_s(),
            broadcaster,
            range_m: radio.range_m,
            max_age_s: scenario.controller().track_timeout_s,
            fuse: scenario.fuses_radio(),
            heard: 0,
            ignored: 0,
            lost: 0,
        }
    }

    /// Whether any UAV broadcasts (an agent without a radio need not listen).
    pub fn any(&self) -> bool {
        self.broadcaster.iter().any(|b| *b)
    }

    /// The broadcasters, from 1 (the keys to listen on).
    pub fn broadcasters(&self) -> Vec<u32> {
        (0..self.broadcaster.len()).filter(|j| self.broadcaster[*j]).map(|j| j as u32 + 1).collect()
    }

    /// Takes `m` when it is a broadcaster's, newer than what is held and not lost to the
    /// scenario's radio loss (for receiver `me`, from 0); it is heard once the radio's delay has
    /// passed.
    pub fn hear(&mut self, me: usize, m: &StateMsg) {
        let j = (m.uav as usize).wrapping_sub(1);
        let newest = |q: &std::collections::VecDeque<StateMsg>, held: Option<StateMsg>| {
            q.back().copied().or(held).is_none_or(|h| m.t_s > h.t_s)
        };
        let valid = j < self.latest.len()
            && self.broadcaster[j]
            && m.t_s.is_finite()
            && m.state.iter().all(|v| v.is_finite())
            && newest(&self.arriving[j], self.latest[j]);
        if !valid {
            self.ignored += 1;
            return;
        }
        if self.loss > 0.0 && uniform([me as u64, j as u64, m.t_s.to_bits()]) < self.loss {
            self.lost += 1;
            return;
        }
        self.heard += 1;
        self.arriving[j].push_back(*m);
        // Never more on the way than the delay can hold back (a report a period).
        while self.arriving[j].len() > 64 {
            self.arriving[j].pop_front();
        }
    }

    /// Forgets every report (a new run).
    pub fn clear(&mut self) {
        self.latest.iter_mut().for_each(|m| *m = None);
        self.arriving.iter_mut().for_each(|q| q.clear());
    }

    /// The reports whose delay is over at `t_s` become the latest.
    fn arrive(&mut self, t_s: f64) {
        for (q, latest) in self.arriving.iter_mut().zip(self.latest.iter_mut()) {
            // Without a delay of the scenario's, what the network brought is there now.
            while q.front().is_some_and(|m| self.delay_s == 0.0 || m.t_s + self.delay_s <= t_s + 1e-9) {
                *latest = q.pop_front();
            }
        }
    }

    /// Appends to `out` what UAV `me` (from 0) hears at `t_s`, where it is at `own`; `out`
    /// already holds what it perceived then (onboard reports of a UAV make its radio report
    /// redundant unless the tracks fuse).
    pub fn observations(&mut self, me: UavId, t_s: f64, own: &State9, out: &mut Vec<Observation>) {
        self.arrive(t_s);
        let perceived = out.len();
        for (j, m) in self.latest.iter().enumerate() {
            let Some(m) = m else { continue };
            let age_s = t_s - m.t_s;
            if j == me.index() || age_s > self.max_age_s {
                continue;
            }
            let onboard = out[..perceived].iter().any(|o| o.id.index() == j && o.source == ObservationSource::Onboard);
            if onboard && !self.fuse {
                continue;
            }
            let mut state = m.state;
            if age_s < 0.0 {
                for k in 0..3 {
                    state[state::X + k] += state[state::VX + k] * age_s;
                }
            }
            let d2 = (0..3).map(|k| (state[state::X + k] - own[state::X + k]).powi(2)).sum::<f64>();
            if d2 > self.range_m * self.range_m {
                continue;
            }
            out.push(Observation {
                id: UavId(j as u32),
                state,
                age_s: age_s.max(0.0),
                source: ObservationSource::Radio,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(text: &str) -> Scenario {
        proxform_scenario::load::parse(text, "radio.toml").expect("valid")
    }

    fn at(uav: u32, t_s: f64, x: f64, vx: f64) -> StateMsg {
        let mut state = State9::zeros();
        state[state::X] = x;
        state[state::VX] = vx;
        StateMsg { uav, k: 0, t_s, state, rejoining: false }
    }

    const V: &str = "[formation.shape]\nkind = \"v\"\nuavs = 5\nspacing_m = 80.0\n";

    #[test]
    fn it_keeps_the_latest_of_broadcasters_and_brings_each_to_the_agents_instant() {
        let sc = scenario(&format!("{V}[radio]\nbroadcast_all = true\n"));
        let mut radio = AgentRadio::new(&sc);
        radio.hear(0, &at(2, 1.0, 10.0, 5.0));
        radio.hear(0, &at(2, 0.9, 99.0, 5.0));
        assert_eq!(radio.ignored, 1, "an older report does not replace a newer one");
        radio.hear(0, &at(3, 1.2, 20.0, 5.0));
        radio.hear(0, &at(9, 1.0, 0.0, 0.0));
        let mut nan = at(4, 1.0, 0.0, 0.0);
        nan.state[state::Y] = f64::NAN;
        radio.hear(0, &nan);
        assert_eq!(radio.ignored, 3, "an unknown UAV and a NaN are not taken");
        let mut out = Vec::new();
        radio.observations(UavId(0), 1.1, &State9::zeros(), &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!((out[0].id, out[0].state[state::X]), (UavId(1), 10.0));
        assert!((out[0].age_s - 0.1).abs() < 1e-12);
        // Measured 0.1 s after the agent's instant: moved back to it, age 0.
        assert_eq!(out[1].id, UavId(2));
        assert!((out[1].state[state::X] - 19.5).abs() < 1e-12 && out[1].age_s == 0.0);
        // Its own report is not an observation; a report older than the track timeout is gone.
        out.clear();
        radio.observations(UavId(1), 100.0, &State9::zeros(), &mut out);
        assert!(out.is_empty(), "{out:?}");
    }

    #[test]
    fn the_scenarios_radio_loss_and_delay_apply_on_top_of_the_network() {
        let sc = scenario(&format!("{V}[radio]\nbroadcast_all = true\nloss = 0.5\ndelay_s = 0.3\n"));
        let mut radio = AgentRadio::new(&sc);
        let mut out = Vec::new();
        for k in 0..400 {
            let t = k as f64 * 0.1;
            radio.hear(0, &at(2, t, k as f64, 1.0));
            out.clear();
            radio.observations(UavId(0), t, &State9::zeros(), &mut out);
            // Nothing newer than 0.3 s: the radio's delay.
            assert!(out.iter().all(|o| o.age_s >= 0.3 - 1e-9), "{t}: {out:?}");
            assert!(!(3..=20).contains(&k) || out.is_empty() || out[0].age_s < 2.0);
        }
        assert!((150..250).contains(&radio.lost), "{} of 400 lost at 0.5", radio.lost);
    }

    #[test]
    fn only_broadcasters_in_range_and_not_perceived_onboard_are_heard() {
        let sc = scenario(&format!("{V}[radio]\nbeacons = [1]\nrange_m = 50.0\n"));
        let mut radio = AgentRadio::new(&sc);
        assert_eq!(radio.broadcasters(), vec![1]);
        radio.hear(0, &at(2, 1.0, 10.0, 0.0));
        assert_eq!(radio.ignored, 1, "UAV 2 does not broadcast");
        radio.hear(0, &at(1, 1.0, 10.0, 0.0));
        let mut out = Vec::new();
        let far = at(5, 1.0, 100.0, 0.0).state;
        radio.observations(UavId(4), 1.0, &far, &mut out);
        assert!(out.is_empty(), "90 m away, beyond the radio's 50 m");
        let seen = Observation { id: UavId(0), state: State9::zeros(), age_s: 0.0, source: ObservationSource::Onboard };
        out.push(seen);
        radio.observations(UavId(4), 1.0, &State9::zeros(), &mut out);
        assert_eq!(out.len(), 1, "perceived onboard: the radio report is redundant");
        out.clear();
        radio.observations(UavId(4), 1.0, &State9::zeros(), &mut out);
        assert_eq!((out.len(), out[0].source), (1, ObservationSource::Radio));
    }
}
