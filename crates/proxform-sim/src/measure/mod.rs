//! Measurement: observers that watch every step of a run (formation errors, metrics,
//! trajectories) and the statistics over runs.

pub mod metrics;
pub mod observer;
pub mod separation;
pub mod stats;
pub mod trajectory;
pub(crate) mod verdict;
