//! The simulated world: the engine and what it simulates around the agents (onboard sensing,
//! radio, wind and turbulence, per-UAV environment, faults in force).

pub mod airwaves;
pub mod engine;
pub mod environment;
pub mod faults;
pub mod measurement;
pub mod membership;
pub mod navigator_check;
pub mod options;
pub mod phases;
pub mod placement;
pub mod plant;
pub mod radio;
pub mod reach;
pub mod remote;
pub mod sensing;
pub mod wind;
