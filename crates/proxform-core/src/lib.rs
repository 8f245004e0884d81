//! proxform-core: the per-UAV side of proximity formation maintenance.
//!
//! This crate owns the 9-parameter behaviour state, the vehicle models, azimuth-area sensing,
//! the proximity formation controller of METHOD.md §2-§7, the baselines, and the [`Agent`]
//! that owns what one UAV owns and steps it. It does no I/O, reads no clock, starts no threads
//! and owns no random number generator: everything it needs arrives as arguments, so the same
//! agent runs in the simulator, behind a network transport, or from Python.

pub mod agent;
pub mod angle;
pub mod assignment;
pub mod azimuth;
pub mod baseline;
pub mod control;
pub mod controller;
pub mod dependency;
pub mod envelope;
pub mod error;
pub mod formation;
pub mod grid;
pub mod horizon;
pub mod method;
pub mod observation;
pub mod own_estimate;
pub mod plan;
pub mod predictor;
pub mod schedule;
pub mod singer;
pub mod state;
pub mod succession;
pub mod vehicle;

pub use agent::{Agent, AgentSetup};
pub use azimuth::AzimuthAreas;
pub use controller::{ControllerParams, ControllerSetup, Decision, Outcome, ProximityController};
pub use dependency::DependencySet;
pub use envelope::Envelope;
pub use error::ConfigError;
pub use formation::{Formation, FormationFrame, FormationSlot};
pub use method::{FormationController, Method, RadioNeed};
pub use observation::{NavigatorReport, Observation, ObservationSource, UavId};
pub use predictor::PredictorKind;
pub use schedule::{FormationSchedule, FormationStage};
pub use state::{Input, State9};
pub use vehicle::{FixedWingModel, KinematicLimits, KinematicModel, MultirotorModel, Setpoint, VehicleModel};
