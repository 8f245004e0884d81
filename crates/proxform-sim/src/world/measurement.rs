//! What a UAV's own sensors say of it, and the radio messages it sends from that.
//!
//! A UAV's measurement of its own state is its true state with white noise (its own-state
//! stream at the step), plus, in flight, the bias of its position fix and its sensor faults
//! (a glitch, a stuck sensor). The agent decides from it, and a UAV that broadcasts sends it:
//! a message carries what the sender believes, not the truth.

use proxform_core::state::{self, State9};
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

/// One radio message: who sent it, what it believed of itself, and where it truly was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Message {
    /// The sender.
    pub sender: u32,
    /// The sender's measurement of its own state when it sent.
    pub state: State9,
    /// Its true position then (for the radio's range).
    pub at: [f64; 3],
}

/// Fills `out` with the messages sent now from the true states `states`: the beacons first,
/// then, when every UAV broadcasts, the others by id; each carries its sender's own
/// measurement. Computed once per step for all receivers.
pub fn compose(sc: &Scenario, states: &[State9], sensors: &OwnSensors<'_>, parallel: bool, out: &mut Vec<Message>) {
    let (radio, beacons) = (sc.radio(), sc.beacons());
    let n = states.len();
    let all = if radio.broadcast_all { n } else { 0 };
    out.clear();
    out.extend(
        beacons
            .iter()
            .map(|b| b.index())
            .chain((0..all).filter(|j| !beacons.iter().any(|b| b.index() == *j)))
            .filter(|&j| j < n)
            .map(|j| Message { sender: j as u32, state: State9::zeros(), at: [0.0; 3] }),
    );
    crate::parallel::for_each_mut(out, parallel, |_, m| {
        let j = m.sender as usize;
        let s = &states[j];
        m.state = sensors.measure(j, s);
        m.at = [s[state::X], s[state::Y], s[state::Z]];
    });
}
