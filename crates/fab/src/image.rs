//! Layer images as PNG: 1-bit (inside white) or 8-bit coverage, row 0 of
//! the file at the largest y, as a printer's projector shows it.

use crate::error::{FabError, Result};
use crate::raster::LayerValues;
use std::path::Path;

/// Greyscale image rows, top row first, one byte per pixel (0 or 255 for
/// binary images).
pub struct GreyImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Whether the image is 1-bit (pixels only 0 or 255, written as a 1-bit PNG)
    /// rather than 8-bit coverage.
    pub binary: bool,
    /// `width * height` bytes, row-major, top row (largest y) first.
    pub pixels: Vec<u8>,
}

impl GreyImage {
    /// The binary image of a layer: white where `f >= 0`.
    pub fn binary(layer: &LayerValues) -> GreyImage {
        let mut pixels = Vec::with_capacity(layer.nx * layer.ny);
        for j in (0..layer.ny).rev() {
            pixels.extend((0..layer.nx).map(|i| if layer.inside(i, j) { 255 } else { 0 }));
        }
        GreyImage {
            width: layer.nx,
            height: layer.ny,
            binary: true,
            pixels,
        }
    }

    /// An 8-bit image from per-pixel coverage stored bottom row first.
    pub fn from_coverage(nx: usize, ny: usize, cov: &[u8]) -> GreyImage {
        let mut pixels = Vec::with_capacity(nx * ny);
        for j in (0..ny).rev() {
            pixels.extend_from_slice(&cov[j * nx..(j + 1) * nx]);
        }
        GreyImage {
            width: nx,
            height: ny,
            binary: false,
            pixels,
        }
    }

    /// PNG bytes: bit depth 1 for binary images, 8 otherwise. `path` only
    /// names the file in errors.
    pub fn encode(&self, path: &Path) -> Result<Vec<u8>> {
        let img = microfrep_io::png::Image {
            width: self.width,
            height: self.height,
            pixels: if self.binary {
                microfrep_io::png::Pixels::Bilevel
            } else {
                microfrep_io::png::Pixels::Grey
            },
            data: self.pixels.clone(),
        };
        Ok(microfrep_io::png::encode(&img, path)?)
    }
}

/// Decodes a greyscale PNG to one byte per pixel (1-bit images expanded to
/// 0 / 255), top row first: for tests and tools that read the stack back.
pub fn decode_png(path: &Path) -> Result<GreyImage> {
    let bytes = std::fs::read(path).map_err(crate::error::io_at(path))?;
    let binary = bytes.get(24) == Some(&1);
    let img = microfrep_io::png::decode(&bytes, path)?;
    if img.pixels != microfrep_io::png::Pixels::Grey {
        return Err(FabError::Invalid(format!(
            "{}: expected a greyscale PNG, got {:?}",
            path.display(),
            img.pixels
        )));
    }
    Ok(GreyImage {
        width: img.width,
        height: img.height,
        binary,
        pixels: img.data,
    })
}
