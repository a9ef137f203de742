//! Microstructures built on the core engine: rod lattices and shells with
//! infill, porous media (Pasko et al. 2009), unit-cell replication and
//! variable, multi-scale and surficial structures (Fryazinov et al.), TPMS
//! and strut lattices with density control, and the built-in example models.
//!
//! Every builder returns a core [`Expr`](microfrep_core::Expr) (inside is
//! `f >= 0`, lengths in mm) and takes its parameters as expressions, so a
//! thickness or cell size may itself be a field that varies in space.
//! Analyses that sample a model ([`cell_report`], [`density`]) report bad
//! boxes, resolutions and targets as [`Error`]s.
//!
//! ```
//! use microfrep_core::{Expr, PointEval, Tape};
//! use microfrep_structures::replicate::{replicate_cell, Wave};
//! use microfrep_structures::tpms::{tpms, Solid, Tpms};
//!
//! let p = Expr::xyz();
//! // A gyroid sheet: cells of 2 mm, wall where |f| < 0.3.
//! let gyroid = tpms(Tpms::Gyroid, Solid::Sheet, &p, 2.0, 0.3);
//! let mut g = PointEval::new(&Tape::new(&gyroid));
//! assert!(g.eval([0.0, 0.0, 0.0]) > 0.0); // on the surface: inside the wall
//! assert!(g.eval([0.5, 0.0, 0.0]) < 0.0); // a quarter cell away: outside
//!
//! // A ball of radius 0.4 on the cell [-0.5, 0.5]^3, repeated every 1 mm.
//! let ball = 0.16 - (p[0].square() + p[1].square() + p[2].square());
//! let saw = || Wave::Sawtooth(Expr::constant(1.0));
//! let balls = replicate_cell(&ball, &[saw(), saw(), saw()], [-0.5; 3], [0.5; 3]);
//! let mut b = PointEval::new(&Tape::new(&balls));
//! assert!((b.eval([3.0, 0.0, 0.0]) - 0.16).abs() < 1e-12); // a ball centre
//! assert!(b.eval([3.5, 0.0, 0.0]) < 0.0); // between two balls
//! ```

#![warn(missing_docs)]

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
