//! proxform-sim: the deterministic stepping engine around the per-UAV controllers.
//!
//! It owns the scenario (who flies where, with which controller, vehicle, noise and path),
//! the engine that steps every UAV from a shared snapshot, the seeded random streams, the
//! observers that measure a run, and batches of seeded runs in parallel. It writes no files:
//! output belongs to the caller.

pub mod autodeps;
pub mod batch;
pub mod compare;
pub mod disturbance;
pub mod engine;
pub mod environment;
pub mod faults;
pub mod grid;
pub mod load;
pub mod metrics;
pub mod normal;
pub mod observer;
pub mod path;
pub mod radio;
pub mod rng;
pub mod scenario;
pub mod sensing;
pub mod shapes;
pub mod spec;
pub mod swarm;
pub mod throughput;
pub mod trajectory;

pub use batch::{run_batch, AxisErrors, BatchResult, Summary, SwarmMetrics};
pub use engine::Simulation;
pub use metrics::{RunMetrics, RunSummary};
pub use observer::{Observer, StepFrame};
pub use path::{NavigatorPath, PaperPath};
pub use scenario::{AllowableErrors, MeasurementNoise, Scenario, ScenarioError};
pub use trajectory::{Trajectory, TrajectoryRow};
