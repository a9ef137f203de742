//! Whole slice stacks written to disk: layers computed in parallel a few at
//! a time and written in order as they finish (memory stays bounded by the
//! batch, whatever the layer count), into a temporary path renamed only when
//! everything succeeded.

use crate::cli_format;
use crate::contour::{contours, signed_area, Polygon};
use crate::coverage::coverage;
use crate::error::{io_at, Result};
use crate::grid::SliceGrid;
use crate::image::GreyImage;
use crate::raster::{rasterize, LayerValues};
use crate::simplify::simplify_closed;
use crate::svg::layer_svg;
use microfrep_core::Shape;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// Contour simplification tolerance, in pixels.
pub const SIMPLIFY_TOL_PIXELS: f64 = 0.25;

/// The built-in stack formats.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Format {
    /// One PNG per layer: 1-bit, or 8-bit area coverage with `aa`.
    Png {
        /// 8-bit grey levels from each pixel's covered area.
        aa: bool,
    },
    /// One SVG of closed contours per layer.
    Svg,
    /// One Common Layer Interface file for all layers.
    Cli,
}

impl std::str::FromStr for Format {
    type Err = String;

    /// `png` (1-bit), `png-aa` (8-bit coverage), `svg` or `cli`.
    fn from_str(name: &str) -> std::result::Result<Format, String> {
        match name.to_ascii_lowercase().as_str() {
            "png" => Ok(Format::Png { aa: false }),
            "png-aa" => Ok(Format::Png { aa: true }),
            "svg" => Ok(Format::Svg),
            "cli" => Ok(Format::Cli),
            other => Err(format!(
                "slice format '{other}': png, png-aa, svg or cli (a 3MF slice stack: \
                 `microfrep slice --format 3mf`)"
            )),
        }
    }
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

/// A layer-stack format: a directory with one file per layer and a
/// manifest, or one file for all layers. The stack writer computes layers in
/// parallel and hands each to the format; a new format (a 3MF slice stack,
/// a material stack) is one more implementation.
pub trait StackFormat: Sync {
    /// Short name, as given to `--format`.
    fn name(&self) -> &'static str;
    /// Whether the output is one file (else a directory of layer files).
    fn single_file(&self) -> bool;
    /// The file name of layer `k` in a directory stack.
    fn layer_name(&self, k: usize) -> String {
        format!("layer_{k:05}.png")
    }
    /// Bytes before the first layer of a single-file stack.
    fn header(&self, _grid: &SliceGrid) -> Vec<u8> {
        Vec::new()
    }
    /// The bytes of layer `k` and its number of solid pixels (called in
    /// parallel for different layers).
    fn layer(
        &self,
        shape: &Shape,
        grid: &SliceGrid,
        k: usize,
        path: &Path,
    ) -> Result<(Vec<u8>, u64)>;
    /// Bytes after the last layer of a single-file stack, or the manifest
    /// of a directory stack.
    fn footer(&self, grid: &SliceGrid) -> Vec<u8>;
}

impl StackFormat for Format {
    fn name(&self) -> &'static str {
        match self {
            Format::Png { aa: false } => "png",
            Format::Png { aa: true } => "png-aa",
            Format::Svg => "svg",
            Format::Cli => "cli",
        }
    }
    fn single_file(&self) -> bool {
        *self == Format::Cli
    }
    fn layer_name(&self, k: usize) -> String {
        match self {
            Format::Svg => format!("layer_{k:05}.svg"),
            _ => format!("layer_{k:05}.png"),
        }
    }
    fn header(&self, grid: &SliceGrid) -> Vec<u8> {
        match self {
            Format::Cli => cli_format::header(bottom(grid), top(grid), grid.layers).into_bytes(),
            _ => Vec::new(),
        }
    }
    fn layer(
        &self,
        shape: &Shape,
        grid: &SliceGrid,
        k: usize,
        path: &Path,
    ) -> Result<(Vec<u8>, u64)> {
        layer_payload(shape, grid, *self, k, top(grid), path)
    }
    fn footer(&self, grid: &SliceGrid) -> Vec<u8> {
        match self {
            Format::Cli => cli_format::FOOTER.as_bytes().to_vec(),
            f => manifest(grid, *f, &|k| f.layer_name(grid.first + k)).into_bytes(),
        }
    }
}

/// The far corner of the sliced box.
/// The lower corner of the layers written (above the stack's own corner
/// for a range of its layers).
fn bottom(grid: &SliceGrid) -> [f64; 3] {
    [
        grid.min[0],
        grid.min[1],
        grid.min[2] + grid.first as f64 * grid.layer,
    ]
}

