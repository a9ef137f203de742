//! Analysis of FRep models (inside is `f >= 0`): volume and volume fraction,
//! surface area and specific surface, connectivity of solid and pores, and
//! local thickness of solid and pore space, each with its accuracy.
//!
//! ```
//! use microfrep_analysis::{analyze, AnalyzeOptions, Grid};
//! use microfrep_core::{Expr, Shape};
//! use microfrep_shapes as prims;
//! let ball = prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0);
//! let grid = Grid::new([[-1.0; 3], [1.0; 3]], 64).unwrap();
//! let opts = AnalyzeOptions { thickness: false, ..AnalyzeOptions::default() };
//! let r = analyze(&Shape::new(ball), None, grid, &opts, &|_, _, _| {}).unwrap();
//! let exact = 4.0 / 3.0 * std::f64::consts::PI;
//! assert!((r.volume() - exact).abs() < 3.0 * r.volume_error() + 1e-3);
//! assert_eq!(r.connectivity.unwrap().surface_euler(), 2);
//! ```
//!
//! Modules: `grid` (voxel grids and the occupancy sampler shared by all;
//! its API is stated at the top of `grid.rs`), `measure` (volume and area
//! from intervals and corner samples, with `volume` and `area` holding the
//! per-tetrahedron closed forms), `connectivity` (slab-wise component
//! labelling, Euler characteristic), `thickness` (exact Euclidean distance
//! transform and local thickness on slabs), `report` (all of them in one
//! call), `partial` (the same measures on ranges of
//! voxel layers, merged exactly: for distributed runs).

#![warn(missing_docs)]

pub mod area;
pub mod attributes;
pub mod connectivity;
mod crease;
pub mod error;
pub mod grid;
pub mod measure;
pub mod partial;
pub mod report;
pub mod summary;
pub mod thickness;
pub mod volume;

pub use connectivity::{connectivity, Connectivity};
pub use error::AnalysisError;
pub use grid::{Grid, Sampler};
pub use measure::{measure, Measures};
pub use report::{analyze, AnalyzeOptions, Report, Stage};
pub use volume::Estimate;
