//! Layer images of an attribute channel for grey-scale vat printing: each
//! pixel inside the solid is `255 * clamp(s, 0, 1)` of channel `s` at the
//! pixel centre, 0 outside (Park et al., Figs. 4-6 cross-sections). A
//! [`StackFormat`], so [`crate::write_stack`] writes it like any stack.

use crate::error::{FabError, Result};
use crate::grid::SliceGrid;
use crate::image::GreyImage;
use crate::raster::rasterize;
use crate::stack::StackFormat;
use microfrep_core::{BatchEval, Shape};
use std::fmt::Write as _;
use std::path::Path;

/// 8-bit grey layers of attribute channel `channel` (0-based index into
/// [`Shape::attributes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AttributeStack {
    /// The channel.
    pub channel: usize,
}

impl AttributeStack {
    /// The stack of channel `channel`, checked against the shape.
    pub fn new(shape: &Shape, channel: usize) -> Result<AttributeStack> {
        let n = shape.attributes().len();
        if channel >= n {
            return Err(FabError::Invalid(format!(
                "attribute {} does not exist: the model has {n} attribute channel(s)",
                channel + 1
            )));
        }
        Ok(AttributeStack { channel })
    }

    /// Grey levels of layer `k`, rows top (largest y) first.
    pub fn layer_pixels(&self, shape: &Shape, grid: &SliceGrid, k: usize) -> Vec<u8> {
        let layer = rasterize(shape, grid, k);
        let (nx, ny) = (grid.nx, grid.ny);
        let mut ev = BatchEval::new(shape.outputs());
        let out = shape.attribute_output(self.channel);
        let mut pixels = vec![0u8; nx * ny];
        let (mut x, mut y, mut z) = (vec![0f32; nx], vec![0f32; nx], vec![0f32; nx]);
        let mut s = vec![0f32; nx];
        for j in 0..ny {
            for i in 0..nx {
                (x[i], y[i], z[i]) = (grid.x(i) as f32, grid.y(j) as f32, grid.z(k) as f32);
            }
            ev.eval_output(out, &x, &y, &z, &mut s);
            let row = ny - 1 - j;
            for i in 0..nx {
                if layer.inside(i, j) && !s[i].is_nan() {
                    pixels[row * nx + i] = (255.0 * s[i].clamp(0.0, 1.0)).round() as u8;
                }
            }
        }
        pixels
    }
}

impl StackFormat for AttributeStack {
    fn name(&self) -> &'static str {
        "png-attribute"
    }
    fn single_file(&self) -> bool {
        false
    }
    fn layer(
        &self,
        shape: &Shape,
        grid: &SliceGrid,
        k: usize,
        path: &Path,
    ) -> Result<(Vec<u8>, u64)> {
        let pixels = self.layer_pixels(shape, grid, k);
        let solid = pixels.iter().filter(|&&v| v > 0).count() as u64;
        let img = GreyImage {
            width: grid.nx,
            height: grid.ny,
            binary: false,
            pixels,
        };
        Ok((img.encode(path)?, solid))
    }
    fn footer(&self, grid: &SliceGrid) -> Vec<u8> {
        let mut s = String::from("{\n  \"format\": \"png-8bit-attribute\",\n");
        let _ = writeln!(s, "  \"attribute\": {},", self.channel + 1);
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
            "  \"notes\": \"grey = 255 * clamp(s, 0, 1) at the pixel centre inside the solid, 0 outside; row 0 is the largest y\","
        );
        s.push_str("  \"layers\": [\n");
        for k in 0..grid.layers {
            let sep = if k + 1 < grid.layers { "," } else { "" };
            let _ = writeln!(
                s,
                "    {{\"file\": \"{}\", \"z\": {}}}{sep}",
                self.layer_name(k),
                grid.z(k)
            );
        }
        s.push_str("  ]\n}\n");
        s.into_bytes()
    }
}
