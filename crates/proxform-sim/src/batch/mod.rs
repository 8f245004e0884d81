//! Batches: seeded runs in parallel, comparisons of methods under conditions, throughput.

pub mod compare;
pub mod minimal;
pub mod runs;
pub mod throughput;
