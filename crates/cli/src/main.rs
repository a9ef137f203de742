//! `microfrep`: a thin shell over the library crates. Each verb parses its
//! options and calls the library; the algorithms and the policies (memory,
//! streaming, atomic outputs) live in the crates.

// The doc comments of the options are their `--help` texts, which clap
// prints as written: `a[K]`, `s[1]`, `X[,Y]` there are notation for the
// user, not links (escaping them for rustdoc would show the backslashes in
// the help).
#![allow(rustdoc::broken_intra_doc_links)]

mod analyze_cmd;
mod cell_cmd;
mod check_cmd;
mod common;
mod eval_cmd;
mod fill_cmd;
mod materials_cmd;
mod mesh_cmd;
mod render_cmd;
mod scan_info_cmd;
mod serve_cmd;
mod slice_cmd;
mod voxels_cmd;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "microfrep",
    version,
    about = "Function-based microstructures: model, check, mesh, slice, analyse"
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
    /// Fill a part (mesh, scan, HyperFun) with a structure: mesh, slices or HyperFun out.
    Fill(fill_cmd::FillArgs),
    /// Multi-material voxel stack (one RGBA PNG per layer) from the attributes s[].
    Materials(materials_cmd::MaterialsArgs),
    /// Watertight triangle mesh of a model (.stl, .obj, .ply, .3mf).
    Mesh(mesh_cmd::MeshArgs),
    /// Slice into layer images (png), contours (svg) or a Common Layer Interface file (cli).
    Slice(slice_cmd::SliceArgs),
    /// What a scan holds: size, spacing, frame, values, histogram, suggested iso values.
    ScanInfo(scan_info_cmd::ScanInfoArgs),
    /// Ray-cast image, cut-away view or section of a model.
    Render(render_cmd::RenderArgs),
    /// Occupancy or field values on a voxel grid (.raw + .json, .vtk, .nrrd).
    Voxels(voxels_cmd::VoxelsArgs),
    /// Volume fraction, surface area, connectivity and thickness, with their accuracy.
    Analyze(analyze_cmd::AnalyzeArgs),
    /// The studio: edit a model in the browser with a live 3D view and analysis.
    Serve(serve_cmd::ServeArgs),
}

fn list_examples(only: Option<&str>) -> anyhow::Result<()> {
    let all = microfrep::structures::examples::all();
    if let Some(n) = only {
        if !all.iter().any(|e| e.name == n) {
            anyhow::bail!("no example named '{n}'");
        }
    }
    for e in all.iter().filter(|e| only.is_none_or(|n| n == e.name)) {
        let (lo, hi) = e.bounds;
        println!(
            "{:<14} bounds {:?}..{:?}\n    {}",
            e.name, lo, hi, e.description
        );
    }
    if only.is_none() {
        println!(
            "\nYour own parts: a .hf model, a mesh (.stl .obj .ply .3mf) or a scan \
             (FILE:iso=V). A scan's coordinates are millimetres in the frame its file \
             names: LPS for DICOM (x to the patient's left, y posterior, z superior), \
             RAS for NIfTI (x right, y anterior); FILE:iso=V,frame=lps|ras|voxel chooses \
             one, and `microfrep scan-info FILE` shows it with suggested iso values."
        );
    }
    Ok(())
}

/// Whether an error is a closed pipe (`microfrep eval ... | head`): the
/// reader has what it wanted, which is not a failure.
fn broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn main() {
    // Ctrl-C and SIGTERM remove the outputs being written, for every verb.
    // Only the first handler of a process can be installed; if that fails
    // the default applies and temporaries may stay.
    let _ = ctrlc::set_handler(|| {
        microfrep::io::atomic::cleanup_all();
        std::process::exit(130);
    });
    let cli = Cli::parse();
    // For the README test: the command line parses, nothing runs.
    if std::env::var_os("MICROFREP_PARSE_ONLY").is_some() {
        std::process::exit(0);
    }
    let res = match cli.cmd {
        Cmd::Examples { name } => list_examples(name.as_deref()),
        Cmd::Eval(a) => eval_cmd::run(a),
        Cmd::Check(a) => check_cmd::run(a),
        Cmd::Cell(a) => cell_cmd::run(a),
        Cmd::Fill(a) => fill_cmd::run(a),
        Cmd::Materials(a) => materials_cmd::run(a),
        Cmd::Mesh(a) => mesh_cmd::run(a),
        Cmd::Slice(a) => slice_cmd::run(a),
        Cmd::Render(a) => render_cmd::run(a),
        Cmd::ScanInfo(a) => scan_info_cmd::run(a),
        Cmd::Voxels(a) => voxels_cmd::run(a),
        Cmd::Analyze(a) => analyze_cmd::run(a),
        Cmd::Serve(a) => serve_cmd::run(a),
    };
    if let Err(e) = res {
        if broken_pipe(&e) {
            std::process::exit(0);
        }
        eprintln!("error: {}", common::chain(&e));
        std::process::exit(1);
    }
}
