//! Whole slice stacks written to disk: layers computed in parallel a few at
//! a time and written in order as they finish (memory stays bounded by the
//! batch, whatever the layer count), into a temporary path renamed only when
//! everything succeeded.

use crate::cli_format;
use crate::contour::{contours, signed_area, Polygon};
use crate::coverage::coverage;
use crate::error::{io_at, FabError, Result};
use crate::grid::SliceGrid;
use crate::image::GreyImage;
use crate::raster::{rasterize, LayerValues};
use crate::simplify::simplify_closed;
use crate::svg::layer_svg;
use microfrep_core::Shape;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::Path;

/// Contour simplification tolerance, in pixels.
pub const SIMPLIFY_TOL_PIXELS: f64 = 0.25;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Format {
    /// One PNG per layer: 1-bit, or 8-bit area coverage with `aa`.
    Png { aa: bool },
    /// One SVG of closed contours per layer.
    Svg,
    /// One Common Layer Interface file for all layers.
    Cli,
}

/// The simplified, oriented loops of a layer (see [`contours`]); loops that
/// collapse below three vertices or to no area are dropped.
pub fn layer_polygons(shape: &Shape, grid: &SliceGrid, layer: &LayerValues) -> Vec<Polygon> {
    let tol = SIMPLIFY_TOL_PIXELS * grid.pixel;
    contours(shape, grid, layer)
        .into_iter()
        .map(|p| simplify_closed(&p, tol))
        .filter(|p| p.len() >= 3 && signed_area(p) != 0.0)
        .collect()
}

