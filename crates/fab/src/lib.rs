//! Direct fabrication from FRep models, no mesh in between: layer images
//! (PNG stacks for DLP and binder-jet printers), layer contours (SVG and the
//! Common Layer Interface for powder-bed machines) and voxel grids.

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
