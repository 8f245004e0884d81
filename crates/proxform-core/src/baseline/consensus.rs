//! Second-order consensus formation control with a leader, over the radio graph.
//!
//! After Ren and Beard ("Distributed Consensus in Multi-vehicle Cooperative Control",
//! Springer 2008, §4.2, consensus with a reference for double integrators; also Ren,
//! "Consensus strategies for cooperative control of vehicle formations", IET CTA 1(2), 2007):
//!
//! `a_i = (1/κ_i)·[Σ_j a_ij (â_j − kp((p_i − p_j) − δ_ij) − kv(v_i − v_j))
//!                + b_i (a_L − kp((p_i − p_L) − δ_iL) − kv(v_i − v_L))]`,  `κ_i = Σ_j a_ij + b_i`,
//!
//! where j runs over the UAVs whose broadcasts i receives this period (`a_ij = 1`, fading while
//! a lost message coasts), `b_i` weighs the navigator (the leader) when heard (as much as all
//! the others together by default, see [`ConsensusGains::leader_share`]), `δ_ij` are the
//! formation offsets `W_ij` and `â_j` each neighbour's acceleration from its α-β track. The
//! attitude follows the same weighted agreement. A UAV that hears nobody flies on.

use std::sync::Arc;

use super::{act, mean_attitude, pd_acceleration, Hearing, PdGains};
use crate::controller::{ControllerSetup, Decision};
use crate::error::{positive, ConfigError};
use crate::formation::Formation;
use crate::observation::{Observation, ObservationSource, UavId};
use crate::state::State9;

/// Gains of the consensus law.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConsensusGains {
    /// PD gains on the relative errors. Default critically damped at 1 rad/s.
    pub pd: PdGains,
    /// The leader's share (> 0): its weight is the constant `b_i = leader_share · max(1, N − 2)`,
    /// N the formation's size, against 1 for each other UAV. Default 1: the leader counts as
    /// much as all the other followers together, whatever the formation's size (with b_i = 1
    /// the six-UAV paper formation lags its navigator by up to 1.1 m as a whole).
    pub leader_share: f64,
}

impl Default for ConsensusGains {
    fn default() -> Self {
        Self { pd: PdGains::critical(1.0), leader_share: 1.0 }
    }
}

impl ConsensusGains {
    /// Checks the gains.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.pd.validate("consensus.kp", "consensus.kv")?;
        positive("consensus.leader_share", self.leader_share)
    }
}

/// The consensus controller of one UAV.
#[derive(Debug, Clone)]
pub struct Consensus {
    gains: ConsensusGains,
    core: Hearing,
    /// Per UAV heard: desired state now and next, and weight (working memory).
    desired: Vec<(State9, State9, f64)>,
}

impl Consensus {
    /// The consensus controller of UAV `id`, with `leader` as the reference.
    pub fn new(
        id: UavId,
        leader: UavId,
        gains: ConsensusGains,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
    ) -> Result<Self, ConfigError> {
        gains.validate()?;
        let cap = formation.len();
        Ok(Self { gains, core: Hearing::new(id, leader, setup, formation, cap)?, desired: Vec::with_capacity(cap) })
    }

    /// The setup shared with the other controllers.
    pub fn setup(&self) -> &ControllerSetup {
        &self.core.setup
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.core.heap_bytes() + self.desired.capacity() * std::mem::size_of::<(State9, State9, f64)>()
    }

    /// One period: agree with every UAV heard.
    pub fn step(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        let core = &mut self.core;
        core.hear(now_s, observations, |o| o.source == ObservationSource::Radio);
        self.desired.clear();
        let b = self.gains.leader_share * (core.formation.len() as f64 - 2.0).max(1.0);
        for h in &core.heard {
            let Some((d_now, d_next)) = core.slot_from(h) else { continue };
            let c = if h.id == core.leader { b } else { 1.0 } * h.weight;
            self.desired.push((d_now, d_next, c));
        }
        let kappa: f64 = self.desired.iter().map(|d| d.2).sum();
        if self.desired.is_empty() || kappa <= 0.0 {
            return Decision::alone();
        }
        let dt = core.setup.params().dt_s;
        let mut a = [0.0; 3];
        for (d_now, d_next, c) in &self.desired {
            let aj = pd_acceleration(own, d_now, d_next, dt, &self.gains.pd);
            for k in 0..3 {
                a[k] += c * aj[k] / kappa;
            }
        }
        let attitude = mean_attitude(own, self.desired.iter().map(|(_, next, c)| (*next, *c)));
        act(&core.setup, own, a, attitude.unwrap_or_else(|| std::array::from_fn(|k| own[6 + k])))
    }
}
