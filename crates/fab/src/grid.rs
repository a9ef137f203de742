//! The slicing grid: layers along z, square pixels in x and y.

use crate::error::{FabError, Result};

/// Largest image side and pixel count accepted, so a typo in the pixel size
/// gives an error instead of an out-of-memory abort.
const MAX_SIDE: usize = 1 << 16;
const MAX_PIXELS: usize = 1 << 28;
const MAX_LAYERS: usize = 1 << 20;

/// Layers of thickness `layer` over the z range of the box, each an image of
/// `nx x ny` square pixels of side `pixel` whose outer corner is `min`.
/// Samples sit at pixel centres and at the middle of each layer. The box is
/// grown to a whole number of pixels and layers.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceGrid {
    /// Outer corner of the grid in model units (millimetres): the lower x, y of
    /// pixel `(0, 0)` and the bottom of layer 0.
    pub min: [f64; 3],
    /// Side of the square pixels in x and y, model units (> 0).
    pub pixel: f64,
    /// Layer thickness along z, model units (> 0).
    pub layer: f64,
    /// Pixels per row (along x), at least 1.
    pub nx: usize,
    /// Pixel rows (along y), at least 1.
    pub ny: usize,
    /// Number of layers (along z), at least 1.
    pub layers: usize,
    /// Number of layer 0 in the whole stack it was taken from
    /// ([`SliceGrid::range`]); 0 for a whole stack. Layer `k` is the
    /// stack's layer `first + k`: its height and its file name.
    pub first: usize,
    /// The height of the middle of layer 0 when it was asked for exactly
    /// ([`SliceGrid::at_height`]); otherwise it is `min[2] + layer / 2`.
    pub mid: Option<f64>,
}

fn count(len: f64, step: f64, what: &str, max: usize) -> Result<usize> {
    // A small slack so 2 / 0.025 is 80 pixels, not 81.
    let n = (len / step - 1e-9).ceil().max(1.0);
    if n > max as f64 {
        return Err(FabError::Invalid(format!(
            "{what}: {n} exceeds the limit of {max} (step too small for the bounds?)"
        )));
    }
    Ok(n as usize)
}

