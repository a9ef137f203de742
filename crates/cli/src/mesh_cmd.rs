//! `microfrep mesh`: triangle mesh of a model to STL, OBJ, PLY or 3MF.

use crate::model;
use anyhow::{bail, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use microfrep_mesh::write::{stream_mesh, stream_temp_paths, write_mesh, Format};
use microfrep_mesh::{check, memory, CellMethod, Grid, MeshOptions, Plan};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

#[derive(Args)]
pub struct MeshArgs {
    /// Model: a HyperFun file (.hf) or a built-in example name (see `microfrep examples`).
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
    /// Write STL or PLY while meshing, never holding the whole mesh (done
    /// anyway when the mesh would not fit in memory); skips the edge check.
    #[arg(long)]
    stream: bool,
    /// Cell method: cubes (default; about a third of the triangles, faster)
    /// or tets (marching tetrahedra: sharp creases cut less).
    #[arg(long, value_enum, default_value_t = Cells::Cubes)]
    cells: Cells,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Cells {
    Cubes,
    Tets,
}

/// The temporary files being written, removed by the Ctrl-C handler.
static PARTIAL: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What the summary reports; the edge check needs the whole mesh, so a
/// streamed mesh has none.
struct Summary {
    triangles: u64,
    vertices: u64,
    bad_edges: Option<usize>,
    euler: Option<i64>,
    volume: f64,
    area: f64,
    bbox: [[f64; 3]; 2],
}

pub fn run(a: MeshArgs) -> Result<()> {
    let start = Instant::now();
    let format = Format::from_path(&a.output)?;
    let m = model::load(&a.model)?;
    let b = match &a.bounds {
        Some(s) => {
            let (lo, hi) = crate::boxarg::parse_box("--bounds", s)?;
            [lo, hi]
        }
        None => {
            let (lo, hi) = crate::slice_cmd::bounds(&m, None)?;
            [lo, hi]
        }
    };
    let resolution = match (a.resolution, a.voxel) {
        (Some(n), _) => n,
        (None, Some(v)) => Grid::resolution_for_voxel(b, v)?,
        (None, None) => 256,
    };
    let mut opts = MeshOptions::new(b, resolution);
    opts.cells = match a.cells {
        Cells::Cubes => CellMethod::Cubes,
        Cells::Tets => CellMethod::Tetrahedra,
    };
    let plan = Plan::new(&m.shape, &opts)?;

    let est = memory::estimate(&plan);
    let streamable = matches!(format, Format::Stl | Format::Ply);
    let avail = memory::available();
    let too_big = |bytes: f64| avail.is_some_and(|m| bytes > m);
    // Meshes too large for memory go straight to disk (STL, PLY).
    let stream = streamable && (a.stream || too_big(est.bytes));
    let predicted = if stream {
        memory::streaming_bytes(&plan, &est)
    } else {
        est.bytes
    };
    if let Some(m) = avail.filter(|&m| predicted > m) {
        let hint = if streamable || stream {
            String::new()
        } else {
            " (or write .stl or .ply, which are streamed to disk)".to_string()
        };
        bail!(
            "meshing at resolution {resolution} needs about {:.1} GiB but {:.1} GiB are \
             available; resolution {} would fit{hint}",
            predicted / GIB,
            m / GIB,
            memory::resolution_fitting(&est, resolution, m)
        );
    }

    // From here on a Ctrl-C removes the partial output. Only the first
    // handler of the process can be installed; an error here just means
    // Ctrl-C falls back to the default (the temporary files stay).
    *PARTIAL.lock().unwrap_or_else(|e| e.into_inner()) = stream_temp_paths(&a.output);
    let _ = ctrlc::set_handler(|| {
        for p in std::mem::take(&mut *PARTIAL.lock().unwrap_or_else(|e| e.into_inner())) {
            let _ = std::fs::remove_file(p);
        }
        std::process::exit(130);
    });

    let bar = (!a.quiet && std::io::stderr().is_terminal()).then(|| {
        let pb = ProgressBar::new(plan.surface_bricks() as u64);
        pb.set_style(
            ProgressStyle::with_template("meshing {bar:40} {pos}/{len} bricks {elapsed}")
                .expect("static template"),
        );
        pb
    });
    let progress = |done: usize| {
        if let Some(pb) = &bar {
            pb.set_position(done as u64);
        }
    };
    let made = if stream {
        stream_mesh(&plan, &a.output, format, format.wants_normals(), &progress).map(|t| Summary {
            triangles: t.triangles,
            vertices: t.vertices,
            bad_edges: None,
            euler: None,
            volume: t.volume,
            area: t.area,
            bbox: t.bbox,
        })
    } else {
        plan.run(&progress).and_then(|mesh| {
            let normals = format.wants_normals().then(|| plan.normals(&mesh));
            write_mesh(&a.output, format, &mesh, normals.as_deref())?;
            let r = check::check(&mesh);
            Ok(Summary {
                triangles: r.triangles as u64,
                vertices: r.vertices as u64,
                bad_edges: Some(r.bad_edges),
                euler: Some(r.euler),
                volume: r.volume,
                area: r.area,
                bbox: r.bbox,
            })
        })
    };
    PARTIAL.lock().unwrap_or_else(|e| e.into_inner()).clear();
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }
    let r = made?;
    // HyperFun run-time errors at the grid nodes: those nodes are NaN, i.e.
    // outside (documented in the README); counted for the summary.
    let errors = m.hf.as_ref().map(|hf| {
        let g = &plan.grid;
        let axis = |a: usize| -> Vec<f64> {
            (0..=g.cells[a])
                .map(|i| g.origin[a] + g.h * i as f64)
                .collect()
        };
        hf.error_census(&axis(0), &axis(1), &axis(2))
    });
    let secs = start.elapsed().as_secs_f64();
    let peak = memory::peak_rss().unwrap_or(f64::NAN);
    if a.json {
        let s = serde_json::json!({
            "output": a.output.display().to_string(),
            "resolution": resolution,
            "cells": format!("{:?}", a.cells).to_lowercase(),
            "cell": plan.grid.h,
            "triangles": r.triangles,
            "vertices": r.vertices,
            "bad_edges": r.bad_edges,
            "euler": r.euler,
            "streamed": stream,
            "volume": r.volume,
            "area": r.area,
            "bbox": r.bbox,
            "seconds": secs,
            "peak_bytes": peak,
            "predicted_peak_bytes": predicted,
            "thin_cells": plan.thin_cells(),
            "runtime_errors": errors.as_ref().map(|c| c.errors),
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
        match (r.bad_edges, r.euler) {
            (Some(b), Some(e)) => println!("  bad edges  {b} (euler {e})"),
            _ => println!("  bad edges  not checked (streamed to disk)"),
        }
        println!("  volume     {:.6}", r.volume);
        println!("  area       {:.6}", r.area);
        println!("  bbox       {:?} .. {:?}", r.bbox[0], r.bbox[1]);
        println!("  time       {secs:.2} s");
        if let Some(c) = &errors {
            println!("  run-time errors at {c}; those nodes count as outside");
        }
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
            predicted / MIB
        );
    }
    Ok(())
}

const MIB: f64 = 1024.0 * 1024.0;
const GIB: f64 = 1024.0 * MIB;
