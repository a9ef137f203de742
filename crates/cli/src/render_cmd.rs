//! `microfrep render`: a ray-cast image, a cut-away, or a section.

use crate::common::{check_extension, frame, load_model, ModelArgs, RunArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep::render::{
    cutaway, ray_cast, ray_cast_attribute, section_image, AttributeShading, Camera, Colormap,
    Plane, SectionShading, View,
};
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
    /// A flat section image on the plane x=V, y=V or z=V: the value, or
    /// with --color-by K the attribute s[K] inside the part, through
    /// --colormap, with a legend and a scale bar in model units.
    #[arg(long)]
    section: Option<Plane>,
    /// Remove the octant nearest the viewer to show the inside.
    #[arg(long)]
    cutaway: bool,
    #[command(flatten)]
    colour: ColourArgs,
    #[command(flatten)]
    run: RunArgs,
}

/// Colouring by an attribute channel (`mesh` and `render`).
#[derive(Args)]
pub struct ColourArgs {
    /// Colour by attribute channel K (1-based, HyperFun's s[K]) through
    /// --colormap over --range.
    #[arg(long = "color-by", visible_alias = "colour-by", value_name = "K")]
    pub color_by: Option<usize>,
    /// Colour map of --color-by (and of a value --section): viridis
    /// (default) or grey.
    #[arg(long, value_name = "MAP")]
    pub colormap: Option<Colormap>,
    /// Values of the map's first and last colour, LO,HI (default: the
    /// channel's smallest and largest value over the mesh's vertices or the
    /// visible surface; for a value section, -M,M with M the largest
    /// magnitude on it).
    #[arg(
        long,
        value_name = "LO,HI",
        value_parser = parse_range,
        allow_hyphen_values = true
    )]
    pub range: Option<(f64, f64)>,
}

/// A 0-based channel, its colour map and range.
pub type ColourRequest = (usize, Colormap, Option<[f64; 2]>);

impl ColourArgs {
    /// The request; `None` without --color-by (then --colormap and
    /// --range are refused: they colour by an attribute).
    pub fn get(&self) -> Result<Option<ColourRequest>> {
        match self.color_by {
            None if self.colormap.is_some() || self.range.is_some() => {
                bail!("--colormap and --range colour by an attribute: give --color-by K")
            }
            None => Ok(None),
            Some(_) => self
                .section()
                .map(|(k, map, range)| k.map(|k| (k, map, range))),
        }
    }

    /// A section's colouring: the channel (`None`: the value), the map and
    /// the range, all optional.
    pub fn section(&self) -> Result<(Option<usize>, Colormap, Option<[f64; 2]>)> {
        let channel = match self.color_by {
            None => None,
            Some(0) => bail!("--color-by K: channels count from 1 (HyperFun's s[1])"),
            Some(k) => Some(k - 1),
        };
        Ok((
            channel,
            self.colormap.unwrap_or(Colormap::Viridis),
            self.range.map(|r| [r.0, r.1]),
        ))
    }
}

fn parse_range(s: &str) -> std::result::Result<(f64, f64), String> {
    let bad = || format!("'{s}': expected LO,HI with finite LO < HI");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let (lo, hi): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(bad());
    }
    Ok((lo, hi))
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
    let colour = match a.section {
        Some(_) => None,
        None => a.colour.get()?,
    };
    let mut range = None;
    let (mut scale_bar, mut pixel) = (None, None);
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
            let (channel, colormap, given) = a.colour.section()?;
            let opts = SectionShading {
                channel,
                colormap,
                range: given,
                legend: true,
            };
            let out = section_image(&m.shape, plane, min, max, w, h, &opts)?;
            range = Some(([out.scale.lo, out.scale.hi], out.bar));
            scale_bar = out.scale_bar;
            pixel = Some((out.pixel, out.origin));
            out.image
        }
        None => {
            let s = if a.cutaway {
                cutaway(&m.shape, a.view, min, max)
            } else {
                m.shape
            };
            match colour {
                Some((channel, colormap, given)) => {
                    let opts = AttributeShading {
                        channel,
                        colormap,
                        range: given,
                        legend: true,
                    };
                    let out = ray_cast_attribute(&s, a.view, min, max, w, h, &opts)?;
                    range = Some(([out.scale.lo, out.scale.hi], out.bar));
                    out.image
                }
                None => ray_cast(&s, &Camera::fit(a.view, min, max, w, h), min, max),
            }
        }
    };
    img.save_png(&a.output)?;
    if a.run.json {
        let mut j = serde_json::json!({ "output": a.output.display().to_string(), "size": [w, h] });
        if let Some((r, bar)) = range {
            j["colour_range"] = serde_json::json!(r);
            j["legend_bar"] = serde_json::json!(bar);
        }
        if let Some((p, origin)) = pixel {
            j["pixel"] = serde_json::json!(p);
            j["origin"] = serde_json::json!(origin);
        }
        if let Some(b) = scale_bar {
            j["scale_bar"] = serde_json::json!({
                "length": b.length,
                "pixels": [b.x, b.y, b.width, b.height],
            });
        }
        println!("{j}");
    }
    Ok(())
}
