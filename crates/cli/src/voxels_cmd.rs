//! `microfrep voxels`: occupancy or field values on a voxel grid.

use crate::common::{
    check_extension, check_terminates, frame, load_model, probe_terminates, ModelArgs, RunArgs,
};
use anyhow::Result;
use clap::Args;
use microfrep::fab::voxels::{write_voxels, VoxelGrid};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct VoxelsArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output: .raw (with a .json sidecar), .vtk or .nrrd.
    #[arg(short, long)]
    output: PathBuf,
    /// Voxel side.
    #[arg(long)]
    voxel: f64,
    /// Write the field's f32 values instead of occupancy bytes (`--field`
    /// binds a data field, as in every verb).
    #[arg(long)]
    values: bool,
    #[command(flatten)]
    run: RunArgs,
}

pub fn run(a: VoxelsArgs) -> Result<()> {
    a.run.init()?;
    check_extension(&a.output, &["raw", "vtk", "nrrd"], "the voxel file")?;
    let m = load_model(&a.model, &a.run)?;
    let b = frame(&m, &a.model, &a.run)?;
    probe_terminates(&m, b.corners())?;
    let grid = VoxelGrid::new(b.min, b.max, a.voxel)?;
    write_voxels(&m.shape, &grid, a.values, &a.output)?;
    let sidecar = a.output.with_extension("json");
    let raw = a.output.extension().is_some_and(|e| e == "raw");
    let outputs: Vec<&Path> = if raw {
        vec![&a.output, &sidecar]
    } else {
        vec![&a.output]
    };
    check_terminates(&m, &outputs)?;
    let [nx, ny, nz] = grid.dims;
    if a.run.json {
        let s = serde_json::json!({
            "output": a.output.display().to_string(),
            "dims": grid.dims,
            "spacing": grid.spacing,
            "origin": grid.origin,
        });
        println!("{s}");
    } else if !a.run.quiet {
        eprintln!("{nx} x {ny} x {nz} voxels -> {}", a.output.display());
    }
    Ok(())
}
