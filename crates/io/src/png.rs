//! The one PNG encoder of microfrep (layer images, renders, material
//! stacks), and a decoder for reading them back in tests and tools.

use crate::{IoError, Result};
use std::path::Path;

/// Pixel layouts microfrep writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixels {
    /// One bit per pixel, given as bytes 0 (black) or nonzero (white).
    Bilevel,
    /// 8-bit grey.
    Grey,
    /// 8-bit RGB.
    Rgb,
    /// 8-bit RGB with alpha.
    Rgba,
}

impl Pixels {
    /// Bytes per pixel of the input data.
    pub fn channels(self) -> usize {
        match self {
            Pixels::Bilevel | Pixels::Grey => 1,
            Pixels::Rgb => 3,
            Pixels::Rgba => 4,
        }
    }
}

/// An image in memory: rows top first, [`Pixels::channels`] bytes a pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Layout of `data` (and of the file).
    pub pixels: Pixels,
    /// Rows, top first.
    pub data: Vec<u8>,
}

/// PNG bytes of `img` (1-bit for [`Pixels::Bilevel`]). `path` only names
/// the file in errors.
pub fn encode(img: &Image, path: &Path) -> Result<Vec<u8>> {
    let err = |source| IoError::Png {
        path: path.to_path_buf(),
        source,
    };
    let (w, h) = (img.width, img.height);
    assert_eq!(
        img.data.len(),
        w * h * img.pixels.channels(),
        "image data size"
    );
    let mut buf = Vec::with_capacity(img.data.len() / 4 + 128);
    let mut enc = ::png::Encoder::new(&mut buf, w as u32, h as u32);
    let packed;
    let data: &[u8] = match img.pixels {
        Pixels::Bilevel => {
            enc.set_color(::png::ColorType::Grayscale);
            enc.set_depth(::png::BitDepth::One);
            packed = pack_bits(&img.data, w, h);
            &packed
        }
        p => {
            enc.set_color(match p {
                Pixels::Grey => ::png::ColorType::Grayscale,
                Pixels::Rgb => ::png::ColorType::Rgb,
                _ => ::png::ColorType::Rgba,
            });
            enc.set_depth(::png::BitDepth::Eight);
            &img.data
        }
    };
    // Fast deflate: layer stacks are written by the thousand and compress
    // well anyway (mostly runs of equal pixels).
    enc.set_compression(::png::Compression::Fast);
    let mut wr = enc.write_header().map_err(err)?;
    wr.write_image_data(data).map_err(err)?;
    wr.finish().map_err(err)?;
    Ok(buf)
}

/// Rows of one bit per pixel, most significant bit first, each row padded
/// to whole bytes.
fn pack_bits(data: &[u8], w: usize, h: usize) -> Vec<u8> {
    let row = w.div_ceil(8);
    let mut out = vec![0u8; row * h];
    for y in 0..h {
        for x in 0..w {
            if data[y * w + x] != 0 {
                out[y * row + x / 8] |= 0x80 >> (x % 8);
            }
        }
    }
    out
}

/// Reads a PNG of any bit depth or colour type into 8-bit samples
/// (bilevel and grey images as [`Pixels::Grey`] with 0 and 255).
pub fn decode(bytes: &[u8], path: &Path) -> Result<Image> {
    let err = |source| IoError::PngDecode {
        path: path.to_path_buf(),
        source,
    };
    let mut dec = ::png::Decoder::new(bytes);
    dec.set_transformations(::png::Transformations::EXPAND | ::png::Transformations::STRIP_16);
    let mut r = dec.read_info().map_err(err)?;
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).map_err(err)?;
    buf.truncate(info.buffer_size());
    let pixels = match info.color_type {
        ::png::ColorType::Grayscale => Pixels::Grey,
        ::png::ColorType::Rgb => Pixels::Rgb,
        ::png::ColorType::Rgba => Pixels::Rgba,
        // Grey with alpha: keep the grey.
        _ => {
            buf = buf.chunks(2).map(|c| c[0]).collect();
            Pixels::Grey
        }
    };
    Ok(Image {
        width: info.width as usize,
        height: info.height as usize,
        pixels,
        data: buf,
    })
}

/// Reads and decodes a PNG file.
pub fn read(path: &Path) -> Result<Image> {
    let bytes = std::fs::read(path).map_err(IoError::at(path))?;
    decode(&bytes, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_every_layout() {
        let p = Path::new("t.png");
        for (pixels, w, h) in [
            (Pixels::Bilevel, 13, 5),
            (Pixels::Grey, 7, 3),
            (Pixels::Rgb, 4, 4),
            (Pixels::Rgba, 3, 2),
        ] {
            let n = w * h * pixels.channels();
            let data: Vec<u8> = (0..n)
                .map(|i| match pixels {
                    Pixels::Bilevel => [0, 255][(i * 7 / 3) % 2],
                    _ => (i * 37 % 256) as u8,
                })
                .collect();
            let img = Image {
                width: w,
                height: h,
                pixels,
                data,
            };
            let back = decode(&encode(&img, p).unwrap(), p).unwrap();
            let want = match pixels {
                Pixels::Bilevel => Image {
                    pixels: Pixels::Grey,
                    ..img.clone()
                },
                _ => img.clone(),
            };
            assert_eq!(back, want, "{pixels:?}");
        }
        assert!(decode(b"not a png", p).is_err());
    }
}
