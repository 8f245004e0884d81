//! Which formation controller a UAV runs, behind one interface.
//!
//! [`Method`] names a controller and its gains (what a scenario or comparison file chooses);
//! [`FormationController`] is the running controller of one UAV. Every method takes the same
//! inputs (time, the UAV's own state estimate, its observations) and returns the same
//! [`Decision`], so the simulator, and later a network agent, drive them all alike. An enum
//! rather than a trait object keeps the per-UAV step monomorphic and the controllers plain data.

use std::sync::Arc;

use crate::baseline::{Consensus, ConsensusGains, Flocking, FlockingGains, LeaderFollower, LeaderFollowerGains};
use crate::controller::{ControllerSetup, Decision, ProximityController};
use crate::dependency::DependencySet;
use crate::error::ConfigError;
use crate::formation::Formation;
use crate::observation::{Observation, UavId};
use crate::state::State9;

/// A formation control method and its gains.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The proximity method of METHOD §2-§7 (its parameters are the controller parameters).
    #[default]
    Proximity,
    /// Leader-follower ([`crate::baseline::LeaderFollower`]).
    LeaderFollower(LeaderFollowerGains),
    /// Second-order consensus with a leader ([`crate::baseline::Consensus`]).
    Consensus(ConsensusGains),
    /// Flocking with a virtual leader ([`crate::baseline::Flocking`]).
    Flocking(FlockingGains),
}

/// Which radio messages a method needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RadioNeed {
    /// None beyond what the scenario configures.
    None,
    /// The navigator's broadcasts.
    Navigator,
    /// Every UAV's broadcasts.
    All,
}

impl Method {
    /// Short name used in files and reports.
    pub fn label(&self) -> &'static str {
        match self {
            Method::Proximity => "proximity",
            Method::LeaderFollower(_) => "leader_follower",
            Method::Consensus(_) => "consensus",
            Method::Flocking(_) => "flocking",
        }
    }

    /// The method with its default gains, by label.
    pub fn from_label(label: &str) -> Option<Self> {
        Some(match label {
            "proximity" => Method::Proximity,
            "leader_follower" => Method::LeaderFollower(LeaderFollowerGains::default()),
            "consensus" => Method::Consensus(ConsensusGains::default()),
            "flocking" => Method::Flocking(FlockingGains::default()),
            _ => return None,
        })
    }

    /// Every label [`Method::from_label`] knows.
    pub const LABELS: [&'static str; 4] = ["proximity", "leader_follower", "consensus", "flocking"];

    /// Whether the method uses what the UAV senses onboard.
    pub fn uses_onboard_sensing(&self) -> bool {
        matches!(self, Method::Proximity | Method::Flocking(_))
    }

    /// The radio messages the method needs.
    pub fn radio_need(&self) -> RadioNeed {
        match self {
            Method::Proximity => RadioNeed::None,
            Method::LeaderFollower(_) | Method::Flocking(_) => RadioNeed::Navigator,
            Method::Consensus(_) => RadioNeed::All,
        }
    }

    /// Checks the gains.
    pub fn validate(&self) -> Result<(), ConfigError> {
        match self {
            Method::Proximity => Ok(()),
            Method::LeaderFollower(g) => g.validate(),
            Method::Consensus(g) => g.validate(),
            Method::Flocking(g) => g.validate(),
        }
    }
}

/// The running controller of one UAV, whichever the method. The baselines are boxed so that
/// the enum is no larger than the proximity controller: a swarm of 10^6 proximity
/// controllers pays nothing for the other variants.
#[derive(Debug, Clone)]
pub enum FormationController {
    /// The proximity controller.
    Proximity(ProximityController),
    /// Leader-follower.
    LeaderFollower(Box<LeaderFollower>),
    /// Consensus.
    Consensus(Box<Consensus>),
    /// Flocking.
    Flocking(Box<Flocking>),
}

impl FormationController {
    /// The controller of UAV `id` for `method`; `leader` is the navigator (the baselines'
    /// reference), `dependency` the UAV's table (the proximity method's main references).
    pub fn new(
        method: &Method,
        id: UavId,
        leader: UavId,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
        dependency: DependencySet,
    ) -> Result<Self, ConfigError> {
        Ok(match *method {
            Method::Proximity => {
                Self::Proximity(ProximityController::new(id, setup, formation, dependency)?.with_navigator(leader))
            }
            Method::LeaderFollower(g) => {
                Self::LeaderFollower(Box::new(LeaderFollower::new(id, leader, g, setup, formation)?))
            }
            Method::Consensus(g) => Self::Consensus(Box::new(Consensus::new(id, leader, g, setup, formation)?)),
            Method::Flocking(g) => Self::Flocking(Box::new(Flocking::new(id, leader, g, setup, formation)?)),
        })
    }

    /// One update period at `now_s` from the UAV's own state estimate and its observations.
    #[inline]
    pub fn step(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        match self {
            Self::Proximity(c) => c.step(now_s, own, observations),
            Self::LeaderFollower(c) => c.step(now_s, own, observations),
            Self::Consensus(c) => c.step(now_s, own, observations),
            Self::Flocking(c) => c.step(now_s, own, observations),
        }
    }

    /// What the UAV knows of the navigator to forward over the radio (the proximity method's
    /// track of it; the baselines forward nothing).
    pub fn navigator_report(&self, now_s: f64) -> Option<crate::NavigatorReport> {
        match self {
            Self::Proximity(c) => c.navigator_report(now_s),
            _ => None,
        }
    }

    /// The shared setup: parameters, vehicle model.
    pub fn setup(&self) -> &ControllerSetup {
        match self {
            Self::Proximity(c) => c.setup(),
            Self::LeaderFollower(c) => c.setup(),
            Self::Consensus(c) => c.setup(),
            Self::Flocking(c) => c.setup(),
        }
    }

    /// Bytes held on the heap (shared setup and formation excluded).
    pub fn heap_bytes(&self) -> usize {
        match self {
            Self::Proximity(c) => c.heap_bytes(),
            Self::LeaderFollower(c) => c.heap_bytes() + std::mem::size_of::<LeaderFollower>(),
            Self::Consensus(c) => c.heap_bytes() + std::mem::size_of::<Consensus>(),
            Self::Flocking(c) => c.heap_bytes() + std::mem::size_of::<Flocking>(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_enum_costs_nothing_over_the_proximity_controller() {
        assert!(std::mem::size_of::<FormationController>() <= std::mem::size_of::<ProximityController>() + 8);
    }
}