fn top(grid: &SliceGrid) -> [f64; 3] {
    [
        grid.min[0] + grid.nx as f64 * grid.pixel,
        grid.min[1] + grid.ny as f64 * grid.pixel,
        grid.min[2] + (grid.first + grid.layers) as f64 * grid.layer,
    ]
}

/// Slices the model into `out`: a directory of images or SVGs with a
/// `manifest.json`, or one file (CLI). A directory output must not exist.
/// The stack is written under a temporary name next to `out` and renamed
/// only when complete ([`microfrep_io::atomic`]); `progress` is called once
/// per finished layer.
pub fn write_stack(
    shape: &Shape,
    grid: &SliceGrid,
    format: &dyn StackFormat,
    out: &Path,
    progress: &(dyn Fn() + Sync),
) -> Result<()> {
    use microfrep_io::{AtomicDir, AtomicFile};
    crate::grid::check_precision(shape, bottom(grid), top(grid))?;
    enum Target {
        File(AtomicFile),
        Dir(AtomicDir),
    }
    let mut target = if format.single_file() {
        let mut f = AtomicFile::create(out)?;
        let head = format.header(grid);
        f.write_all(&head).map_err(io_at(out))?;
        Target::File(f)
    } else {
        Target::Dir(AtomicDir::create(out)?)
    };
    let batch = layers_in_flight(grid, microfrep_io::limits::memory_limit())?;
    let mut solid = 0u64;
    for start in (0..grid.layers).step_by(batch) {
        let end = (start + batch).min(grid.layers);
        let payloads: Vec<Result<(Vec<u8>, u64)>> = (start..end)
            .into_par_iter()
            .map(|k| format.layer(shape, grid, k, &out.join(format.layer_name(grid.first + k))))
            .collect();
        for (k, p) in (start..end).zip(payloads) {
            let (bytes, n) = p?;
            solid += n;
            match &mut target {
                Target::File(f) => f.write_all(&bytes).map_err(io_at(out))?,
                Target::Dir(d) => d.write(&format.layer_name(grid.first + k), &bytes)?,
            }
            progress();
        }
    }
    if solid == 0 {
        // Dropping the target removes the temporary: nothing is written.
        return Err(crate::FabError::Empty(format!(
            "{}: no pixel of the {} layers ({} x {} pixels of {}, layers of {}) is inside the \
             model: the part is thinner than a layer or a pixel, undefined (NaN) or outside \
             the box; use finer --layer and --pixel or check --bounds",
            out.display(),
            grid.layers,
            grid.nx,
            grid.ny,
            grid.pixel,
            grid.layer
        )));
    }
    let tail = format.footer(grid);
    match target {
        Target::File(mut f) => {
            f.write_all(&tail).map_err(io_at(out))?;
            f.commit()?;
        }
        Target::Dir(d) => {
            d.write("manifest.json", &tail)?;
            d.commit()?;
        }
    }
    Ok(())
}

/// Bytes per pixel of a layer being made: its values (4), its image or
/// coverage (1 to 2) and encoded bytes, with slack for contours.
const BYTES_PER_PIXEL: f64 = 10.0;

/// Layers computed at once: two per thread, fewer when their images would
/// not fit `limit` bytes (with a fifth kept free); an error when one layer
/// alone does not fit.
pub fn layers_in_flight(grid: &SliceGrid, limit: Option<f64>) -> Result<usize> {
    let per_layer = BYTES_PER_PIXEL * (grid.nx * grid.ny) as f64 + 1e6;
    let want = 2 * rayon::current_num_threads();
    let Some(limit) = limit else {
        return Ok(want);
    };
    let fit = (0.8 * limit / per_layer).floor();
    if fit < 1.0 {
        return Err(crate::FabError::TooLarge(format!(
            "a layer of {} x {} pixels needs about {:.0} MiB but {:.0} MiB are available; use a \
             coarser --pixel",
            grid.nx,
            grid.ny,
            per_layer / MIB,
            limit / MIB
        )));
    }
    Ok(want.min(fit as usize))
}

const MIB: f64 = 1024.0 * 1024.0;

/// The bytes one layer contributes: a PNG, an SVG or a CLI layer block.
fn layer_payload(
    shape: &Shape,
    grid: &SliceGrid,
    format: Format,
    k: usize,
    max: [f64; 3],
    path: &Path,
) -> Result<(Vec<u8>, u64)> {
    let layer = rasterize(shape, grid, k);
    let solid = layer.values.iter().filter(|&&v| v >= 0.0).count() as u64;
    let bytes = match format {
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
    };
    Ok((bytes, solid))
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
    let _ = writeln!(s, "  \"first_layer\": {},", grid.first);
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
