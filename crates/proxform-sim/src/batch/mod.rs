//! Batches: seeded runs in parallel, comparisons of methods under conditions, throughput.

pub mod compare;
pub mod runs;
pub mod throughput;
