//! Direct fabrication from FRep models, no mesh in between: layer images
//! (PNG stacks for DLP and binder-jet printers), layer contours (SVG and the
//! Common Layer Interface for powder-bed machines) and voxel grids.
//!
//! A model is sliced on a [`SliceGrid`]: layers of a given thickness along
//! z, each an image of square pixels, all in model units (millimetres).
//! [`rasterize`] samples one layer at its middle height (tiles proven
//! inside or outside by interval arithmetic are not sampled);
//! [`layer_polygons`] turns a layer into closed, simplified contours
//! (outer loops counter-clockwise, holes clockwise); [`write_stack`] writes
//! a whole stack in one of the [`Format`]s, layers computed in parallel
//! and the output appearing only when complete. [`voxels::write_voxels`]
//! samples a [`voxels::VoxelGrid`] into NRRD, VTK or raw files. Bad sizes
//! and boxes give a [`FabError`], never a panic or an absurd allocation.
//!
//! ```
//! use microfrep_core::{Expr, Shape};
//! use microfrep_fab::{cli_format::read_cli, contour::signed_area};
//! use microfrep_fab::{layer_polygons, rasterize, write_stack, Format, SliceGrid};
//! use microfrep_shapes as prims;
//!
//! // A ball of radius 1 mm, layers of 0.1 mm, pixels of 0.05 mm.
//! let ball = Shape::new(prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0));
//! let grid = SliceGrid::new([-1.0; 3], [1.0; 3], 0.1, 0.05).unwrap();
//! assert_eq!((grid.nx, grid.ny, grid.layers), (40, 40, 20));
//!
//! // Layer 10 is sampled at z = 0.05: the centre is solid, a corner is not.
//! let layer = rasterize(&ball, &grid, 10);
//! assert!((layer.z - 0.05).abs() < 1e-12);
//! assert!(layer.inside(20, 20) && !layer.inside(0, 0));
//!
//! // Its contour is one counter-clockwise loop enclosing the disc's area.
//! let loops = layer_polygons(&ball, &grid, &layer);
//! assert_eq!(loops.len(), 1);
//! let disc = std::f64::consts::PI * (1.0 - 0.05 * 0.05);
//! assert!((signed_area(&loops[0]) - disc).abs() < 0.01 * disc);
//!
//! // The whole stack as one Common Layer Interface file, read back.
//! let out = std::env::temp_dir().join(format!("microfrep-fab-doc-{}.cli", std::process::id()));
//! write_stack(&ball, &grid, &Format::Cli, &out, &|| {}).unwrap();
//! let cli = read_cli(&std::fs::read_to_string(&out).unwrap()).unwrap();
//! std::fs::remove_file(&out).unwrap();
//! assert_eq!(cli.layers.len(), 20);
//! ```

#![warn(missing_docs)]

pub mod attribute;
pub mod cli_format;
pub mod contour;
pub mod coverage;
mod error;
pub mod grid;
pub mod image;
pub mod raster;
pub mod simplify;
pub mod stack;
pub mod svg;
pub mod voxels;

pub use attribute::AttributeStack;
pub use error::{FabError, Result};
pub use grid::SliceGrid;
pub use raster::{rasterize, rasterize_at, rasterize_with, LayerValues};
pub use stack::{layer_polygons, write_stack, Format, StackFormat};
