//! Microstructures built on the core engine: rod lattices and shells with
//! infill, porous media (Pasko et al. 2009), unit-cell replication and
//! variable, multi-scale and surficial structures (Fryazinov et al.), TPMS
//! and strut lattices with density control, and the built-in example models.

pub mod cell_report;
pub mod density;
pub mod error;
pub mod examples;
pub mod infill;
pub mod lattice;
pub mod porous;
pub mod replicate;
pub mod sampling;
pub mod strut_graph;
pub mod struts;
pub mod surficial;
pub mod tpms;
pub mod variable;

pub use error::{Error, Result};
