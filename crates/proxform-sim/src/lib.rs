//! proxform-sim: the simulated world around the per-UAV agents, its measurement, and batches.
//!
//! - [`world`]: the engine that steps every UAV in named phases (perceive, estimate, decide,
//!   actuate, propagate) from a shared snapshot, the onboard sensor, the radio, wind and
//!   faults. Each UAV's decision is its [`proxform_core::Agent`]'s step.
//! - [`fast`]: the structure-of-arrays engine for large swarms (the same method over arrays);
//!   [`flight`] runs a flight on whichever engine the scenario chooses.
//! - [`random`]: the seeded random streams every draw comes from.
//! - [`measure`]: observers that watch a run (metrics, trajectories).
//! - [`batch`]: seeded runs in parallel, comparisons of methods, throughput.
//!
//! The scenario is [`proxform_scenario::Scenario`]; how to run it (adjustment on or off, the
//! neighbour search) is [`RunOptions`]. This crate writes no files: output belongs to the
//! caller.

pub mod batch;
pub mod fast;
pub mod flight;
pub mod measure;
pub mod parallel;
pub mod random;
pub mod world;

pub use batch::aggregate::{Aggregator, RunCounts};
pub use batch::compare;
pub use batch::journal::{JournalHeader, Shard};
pub use batch::runs::{
    fly_runs, run_batch, run_batch_stoppable, run_batch_with_agents, run_one, AxisErrors, BatchResult, FlownSummary,
    FormingSummary, IsolationSummary, SensorFaultSummary, Summary, SwarmMetrics, TransitionSummary,
    UncontrolledSummary,
};
pub use flight::{bytes_estimate, engine_for, EngineKind, Flight};
pub use measure::metrics::{
    FormingMetrics, IsolationMetrics, RunMetrics, RunSummary, SensorFaultMetrics, TransitionMetrics,
};
pub use measure::observer::{Observer, StepFrame, StepOutcome, UavStep};
pub use measure::trajectory::{Trajectory, TrajectoryRow};
pub use world::engine::Simulation;
pub use world::options::RunOptions;
