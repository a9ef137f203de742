//! `microfrep analyze`: volume fraction, surface area, connectivity and
//! thickness of a model, with the accuracy of each figure.

use crate::model;
use crate::slice_cmd::bounds;
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use microfrep_analysis::thickness::{PhaseThickness, Thickness, ThicknessStats};
use microfrep_analysis::{analyze, AnalyzeOptions, Grid, Report, Stage};
use serde_json::{json, Value};
use std::io::IsTerminal;
use std::sync::Mutex;

/// Voxels on the longest side when neither --resolution nor --voxel is given.
pub const DEFAULT_RESOLUTION: usize = 256;

#[derive(Args)]
pub struct AnalyzeArgs {
    /// Model: a .hf file or a built-in example name (see `microfrep examples`).
    model: String,
    /// Box to analyse: xmin,ymin,zmin,xmax,ymax,zmax (default: the example's
    /// bounds, else from interval analysis).
    #[arg(long, allow_hyphen_values = true)]
    bounds: Option<String>,
    /// Measure inside this model (e.g. the part's envelope) instead of the
    /// whole box: porosity inside the part.
    #[arg(long)]
    region: Option<String>,
    /// Voxels along the longest side of the box (rounded up to even).
    #[arg(long, conflicts_with = "voxel")]
    resolution: Option<usize>,
    /// Voxel size in model units (millimetres).
    #[arg(long)]
    voxel: Option<f64>,
    /// Skip the component labelling.
    #[arg(long)]
    no_connectivity: bool,
    /// Skip the local thickness and pore size.
    #[arg(long)]
    no_thickness: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(a: AnalyzeArgs) -> Result<()> {
    let m = model::load(&a.model)?;
    let (lo, hi) = bounds(&m, a.bounds.as_deref())?;
    let b = [lo, hi];
    let grid = match (a.resolution, a.voxel) {
        (Some(n), _) => Grid::new(b, n)?,
        (None, Some(v)) => Grid::with_voxel(b, v)?,
        (None, None) => Grid::new(b, DEFAULT_RESOLUTION)?,
    };
    let region = match &a.region {
        Some(r) => Some(model::load(r).with_context(|| format!("--region '{r}'"))?),
        None => None,
    };
    let mut opts = AnalyzeOptions {
        connectivity: !a.no_connectivity,
        thickness: !a.no_thickness,
        ..AnalyzeOptions::default()
    };
    if let Some(avail) = microfrep_mesh::memory::available() {
        opts.memory_limit = (0.8 * avail) as u64;
        opts.thickness_options.memory_limit = opts.memory_limit;
    }

    let bar = (!a.quiet && std::io::stderr().is_terminal()).then(|| {
        let pb = ProgressBar::new(1);
        pb.set_style(
            ProgressStyle::with_template("{msg:16} {bar:40} {pos}/{len} {elapsed}")
                .expect("static template"),
        );
        pb
    });
    let stage = Mutex::new(None::<Stage>);
    let progress = |s: Stage, done: usize, total: usize| {
        if let Some(pb) = &bar {
            let mut cur = stage.lock().unwrap_or_else(|e| e.into_inner());
            if *cur != Some(s) {
                *cur = Some(s);
                pb.set_message(s.name());
                pb.set_length(total as u64);
            }
            pb.set_position(done as u64);
        }
    };
    let report = analyze(
        &m.shape,
        region.as_ref().map(|r| &r.shape),
        grid,
        &opts,
        &progress,
    )?;
    if let Some(pb) = bar {
        pb.finish_and_clear();
    }
    if a.json {
        println!("{}", to_json(&a, &report));
    } else {
        print_text(&a, &report);
    }
    Ok(())
}

fn to_json(a: &AnalyzeArgs, r: &Report) -> Value {
    let g = &r.grid;
    let m = &r.measures;
    let conn = r.connectivity.as_ref().map(|c| {
        json!({
            "solid_connectivity": 26,
            "pore_connectivity": 6,
            "solid_components": c.solid_components,
            "solid_volumes": c.solid_volumes,
            "pore_components": c.pore_components,
            "pore_volume": c.pore_volume,
            "open_pore_volume": c.open_pore_volume,
            "open_pore_fraction": c.open_pore_fraction(),
            "closed_pores": c.closed_pores,
            "closed_pore_volume": c.closed_pore_volume,
            "percolates": { "x": c.percolates[0], "y": c.percolates[1], "z": c.percolates[2] },
            "euler_solid": c.euler,
            "euler_surface": c.surface_euler(),
        })
    });
    json!({
        "model": a.model,
        "region": a.region,
        "bounds": [g.lo, g.hi],
        "dims": g.dims,
        "voxel": g.step,
        "volume": { "value": r.volume(), "error": r.volume_error(), "coarse": m.volume.coarse },
        "region_volume": { "value": r.region_volume(), "error": r.region_volume_error() },
        "volume_fraction": { "value": r.volume_fraction(), "error": r.volume_fraction_error() },
        "porosity": { "value": r.porosity(), "error": r.volume_fraction_error() },
        "area": { "value": r.area(), "error": r.area_error(), "coarse": m.area.coarse },
        "specific_surface": { "value": r.specific_surface(), "error": r.specific_surface_error() },
        "proven_volume": m.proven_volume,
        "bricks": { "sampled": m.sampled_bricks, "total": m.bricks },
        "refine_depth": m.refine_depth,
        "creased_cells": m.creased_cells,
        "connectivity": conn,
        "thickness": r.thickness.as_ref().map(thickness_json),
        "seconds": { "measure": r.seconds[0], "connectivity": r.seconds[1], "thickness": r.seconds[2] },
        "accuracy": "errors are estimates from the grid and the grid coarsened by 2 \
                     (Richardson: second order on smooth surfaces, first order at creases); \
                     connectivity and thickness are exact on the voxel grid",
    })
}

fn thickness_json(t: &Thickness) -> Value {
    let phase = |p: &PhaseThickness| match p {
        PhaseThickness::Skipped => json!("skipped"),
        PhaseThickness::Empty => json!("empty"),
        PhaseThickness::Unbounded { voxels } => json!({ "unbounded": true, "voxels": voxels }),
        PhaseThickness::Measured(s) => stats_json(s),
    };
    json!({
        "voxel": t.voxel,
        "solid": phase(&t.solid),
        "pore": phase(&t.pore),
        "slabs": t.slabs,
        "diameter_cap": t.diameter_cap,
    })
}

fn stats_json(s: &ThicknessStats) -> Value {
    json!({
        "voxels": s.voxels,
        "mean": s.mean,
        "min": s.min,
        "p10": s.p10,
        "median": s.median,
        "p90": s.p90,
        "max": s.max,
        "capped_voxels": s.capped_voxels,
        "exact_up_to": s.exact_up_to,
        "ladder_ratio": s.ladder_ratio,
        "histogram": { "edges": s.histogram.edges, "counts": s.histogram.counts },
    })
}

fn print_text(a: &AnalyzeArgs, r: &Report) {
    let g = &r.grid;
    let m = &r.measures;
    println!("analysis of {}", a.model);
    println!(
        "  grid        {} x {} x {} voxels of {:.6} (bounds {:?} .. {:?})",
        g.dims[0],
        g.dims[1],
        g.dims[2],
        g.voxel_size(),
        g.lo,
        g.hi
    );
    let within = match &a.region {
        Some(name) => format!("inside region {name}"),
        None => "in the bounds".to_string(),
    };
    println!(
        "  volume      {:.6} ± {:.2e} ({within})",
        r.volume(),
        r.volume_error()
    );
    println!(
        "  region      {:.6} ± {:.2e}",
        r.region_volume(),
        r.region_volume_error()
    );
    println!(
        "  fraction    {:.6} ± {:.2e} (porosity {:.6})",
        r.volume_fraction(),
        r.volume_fraction_error(),
        r.porosity()
    );
    println!("  area        {:.6} ± {:.2e}", r.area(), r.area_error());
    println!(
        "  specific    {:.6} ± {:.2e} (area / volume)",
        r.specific_surface(),
        r.specific_surface_error()
    );
    println!(
        "  sampling    {} of {} bricks sampled, the rest ({:.1}% of the region) exact by \
         intervals; {} voxels with creases or sharp curvature halved {} time(s)",
        m.sampled_bricks,
        m.bricks,
        100.0 * m.proven_volume / r.region_volume().max(f64::MIN_POSITIVE),
        m.creased_cells,
        m.refine_depth
    );
    if let Some(c) = &r.connectivity {
        let others = c.solid_volumes.iter().skip(1).fold(0.0, |a, v| a + v);
        println!(
            "  solid       {} component(s) (26-connected); volume outside the largest {:.6}",
            c.solid_components, others
        );
        println!(
            "  pores       {} component(s) (6-connected), {:.2}% of pore volume open to the \
             outside, {} closed (volume {:.6})",
            c.pore_components,
            100.0 * c.open_pore_fraction(),
            c.closed_pores,
            c.closed_pore_volume
        );
        let yn = |b: bool| if b { "yes" } else { "no" };
        println!(
            "  percolation x {}, y {}, z {}",
            yn(c.percolates[0]),
            yn(c.percolates[1]),
            yn(c.percolates[2])
        );
        println!(
            "  euler       {} (solid), {} (its surface)",
            c.euler,
            c.surface_euler()
        );
    }
    if let Some(t) = &r.thickness {
        for (name, p) in [("thickness", &t.solid), ("pore size", &t.pore)] {
            match p {
                PhaseThickness::Measured(s) => {
                    println!(
                        "  {name:<11} mean {:.5}, median {:.5}, p10 {:.5}, p90 {:.5}, max {:.5}",
                        s.mean, s.median, s.p10, s.p90, s.max
                    );
                    if let Some(cut) = s.exact_up_to {
                        println!(
                            "  note        {name} above {cut:.5} is a lower bound \
                             (radius ladder {:.1} % apart, to bound the work)",
                            100.0 * (s.ladder_ratio - 1.0)
                        );
                    }
                    if s.capped_voxels > 0 {
                        println!(
                            "  note        {} {name} voxels capped at the slab limit",
                            s.capped_voxels
                        );
                    }
                }
                PhaseThickness::Unbounded { .. } => {
                    println!("  {name:<11} unbounded (the phase fills the grid)")
                }
                PhaseThickness::Empty => println!("  {name:<11} none (empty phase)"),
                PhaseThickness::Skipped => {}
            }
        }
        if let Some(cap) = t.diameter_cap {
            println!("  note        thickness above {cap:.5} is capped (slabbed grid)");
        }
    }
    println!(
        "  accuracy    ± are Richardson estimates (grid vs grid coarsened by 2); \
         connectivity and thickness are exact on the voxel grid unless a note says otherwise"
    );
    let mut times = format!("{:.2} s volume/area", r.seconds[0]);
    if r.connectivity.is_some() {
        times += &format!(", {:.2} s connectivity", r.seconds[1]);
    }
    if r.thickness.is_some() {
        times += &format!(", {:.2} s thickness", r.seconds[2]);
    }
    println!("  time        {times}");
}
