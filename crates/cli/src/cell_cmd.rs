//! `microfrep cell`: checks a unit cell before replication (Fryazinov et
//! al. Eqs. 4-6) and says which replicating function is safe on each axis.

use crate::common::{load_model, parse_box, ModelArgs, RunArgs};
use anyhow::{Context, Result};
use clap::Args;
use microfrep::structures::cell_report::{cell_report, to_json};

#[derive(Args)]
pub struct CellArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// The unit cell's box: xmin,ymin,zmin,xmax,ymax,zmax.
    #[arg(long = "box", allow_hyphen_values = true)]
    cell_box: String,
    /// Absolute tolerance for comparing function values.
    #[arg(long, default_value_t = 1e-6)]
    tolerance: f64,
    /// Samples per face edge (2 to 128); symmetry uses this many per axis.
    #[arg(long, default_value_t = 17)]
    samples: usize,
    #[command(flatten)]
    run: RunArgs,
}

pub fn run(a: CellArgs) -> Result<()> {
    a.run.init()?;
    let (min, max) = parse_box("--box", &a.cell_box)?;
    let m = load_model(&a.model, &a.run)?;
    let r = cell_report(m.shape.value(), min, max, a.samples, a.tolerance)
        .with_context(|| format!("checking the unit cell of {}", a.model.model))?;
    if a.run.json {
        println!("{}", serde_json::to_string_pretty(&to_json(&r, min, max))?);
    } else if !a.run.quiet {
        print!("{}", r.to_text(min, max));
    }
    Ok(())
}
