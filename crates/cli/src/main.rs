//! `microfrep`: a thin shell over the library crates. Argument parsing,
//! model loading and printing only; the algorithms live in the crates.

mod analyze_cmd;
mod boxarg;
mod cell_cmd;
mod check_cmd;
mod eval_cmd;
mod mesh_cmd;
mod model;
mod render_cmd;
mod slice_cmd;
mod voxels_cmd;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "microfrep",
    version,
    about = "Function-based microstructures: model, check, mesh, slice"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// List the built-in example models, or describe one.
    Examples {
        /// Show only this example.
        name: Option<String>,
    },
    /// Evaluate a model at points given as arguments (x y z ...) or on stdin.
    Eval(eval_cmd::EvalArgs),
    /// Parse and check a HyperFun model: objects, parameters, errors, warnings.
    Check(check_cmd::CheckArgs),
    /// Check a unit cell before replication: connectivity, symmetry, safe replication.
    Cell(cell_cmd::CellArgs),
    /// Watertight triangle mesh of a model (.stl, .obj, .ply, .3mf).
    Mesh(mesh_cmd::MeshArgs),
    /// Slice into layer images (png), contours (svg) or a Common Layer Interface file (cli).
    Slice(slice_cmd::SliceArgs),
    /// Ray-cast image, cut-away view or section of a model.
    Render(render_cmd::RenderArgs),
    /// Occupancy or field values on a voxel grid (.raw + .json, .vtk, .nrrd).
    Voxels(voxels_cmd::VoxelsArgs),
    /// Volume fraction, surface area, connectivity and thickness, with their accuracy.
    Analyze(analyze_cmd::AnalyzeArgs),
}

fn main() {
    // Every verb (check included) sees the mf* microstructure functions.
    microfrep_structures_hf::install();
    let cli = Cli::parse();
    let res = match cli.cmd {
        Cmd::Examples { name } => model::list_examples(name.as_deref()),
        Cmd::Eval(a) => eval_cmd::run(a),
        Cmd::Check(a) => check_cmd::run(a),
        Cmd::Cell(a) => cell_cmd::run(a),
        Cmd::Mesh(a) => mesh_cmd::run(a),
        Cmd::Slice(a) => slice_cmd::run(a),
        Cmd::Render(a) => render_cmd::run(a),
        Cmd::Voxels(a) => voxels_cmd::run(a),
        Cmd::Analyze(a) => analyze_cmd::run(a),
    };
    if let Err(e) = res {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
