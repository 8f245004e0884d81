//! Formation geometry: generated shapes, the large-swarm lattice, and dependency tables
//! derived from the slots.

pub mod autodeps;
pub mod lattice;
pub mod shapes;
