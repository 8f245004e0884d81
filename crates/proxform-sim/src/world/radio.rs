//! The radio channel of each receiver: i.i.d. losses and a Gilbert-Elliott two-state chain
//! (good, bad) stepped once per period, which loses each message with `loss_bad` in the bad
//! state. The radio's parameters are the scenario's ([`proxform_scenario::radio`]).

use proxform_scenario::radio::RadioModel;

use crate::random::StepRng;

/// Steps a receiver's Gilbert-Elliott channel: `bad` is its state, updated in place.
#[inline]
pub fn step_channel(radio: &RadioModel, bad: &mut bool, rng: &mut StepRng) {
    if let Some(ge) = radio.burst {
        let u = uniform(rng);
        *bad = if *bad { u >= ge.p_bad_to_good } else { u < ge.p_good_to_bad };
    }
}

/// Whether one message gets through, given the receiver's channel state.
#[inline]
pub fn delivered(radio: &RadioModel, bad: bool, rng: &mut StepRng) -> bool {
    if radio.loss > 0.0 && uniform(rng) < radio.loss {
        return false;
    }
    match radio.burst {
        Some(ge) if bad => uniform(rng) >= ge.loss_bad,
        _ => true,
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
    use crate::random::{stream_key, Source};
    use proxform_scenario::radio::GilbertElliott;

    #[test]
    fn losses_match_their_probabilities() {
        let key = stream_key(1, 0, 0, Source::Radio);
        let iid = RadioModel { loss: 0.3, ..RadioModel::default() };
        let n = 100_000;
        let got = (0..n).filter(|&k| delivered(&iid, false, &mut StepRng::new(key, k))).count() as f64 / n as f64;
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
            step_channel(&ge, &mut bad, &mut rng);
            let l = !delivered(&ge, bad, &mut rng);
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
