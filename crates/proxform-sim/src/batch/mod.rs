//! Batches: seeded runs in parallel, comparisons of methods under conditions, throughput.

pub mod aggregate;
pub mod compare;
pub mod journal;
pub mod merge;
pub mod minimal;
pub mod runs;
pub mod sweep;
pub mod throughput;
