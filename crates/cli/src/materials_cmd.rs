//! `microfrep materials`: a multi-material voxel stack for material-jetting
//! printers: one RGBA PNG per layer, each voxel inside the solid one
//! material, dithered so each material's share follows the attributes.

use crate::common::{frame, load_model, ModelArgs, RunArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep::graded::dither::Method;
use microfrep::graded::stack::{
    find_preset, write_material_stack, MaterialStack, Palette, ShapeSource, StackGrid,
};
use std::path::PathBuf;

#[derive(Args)]
pub struct MaterialsArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output directory (must not exist).
    #[arg(short, long)]
    output: PathBuf,
    /// Materials NAME=#RRGGBB,...: material k takes the share s[k], the last
    /// one the remainder.
    #[arg(long)]
    palette: String,
    /// Layer thickness (or from --preset).
    #[arg(long)]
    layer: Option<f64>,
    /// Voxel pitch X[,Y] (or from --preset).
    #[arg(long)]
    pixel: Option<String>,
    /// A printer grid: mj-600x300-27um, mj-600x300-14um, mj-600x600-27um,
    /// vat-50um or dlp-25um (an unknown name lists them with their pitches).
    #[arg(long)]
    preset: Option<String>,
    /// error-diffusion (default), stochastic or ordered.
    #[arg(long, default_value = "error-diffusion")]
    dither: String,
    /// Seed of stochastic dithering.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    run: RunArgs,
}

pub fn run(a: MaterialsArgs) -> Result<()> {
    a.run.init()?;
    let palette = Palette::parse(&a.palette)?;
    let method = match a.dither.as_str() {
        "error-diffusion" => Method::ErrorDiffusion,
        "stochastic" => Method::Stochastic { seed: a.seed },
        "ordered" => Method::Ordered,
        d => bail!("--dither {d}: error-diffusion, stochastic or ordered"),
    };
    let m = load_model(&a.model, &a.run)?;
    let n = palette.len();
    let channels = m.shape.attributes().len();
    if channels + 1 < n {
        bail!(
            "{n} materials need {} attribute channels s[1..]; the model has {channels}",
            n - 1
        );
    }
    let b = frame(&m, &a.model, &a.run)?;
    let grid = match (&a.preset, a.layer, &a.pixel) {
        (Some(p), None, None) => {
            let p = find_preset(p).map_err(|e| anyhow::anyhow!("--preset: {e}"))?;
            StackGrid::from_preset(b.min, b.max, p)?
        }
        (None, Some(layer), Some(px)) => {
            let v: Vec<f64> = px
                .split(',')
                .map(|t| t.trim().parse())
                .collect::<Result<_, _>>()
                .with_context(|| format!("--pixel '{px}': X or X,Y"))?;
            let pitch = match v[..] {
                [x] => [x, x],
                [x, y] => [x, y],
                _ => bail!("--pixel '{px}': X or X,Y"),
            };
            StackGrid::new(b.min, b.max, pitch, layer)?
        }
        _ => bail!("give --preset, or --layer and --pixel"),
    };
    let mut opts = MaterialStack::new(palette);
    opts.method = method;
    opts.preset = a.preset.clone();
    let src = ShapeSource::new(&m.shape, &grid, n)?;
    let (nx, ny) = (grid.nx, grid.ny);
    let mut source =
        |k: usize, fractions: &mut [f32], inside: &mut [bool]| src.fill(k, fractions, inside);
    let bar = a.run.bar("layers");
    bar.set_message("dithering");
    let r = write_material_stack(&a.output, &grid, &opts, &mut source, &|d, t| {
        bar.set_length(t);
        bar.set_position(d);
    });
    bar.finish_and_clear();
    let r = r?;
    if a.run.json {
        let s = serde_json::json!({
            "output": a.output.display().to_string(), "layers": r.layers,
            "counts": r.dither.counts, "integrals": r.dither.integrals,
        });
        println!("{s}");
    } else if !a.run.quiet {
        println!(
            "wrote {} ({} layers of {nx} x {ny})",
            a.output.display(),
            r.layers
        );
        for (k, (c, i)) in r.dither.counts.iter().zip(&r.dither.integrals).enumerate() {
            println!("  material {}: {c} voxels (target {:.1})", k + 1, i);
        }
    }
    Ok(())
}
