//! Leader-follower formation control: every follower tracks the navigator's broadcast state
//! plus its formation offset.
//!
//! The classic scheme of Desai, Ostrowski and Kumar ("Modeling and control of formations of
//! nonholonomic mobile robots", IEEE Trans. Robotics and Automation 17(6), 2001), here in its
//! Cartesian "l-ψ"-free form for a point-mass-like vehicle: follower i commands
//! `a_i = a_d − kp·(p_i − p_d) − kv·(v_i − v_d)` with `X_d = X_L + W_iL`, the leader's state
//! predicted from its broadcasts (α-β track, delay compensated), and steers its attitude to the
//! leader's plus the slot's attitude offset. It needs the leader's messages: without them the
//! follower flies on.

use std::sync::Arc;

use super::{act, pd_acceleration, Hearing, PdGains};
use crate::controller::{ControllerSetup, Decision};
use crate::error::ConfigError;
use crate::formation::Formation;
use crate::observation::{Observation, UavId};
use crate::state::{State9, ALPHA};

/// Gains of the leader-follower law.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LeaderFollowerGains {
    /// PD gains toward the slot. Default critically damped at 1 rad/s: kp 1/s², kv 2/s.
    pub pd: PdGains,
}

impl Default for LeaderFollowerGains {
    fn default() -> Self {
        Self { pd: PdGains::critical(1.0) }
    }
}

impl LeaderFollowerGains {
    /// Checks the gains.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.pd.validate("leader_follower.kp", "leader_follower.kv")
    }
}

/// The leader-follower controller of one UAV.
#[derive(Debug, Clone)]
pub struct LeaderFollower {
    gains: LeaderFollowerGains,
    core: Hearing,
}

impl LeaderFollower {
    /// Follower `id` of `leader`.
    pub fn new(
        id: UavId,
        leader: UavId,
        gains: LeaderFollowerGains,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
    ) -> Result<Self, ConfigError> {
        gains.validate()?;
        let cap = 1;
        Ok(Self { gains, core: Hearing::new(id, leader, setup, formation, cap)? })
    }

    /// The setup shared with the other controllers.
    pub fn setup(&self) -> &ControllerSetup {
        &self.core.setup
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        self.core.heap_bytes()
    }

    /// One period: track the leader's slot.
    pub fn step(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        let c = &mut self.core;
        let leader = c.leader;
        c.hear(now_s, observations, |o| o.id == leader);
        let Some(h) = c.heard.first() else { return Decision::alone() };
        let Some((d_now, d_next)) = c.slot_from(h) else { return Decision::alone() };
        let a = pd_acceleration(own, &d_now, &d_next, c.setup.params().dt_s, &self.gains.pd);
        act(&c.setup, own, a, std::array::from_fn(|k| d_next[ALPHA + k]))
    }
}
