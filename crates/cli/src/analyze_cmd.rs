//! `microfrep analyze`: volume fraction, surface area, connectivity and
//! thickness of a model, with the accuracy of each figure.

use crate::common::{check_terminates, frame, load_model, probe_terminates, ModelArgs, RunArgs};
use anyhow::{Context, Result};
use clap::Args;
use microfrep::analysis::summary::{to_json, to_text};
use microfrep::analysis::{analyze, AnalyzeOptions, Grid, Stage};
use std::sync::Mutex;

/// Voxels on the longest side when neither --resolution nor --voxel is given.
pub const DEFAULT_RESOLUTION: usize = 256;

#[derive(Args)]
pub struct AnalyzeArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Measure inside this model (e.g. the part's envelope: a .hf file, a
    /// mesh, a scan) instead of the whole box: porosity inside the part.
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
    #[command(flatten)]
    run: RunArgs,
}

pub fn run(a: AnalyzeArgs) -> Result<()> {
    a.run.init()?;
    let m = load_model(&a.model, &a.run)?;
    let b = frame(&m, &a.model, &a.run)?.corners();
    probe_terminates(&m, b)?;
    let grid = match (a.resolution, a.voxel) {
        (Some(n), _) => Grid::new(b, n)?,
        (None, Some(v)) => Grid::with_voxel(b, v)?,
        (None, None) => Grid::new(b, DEFAULT_RESOLUTION)?,
    };
    let region = match &a.region {
        Some(r) => {
            let ra = crate::common::ModelArgs {
                model: r.clone(),
                object: None,
                params: Vec::new(),
                fields: Vec::new(),
                bounds: None,
            };
            Some(load_model(&ra, &a.run).with_context(|| format!("--region '{r}'"))?)
        }
        None => None,
    };
    let mut opts = AnalyzeOptions {
        connectivity: !a.no_connectivity,
        thickness: !a.no_thickness,
        ..AnalyzeOptions::default()
    };
    if let Some(avail) = microfrep::io::limits::memory_limit() {
        opts.memory_limit = (0.8 * avail) as u64;
        opts.thickness_options.memory_limit = opts.memory_limit;
    }
    let bar = a.run.bar("");
    let stage = Mutex::new(None::<Stage>);
    let progress = |s: Stage, done: usize, total: usize| {
        let mut cur = stage.lock().unwrap_or_else(|e| e.into_inner());
        if *cur != Some(s) {
            *cur = Some(s);
            bar.set_message(s.name());
            bar.set_length(total as u64);
        }
        bar.set_position(done as u64);
    };
    let report = analyze(
        &m.shape,
        region.as_ref().map(|r| &r.shape),
        grid,
        &opts,
        &progress,
    );
    bar.finish_and_clear();
    let report = report?;
    check_terminates(&m, &[])?;
    let name = a.model.model.as_str();
    if a.run.json {
        println!("{}", to_json(&report, name, a.region.as_deref()));
    } else if !a.run.quiet {
        print!("{}", to_text(&report, name, a.region.as_deref()));
    }
    Ok(())
}
