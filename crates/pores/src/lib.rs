//! Irregular porous structures of Kou and Tan (2013), "An approach of
//! irregular porous structure modeling based on subdivision and NURBS", as
//! FRep fields.
//!
//! A box around the part is subdivided by the requested pore size
//! (quadtree / octree, Eqs. 1-3, or T-mesh refinement, Sec. 3.2; cells
//! outside the part are dropped), each cell gets one smooth pore whose
//! control polygon / polyhedron is derived from the cell (Sec. 4), and the
//! pore's parameters are solved so that the cell has its target porosity
//! (constant or a field), with seeded randomness making every pore
//! different. The result is a [`microfrep_core::Field`], so it composes
//! with every other model and meshes, slices and renders like one.
//!
//! - 2D ([`Dim::Two`], in the xy plane, extruded along z): the derived
//!   polygon from four distances along the sides (Eq. 4), the closed
//!   quadratic B-spline (the paper's "order 3" NURBS) on it, whose area is
//!   exactly 5/6 of the polygon's ([`curve::ALPHA`], the paper's 0.83),
//!   the fourth distance from Eq. 8. The field is the exact signed distance
//!   to the curve. SVG sections: [`svg::section_svg`].
//! - 3D ([`Dim::Three`]): the derived polyhedron by the centroid rule
//!   (Eq. 9) on a parent box 1.6 times the cell, and the Doo-Sabin limit
//!   surface of that polyhedron (the quadratic subdivision surface the
//!   paper cites, and the surface analogue of the 2D curve) as the pore.
//!   See [`pore3`] for how the surface is evaluated and [`field`] for the
//!   field. The regular Doo-Sabin pore reaches the cell faces only at
//!   porosity 0.6274 (the paper's 52.36 % is a sphere's), so below that a
//!   pore keeps a small reach past the faces ([`Options::opening`]) and
//!   gives up volume in its shape instead: the pores open into all their
//!   neighbours from porosity 0.4559 up.
//!
//! The paper's controls are [`Options`]: irregularity, parent scale,
//! subdivision (tree or T-mesh), the 2D curve's corner weight (rational
//! arcs, [`curve`]), and the pore size as a cell edge or as the cell area /
//! volume per pore ([`SizeMeasure`]).
//!
//! ```
//! use microfrep_core::{Expr, PointEval, Tape};
//! use microfrep_shapes as prims;
//! use microfrep_pores::{Options, Pores, Spec};
//! let part = prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0);
//! let built = Pores::build(
//!     &part,
//!     [[-1.0; 3], [1.0; 3]],
//!     Spec::Constant(0.5),
//!     Spec::Constant(0.7),
//!     7,
//!     &Options::default(),
//! )
//! .unwrap();
//! assert!(built.pores > 20);
//! let solid = built.solid(&part);
//! let tape = Tape::new(&solid);
//! let mut ev = PointEval::new(&tape);
//! // The centre of a cell is inside its pore; outside the sphere is outside.
//! assert!(ev.eval([0.25, 0.25, 0.25]) < 0.0);
//! assert!(ev.eval([1.5, 0.0, 0.0]) < 0.0);
//! ```

#![warn(missing_docs)]

mod build;
pub mod cubemap;
pub mod curve;
pub mod doo_sabin;
mod error;
pub mod field;
pub mod pore2;
pub mod pore3;
pub mod raster;
mod rng;
pub mod svg;
pub mod tree;

pub use build::{
    part_bounds, porosity_extremes_3d, porosity_range, Built, Dim, HandSet, Options, PoreCell,
    PoreShape, Pores, PorositySpec, SizeMeasure, SizeSpec, Spec, SplitRule,
};
pub use error::PoreError;
pub use field::PoreField;
pub use tree::{Cell, CellInfo, Inside, Split, Subdivision};