impl SliceGrid {
    /// The grid covering the box `min..max` (model units) with layers of
    /// thickness `layer` and pixels of side `pixel`; counts are rounded up, so
    /// the grid may reach a little past `max`.
    ///
    /// # Errors
    /// [`FabError::Invalid`] when a size is not a positive number, the box is
    /// not finite with `min < max` on every axis, a pixel or layer is larger
    /// than the box, f32 samples could not resolve the steps at the box's
    /// coordinates, or the image side (65536), pixel count (2^28) or layer
    /// count (2^20) would exceed its limit.
    pub fn new(min: [f64; 3], max: [f64; 3], layer: f64, pixel: f64) -> Result<SliceGrid> {
        for (name, v) in [("layer", layer), ("pixel", pixel)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(FabError::Invalid(format!(
                    "{name} size must be positive, got {v}"
                )));
            }
        }
        for a in 0..3 {
            if !(min[a].is_finite() && max[a].is_finite() && max[a] > min[a]) {
                return Err(FabError::Invalid(format!(
                    "bounds on axis {a} must be finite with min < max, got {} .. {}",
                    min[a], max[a]
                )));
            }
        }
        for (a, name, step, what) in [
            (0, "width", pixel, "pixel"),
            (1, "depth", pixel, "pixel"),
            (2, "height", layer, "layer"),
        ] {
            let side = max[a] - min[a];
            // The box's sides come from subtractions: a layer equal to the
            // height as written (0.2 for 10..10.2) is accepted.
            if step > side * (1.0 + 1e-9) {
                let side = microfrep_io::text::sig(side, 6);
                return Err(FabError::Invalid(format!(
                    "the {what} size {step} exceeds the box's {name} {side}: its samples would \
                     lie outside the box; use a {what} of at most {side} or a larger box"
                )));
            }
        }
        microfrep_io::precision::check_grid(min, max, pixel.min(layer))
            .map_err(|e| FabError::Invalid(format!("cannot slice: {e}")))?;
        let nx = count(max[0] - min[0], pixel, "image width", MAX_SIDE)?;
        let ny = count(max[1] - min[1], pixel, "image height", MAX_SIDE)?;
        if nx * ny > MAX_PIXELS {
            return Err(FabError::Invalid(format!(
                "image of {nx} x {ny} pixels exceeds the limit of {MAX_PIXELS} pixels"
            )));
        }
        let layers = count(max[2] - min[2], layer, "layer count", MAX_LAYERS)?;
        Ok(SliceGrid {
            min,
            pixel,
            layer,
            nx,
            ny,
            layers,
            first: 0,
            mid: None,
        })
    }

    /// Layers `from..=to` of this stack (numbered from 0, as in a whole
    /// run), at the heights and with the file names they have there.
    pub fn range(&self, from: usize, to: usize) -> Result<SliceGrid> {
        let last = self.first + self.layers - 1;
        if from > to || from < self.first || to > last {
            return Err(FabError::Invalid(format!(
                "layers {from}..{to}: the stack has layers {}..{last} (0-based, both ends included)",
                self.first
            )));
        }
        Ok(SliceGrid {
            layers: to - from + 1,
            first: from,
            ..self.clone()
        })
    }

    /// One layer of thickness `layer` whose middle is at height `z`, over
    /// the x and y of the box `min..max` (which must hold `z`).
    pub fn at_height(
        min: [f64; 3],
        max: [f64; 3],
        z: f64,
        layer: f64,
        pixel: f64,
    ) -> Result<SliceGrid> {
        if !(z.is_finite() && z >= min[2] && z <= max[2]) {
            return Err(FabError::Invalid(format!(
                "height z = {z} is outside the box's z range {} .. {}",
                min[2], max[2]
            )));
        }
        let mut g = SliceGrid::new(min, max, layer.min(max[2] - min[2]), pixel)?;
        g.layer = layer;
        g.layers = 1;
        g.first = 0;
        g.min[2] = z - 0.5 * layer;
        // Sampled at `z` itself, not at a rounded bottom plus half a layer.
        g.mid = Some(z);
        Ok(g)
    }

    /// Height of the middle of layer `k`.
    pub fn z(&self, k: usize) -> f64 {
        match self.mid {
            Some(m) => m + (self.first + k) as f64 * self.layer,
            None => self.min[2] + ((self.first + k) as f64 + 0.5) * self.layer,
        }
    }

    /// x of the centre of pixel column `i`.
    pub fn x(&self, i: usize) -> f64 {
        self.min[0] + (i as f64 + 0.5) * self.pixel
    }

    /// y of the centre of pixel row `j` (row 0 is the lowest y).
    pub fn y(&self, j: usize) -> f64 {
        self.min[1] + (j as f64 + 0.5) * self.pixel
    }
}

/// Refuses a model whose f32 batch values disagree with its f64 values in
/// the box `min..max` (see [`microfrep_io::precision::check_agreement`]):
/// the layers or voxels would be silently wrong.
pub fn check_precision(shape: &microfrep_core::Shape, min: [f64; 3], max: [f64; 3]) -> Result<()> {
    use microfrep_io::precision::{check_agreement, probe_points, PROBE_POINTS};
    let pts = probe_points(min, max, PROBE_POINTS);
    let axis = |a: usize| -> Vec<f32> { pts.iter().map(|p| p[a] as f32).collect() };
    let mut v32 = vec![0.0f32; pts.len()];
    shape.batch().eval(&axis(0), &axis(1), &axis(2), &mut v32);
    let mut pe = shape.point();
    let v64: Vec<f64> = pts.iter().map(|p| pe.eval(*p)).collect();
    check_agreement(&pts, &v32, &v64).map_err(FabError::Precision)
}
