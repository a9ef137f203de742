//! `microfrep slice`: layer images, SVG contours or a CLI file.

use crate::model;
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use microfrep_core::Tape;
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
    /// Model: a built-in example name.
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
    /// Box to slice: xmin,ymin,zmin,xmax,ymax,zmax (default: the example's bounds).
    #[arg(long, allow_hyphen_values = true)]
    bounds: Option<String>,
    #[arg(long, value_enum, default_value_t = SliceFormat::Png)]
    format: SliceFormat,
    /// 8-bit images whose grey level is the pixel's area coverage.
    #[arg(long)]
    aa: bool,
}

/// The box from `--bounds`, else the built-in example's own.
pub fn bounds(model: &str, arg: Option<&str>) -> Result<([f64; 3], [f64; 3])> {
    if let Some(s) = arg {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .with_context(|| format!("--bounds '{s}': not a list of numbers"))?;
        if v.len() != 6 {
            bail!("--bounds '{s}': expected 6 numbers xmin,ymin,zmin,xmax,ymax,zmax");
        }
        return Ok(([v[0], v[1], v[2]], [v[3], v[4], v[5]]));
    }
    match microfrep_structures::examples::by_name(model) {
        Some(e) => Ok(e.bounds),
        None => bail!("model '{model}' has no built-in bounds: give --bounds"),
    }
}

pub fn run(a: SliceArgs) -> Result<()> {
    let m = model::load(&a.model)?;
    let (min, max) = bounds(&a.model, a.bounds.as_deref())?;
    let grid = SliceGrid::new(min, max, a.layer, a.pixel)?;
    let format = match a.format {
        SliceFormat::Png => Format::Png { aa: a.aa },
        SliceFormat::Svg if a.aa => bail!("--aa applies to --format png only"),
        SliceFormat::Cli if a.aa => bail!("--aa applies to --format png only"),
        SliceFormat::Svg => Format::Svg,
        SliceFormat::Cli => Format::Cli,
    };
    let tape = Tape::new(&m.expr);
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
    write_stack(&tape, &grid, format, &a.output, &|| bar.inc(1))?;
    bar.finish_and_clear();
    eprintln!(
        "{} layers of {} x {} pixels -> {}",
        grid.layers,
        grid.nx,
        grid.ny,
        a.output.display()
    );
    Ok(())
}
