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
    /// Layer thickness (default: the preset's).
    #[arg(long)]
    layer: Option<f64>,
    /// Pixel size (default: the preset's).
    #[arg(long)]
    pixel: Option<f64>,
    /// A printer grid that sets the pixel and layer: vat-50um (the
    /// default), dlp-25um, mj-600x600-27um (the presets of `materials`
    /// with square pixels; an unknown name lists them all).
    #[arg(long)]
    preset: Option<String>,
    /// Only the layer whose middle is at this height (one layer, sampled
    /// exactly at z).
    #[arg(long, allow_hyphen_values = true, conflicts_with = "layers")]
    z: Option<f64>,
    /// Only layers FROM..TO of the whole stack (0-based, both included),
    /// at the heights and with the file names they have in the whole
    /// stack, e.g. --layers 100..120.
    #[arg(long)]
    layers: Option<String>,
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
    let (layer, pixel, preset) = grid_steps(&a)?;
    let grid = match (a.z, &a.layers) {
        (Some(z), _) => SliceGrid::at_height(b.min, b.max, z, layer, pixel)?,
        (None, Some(r)) => {
            let (from, to) = parse_range(r)?;
            SliceGrid::new(b.min, b.max, layer, pixel)?.range(from, to)?
        }
        (None, None) => SliceGrid::new(b.min, b.max, layer, pixel)?,
    };
    if !a.run.quiet && !a.run.json {
        eprintln!("{}", plan(&grid, a.format, preset));
    }
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
            "first_layer": grid.first,
            "layer": grid.layer,
            "pixel": grid.pixel,
            "preset": preset,
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

/// The layer and pixel: given, or the preset's (`vat-50um` by default).
fn grid_steps(a: &SliceArgs) -> Result<(f64, f64, Option<&'static str>)> {
    let name = match (&a.preset, a.layer, a.pixel) {
        (Some(p), _, _) => p.as_str(),
        (None, Some(l), Some(p)) => return Ok((l, p, None)),
        (None, _, _) => "vat-50um",
    };
    let p = microfrep::graded::stack::find_preset(name)
        .map_err(|e| anyhow::anyhow!("--preset: {e}"))?;
    let [px, py] = p.pitch();
    if (px - py).abs() > 1e-12 * px {
        bail!(
            "--preset {}: its pixels are {:.4} x {:.4} mm, and slice images have square pixels; \
             use a preset with square pixels (vat-50um, dlp-25um, mj-600x600-27um), give \
             --pixel, or write a material stack with `materials --preset {}`",
            p.name,
            px,
            py,
            p.name
        );
    }
    Ok((
        a.layer.unwrap_or(p.layer),
        a.pixel.unwrap_or(px),
        Some(p.name),
    ))
}

/// `FROM..TO` (also `FROM..=TO`), 0-based layer numbers, both included.
fn parse_range(s: &str) -> Result<(usize, usize)> {
    let bad = || {
        anyhow::anyhow!("--layers '{s}': expected FROM..TO, e.g. 100..120 (0-based, both included)")
    };
    let (f, t) = s.split_once("..").ok_or_else(bad)?;
    let t = t.strip_prefix('=').unwrap_or(t);
    let from: usize = f.trim().parse().map_err(|_| bad())?;
    let to: usize = t.trim().parse().map_err(|_| bad())?;
    if from > to {
        return Err(bad());
    }
    Ok((from, to))
}

/// What will be written, said before the work starts.
fn plan(grid: &SliceGrid, format: SliceFormat, preset: Option<&str>) -> String {
    use microfrep::io::text::sig;
    let pixels = grid.nx as u64 * grid.ny as u64;
    let (what, bytes) = match format {
        // 1-bit images before compression; contours are far smaller.
        SliceFormat::Png => ("PNG images", pixels.div_ceil(8) * grid.layers as u64),
        SliceFormat::Svg => ("SVG contours", 0),
        SliceFormat::Cli => ("CLI contours", 0),
        SliceFormat::ThreeMf => ("3MF slice contours", 0),
    };
    let size = if bytes > 0 {
        format!(
            ", up to {} before compression",
            microfrep::scan::volume::describe_bytes(bytes)
        )
    } else {
        String::new()
    };
    let which = if grid.layers == 1 {
        format!("layer at z = {}", sig(grid.z(0), 8))
    } else if grid.first > 0 {
        format!("layers {}..{}", grid.first, grid.first + grid.layers - 1)
    } else {
        format!("{} layers", grid.layers)
    };
    let from = preset.map(|p| format!(" (preset {p})")).unwrap_or_default();
    format!(
        "slicing: {which} of {} x {} pixels, pixel {} and layer {}{from}: {what}{size}",
        grid.nx,
        grid.ny,
        sig(grid.pixel, 6),
        sig(grid.layer, 6)
    )
}
