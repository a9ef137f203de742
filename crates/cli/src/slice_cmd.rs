//! `microfrep slice`: layer images, SVG contours or a CLI file.

use crate::common::{check_terminates, frame, load_model, probe_terminates, ModelArgs, RunArgs};
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use microfrep::fab::{write_stack, Format, SliceGrid};
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum SliceFormat {
    Png,
    Svg,
    Cli,
    /// One 3MF file with the slice extension (and a coarse mesh).
    #[value(name = "3mf")]
    ThreeMf,
}

#[derive(Args)]
pub struct SliceArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output directory (png, svg; must not exist) or file (cli).
    #[arg(short, long)]
    output: PathBuf,
    /// Layer thickness.
    #[arg(long, default_value_t = 0.05)]
    layer: f64,
    /// Pixel size.
    #[arg(long, default_value_t = 0.025)]
    pixel: f64,
    #[arg(long, value_enum, default_value_t = SliceFormat::Png)]
    format: SliceFormat,
    /// 8-bit images whose grey level is the pixel's area coverage.
    #[arg(long)]
    aa: bool,
    /// 8-bit images of attribute channel K (1-based, HyperFun's s[K]):
    /// 255 * clamp(s[K], 0, 1) inside the solid, 0 outside.
    #[arg(long, conflicts_with = "aa")]
    attribute: Option<usize>,
    #[command(flatten)]
    run: RunArgs,
}

pub fn run(a: SliceArgs) -> Result<()> {
    a.run.init()?;
    let format = match a.format {
        SliceFormat::Png => Format::Png { aa: a.aa },
        _ if a.aa => bail!("--aa applies to --format png only"),
        SliceFormat::Svg => Format::Svg,
        SliceFormat::Cli => {
            crate::common::check_extension(&a.output, &["cli"], "a CLI slice file")?;
            Format::Cli
        }
        SliceFormat::ThreeMf => {
            crate::common::check_extension(&a.output, &["3mf"], "a 3MF slice stack")?;
            Format::Cli
        }
    };
    let m = load_model(&a.model, &a.run)?;
    let b = frame(&m, &a.model, &a.run)?;
    probe_terminates(&m, b.corners())?;
    let grid = SliceGrid::new(b.min, b.max, a.layer, a.pixel)?;
    let bar = a.run.bar("layers");
    bar.set_message("slicing");
    bar.set_length(grid.layers as u64);
    let written = match a.attribute {
        Some(k) if k == 0 || !matches!(a.format, SliceFormat::Png) => {
            bail!("--attribute K (from 1) writes png layers")
        }
        Some(k) => microfrep::fab::AttributeStack::new(&m.shape, k - 1)
            .and_then(|f| write_stack(&m.shape, &grid, &f, &a.output, &|| bar.inc(1)))
            .map_err(anyhow::Error::new),
        None if matches!(a.format, SliceFormat::ThreeMf) => {
            microfrep::export::slice_3mf(&m.shape, &grid, 128, &a.output, &|| bar.inc(1))
                .map(|_| ())
                .map_err(anyhow::Error::new)
        }
        None => write_stack(&m.shape, &grid, &format, &a.output, &|| bar.inc(1))
            .map_err(anyhow::Error::new),
    };
    bar.finish_and_clear();
    written?;
    check_terminates(&m, &[&a.output])?;
    // Run-time errors at the pixel centres: those pixels are NaN (empty).
    let xs: Vec<f64> = (0..grid.nx).map(|i| grid.x(i)).collect();
    let ys: Vec<f64> = (0..grid.ny).map(|j| grid.y(j)).collect();
    let zs: Vec<f64> = (0..grid.layers).map(|k| grid.z(k)).collect();
    let census = m.shape.error_census(&xs, &ys, &zs);
    if a.run.json {
        let s = serde_json::json!({
            "output": a.output.display().to_string(),
            "layers": grid.layers,
            "image_size": [grid.nx, grid.ny],
            "bounds": [b.min, b.max],
            "runtime_errors": census.as_ref().map(|c| c.errors),
        });
        println!("{s}");
    } else if !a.run.quiet {
        if let Some(c) = census.filter(|c| c.errors > 0) {
            eprintln!("run-time errors at {c}; those pixels are empty");
        }
        eprintln!(
            "{} layers of {} x {} pixels -> {}",
            grid.layers,
            grid.nx,
            grid.ny,
            a.output.display()
        );
    }
    Ok(())
}
