//! Layer images as PNG: 1-bit (inside white) or 8-bit coverage, row 0 of
//! the file at the largest y, as a printer's projector shows it.

use crate::error::{FabError, Result};
use crate::raster::LayerValues;
use std::path::Path;

/// Greyscale image rows, top row first, one byte per pixel (0 or 255 for
/// binary images).
pub struct GreyImage {
    pub width: usize,
    pub height: usize,
    pub binary: bool,
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
        let err = |e: png::EncodingError| FabError::Encode {
            path: path.to_path_buf(),
            msg: e.to_string(),
        };
        let mut buf = Vec::new();
        let mut enc = png::Encoder::new(&mut buf, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Grayscale);
        let data = if self.binary {
            enc.set_depth(png::BitDepth::One);
            self.pack_bits()
        } else {
            enc.set_depth(png::BitDepth::Eight);
            self.pixels.clone()
        };
        let mut w = enc.write_header().map_err(err)?;
        w.write_image_data(&data).map_err(err)?;
        w.finish().map_err(err)?;
        Ok(buf)
    }

    /// Rows of 1-bit pixels, most significant bit first, each row padded to
    /// a whole byte.
    fn pack_bits(&self) -> Vec<u8> {
        let stride = self.width.div_ceil(8);
        let mut out = vec![0u8; stride * self.height];
        for (r, row) in self.pixels.chunks(self.width).enumerate() {
            for (i, &p) in row.iter().enumerate() {
                if p >= 128 {
                    out[r * stride + i / 8] |= 0x80 >> (i % 8);
                }
            }
        }
        out
    }
}

/// Decodes a greyscale PNG to one byte per pixel (1-bit images expanded to
/// 0 / 255), top row first: for tests and tools that read the stack back.
pub fn decode_png(path: &Path) -> Result<GreyImage> {
    let file = std::fs::File::open(path).map_err(crate::error::io_at(path))?;
    let err = |e: png::DecodingError| FabError::Encode {
        path: path.to_path_buf(),
        msg: e.to_string(),
    };
    let mut dec = png::Decoder::new(std::io::BufReader::new(file));
    dec.set_transformations(png::Transformations::EXPAND);
    let mut reader = dec.read_info().map_err(err)?;
    let mut buf = vec![0u8; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(err)?;
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Eight {
        return Err(FabError::Encode {
            path: path.to_path_buf(),
            msg: format!(
                "expected greyscale, got {:?} at {:?} bits",
                info.color_type, info.bit_depth
            ),
        });
    }
    let (w, h) = (info.width as usize, info.height as usize);
    let binary = reader.info().bit_depth == png::BitDepth::One;
    let mut pixels = Vec::with_capacity(w * h);
    for r in 0..h {
        pixels.extend_from_slice(&buf[r * info.line_size..r * info.line_size + w]);
    }
    Ok(GreyImage {
        width: w,
        height: h,
        binary,
        pixels,
    })
}
