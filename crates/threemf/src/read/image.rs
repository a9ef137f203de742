//! PNG sheets of image stacks (volumetric extension), read after the root
//! part.

use super::package::{open_counted, Budget};
use crate::error::{invalid, Error, Result};
use crate::model::Model;
use crate::volumetric::PixelLayout;
use std::io::{BufRead, BufReader, Read, Seek};

/// Decodes the sheets of every image stack of `model` (read from the root
/// part `root`) into its samples.
pub(super) fn read_sheets<R: Read + Seek>(
    zip: &mut zip::ZipArchive<R>,
    root: &str,
    model: &mut Model,
    budget: &Budget,
) -> Result<()> {
    for im in &mut model.images {
        let expected = im.dims;
        let mut layout = None;
        let mut depth = 0u8;
        let nx = expected[0];
        let ny = expected[1];
        let mut samples = Vec::new();
        for (k, path) in im.sheet_paths.iter().enumerate() {
            let part = path.trim_start_matches('/').to_string();
            let ctx = format!("imagesheet {k} of image3d {} in /{root}", im.id);
            let f = open_counted(zip, &part, &ctx, |_| 0, budget)?;
            let (l, d, data) = decode_sheet(BufReader::new(f), &part, nx, ny)?;
            if layout.is_some_and(|x| x != l) || (depth != 0 && depth != d) {
                return Err(invalid(
                    &part,
                    0,
                    "all sheets of an image stack must have the same channels and bit depth",
                ));
            }
            if samples.is_empty() {
                let n = (nx * ny * expected[2] * l.channels()) as u64;
                budget.take(&part, n * 2, || {
                    format!("image3d {} of {expected:?} samples", im.id)
                })?;
                samples.reserve(n as usize);
            }
            layout = Some(l);
            depth = d;
            samples.extend(data);
        }
        im.layout = layout.unwrap_or(PixelLayout::Y);
        im.bit_depth = depth.max(8);
        im.samples = samples;
    }
    Ok(())
}

/// Decodes one PNG sheet into samples (flipped so that `iy = 0` is the
/// bottom row).
fn decode_sheet<R: BufRead>(
    r: R,
    part: &str,
    nx: usize,
    ny: usize,
) -> Result<(PixelLayout, u8, Vec<u16>)> {
    let mut dec = png::Decoder::new_with_limits(
        r,
        png::Limits {
            bytes: (nx * ny * 8).max(1 << 16),
        },
    );
    dec.set_transformations(png::Transformations::EXPAND);
    let err = |source| Error::PngDecode {
        part: part.to_string(),
        source,
    };
    let mut reader = dec.read_info().map_err(err)?;
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    if w != nx || h != ny {
        return Err(invalid(
            part,
            0,
            format!("sheet is {w}x{h}, the image stack says {nx}x{ny}"),
        ));
    }
    let mut data = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut data).map_err(err)?;
    let layout = match info.color_type {
        png::ColorType::Grayscale => PixelLayout::Y,
        png::ColorType::GrayscaleAlpha => PixelLayout::YA,
        png::ColorType::Rgb => PixelLayout::Rgb,
        png::ColorType::Rgba => PixelLayout::Rgba,
        png::ColorType::Indexed => {
            return Err(invalid(part, 0, "indexed PNG sheets are not supported"))
        }
    };
    let (depth, bytes) = match info.bit_depth {
        png::BitDepth::Sixteen => (16u8, 2usize),
        png::BitDepth::Eight => (8, 1),
        d => {
            return Err(invalid(
                part,
                0,
                format!("PNG bit depth {d:?} (only 8 and 16 are supported)"),
            ));
        }
    };
    let nc = layout.channels();
    let mut out = Vec::with_capacity(nx * ny * nc);
    for iy in 0..ny {
        let row = &data[(ny - 1 - iy) * info.line_size..][..nx * nc * bytes];
        if bytes == 2 {
            out.extend(
                row.chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]])),
            );
        } else {
            out.extend(row.iter().map(|&b| b as u16));
        }
    }
    Ok((layout, depth, out))
}