/// Slices the model into `out`: a directory of images or SVGs with a
/// `manifest.json`, or one CLI file. `out` must not exist. `progress` is
/// called once per finished layer.
pub fn write_stack(
    shape: &Shape,
    grid: &SliceGrid,
    format: Format,
    out: &Path,
    progress: &(dyn Fn() + Sync),
) -> Result<()> {
    if out.exists() {
        return Err(FabError::Invalid(format!(
            "{} already exists; remove it or choose another output",
            out.display()
        )));
    }
    let name = out
        .file_name()
        .ok_or_else(|| FabError::Invalid(format!("{}: not a file name", out.display())))?;
    let tmp = out.with_file_name(format!(
        ".{}.partial-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let res = write_into(shape, grid, format, &tmp, progress);
    let res = res.and_then(|_| fs::rename(&tmp, out).map_err(io_at(out)));
    if res.is_err() {
        // Best effort: the error being reported matters more than this one.
        let _ = fs::remove_dir_all(&tmp).or_else(|_| fs::remove_file(&tmp));
    }
    res
}

fn write_into(
    shape: &Shape,
    grid: &SliceGrid,
    format: Format,
    tmp: &Path,
    progress: &(dyn Fn() + Sync),
) -> Result<()> {
    let max = [
        grid.min[0] + grid.nx as f64 * grid.pixel,
        grid.min[1] + grid.ny as f64 * grid.pixel,
        grid.min[2] + grid.layers as f64 * grid.layer,
    ];
    let mut cli = None;
    match format {
        Format::Cli => {
            let f = fs::File::create(tmp).map_err(io_at(tmp))?;
            let mut w = std::io::BufWriter::new(f);
            w.write_all(cli_format::header(grid.min, max, grid.layers).as_bytes())
                .map_err(io_at(tmp))?;
            cli = Some(w);
        }
        _ => fs::create_dir(tmp).map_err(io_at(tmp))?,
    }
    let file_name = |k: usize| match format {
        Format::Svg => format!("layer_{k:05}.svg"),
        _ => format!("layer_{k:05}.png"),
    };
    let batch = 2 * rayon::current_num_threads();
    for start in (0..grid.layers).step_by(batch) {
        let end = (start + batch).min(grid.layers);
        let payloads: Vec<Result<Vec<u8>>> = (start..end)
            .into_par_iter()
            .map(|k| {
                let path = tmp.join(file_name(k));
                layer_payload(shape, grid, format, k, max, &path)
            })
            .collect();
        for (k, p) in (start..end).zip(payloads) {
            let bytes = p?;
            match cli.as_mut() {
                Some(w) => w.write_all(&bytes).map_err(io_at(tmp))?,
                None => {
                    let path = tmp.join(file_name(k));
                    fs::write(&path, bytes).map_err(io_at(&path))?;
                }
            }
            progress();
        }
    }
    match cli {
        Some(mut w) => {
            w.write_all(cli_format::FOOTER.as_bytes())
                .map_err(io_at(tmp))?;
            w.into_inner()
                .map_err(|e| FabError::Io {
                    path: tmp.to_path_buf(),
                    err: e.into_error(),
                })?
                .sync_all()
                .map_err(io_at(tmp))
        }
        None => {
            let path = tmp.join("manifest.json");
            fs::write(&path, manifest(grid, format, &file_name)).map_err(io_at(&path))
        }
    }
}

/// The bytes one layer contributes: a PNG, an SVG or a CLI layer block.
fn layer_payload(
    shape: &Shape,
    grid: &SliceGrid,
    format: Format,
    k: usize,
    max: [f64; 3],
    path: &Path,
) -> Result<Vec<u8>> {
    let layer = rasterize(shape, grid, k);
    Ok(match format {
        Format::Png { aa: false } => GreyImage::binary(&layer).encode(path)?,
        Format::Png { aa: true } => {
            let cov = coverage(shape, &layer, grid.pixel, [grid.min[0], grid.min[1]]);
            GreyImage::from_coverage(grid.nx, grid.ny, &cov).encode(path)?
        }
        Format::Svg => {
            let polys = layer_polygons(shape, grid, &layer);
            let tol = SIMPLIFY_TOL_PIXELS * grid.pixel;
            let lo = [grid.min[0], grid.min[1]];
            layer_svg(&polys, layer.z, lo, [max[0], max[1]], tol).into_bytes()
        }
        Format::Cli => {
            let polys = layer_polygons(shape, grid, &layer);
            let top = grid.min[2] + (k + 1) as f64 * grid.layer;
            cli_format::layer_block(top, &polys).into_bytes()
        }
    })
}

/// `manifest.json`: geometry of the stack and one entry per layer.
fn manifest(grid: &SliceGrid, format: Format, file_name: &dyn Fn(usize) -> String) -> String {
    let kind = match format {
        Format::Png { aa: false } => "png-1bit",
        Format::Png { aa: true } => "png-8bit-coverage",
        Format::Svg => "svg",
        Format::Cli => "cli",
    };
    let mut s = String::from("{\n");
    let _ = writeln!(s, "  \"format\": \"{kind}\",");
    let _ = writeln!(s, "  \"pixel_size\": {},", grid.pixel);
    let _ = writeln!(s, "  \"layer_thickness\": {},", grid.layer);
    let _ = writeln!(
        s,
        "  \"origin\": [{}, {}, {}],",
        grid.min[0], grid.min[1], grid.min[2]
    );
    let _ = writeln!(s, "  \"image_size\": [{}, {}],", grid.nx, grid.ny);
    let _ = writeln!(
        s,
        "  \"notes\": \"origin is the outer corner of the bottom-left pixel at the bottom of \
         layer 0; image row 0 is the largest y; z is the middle of the layer, where it was sampled\","
    );
    if format == Format::Svg {
        let _ = writeln!(
            s,
            "  \"simplification_tolerance\": {},",
            SIMPLIFY_TOL_PIXELS * grid.pixel
        );
    }
    s.push_str("  \"layers\": [\n");
    for k in 0..grid.layers {
        let sep = if k + 1 < grid.layers { "," } else { "" };
        let _ = writeln!(
            s,
            "    {{\"file\": \"{}\", \"z\": {}}}{sep}",
            file_name(k),
            grid.z(k)
        );
    }
    s.push_str("  ]\n}\n");
    s
}
