//! `microfrep render`: a ray-cast image, a cut-away, or a section.

use crate::common::{check_extension, frame, load_model, ModelArgs, RunArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep::render::{cutaway, ray_cast, section, Camera, Plane, View};
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output PNG.
    #[arg(short, long)]
    output: PathBuf,
    /// Image size WxH.
    #[arg(long, default_value = "1024x768")]
    size: String,
    /// iso, front, top or side.
    #[arg(long, default_value = "iso")]
    view: View,
    /// A flat section image of the value on the plane x=V, y=V or z=V.
    #[arg(long)]
    section: Option<Plane>,
    /// Remove the octant nearest the viewer to show the inside.
    #[arg(long)]
    cutaway: bool,
    #[command(flatten)]
    run: RunArgs,
}

fn size(s: &str) -> Result<(usize, usize)> {
    let (w, h) = s
        .split_once('x')
        .with_context(|| format!("--size '{s}': expected WxH"))?;
    let w: usize = w
        .parse()
        .with_context(|| format!("--size '{s}': bad width"))?;
    let h: usize = h
        .parse()
        .with_context(|| format!("--size '{s}': bad height"))?;
    microfrep::render::camera::check_size(w, h)?;
    Ok((w, h))
}

pub fn run(a: RenderArgs) -> Result<()> {
    a.run.init()?;
    check_extension(&a.output, &["png"], "the image")?;
    let (w, h) = size(&a.size)?;
    let m = load_model(&a.model, &a.run)?;
    let b = frame(&m, &a.model, &a.run)?;
    let (min, max) = (b.min, b.max);
    let img = match a.section {
        Some(_) if a.cutaway => bail!("--section and --cutaway do not combine"),
        Some(plane) => {
            let (lo, hi) = (min[plane.axis], max[plane.axis]);
            if !(lo..=hi).contains(&plane.value) {
                bail!(
                    "--section {}: the plane is outside the box ({} .. {} on that axis)",
                    plane.value,
                    lo,
                    hi
                );
            }
            section(&m.shape, plane, min, max, w, h)
        }
        None => {
            let s = if a.cutaway {
                cutaway(&m.shape, a.view, min, max)
            } else {
                m.shape
            };
            ray_cast(&s, &Camera::fit(a.view, min, max, w, h), min, max)
        }
    };
    img.save_png(&a.output)?;
    if a.run.json {
        println!(
            "{}",
            serde_json::json!({ "output": a.output.display().to_string(), "size": [w, h] })
        );
    }
    Ok(())
}
