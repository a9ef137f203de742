//! `microfrep voxels`: occupancy or field values on a voxel grid.

use crate::model;
use crate::slice_cmd::bounds;
use anyhow::Result;
use clap::Args;
use microfrep_fab::voxels::{write_voxels, VoxelGrid};
use std::path::PathBuf;

#[derive(Args)]
pub struct VoxelsArgs {
    /// Model: a HyperFun file (.hf) or a built-in example name (see `microfrep examples`).
    model: String,
    /// Output: .raw (with a .json sidecar), .vtk or .nrrd.
    #[arg(short, long)]
    output: PathBuf,
    /// Voxel side.
    #[arg(long)]
    voxel: f64,
    /// Write f32 values instead of occupancy bytes.
    #[arg(long)]
    field: bool,
    /// Box to sample: xmin,ymin,zmin,xmax,ymax,zmax (default: the example's bounds, else from interval analysis).
    #[arg(long, allow_hyphen_values = true)]
    bounds: Option<String>,
}

pub fn run(a: VoxelsArgs) -> Result<()> {
    let m = model::load(&a.model)?;
    let (min, max) = bounds(&m, a.bounds.as_deref())?;
    let grid = VoxelGrid::new(min, max, a.voxel)?;
    write_voxels(&m.shape, &grid, a.field, &a.output)?;
    let [nx, ny, nz] = grid.dims;
    eprintln!("{nx} x {ny} x {nz} voxels -> {}", a.output.display());
    Ok(())
}
