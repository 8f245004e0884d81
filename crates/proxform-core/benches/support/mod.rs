//! Set-ups shared by the benchmarks and the instruction-count example.

pub mod ring;
pub mod variants;
