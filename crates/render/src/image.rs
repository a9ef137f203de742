//! 8-bit RGB images and their PNG encoding.

use crate::error::{RenderError, Result};
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    /// Rows top first, three bytes per pixel.
    pub data: Vec<u8>,
}

impl RgbImage {
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        let k = 3 * (y * self.width + x);
        [self.data[k], self.data[k + 1], self.data[k + 2]]
    }

    pub fn encode_png(&self) -> std::result::Result<Vec<u8>, png::EncodingError> {
        let mut buf = Vec::new();
        let mut enc = png::Encoder::new(&mut buf, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header()?;
        w.write_image_data(&self.data)?;
        w.finish()?;
        Ok(buf)
    }

    /// Writes the PNG through a temporary file renamed when complete.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let err = |msg: String| RenderError::Write {
            path: path.to_path_buf(),
            msg,
        };
        let bytes = self.encode_png().map_err(|e| err(e.to_string()))?;
        let name = path
            .file_name()
            .ok_or_else(|| err("not a file name".into()))?;
        let tmp = path.with_file_name(format!(
            ".{}.partial-{}",
            name.to_string_lossy(),
            std::process::id()
        ));
        let res = std::fs::write(&tmp, bytes).and_then(|_| std::fs::rename(&tmp, path));
        if let Err(e) = res {
            let _ = std::fs::remove_file(&tmp);
            return Err(err(e.to_string()));
        }
        Ok(())
    }
}
