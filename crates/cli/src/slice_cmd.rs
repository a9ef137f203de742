//! `microfrep slice`: layer images, SVG contours or a CLI file.

use crate::model;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use microfrep_fab::{write_stack, Format, SliceGrid};
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum SliceFormat {
    Png,
    Svg,
    Cli,
}

#[derive(Args)]
pub struct SliceArgs {
    /// Model: a HyperFun file (.hf) or a built-in example name (see `microfrep examples`).
    model: String,
    /// Output directory (png, svg) or file (cli); must not exist.
    #[arg(short, long)]
    output: PathBuf,
    /// Layer thickness.
    #[arg(long, default_value_t = 0.05)]
    layer: f64,
    /// Pixel size.
    #[arg(long, default_value_t = 0.025)]
    pixel: f64,
    /// Box to slice: xmin,ymin,zmin,xmax,ymax,zmax (default: the example's bounds, else from interval analysis).
    #[arg(long, allow_hyphen_values = true)]
    bounds: Option<String>,
    #[arg(long, value_enum, default_value_t = SliceFormat::Png)]
    format: SliceFormat,
    /// 8-bit images whose grey level is the pixel's area coverage.
    #[arg(long)]
    aa: bool,
}

/// The box from `--bounds`, else the model's own (a built-in example's
/// box, else what interval analysis proves): one rule for every verb.
pub fn bounds(m: &model::Model, arg: Option<&str>) -> Result<([f64; 3], [f64; 3])> {
    if let Some(s) = arg {
        return crate::boxarg::parse_box("--bounds", s);
    }
    let b = m.shape.bounds().context("the model's bounds")?;
    Ok((b.min, b.max))
}

pub fn run(a: SliceArgs) -> Result<()> {
    let m = model::load(&a.model)?;
    let (min, max) = bounds(&m, a.bounds.as_deref())?;
    let grid = SliceGrid::new(min, max, a.layer, a.pixel)?;
    let format = match a.format {
        SliceFormat::Png => Format::Png { aa: a.aa },
        SliceFormat::Svg if a.aa => bail!("--aa applies to --format png only"),
        SliceFormat::Cli if a.aa => bail!("--aa applies to --format png only"),
        SliceFormat::Svg => Format::Svg,
        SliceFormat::Cli => Format::Cli,
    };
    let bar = ProgressBar::with_draw_target(
        Some(grid.layers as u64),
        if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} layers {elapsed} (eta {eta})")
            .expect("static template"),
    );
    write_stack(&m.shape, &grid, format, &a.output, &|| bar.inc(1))?;
    bar.finish_and_clear();
    // HyperFun run-time errors at the pixel centres: those pixels are NaN,
    // i.e. empty (documented in the README); counted for the summary.
    if let Some(hf) = &m.hf {
        let xs: Vec<f64> = (0..grid.nx).map(|i| grid.x(i)).collect();
        let ys: Vec<f64> = (0..grid.ny).map(|j| grid.y(j)).collect();
        let zs: Vec<f64> = (0..grid.layers).map(|k| grid.z(k)).collect();
        let c = hf.error_census(&xs, &ys, &zs);
        eprintln!("run-time errors at {c}; those pixels are empty");
    }
    eprintln!(
        "{} layers of {} x {} pixels -> {}",
        grid.layers,
        grid.nx,
        grid.ny,
        a.output.display()
    );
    Ok(())
}
