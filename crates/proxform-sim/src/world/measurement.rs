//! What a UAV's own sensors say of it, and the radio messages it sends from that.
//!
//! A UAV's measurement of its own state is its true state with white noise (its own-state
//! stream at the step), plus, in flight, the bias of its position fix and its sensor faults
//! (a glitch, a stuck sensor). The agent decides from it, and a UAV that broadcasts sends it:
//! a message carries what the sender believes, not the truth (the navigator's, checked first
//! when the own-sensor check or filter is on: [`super::navigator_check`]).

use proxform_core::assignment::Lead;
use proxform_core::state::{self, State9};
use proxform_core::UavId;
use proxform_scenario::Scenario;

use super::environment::UavEnv;
use super::faults::FaultStep;
use super::sensing::noisy;
use crate::random::{Source, StreamKey};

/// The own sensors of every UAV at one step.
#[derive(Debug, Clone, Copy)]
pub struct OwnSensors<'a> {
    /// Noise σ per state parameter.
    pub sigma: State9,
    /// The step's random streams.
    pub key: StreamKey,
    /// Per-UAV environment (the position-fix bias), empty when the scenario needs none.
    pub env: &'a [UavEnv],
    /// The sensor faults in force; None during the warm-up (ideal sensors but for the noise).
    pub faults: Option<&'a FaultStep>,
}

impl OwnSensors<'_> {
    /// UAV `i`'s measurement of its own state, `truth`.
    #[inline]
    pub fn measure(&self, i: usize, truth: &State9) -> State9 {
        let mut own = noisy(truth, &self.sigma, &mut self.key.rng(i as u64, Source::OwnState));
        if let Some(faults) = self.faults {
            if let Some(e) = self.env.get(i) {
                for k in 0..3 {
                    own[state::X + k] += e.gnss_bias[k];
                }
            }
            faults.corrupt(i, &mut own);
        }
        own
    }
}

/// One radio message: who sent it, about whom, what it said, and where the sender truly was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Message {
    /// The sender.
    pub sender: u32,
    /// The UAV the message is about: the sender itself (its own measured state), or the
    /// navigator when the sender relays what it knows of it.
    pub about: u32,
    /// The state it reports: the sender's measurement of itself when it sent, or its track of
    /// the navigator.
    pub state: State9,
    /// How old that state was when sent (s): 0 for the sender's own.
    pub age_s: f64,
    /// The sender's true position then (for the radio's range).
    pub at: [f64; 3],
    /// A relay whose position is relative to its sender (relative sensing): a receiver places
    /// it from its own onboard observation of the sender.
    pub relative: bool,
}

impl Message {
    /// Whether the sender forwards what it knows of another UAV.
    pub fn is_relay(&self) -> bool {
        self.about != self.sender
    }
}

/// The UAVs (of `n`) that send their own measurement now, in the order their messages are
/// heard: the beacons first (a lost navigator's beacon passes to its successor, the leader of
/// `lead`), then, when every UAV broadcasts, the others by id.
pub fn senders(sc: &Scenario, lead: Lead, n: usize) -> impl Iterator<Item = usize> + '_ {
    let (radio, beacons) = (sc.radio(), sc.beacons());
    let all = if radio.broadcast_all { n } else { 0 };
    let beacon = move |b: &UavId| if *b == lead.navigator { lead.leader.index() } else { b.index() };
    beacons
        .iter()
        .map(beacon)
        .chain((0..all).filter(move |j| !beacons.iter().any(|b| beacon(b) == *j)))
        .filter(move |&j| j < n)
}

/// Fills `out` with the messages sent now from the true states `states`: the beacons first
/// (a lost navigator's beacon passes to its successor, the leader of `lead`), then, when
/// every UAV broadcasts, the others by id; each carries its sender's own measurement.
/// Computed once per step for all receivers.
pub fn compose(
    sc: &Scenario,
    states: &[State9],
    sensors: &OwnSensors<'_>,
    (lead, parallel): (Lead, bool),
    out: &mut Vec<Message>,
) {
    out.clear();
    out.extend(senders(sc, lead, states.len()).map(|j| Message {
        sender: j as u32,
        about: j as u32,
        state: State9::zeros(),
        age_s: 0.0,
        at: [0.0; 3],
        relative: false,
    }));
    crate::parallel::for_each_mut(out, parallel, |_, m| {
        let j = m.sender as usize;
        let s = &states[j];
        m.state = sensors.measure(j, s);
        m.at = [s[state::X], s[state::Y], s[state::Z]];
    });
}

/// Replaces the state of the leader's own message among `out` (the navigator's, or its
/// successor's once it leads; sent at `t`; `states` the true states) by what its check (None:
/// the warm-up) makes of the reading: the one place both engines check it.
pub fn check_navigator(
    sc: &Scenario,
    (leader, t, states): (UavId, f64, &[State9]),
    check: Option<&mut super::navigator_check::NavigatorCheck>,
    out: &mut [Message],
) {
    let Some(check) = check.filter(|_| proxform_core::own_estimate::OwnEstimate::used(sc.controller())) else {
        return;
    };
    let lead = leader.0;
    if let Some(m) = out.iter_mut().find(|m| m.sender == lead && m.about == lead) {
        m.state = check.checked(sc.controller(), (lead, t), (&states[lead as usize], &m.state));
    }
}

/// Appends to `out` the relays of this step (`radio.relay_navigator`): every active follower
/// whose agent knows the leader (the navigator, or its successor `leader`) forwards that
/// knowledge (its track's state and age at `t`; with relative sensing, its position relative
/// to the sender's own fix). Nothing without relaying, or when the agents run outside the
/// engine.
pub fn relays(
    sc: &Scenario,
    states: &[State9],
    active: &[bool],
    (agents, leader): (&[Option<proxform_core::Agent>], UavId),
    t: f64,
    out: &mut Vec<Message>,
) {
    if !sc.radio().relay_navigator {
        return;
    }
    let nav = leader.0;
    for (j, agent) in agents.iter().enumerate() {
        let Some(agent) = agent.as_ref().filter(|_| active.get(j).copied().unwrap_or(false)) else { continue };
        if let Some(r) = agent.navigator_report(t) {
            let s = &states[j];
            out.push(Message {
                sender: j as u32,
                about: nav,
                state: r.state,
                age_s: r.age_s,
                at: [s[state::X], s[state::Y], s[state::Z]],
                relative: r.relative,
            });
        }
    }
}
