//! Layer images of an attribute channel for grey-scale vat printing: each
//! pixel inside the solid is `255 * clamp(s, 0, 1)` of channel `s` at the
//! pixel centre, 0 outside (Park et al., Figs. 4-6 cross-sections). A
//! [`StackFormat`], so [`crate::write_stack`] writes it like any stack.

use crate::error::{FabError, Result};
use crate::grid::SliceGrid;
use crate::image::GreyImage;
use crate::raster::{rasterize, LayerValues};
use crate::stack::StackFormat;
use microfrep_core::{BatchEval, Interval, IntervalEval, Shape, Simplify, Tape};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// 8-bit grey layers of attribute channel `channel` (0-based index into
/// [`Shape::attributes`]).
///
/// The channel is compiled alone, once per stack. Per layer, only pixels
/// inside the solid are evaluated: tiles with no inside pixel are skipped,
/// tiles whose interval bounds give one grey level (with a margin far wider
/// than f32 rounding) are filled, tiles whose intervals decide branches
/// are evaluated with the exactly simplified tape, and the rest are
/// sampled at their inside pixels, rows of tiles in parallel.
#[derive(Clone, Debug)]
pub struct AttributeStack {
    /// The channel.
    pub channel: usize,
    /// The channel's expression alone.
    tape: Tape,
}

/// Side of the tiles that bands of rows are cut into.
const TILE: usize = 64;
/// Side of the leaves sampled in one batch (16 x 16 = one block).
const LEAF: usize = 16;
/// Tiles at least this many pixels on a side may get their own tape.
const SIMPLIFY_TILE: usize = 32;

/// Tiles below [`SIMPLIFY_TILE`] are bounded only when their parent's
/// bounds spanned at most this many grey levels (else bounding them rarely
/// pays: smooth channels vary by many levels over a tile, and a child spans
/// about half its parent's levels, so it is uniform only when the parent
/// spanned very few; with 8 the Bezier cube's leaves were bounded in vain).
const CLOSE_LEVELS: u8 = 2;

/// Grey level of attribute value `s`: `round(255 clamp(s, 0, 1))`.
fn grey(s: f32) -> u8 {
    (255.0 * s.clamp(0.0, 1.0)).round() as u8
}

/// The grey level every value of `b` takes, with a margin wide enough
/// that f32 evaluation of any point of the box lands on it too.
fn uniform_grey(b: Interval) -> Option<u8> {
    if b.may_be_nan() || b.lo.is_nan() || b.hi.is_nan() || b.lo > b.hi {
        return None;
    }
    let m = 1e-4 * b.lo.abs().max(b.hi.abs()).max(1.0);
    let (lo, hi) = (grey((b.lo - m) as f32), grey((b.hi + m) as f32));
    (lo == hi).then_some(lo)
}

/// Per-thread evaluators of the channel (or of a tile's shorter tape).
struct Evals {
    tape: Tape,
    batch: BatchEval,
    interval: IntervalEval,
}

impl Evals {
    fn new(tape: &Tape) -> Evals {
        Evals {
            tape: tape.clone(),
            batch: BatchEval::new(tape),
            interval: IntervalEval::new(tape),
        }
    }
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
        Ok(AttributeStack {
            channel,
            tape: Tape::new(&shape.attributes()[channel].expr),
        })
    }

    /// Grey levels of layer `k`, rows top (largest y) first.
    pub fn layer_pixels(&self, shape: &Shape, grid: &SliceGrid, k: usize) -> Vec<u8> {
        let layer = rasterize(shape, grid, k);
        self.grey_layer(grid, &layer)
    }

    /// Grey levels over the inside pixels of `layer` (sampled on `grid`).
    fn grey_layer(&self, grid: &SliceGrid, layer: &LayerValues) -> Vec<u8> {
        let (nx, ny) = (grid.nx, grid.ny);
        let mut pixels = vec![0u8; nx * ny];
        if nx == 0 || ny == 0 {
            return pixels;
        }
        // Bands of TILE image rows counted from the bottom (j), stored top
        // row first: band b holds rows j0..j0 + h at pixel rows
        // ny - j0 - h .. ny - j0. Cut the buffer from its end.
        let bands: Vec<(usize, &mut [u8])> = {
            let mut out = Vec::new();
            let mut rest = &mut pixels[..];
            let mut j0 = 0;
            while j0 < ny {
                let h = TILE.min(ny - j0);
                let (head, tail) = rest.split_at_mut((ny - j0 - h) * nx);
                out.push((j0, tail));
                rest = head;
                j0 += h;
            }
            out
        };
        let z = layer.z;
        bands.into_par_iter().for_each_init(
            || Evals::new(&self.tape),
            |ev, (j0, rows)| {
                let h = rows.len() / nx;
                let band = Band {
                    grid,
                    layer,
                    z,
                    j0,
                    h,
                };
                for i0 in (0..nx).step_by(TILE) {
                    let w = TILE.min(nx - i0);
                    band.tile(ev, rows, [i0, j0], [w, h], true);
                }
            },
        );
        pixels
    }
}

