//! One layer's values at pixel centres. Tiles are classified by interval
//! arithmetic over the area they cover; only tiles the surface may cross are
//! sampled, 256 pixels per batch.

use crate::grid::SliceGrid;
use microfrep_core::{BatchEval, Interval, IntervalEval, Shape, Simplify, Tape};
use rayon::prelude::*;

/// Side of the tiles that rows of work are cut into.
const TILE: usize = 64;
/// Side of the leaf tiles sampled in one batch (16 x 16 = one block).
const LEAF: usize = 16;

/// Pixel values of one layer, row-major with row 0 at the lowest y. Pixels
/// of tiles proven inside hold `+inf`, proven outside `-inf`; the others hold
/// the sampled value. Inside is `v >= 0` either way.
pub struct LayerValues {
    /// Pixels per row (the grid's `nx`).
    pub nx: usize,
    /// Rows (the grid's `ny`).
    pub ny: usize,
    /// Height of the sampled plane, the layer's middle, in model units.
    pub z: f64,
    /// `nx * ny` values, index `j * nx + i` for column `i`, row `j`.
    pub values: Vec<f32>,
}

impl LayerValues {
    /// Value at pixel column `i`, row `j` (row 0 at the lowest y); `+inf` or
    /// `-inf` in tiles proven inside or outside. Panics when `i >= nx` or
    /// `j >= ny`.
    pub fn at(&self, i: usize, j: usize) -> f32 {
        self.values[j * self.nx + i]
    }

    /// Whether pixel `(i, j)` is inside the model (value `>= 0`; NaN counts as
    /// outside). Panics out of range like [`LayerValues::at`].
    pub fn inside(&self, i: usize, j: usize) -> bool {
        self.at(i, j) >= 0.0
    }
}

/// Per-thread evaluators.
struct Evals {
    tape: Tape,
    batch: BatchEval,
    interval: IntervalEval,
    /// Whether tiles may switch to a tape shortened for their area.
    simplify: bool,
    /// Evaluators of the shortened tapes used lately, newest last: tiles
    /// far apart often decide the same branches, and making evaluators
    /// (the batch plan's lowering) cost about 5 % of a layer when every
    /// shortened tile made its own.
    short: Vec<Evals>,
}

/// Shortened tapes whose evaluators a thread keeps.
const KEPT_SHORT: usize = 8;

impl Evals {
    fn new(tape: &Tape, simplify: bool) -> Evals {
        Evals {
            tape: tape.clone(),
            batch: BatchEval::new(tape),
            interval: IntervalEval::new(tape),
            simplify,
            short: Vec::new(),
        }
    }

    /// Evaluators of `t`, a shortening of this tape: kept ones if `t` is
    /// the same tape as one of them, else new ones (give them back with
    /// [`Evals::keep`]).
    fn shortened(&mut self, t: Tape) -> Evals {
        let same = |e: &Evals| e.tape.ops() == t.ops() && e.tape.outputs() == t.outputs();
        match self.short.iter().position(same) {
            Some(k) => self.short.remove(k),
            None => Evals::new(&t, true),
        }
    }

    /// Keeps `e` (from [`Evals::shortened`]) as the newest, dropping the
    /// oldest beyond [`KEPT_SHORT`].
    fn keep(&mut self, e: Evals) {
        if self.short.len() == KEPT_SHORT {
            self.short.remove(0);
        }
        self.short.push(e);
    }
}

/// Whether [`rasterize_at`] shortens the tape per tile (see
/// [`rasterize_with`]); measured by `bench/run slice`.
pub const SIMPLIFY_TILES: bool = true;

/// Tiles at least this many pixels on a side may get their own tape.
const SIMPLIFY_TILE: usize = 64;

/// Samples layer `k` of `grid`, tile rows in parallel.
pub fn rasterize(shape: &Shape, grid: &SliceGrid, k: usize) -> LayerValues {
    rasterize_at(shape, grid, grid.z(k))
}

/// Samples the grid's image at height `z`.
pub fn rasterize_at(shape: &Shape, grid: &SliceGrid, z: f64) -> LayerValues {
    rasterize_with(shape, grid, z, SIMPLIFY_TILES)
}

/// [`rasterize_at`], choosing whether tiles of 64 pixels and more whose
/// interval decides set-operation branches are sampled with the shortened
/// tape ([`microfrep_core::Simplify::Sign`]: the same inside and outside,
/// other values near the surface).
pub fn rasterize_with(shape: &Shape, grid: &SliceGrid, z: f64, simplify: bool) -> LayerValues {
    let (nx, ny) = (grid.nx, grid.ny);
    let mut values = vec![0.0f32; nx * ny];
    values.par_chunks_mut(BAND * nx).enumerate().for_each_init(
        || BandRaster(Evals::new(shape.tape(), simplify)),
        |r, (b, rows)| r.band(grid, z, b * BAND, rows),
    );
    LayerValues { nx, ny, z, values }
}

