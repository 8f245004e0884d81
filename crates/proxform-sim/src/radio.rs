//! The radio: who hears whom, how late and how reliably.
//!
//! A UAV that broadcasts sends, every period, its own measured state (the estimate it has of
//! itself). A receiver gets the message `delay_steps` periods later if the sender was within
//! radio range when it sent, the radio is not blacked out, and the message is not lost. Losses
//! are i.i.d. with probability `loss`, plus, when `burst` is set, a Gilbert-Elliott channel per
//! receiver: a two-state Markov chain (good, bad) stepped once per period, which loses each
//! message with `loss_bad` in the bad state. Broadcasting from every UAV costs O(N²) per step;
//! large swarms name a few broadcasters (`beacons`) instead.

use crate::rng::StepRng;

/// Gilbert-Elliott bursty loss (per receiver).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GilbertElliott {
    /// Probability per period of going from good to bad.
    pub p_good_to_bad: f64,
    /// Probability per period of going from bad to good.
    pub p_bad_to_good: f64,
    /// Loss probability in the bad state.
    pub loss_bad: f64,
}

/// The radio model of a scenario. The default is an ideal radio with no broadcasters.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RadioModel {
    /// True when every UAV broadcasts (besides the listed beacons).
    pub broadcast_all: bool,
    /// Range of a message (m); `f64::INFINITY` for no limit.
    pub range_m: f64,
    /// Delay of every message, in update periods.
    pub delay_steps: u32,
    /// i.i.d. loss probability of each message.
    pub loss: f64,
    /// Optional bursty loss.
    pub burst: Option<GilbertElliott>,
}

impl Default for RadioModel {
    fn default() -> Self {
        Self { broadcast_all: false, range_m: f64::INFINITY, delay_steps: 0, loss: 0.0, burst: None }
    }
}

impl RadioModel {
    /// The same broadcasters and range with no delay and no loss.
    pub fn ideal(&self) -> Self {
        Self { delay_steps: 0, loss: 0.0, burst: None, ..*self }
    }

    /// Steps the receiver's Gilbert-Elliott channel: `bad` is its state, updated in place.
    #[inline]
    pub fn step_channel(&self, bad: &mut bool, rng: &mut StepRng) {
        if let Some(ge) = self.burst {
            let u = uniform(rng);
            *bad = if *bad { u >= ge.p_bad_to_good } else { u < ge.p_good_to_bad };
        }
    }

    /// Whether one message gets through, given the receiver's channel state.
    #[inline]
    pub fn delivered(&self, bad: bool, rng: &mut StepRng) -> bool {
        if self.loss > 0.0 && uniform(rng) < self.loss {
            return false;
        }
        match self.burst {
            Some(ge) if bad => uniform(rng) >= ge.loss_bad,
            _ => true,
        }
    }
}

/// Uniform in [0, 1).
#[inline]
pub fn uniform(rng: &mut StepRng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{stream_key, Source};

    #[test]
    fn losses_match_their_probabilities() {
        let key = stream_key(1, 0, 0, Source::Radio);
        let iid = RadioModel { loss: 0.3, ..RadioModel::default() };
        let n = 100_000;
        let got = (0..n).filter(|&k| iid.delivered(false, &mut StepRng::new(key, k))).count() as f64 / n as f64;
        assert!((got - 0.7).abs() < 0.01, "{got}");
        // Gilbert-Elliott: stationary bad fraction p_gb / (p_gb + p_bg), losses in bursts.
        let ge = RadioModel {
            burst: Some(GilbertElliott { p_good_to_bad: 0.05, p_bad_to_good: 0.2, loss_bad: 1.0 }),
            ..RadioModel::default()
        };
        let mut bad = false;
        let (mut lost, mut runs, mut prev_lost) = (0u64, 0u64, false);
        for k in 0..n {
            let mut rng = StepRng::new(key, k);
            ge.step_channel(&mut bad, &mut rng);
            let l = !ge.delivered(bad, &mut rng);
            lost += u64::from(l);
            runs += u64::from(l && !prev_lost);
            prev_lost = l;
        }
        let frac = lost as f64 / n as f64;
        assert!((frac - 0.2).abs() < 0.02, "{frac}");
        // Mean burst length 1 / p_bad_to_good = 5 periods.
        let mean_burst = lost as f64 / runs as f64;
        assert!((mean_burst - 5.0).abs() < 0.5, "{mean_burst}");
    }
}
