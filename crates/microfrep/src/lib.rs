//! microfrep: design, check and fabricate procedural function-based
//! microstructures.
//!
//! This crate is the front door: it re-exports every library crate under a
//! short name and holds the one loader of models ([`load()`]), which every
//! host (the `microfrep` CLI, the studio, the Python bindings) uses, so a
//! HyperFun file, a mesh, a scan or a built-in example becomes the same
//! [`Shape`] everywhere.
//!
//! | module | crate | concern |
//! | --- | --- | --- |
//! | [`core`] | `microfrep-core` | expression graph, tape, evaluators, [`Shape`] |
//! | [`shapes`] | `microfrep-shapes` | primitives with HyperFun's exact formulas |
//! | [`hyperfun`] | `microfrep-hyperfun` | the HyperFun language |
//! | [`structures`] | `microfrep-structures` | lattices, TPMS, struts, porous media, replication |
//! | [`pores`] | `microfrep-pores` | irregular pores by subdivision (Kou and Tan) |
//! | [`graded`] | `microfrep-graded` | graded materials, Bezier data, dithering, material stacks |
//! | [`meshfield`] | `microfrep-meshfield` | triangle meshes as signed fields |
//! | [`scan`] | `microfrep-scan` | volume images as signed fields |
//! | [`mesh`] | `microfrep-mesh` | watertight meshing and mesh files |
//! | [`fab`] | `microfrep-fab` | slices, contours, voxels |
//! | [`render`] | `microfrep-render` | ray casting, sections |
//! | [`analysis`] | `microfrep-analysis` | porosity, area, connectivity, thickness |
//! | [`threemf`] | `microfrep-3mf` | 3MF packages and extensions |
//! | [`io`] | `microfrep-io` | atomic outputs, PNG, limits |
//!
//! ```
//! use microfrep::{load, LoadOptions};
//! let m = load::load("toriball", &LoadOptions::default()).unwrap();
//! let b = m.shape.bounds().unwrap();
//! assert!(b.size()[0] > 1.9 && b.size()[0] < 2.1);
//! assert!(m.shape.point().eval([0.0, 0.0, 0.0]).is_finite());
//! ```

#![warn(missing_docs)]

pub mod export;
pub mod fill;
pub mod load;

pub use load::{load, LoadError, LoadOptions, Loaded, SourceKind};
pub use microfrep_3mf as threemf;
pub use microfrep_analysis as analysis;
pub use microfrep_core as core;
pub use microfrep_core::{Bounds, Expr, Field, Shape};
pub use microfrep_fab as fab;
pub use microfrep_graded as graded;
pub use microfrep_hyperfun as hyperfun;
pub use microfrep_io as io;
pub use microfrep_mesh as mesh;
pub use microfrep_meshfield as meshfield;
pub use microfrep_pores as pores;
pub use microfrep_render as render;
pub use microfrep_scan as scan;
pub use microfrep_shapes as shapes;
pub use microfrep_structures as structures;

/// Adds microfrep's HyperFun library (the `mf*` microstructure, graded and
/// pore functions) to every HyperFun parse and lowering of this process.
/// [`load()`] does this itself; call it before using [`hyperfun`] directly.
pub fn install_library() {
    microfrep_structures_hf::install();
}
