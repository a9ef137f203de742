//! `microfrep render`: a ray-cast image, a cut-away, or a section.

use crate::model;
use crate::slice_cmd::bounds;
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep_render::{cutaway, ray_cast, section, Camera, Plane, View};
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    /// Model: a HyperFun file (.hf) or a built-in example name (see `microfrep examples`).
    model: String,
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
    /// Box to frame: xmin,ymin,zmin,xmax,ymax,zmax (default: the example's bounds, else from interval analysis).
    #[arg(long, allow_hyphen_values = true)]
    bounds: Option<String>,
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
    microfrep_render::camera::check_size(w, h)?;
    Ok((w, h))
}

pub fn run(a: RenderArgs) -> Result<()> {
    let m = model::load(&a.model)?;
    let (min, max) = bounds(&m, a.bounds.as_deref())?;
    let (w, h) = size(&a.size)?;
    let img = match a.section {
        Some(_) if a.cutaway => bail!("--section and --cutaway do not combine"),
        Some(plane) => section(&m.shape, plane, min, max, w, h),
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
    Ok(())
}
