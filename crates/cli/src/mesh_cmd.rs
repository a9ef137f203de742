//! `microfrep mesh`: triangle mesh of a model to STL, OBJ, PLY or 3MF.

use crate::common::{check_terminates, frame, load_model, probe_terminates, ModelArgs, RunArgs};
use anyhow::Result;
use clap::Args;
use microfrep::mesh::job::{mesh_to_file, AutoOptions, JobOptions};
use microfrep::mesh::report;
use microfrep::mesh::write::colour::ColourBy;
use microfrep::mesh::{CellMethod, Grid, MeshOptions};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct MeshArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output file; the format follows the extension (.stl, .obj, .ply, .3mf).
    #[arg(short, long)]
    output: PathBuf,
    /// Cells along the longest side of the box (default 256), or `auto`:
    /// the coarsest (from 32 up by 1.5) whose mesh keeps the model's volume
    /// within 0.5 %.
    #[arg(long, conflicts_with = "voxel", value_parser = parse_resolution)]
    resolution: Option<Resolution>,
    /// Cell size in model units (millimetres).
    #[arg(long)]
    voxel: Option<f64>,
    /// Write STL or PLY while meshing, never holding the whole mesh (done
    /// anyway when the mesh would not fit in memory); skips the edge check.
    #[arg(long)]
    stream: bool,
    /// Fail (writing nothing) when the mesh has more than PCT % less
    /// volume than the model sampled in every cell: thin features lost.
    #[arg(long, value_name = "PCT", default_value_t = 5.0)]
    max_volume_loss: f64,
    /// Leave every vertex on the surface: no chordal volume correction.
    #[arg(long)]
    no_volume_correction: bool,
    /// Cell method: cubes (default; about a third of the triangles, faster)
    /// or tets (marching tetrahedra: sharp creases cut less).
    #[arg(long, value_enum, default_value_t = Cells::Cubes)]
    cells: Cells,
    /// Vertex colours from an attribute (.ply, .obj, .3mf; not .stl).
    #[command(flatten)]
    colour: crate::render_cmd::ColourArgs,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Cells {
    Cubes,
    Tets,
}

#[derive(Clone, Copy, Debug)]
enum Resolution {
    Cells(usize),
    Auto,
}

fn parse_resolution(s: &str) -> Result<Resolution, String> {
    match s {
        "auto" => Ok(Resolution::Auto),
        _ => s
            .parse()
            .map(Resolution::Cells)
            .map_err(|_| format!("'{s}' is not a cell count or 'auto'")),
    }
}

pub fn run(a: MeshArgs) -> Result<()> {
    let start = Instant::now();
    a.run.init()?;
    microfrep::mesh::write::format_of(&a.output)?;
    let m = load_model(&a.model, &a.run)?;
    let b = frame(&m, &a.model, &a.run)?.corners();
    probe_terminates(&m, b)?;
    let (resolution, auto) = match (a.resolution, a.voxel) {
        (Some(Resolution::Cells(n)), _) => (n, None),
        (Some(Resolution::Auto), _) => (0, Some(AutoOptions::default())),
        (None, Some(v)) => (Grid::resolution_for_voxel(b, v)?, None),
        (None, None) => (256, None),
    };
    if !(a.max_volume_loss >= 0.0 && a.max_volume_loss <= 100.0) {
        anyhow::bail!(
            "--max-volume-loss {}: give a percentage from 0 to 100",
            a.max_volume_loss
        );
    }
    let mut opts = MeshOptions::new(b, resolution);
    opts.volume_correction = !a.no_volume_correction;
    opts.cells = match a.cells {
        Cells::Cubes => CellMethod::Cubes,
        Cells::Tets => CellMethod::Tetrahedra,
    };
    let bar = a.run.bar("bricks");
    bar.set_message("meshing");
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let job = JobOptions {
        stream: a.stream,
        max_volume_loss: Some(a.max_volume_loss / 100.0),
        auto,
        colour: a.colour.get()?.map(|(channel, colormap, range)| ColourBy {
            channel,
            colormap,
            range,
        }),
        ..JobOptions::default()
    };
    let s = mesh_to_file(&m.shape, &opts, &a.output, &job, &progress);
    bar.finish_and_clear();
    let s = s?;
    check_terminates(&m, &[&a.output])?;
    let secs = start.elapsed().as_secs_f64();
    let peak = microfrep::io::limits::peak_rss().unwrap_or(f64::NAN);
    let out = a.output.display().to_string();
    let range = s.colour_scale.map(|c| [c.lo, c.hi]);
    if a.run.json {
        let mut j = report::to_json(&s, &out, secs, peak);
        if let Some(r) = range {
            j["colour_range"] = serde_json::json!(r);
        }
        println!("{j}");
    } else if !a.run.quiet {
        print!("{}", report::to_text(&s, &out, secs, peak));
        if let Some([lo, hi]) = range {
            println!(
                "  colours    attribute {} over {lo} .. {hi}",
                a.colour.color_by.unwrap_or(0)
            );
        }
    }
    Ok(())
}
