//! The radio: who hears whom, how late and how reliably.
//!
//! A UAV that broadcasts sends, every period, its own measured state (the estimate it has of
//! itself). A receiver gets the message `delay_steps` periods later if the sender was within
//! radio range when it sent, the radio is not blacked out, and the message is not lost. Losses
//! are i.i.d. with probability `loss`, plus, when `burst` is set, a Gilbert-Elliott channel per
//! receiver: a two-state Markov chain (good, bad) stepped once per period, which loses each
//! message with `loss_bad` in the bad state. Broadcasting from every UAV costs O(N²) per step;
//! large swarms name a few broadcasters (`beacons`) instead. With `relay_navigator`, every UAV
//! also forwards, each period, what it knows of the navigator (its track of it, with its age),
//! so that the navigator's state reaches UAVs beyond its radio range hop by hop.

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
    /// Every UAV forwards its latest knowledge of the navigator each period (one more message
    /// per UAV and period).
    pub relay_navigator: bool,
}

impl Default for RadioModel {
    fn default() -> Self {
        Self {
            broadcast_all: false,
            range_m: f64::INFINITY,
            delay_steps: 0,
            loss: 0.0,
            burst: None,
            relay_navigator: false,
        }
    }
}

impl GilbertElliott {
    /// The share of periods the channel spends in its bad state, in the long run.
    pub fn bad_fraction(&self) -> f64 {
        let moves = self.p_good_to_bad + self.p_bad_to_good;
        if moves > 0.0 {
            self.p_good_to_bad / moves
        } else {
            0.0
        }
    }
}

impl RadioModel {
    /// The same broadcasters and range with no delay and no loss.
    pub fn ideal(&self) -> Self {
        Self { delay_steps: 0, loss: 0.0, burst: None, ..*self }
    }

    /// The share of messages lost in the long run: the i.i.d. loss and, with bursts, the bad
    /// state's loss for the share of periods spent in it.
    pub fn mean_loss(&self) -> f64 {
        let bad = self.burst.map_or(0.0, |b| b.bad_fraction() * b.loss_bad);
        1.0 - (1.0 - self.loss) * (1.0 - bad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mean_loss_counts_the_bad_state_for_its_share_of_the_time() {
        let iid = RadioModel { loss: 0.1, ..RadioModel::default() };
        assert!((iid.mean_loss() - 0.1).abs() < 1e-12);
        // Bad a fifth of the time (0.05 in, 0.2 out), losing half there: 10 %; with 10 % i.i.d.
        // besides, 1 − 0.9 · 0.9 = 19 %.
        let burst = GilbertElliott { p_good_to_bad: 0.05, p_bad_to_good: 0.2, loss_bad: 0.5 };
        let bursty = RadioModel { burst: Some(burst), ..RadioModel::default() };
        assert!((bursty.mean_loss() - 0.1).abs() < 1e-12, "{}", bursty.mean_loss());
        assert!((RadioModel { loss: 0.1, ..bursty }.mean_loss() - 0.19).abs() < 1e-12);
    }
}
