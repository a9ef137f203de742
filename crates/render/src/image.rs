//! 8-bit RGB images and their PNG encoding.

use crate::error::Result;
use std::path::Path;

/// An 8-bit RGB image held in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Rows top first, three bytes per pixel.
    pub data: Vec<u8>,
}

impl RgbImage {
    /// The colour at column `x`, row `y` (row 0 at the top).
    ///
    /// # Panics
    ///
    /// If the pixel is outside the image.
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        let k = 3 * (y * self.width + x);
        [self.data[k], self.data[k + 1], self.data[k + 2]]
    }

    /// PNG bytes of the image.
    pub fn encode_png(&self) -> Result<Vec<u8>> {
        Ok(microfrep_io::png::encode(
            &self.as_png(),
            std::path::Path::new("image"),
        )?)
    }

    fn as_png(&self) -> microfrep_io::png::Image {
        microfrep_io::png::Image {
            width: self.width,
            height: self.height,
            pixels: microfrep_io::png::Pixels::Rgb,
            data: self.data.clone(),
        }
    }

    /// Writes the PNG atomically (a temporary renamed when complete).
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let bytes = microfrep_io::png::encode(&self.as_png(), path)?;
        microfrep_io::atomic::write_file(path, &bytes)?;
        Ok(())
    }
}
