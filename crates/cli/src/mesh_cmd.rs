//! `microfrep mesh`: triangle mesh of a model to STL, OBJ, PLY or 3MF.

use crate::model;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use microfrep_core::Tape;
use microfrep_mesh::write::{temp_path, write_mesh, Format};
use microfrep_mesh::{bounds, check, memory, Grid, MeshOptions, Plan};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Args)]
pub struct MeshArgs {
    /// Model: a built-in example name (see `microfrep examples`).
    model: String,
    /// Output file; the format follows the extension (.stl, .obj, .ply, .3mf).
    #[arg(short, long)]
    output: PathBuf,
    /// Box to mesh: xmin,ymin,zmin,xmax,ymax,zmax (default: from interval analysis).
    #[arg(long, allow_hyphen_values = true)]
    bounds: Option<String>,
    /// Cells along the longest side of the box.
    #[arg(long, conflicts_with = "voxel")]
    resolution: Option<usize>,
    /// Cell size in model units (millimetres).
    #[arg(long)]
    voxel: Option<f64>,
    /// No progress bar and no summary.
    #[arg(long)]
    quiet: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// The file being written, removed by the Ctrl-C handler.
static PARTIAL: Mutex<Option<PathBuf>> = Mutex::new(None);

fn parse_bounds(s: &str) -> Result<[[f64; 3]; 2]> {
    let v: Vec<f64> = s
        .split(',')
        .enumerate()
        .map(|(i, t)| {
            t.trim()
                .parse::<f64>()
                .with_context(|| format!("--bounds: value {} ('{t}') is not a number", i + 1))
        })
        .collect::<Result<_>>()?;
    if v.len() != 6 {
        bail!(
            "--bounds needs 6 numbers xmin,ymin,zmin,xmax,ymax,zmax, got {}",
            v.len()
        );
    }
    Ok([[v[0], v[1], v[2]], [v[3], v[4], v[5]]])
}

pub fn run(a: MeshArgs) -> Result<()> {
    let start = Instant::now();
    let format = Format::from_path(&a.output)?;
    let m = model::load(&a.model)?;
    let b = match &a.bounds {
        Some(s) => parse_bounds(s)?,
        None => bounds::model_bounds(&Tape::new(&m.expr))
            .with_context(|| format!("model '{}'", a.model))?,
    };
    let resolution = match (a.resolution, a.voxel) {
        (Some(n), _) => n,
        (None, Some(v)) => Grid::resolution_for_voxel(b, v)?,
        (None, None) => 256,
    };
    let plan = Plan::new(&m.expr, &MeshOptions::new(b, resolution))?;

    let est = memory::estimate(&plan);
    if let Some(avail) = memory::available() {
        if est.bytes > avail {
            bail!(
                "meshing at resolution {resolution} needs about {:.1} GiB but {:.1} GiB are \
                 available; resolution {} would fit",
                est.bytes / GIB,
                avail / GIB,
                memory::resolution_fitting(&est, resolution, avail)
            );
        }
    }

    let bar = (!a.quiet && std::io::stderr().is_terminal()).then(|| {
        let pb = ProgressBar::new(plan.surface_bricks() as u64);
        pb.set_style(
            ProgressStyle::with_template("meshing {bar:40} {pos}/{len} bricks {elapsed}")
                .expect("static template"),
        );
        pb
    });
    let mesh = plan.run(&|done| {
        if let Some(pb) = &bar {
            pb.set_position(done as u64);
        }
    })?;
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }

    let normals = format.wants_normals().then(|| plan.normals(&mesh));
    *PARTIAL.lock().unwrap_or_else(|e| e.into_inner()) = Some(temp_path(&a.output));
    // Only the first handler of the process can be installed; an error here
    // just means Ctrl-C falls back to the default (the .part file stays).
    let _ = ctrlc::set_handler(|| {
        if let Some(p) = PARTIAL.lock().unwrap_or_else(|e| e.into_inner()).take() {
            let _ = std::fs::remove_file(p);
        }
        std::process::exit(130);
    });
    let written = write_mesh(&a.output, format, &mesh, normals.as_deref());
    PARTIAL.lock().unwrap_or_else(|e| e.into_inner()).take();
    written?;

    let r = check::check(&mesh);
    let secs = start.elapsed().as_secs_f64();
    let peak = memory::peak_rss().unwrap_or(f64::NAN);
    if a.json {
        let s = serde_json::json!({
            "output": a.output.display().to_string(),
            "resolution": resolution,
            "cell": plan.grid.h,
            "triangles": r.triangles,
            "vertices": r.vertices,
            "bad_edges": r.bad_edges,
            "euler": r.euler,
            "volume": r.volume,
            "area": r.area,
            "bbox": r.bbox,
            "seconds": secs,
            "peak_bytes": peak,
            "predicted_peak_bytes": est.bytes,
            "thin_cells": plan.thin_cells(),
        });
        println!("{s}");
    } else if !a.quiet {
        println!("wrote {}", a.output.display());
        println!(
            "  grid       {resolution} cells on the longest side, cell {:.6}",
            plan.grid.h
        );
        println!("  triangles  {}", r.triangles);
        println!("  vertices   {}", r.vertices);
        println!("  bad edges  {} (euler {})", r.bad_edges, r.euler);
        println!("  volume     {:.6}", r.volume);
        println!("  area       {:.6}", r.area);
        println!("  bbox       {:?} .. {:?}", r.bbox[0], r.bbox[1]);
        println!("  time       {secs:.2} s");
        if plan.thin_cells() > 0 {
            println!(
                "  note       interval analysis found {} cells that may hold features \
                 thinner than a cell; they are not in the mesh (try a finer resolution)",
                plan.thin_cells()
            );
        }
        println!(
            "  peak mem   {:.1} MiB (predicted {:.1} MiB)",
            peak / MIB,
            est.bytes / MIB
        );
    }
    Ok(())
}

const MIB: f64 = 1024.0 * 1024.0;
const GIB: f64 = 1024.0 * MIB;
