//! A formation that changes in flight: from given times on, the UAVs keep other slots (and
//! lean on other references). Every agent knows the schedule, as it knows the formation, and
//! switches by itself when its clock reaches a change; nothing is sent.

use std::sync::Arc;

use crate::dependency::DependencySet;
use crate::error::ConfigError;
use crate::formation::Formation;

/// From `at_s` on, the formation and every UAV's dependency table are these.
#[derive(Debug, Clone)]
pub struct FormationStage {
    /// When the stage starts (s, > 0).
    pub at_s: f64,
    /// Its formation (as many slots as the first).
    pub formation: Arc<Formation>,
    /// Every UAV's dependency table in it.
    pub dependencies: Vec<DependencySet>,
}

/// The stages after the first formation, in time order.
#[derive(Debug, Clone, Default)]
pub struct FormationSchedule {
    stages: Vec<FormationStage>,
}

impl FormationSchedule {
    /// Checks the stages: strictly later one after the other, each of `uavs` slots with one
    /// table per slot.
    pub fn new(stages: Vec<FormationStage>, uavs: usize) -> Result<Self, ConfigError> {
        let mut last = 0.0;
        for s in &stages {
            if !(s.at_s.is_finite() && s.at_s > last) {
                return Err(ConfigError::OutOfRange {
                    field: "formation change at_s",
                    value: s.at_s,
                    expected: "a time after the start and after the change before",
                });
            }
            last = s.at_s;
            if s.formation.len() != uavs || s.dependencies.len() != uavs {
                return Err(ConfigError::OutOfRange {
                    field: "formation change slots",
                    value: s.formation.len() as f64,
                    expected: "as many slots and tables as the first formation",
                });
            }
        }
        Ok(Self { stages })
    }

    /// The stages.
    pub fn stages(&self) -> &[FormationStage] {
        &self.stages
    }

    /// True when the formation never changes.
    pub fn is_empty(&self) -> bool {
        self.stages.is_empty()
    }

    /// The stage in force at `t_s` (None: the first formation).
    pub fn at(&self, t_s: f64) -> Option<&FormationStage> {
        self.stages.iter().rev().find(|s| t_s >= s.at_s - 1e-9)
    }
}
