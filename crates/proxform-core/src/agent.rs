//! What one UAV owns, and its step: the piece the simulator, a network agent and Python share.
//!
//! An [`Agent`] owns its formation controller (whichever the method), its neighbour tracks
//! (inside the controller) and its estimate of its own state. One [`Agent::step`] is one update
//! period: the UAV's own measurement and what reached it since the last period (onboard
//! detections, radio messages) in, its [`Decision`] out. Where the observations come from,
//! noise, actuation and the plant stay outside it.

use std::sync::Arc;

use crate::controller::{ControllerSetup, Decision};
use crate::dependency::DependencySet;
use crate::error::ConfigError;
use crate::formation::Formation;
use crate::method::{FormationController, Method};
use crate::observation::{Observation, UavId};
use crate::state::{self, State9};
use crate::vehicle::VehicleModel;

/// What every agent of a formation shares: the method, the navigator (the baselines' leader),
/// the controller setup, the formation and every UAV's dependency table.
#[derive(Debug, Clone)]
pub struct AgentSetup {
    method: Method,
    navigator: UavId,
    controller: Arc<ControllerSetup>,
    formation: Arc<Formation>,
    dependencies: Vec<DependencySet>,
}

impl AgentSetup {
    /// Checks that the navigator and every table belong to the formation.
    pub fn new(
        method: Method,
        navigator: UavId,
        controller: Arc<ControllerSetup>,
        formation: Arc<Formation>,
        dependencies: Vec<DependencySet>,
    ) -> Result<Self, ConfigError> {
        let n = formation.len();
        if navigator.index() >= n {
            return Err(ConfigError::UnknownUav { id: navigator, size: n });
        }
        if dependencies.len() != n {
            return Err(ConfigError::OutOfRange {
                field: "dependency tables",
                value: dependencies.len() as f64,
                expected: "one table per slot of the formation",
            });
        }
        method.validate()?;
        Ok(Self { method, navigator, controller, formation, dependencies })
    }

    /// The followers' method.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// The navigator.
    pub fn navigator(&self) -> UavId {
        self.navigator
    }

    /// The controller setup (parameters, vehicle, derived quantities).
    pub fn controller(&self) -> &Arc<ControllerSetup> {
        &self.controller
    }

    /// The formation.
    pub fn formation(&self) -> &Arc<Formation> {
        &self.formation
    }

    /// Every UAV's dependency table.
    pub fn dependencies(&self) -> &[DependencySet] {
        &self.dependencies
    }
}

/// One UAV: its controller, its tracks and its own-state estimate.
#[derive(Debug, Clone)]
pub struct Agent {
    controller: FormationController,
    /// The own state this UAV expects at the next step: the model applied to its estimate and
    /// the input it chose (None before the first step, and when the own-state filter is off;
    /// boxed so that agents without it stay small).
    own_prediction: Option<Box<State9>>,
}

impl Agent {
    /// The agent of follower `id`.
    pub fn new(setup: &AgentSetup, id: UavId) -> Result<Self, ConfigError> {
        let deps = setup.dependencies.get(id.index()).cloned().unwrap_or_default();
        let controller = FormationController::new(
            &setup.method,
            id,
            setup.navigator,
            setup.controller.clone(),
            setup.formation.clone(),
            deps,
        )?;
        Ok(Self { controller, own_prediction: None })
    }

    /// One update period at `now_s`: `own_measured` is the UAV's measurement of its own state,
    /// `heard` what reached it (each id at most once). The own-state filter (gain < 1) blends
    /// the measurement with the UAV's own prediction before the controller decides.
    pub fn step(&mut self, now_s: f64, own_measured: &State9, heard: &[Observation]) -> Decision {
        let setup = self.controller.setup();
        let gain = setup.params().own_filter_gain;
        let own = match self.own_prediction {
            Some(ref pred) if gain < 1.0 => {
                // Position and velocity are filtered; attitude, measured far more finely than
                // its tolerances, is taken as measured (filtering it would only add lag).
                let mut own = **pred + gain * state::difference(own_measured, pred);
                for k in state::ALPHA..=state::GAMMA {
                    own[k] = own_measured[k];
                }
                own
            }
            _ => *own_measured,
        };
        let decision = self.controller.step(now_s, &own, heard);
        if gain < 1.0 {
            let setup = self.controller.setup();
            let next = setup.vehicle().propagate(&own, &decision.input, setup.params().dt_s);
            match &mut self.own_prediction {
                Some(p) => **p = next,
                None => self.own_prediction = Some(Box::new(next)),
            }
        }
        decision
    }

    /// Forgets the own-state prediction (after inputs that were not applied, such as a
    /// warm-up's).
    pub fn forget_own_estimate(&mut self) {
        self.own_prediction = None;
    }

    /// The vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        self.controller.setup().vehicle()
    }

    /// The controller.
    pub fn controller(&self) -> &FormationController {
        &self.controller
    }

    /// Bytes held on the heap (shared setup and formation excluded).
    pub fn heap_bytes(&self) -> usize {
        self.controller.heap_bytes() + self.own_prediction.as_ref().map_or(0, |_| std::mem::size_of::<State9>())
    }
}
