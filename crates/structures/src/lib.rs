//! Microstructures built on the core engine: rod lattices (Pasko et al.),
//! unit-cell replication (Fryazinov et al.) and the built-in example models.

pub mod examples;
pub mod lattice;
pub mod replicate;