/// One band of rows being filled.
struct Band<'a> {
    grid: &'a SliceGrid,
    layer: &'a LayerValues,
    z: f64,
    /// First image row (from the bottom) and row count of the band.
    j0: usize,
    h: usize,
}

impl Band<'_> {
    /// Index into the band's buffer of pixel `(i, j)` (image row j).
    fn at(&self, i: usize, j: usize) -> usize {
        (self.j0 + self.h - 1 - j) * self.grid.nx + i
    }

    /// Fills the tile at pixel `at` of size `size`. Small tiles are bounded
    /// only when `close`: their parent's bounds spanned few grey levels.
    fn tile(&self, ev: &mut Evals, rows: &mut [u8], at: [usize; 2], size: [usize; 2], close: bool) {
        let (grid, layer) = (self.grid, self.layer);
        let cols = at[0]..at[0] + size[0];
        // Stops at the first inside pixel (most tiles of a solid's interior
        // have one at their corner), so tiles are not counted at every level.
        let any_inside = (at[1]..at[1] + size[1]).any(|j| cols.clone().any(|i| layer.inside(i, j)));
        if !any_inside {
            return;
        }
        let big = size[0] >= SIMPLIFY_TILE && size[1] >= SIMPLIFY_TILE;
        if !(big || close) {
            return self.split_or_sample(ev, rows, at, size, false);
        }
        // The pixel centres' extent, as given to the batch evaluator too.
        let xs = Interval::with_f32_ends(grid.x(at[0]), grid.x(at[0] + size[0] - 1));
        let ys = Interval::with_f32_ends(grid.y(at[1]), grid.y(at[1] + size[1] - 1));
        let b = ev
            .interval
            .eval(xs, ys, Interval::with_f32_ends(self.z, self.z));
        if let Some(g) = uniform_grey(b) {
            if g != 0 {
                for j in at[1]..at[1] + size[1] {
                    for i in cols.clone() {
                        if layer.inside(i, j) {
                            rows[self.at(i, j)] = g;
                        }
                    }
                }
            }
            return;
        }
        if big {
            let short = ev
                .tape
                .simplify(ev.interval.values(), Simplify::Exact)
                .filter(|t| 10 * t.len() < 8 * ev.tape.len());
            if let Some(t) = short {
                let mut local = Evals::new(&t);
                return self.tile(&mut local, rows, at, size, close);
            }
        }
        let near = !b.may_be_nan()
            && b.lo <= b.hi
            && grey(b.hi as f32).saturating_sub(grey(b.lo as f32)) <= CLOSE_LEVELS;
        self.split_or_sample(ev, rows, at, size, near)
    }

    /// Quarters a tile, or samples a leaf at its inside pixels.
    fn split_or_sample(
        &self,
        ev: &mut Evals,
        rows: &mut [u8],
        at: [usize; 2],
        size: [usize; 2],
        close: bool,
    ) {
        let (grid, layer) = (self.grid, self.layer);
        let cols = at[0]..at[0] + size[0];
        if size[0] > LEAF || size[1] > LEAF {
            let hw = size[0].div_ceil(2);
            let hh = size[1].div_ceil(2);
            for (dx, w) in [(0, hw), (hw, size[0] - hw)] {
                for (dy, h) in [(0, hh), (hh, size[1] - hh)] {
                    if w > 0 && h > 0 {
                        self.tile(ev, rows, [at[0] + dx, at[1] + dy], [w, h], close);
                    }
                }
            }
            return;
        }
        // A leaf: its inside pixels in one batch.
        let mut idx = [0usize; LEAF * LEAF];
        let mut n = 0;
        {
            let zf = self.z as f32;
            let (x, y, zz) = ev.batch.coords_mut();
            for j in at[1]..at[1] + size[1] {
                let yf = grid.y(j) as f32;
                for i in cols.clone() {
                    if layer.inside(i, j) {
                        x[n] = grid.x(i) as f32;
                        y[n] = yf;
                        zz[n] = zf;
                        idx[n] = self.at(i, j);
                        n += 1;
                    }
                }
            }
        }
        let s = ev.batch.eval_loaded(n);
        for (&q, &v) in idx[..n].iter().zip(s) {
            if !v.is_nan() {
                rows[q] = grey(v);
            }
        }
    }
}

/// The grey levels of layer `k` the straightforward way, for tests: the
/// shape's whole output tape evaluated at every pixel centre.
#[doc(hidden)]
pub fn reference_layer_pixels(
    shape: &Shape,
    grid: &SliceGrid,
    k: usize,
    channel: usize,
) -> Vec<u8> {
    let layer = rasterize(shape, grid, k);
    let (nx, ny) = (grid.nx, grid.ny);
    let mut ev = BatchEval::new(shape.outputs());
    let out = shape.attribute_output(channel);
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
                pixels[row * nx + i] = grey(s[i]);
            }
        }
    }
    pixels
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
