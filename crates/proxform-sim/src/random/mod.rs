//! Seeded random streams: every draw of a run comes from a generator keyed by its stream
//! (seed, run, UAV, source) and the step, and normal deviates from a shared ziggurat.

pub mod bulk;
pub mod normal;
pub mod rng;

pub use normal::Ziggurat;
pub use rng::{stream_key, RunKey, Source, StepRng, StreamKey};
