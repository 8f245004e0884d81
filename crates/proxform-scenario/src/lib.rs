//! proxform-scenario: what a flight is, and the file format that describes it.
//!
//! A scenario file (or a Python dict) is parsed into a [`ScenarioSpec`], the raw tables as
//! written; one conversion ([`convert`]) checks every value, fills every default
//! ([`defaults`]) and gives a [`Scenario`] whose fields cannot be changed from outside. The
//! formation's geometry (shapes, the lattice, derived dependency tables), the navigator's path
//! and the world's parameters (noise, wind, radio, faults) are here too, and the comparison
//! file format. This crate has no simulator in it: a network agent on a companion computer
//! reads the same scenario as the simulator does.

pub mod builtin;
pub mod comparison;
pub mod convert;
pub mod defaults;
pub mod faults;
pub mod formation;
pub mod load;
pub mod overrides;
pub mod path;
pub mod placement;
pub mod radio;
pub mod resolved;
pub mod scenario;
pub mod spec;
pub mod wind;

pub use convert::SpecError;
pub use load::LoadError;
pub use path::NavigatorPath;
pub use scenario::{
    in_slots, AllowableErrors, CorrelatedNoise, EngineChoice, MeasurementNoise, NetworkFaults, Scenario,
};
pub use spec::ScenarioSpec;