/// Rows in a band of [`BandRaster::band`]: bands start at multiples of it.
pub(crate) const BAND: usize = TILE;

/// One thread's evaluators for sampling a layer band by band, as
/// [`rasterize_at`] does (the same values), for consumers that use each band
/// while it is in cache.
pub(crate) struct BandRaster(Evals);

impl BandRaster {
    /// Evaluators of `shape`, shortening tapes per tile.
    pub(crate) fn new(shape: &Shape) -> BandRaster {
        BandRaster(Evals::new(shape.tape(), SIMPLIFY_TILES))
    }

    /// Samples image rows `j0..j0 + rows.len() / nx` at height `z` into
    /// `rows` (row-major, lowest y first); `j0` is a multiple of [`BAND`]
    /// and there are at most [`BAND`] rows.
    pub(crate) fn band(&mut self, grid: &SliceGrid, z: f64, j0: usize, rows: &mut [f32]) {
        let nx = grid.nx;
        let h = rows.len() / nx;
        debug_assert!(j0 % BAND == 0 && h <= BAND);
        for i0 in (0..nx).step_by(TILE) {
            let w = TILE.min(nx - i0);
            tile(&mut self.0, grid, z, rows, [i0, j0], [w, h], j0);
        }
    }
}

/// Classifies the tile at pixel `at` of size `size` and fills its pixels in
/// `rows` (which start at image row `row0`), splitting ambiguous tiles down
/// to leaves.
fn tile(
    ev: &mut Evals,
    grid: &SliceGrid,
    z: f64,
    rows: &mut [f32],
    at: [usize; 2],
    size: [usize; 2],
    row0: usize,
) {
    let nx = grid.nx;
    let p = grid.pixel;
    // The whole area of the pixels, so the anti-aliased coverage of a
    // uniform tile is exact too.
    let xs = Interval::new(
        grid.min[0] + at[0] as f64 * p,
        grid.min[0] + (at[0] + size[0]) as f64 * p,
    );
    let ys = Interval::new(
        grid.min[1] + at[1] as f64 * p,
        grid.min[1] + (at[1] + size[1]) as f64 * p,
    );
    let b = ev.interval.eval(xs, ys, Interval::point(z));
    // A possible NaN (outside by the sign rule) rules out "all inside".
    let fill = if b.lo >= 0.0 && !b.may_be_nan() {
        Some(f32::INFINITY)
    } else if b.hi < 0.0 {
        Some(f32::NEG_INFINITY)
    } else {
        None
    };
    if let Some(v) = fill {
        for j in at[1]..at[1] + size[1] {
            let r = (j - row0) * nx;
            rows[r + at[0]..r + at[0] + size[0]].fill(v);
        }
        return;
    }
    if ev.simplify && size[0] >= SIMPLIFY_TILE && size[1] >= SIMPLIFY_TILE {
        let short = ev
            .tape
            .simplify(ev.interval.values(), Simplify::Sign)
            .filter(|t| 10 * t.len() < 8 * ev.tape.len());
        if let Some(t) = short {
            let mut local = ev.shortened(t);
            tile(&mut local, grid, z, rows, at, size, row0);
            ev.keep(local);
            return;
        }
    }
    if size[0] > LEAF || size[1] > LEAF {
        let hw = size[0].div_ceil(2);
        let hh = size[1].div_ceil(2);
        for (dx, w) in [(0, hw), (hw, size[0] - hw)] {
            for (dy, h) in [(0, hh), (hh, size[1] - hh)] {
                if w > 0 && h > 0 {
                    tile(ev, grid, z, rows, [at[0] + dx, at[1] + dy], [w, h], row0);
                }
            }
        }
        return;
    }
    let n = size[0] * size[1];
    {
        let (x, y, zz) = ev.batch.coords_mut();
        for dj in 0..size[1] {
            for di in 0..size[0] {
                let q = dj * size[0] + di;
                x[q] = grid.x(at[0] + di) as f32;
                y[q] = grid.y(at[1] + dj) as f32;
                zz[q] = z as f32;
            }
        }
    }
    let out = ev.batch.eval_loaded(n);
    for dj in 0..size[1] {
        let r = (at[1] + dj - row0) * nx + at[0];
        rows[r..r + size[0]].copy_from_slice(&out[dj * size[0]..(dj + 1) * size[0]]);
    }
}
