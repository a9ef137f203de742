//! Layer images of an attribute channel for grey-scale vat printing: each
//! pixel inside the solid is `255 * clamp(s, 0, 1)` of channel `s` at the
//! pixel centre, 0 outside (Park et al., Figs. 4-6 cross-sections). A
//! [`StackFormat`], so [`crate::write_stack`] writes it like any stack.

use crate::error::{FabError, Result};
use crate::grid::SliceGrid;
use crate::raster::{rasterize, BandRaster, BAND};
use crate::stack::StackFormat;
use microfrep_core::{BatchEval, Interval, IntervalEval, Shape, Simplify, Tape, BLOCK};
use rayon::prelude::*;
use std::cell::Cell;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// 8-bit grey layers of attribute channel `channel` (0-based index into
/// [`Shape::attributes`]).
///
/// The channel is compiled alone, once per stack (with the costly
/// operations of a select's two branches, such as the two powers of a
/// gain, run once on the picked operand: the same bits), and cut to the
/// branches each layer needs, with the identities the cuts leave (`x * 1`,
/// zero terms of decided derivatives) folded away. Bands of rows are sampled for the shape's value (as
/// [`rasterize`] samples it) and graded at once, in parallel. Only pixels
/// inside the solid are evaluated: tiles with no inside pixel are skipped,
/// tiles whose interval bounds give one grey level (with a margin far wider
/// than f32 rounding) are filled, tiles whose intervals decide branches
/// that cost a fifth of the evaluation are evaluated with the exactly
/// simplified tape (the evaluators of a few such tapes kept per thread),
/// and the inside pixels of the rest join full blocks of their tape's
/// evaluator. Tile sizes whose bounds did not pay on a layer's probe bands
/// are bounded only now and then on its other bands. Every grey level is
/// the one f32 evaluation of the whole channel at the pixel centre gives
/// (with its real powers of whole exponents evaluated as integer powers,
/// a power next to one with the exponent one more as their quotient by
/// the base, and its divisions by constants as products with their
/// inverses, which moves a level only where the exact value is within a
/// few f32 roundings of a half level).
#[derive(Clone, Debug)]
pub struct AttributeStack {
    /// The channel.
    pub channel: usize,
    /// The channel's expression alone.
    tape: Tape,
    /// Shorter tapes of the channel met so far.
    known: Arc<Known>,
}

/// What bounding tiles of one size cost and gained (filled tiles, shorter
/// tapes) on a layer's probe bands: on models whose bounds are too wide to
/// decide anything (long channels, where bounding a tile costs as much as
/// sampling many pixels) or decide too little, the other bands bound tiles
/// of that size only now and then. The probes are the bands nearest the
/// middle, taken in a fixed order until one bounded tiles, so which tiles
/// are bounded is the same on every run (and bounding changes only the
/// time, not a level, anyway).
#[derive(Clone, Copy, Debug, Default)]
struct Payoff {
    tries: u32,
    /// Sum of the [`tape_cost`] of the tapes bounded.
    spent: u64,
    /// Sum over filled or shortened tiles of inside pixels times the cost
    /// per pixel saved.
    gained: u64,
}

/// The cost of bounding a tile in pixels sampled with the same tape: one
/// interval step (f64 with outward rounding, scalar, library powers) costs
/// about as much as one batch step on this many pixels.
const BOUND_PIXELS: u64 = 64;

impl Payoff {
    /// The entry for tiles of `size`: over 32 pixels, over 16, the rest.
    fn level(size: [usize; 2]) -> usize {
        match size[0].max(size[1]) {
            33.. => 0,
            17..=32 => 1,
            _ => 2,
        }
    }

    fn add(self, o: Payoff) -> Payoff {
        Payoff {
            tries: self.tries + o.tries,
            spent: self.spent + o.spent,
            gained: self.gained + o.gained,
        }
    }

    /// Whether bounding these tiles may pay: fewer than 2 tries tell
    /// nothing, else the sampling saved must have been at least a quarter
    /// of the bounding (a few probed tiles are a rough guide; bounding in
    /// vain costs less than missing fills and shorter tapes).
    fn paid(self) -> bool {
        self.tries < 2 || 4 * self.gained >= BOUND_PIXELS * self.spent
    }

    /// Bound one tile in this many: every one where bounding paid, one in
    /// 16 where it saved too little, one in 64 where it saved nothing at
    /// all (a long channel whose bounds decide nothing: each costs as much
    /// as sampling hundreds of pixels).
    fn stride(self) -> u32 {
        if self.paid() {
            1
        } else if self.gained == 0 {
            64
        } else {
            16
        }
    }
}

/// Which tile sizes a band bounds, and what bounding them gave.
struct Policy {
    /// Per [`Payoff::level`]: bound one tile in this many
    /// ([`Payoff::stride`]).
    stride: [u32; 3],
    skipped: Cell<[u32; 3]>,
    seen: Cell<[Payoff; 3]>,
}

impl Policy {
    fn new(stride: [u32; 3]) -> Policy {
        Policy {
            stride,
            skipped: Cell::new([0; 3]),
            seen: Cell::new([Payoff::default(); 3]),
        }
    }

    /// Whether to bound the next tile of `level`.
    fn worth(&self, level: usize) -> bool {
        if self.stride[level] <= 1 {
            return true;
        }
        let mut s = self.skipped.get();
        s[level] += 1;
        self.skipped.set(s);
        s[level].is_multiple_of(self.stride[level])
    }

    /// A tile of `level` bounded with a tape of `cost`, saving `gained`
    /// (inside pixels times cost per pixel).
    fn record(&self, level: usize, cost: u32, gained: u64) {
        let mut s = self.seen.get();
        s[level].tries += 1;
        s[level].spent += u64::from(cost);
        s[level].gained += gained;
        self.seen.set(s);
    }
}

/// An evaluator of the channel (or of a tile's shorter tape) with the
/// inside pixels loaded into its batch and waiting for a full block.
struct Evals {
    tape: Tape,
    /// [`tape_cost`] of the tape.
    cost: u32,
    /// Whether the tape has steps exact simplification can cut (`min`,
    /// `max`, `select`).
    branches: bool,
    batch: BatchEval,
    interval: IntervalEval,
    /// Indices into the band's buffer of the `n` pixels loaded so far.
    idx: Box<[usize; BLOCK]>,
    n: usize,
}

impl Evals {
    /// Evaluators of `tape` for points at height `z` (set in every lane
    /// once: the batch evaluator never writes its inputs).
    fn new(tape: &Tape, z: f32) -> Evals {
        let mut batch = BatchEval::new(tape);
        batch.coords_mut().2.fill(z);
        Evals {
            tape: tape.clone(),
            cost: tape_cost(tape),
            branches: tape.ops().iter().any(|op| {
                use microfrep_core::{BinaryOp as B, Op};
                matches!(op, Op::Binary(B::Min | B::Max, ..) | Op::Select(..))
            }),
            batch,
            interval: IntervalEval::new(tape),
            idx: Box::new([0; BLOCK]),
            n: 0,
        }
    }

    /// Evaluates the loaded pixels and stores their grey levels.
    fn flush(&mut self, rows: &mut [u8]) {
        let n = std::mem::take(&mut self.n);
        if n == 0 {
            return;
        }
        let s = self.batch.eval_loaded(n);
        // The levels in one vector loop, then stored to their pixels. NaN
        // (undefined) gives 0 like outside.
        let mut g = [0u8; BLOCK];
        for (g, &v) in g.iter_mut().zip(s) {
            *g = grey(v);
        }
        for (&q, &g) in self.idx[..n].iter().zip(&g) {
            rows[q] = g;
        }
    }
}

/// Whether two tapes made from one tape by simplification are the same
/// (constants compared by their bits, so NaN constants match).
fn same_tape(a: &Tape, b: &Tape) -> bool {
    use microfrep_core::Op;
    a.outputs() == b.outputs()
        && a.ops().len() == b.ops().len()
        && a.ops().iter().zip(b.ops()).all(|(x, y)| match (x, y) {
            (Op::Const(c), Op::Const(d)) => c.to_bits() == d.to_bits(),
            _ => x == y,
        })
}

/// The channel's expression as the stack evaluates it: real powers with
/// whole exponents as integer powers (a few multiplications instead of the
/// exp/ln kernels), a real power next to the power of the same base with
/// the exponent one more (a gradient's) as the quotient of that power and
/// the base (one power kernel instead of two), and divisions by constants
/// as products with their inverses (a multiplication instead of a
/// division): a few f32 roundings, far below the half level of 1/510 that
/// could move a level, so within one level of the exact value as before.
fn channel_expr(shape: &Shape, channel: usize) -> microfrep_core::Expr {
    shape.attributes()[channel]
        .expr
        .with_integer_powers()
        .with_neighbour_powers_shared()
        .with_constant_divisors_inverted()
}

/// The channel's tape as the stack evaluates it: [`channel_expr`] with the
/// costly operations of both branches of a select evaluated once
/// ([`Tape::merge_branches`]: the same bits at every point).
fn channel_tape(shape: &Shape, channel: usize) -> Tape {
    let t = Tape::new(&channel_expr(shape, channel));
    t.merge_branches().unwrap_or(t)
}

/// Rough cost per point of evaluating `t` in batches, in units of one
/// vectorised add: the transcendental kernels (f64 polynomials, and the
/// scalar library calls for the rarer ones) weigh tens of simple steps, so
/// a tile that decides which side of a `pow` it needs gains more than its
/// share of steps says.
fn tape_cost(t: &Tape) -> u32 {
    use microfrep_core::{BinaryOp as B, Op, UnaryOp as U};
    t.ops()
        .iter()
        .map(|op| match op {
            Op::Var(_) | Op::Const(_) | Op::Param(_) => 0,
            Op::Unary(U::Exp | U::Ln | U::Sin | U::Cos, _) => 12,
            Op::Unary(U::Tan | U::Asin | U::Acos | U::Atan | U::Sinh | U::Cosh | U::Tanh, _) => 40,
            Op::Unary(U::Sqrt, _) | Op::Binary(B::Div, ..) => 2,
            Op::Binary(B::Pow, ..) => 24,
            Op::Binary(B::Atan2 | B::Rem, ..) => 40,
            Op::Field { .. } => 40,
            _ => 1,
        })
        .sum()
}

/// Shorter tapes met so far by a stack, shared by its threads and layers:
/// a tape found here comes with its batch lowering made (once per tape,
/// not once per layer and thread).
#[derive(Debug, Default)]
struct Known(Mutex<Vec<Tape>>);

/// Tapes [`Known`] keeps (the first met).
const KNOWN_TAPES: usize = 64;

impl Known {
    /// The known tape equal to `t`, or `t`, now known if there is room.
    fn get(&self, t: Tape) -> Tape {
        let Ok(mut known) = self.0.lock() else {
            return t;
        };
        if let Some(k) = known.iter().find(|k| same_tape(k, &t)) {
            return k.clone();
        }
        if known.len() < KNOWN_TAPES {
            known.push(t.clone());
        }
        t
    }
}

/// Simplified tapes kept per thread (with their evaluators, which are
/// costly to make: tiles of one model mostly decide the same branches).
const CACHED_TAPES: usize = 8;

/// One thread's evaluators: the channel's (index 0) and those of the
/// shorter tapes tiles were given, in the order they were first needed.
struct Worker<'a> {
    evals: Vec<Evals>,
    known: &'a Known,
    /// The layer's height, in f32.
    z: f32,
}

impl Worker<'_> {
    /// The index of the evaluator of `t`, made if new.
    fn find_or_add(&mut self, t: Tape) -> usize {
        if let Some(e) = (1..self.evals.len()).find(|&e| same_tape(&self.evals[e].tape, &t)) {
            return e;
        }
        self.evals.push(Evals::new(&self.known.get(t), self.z));
        self.evals.len() - 1
    }

    /// Flushes every evaluator into `rows`, then drops the first needed
    /// shorter tapes beyond [`CACHED_TAPES`] (between tiles, so no index held by a
    /// tile in progress moves).
    fn finish(&mut self, rows: &mut [u8]) {
        for e in &mut self.evals {
            e.flush(rows);
        }
        let extra = self.evals.len().saturating_sub(1 + CACHED_TAPES);
        self.evals.drain(1..1 + extra);
    }
}

/// Side of the tiles that bands of rows are cut into (one bit of a `u64`
/// per column of a tile in the inside masks).
const TILE: usize = 64;
const _: () = assert!(TILE == u64::BITS as usize);
/// Side of the leaves sampled together (their inside pixels join the
/// evaluator's block).
const LEAF: usize = 16;
/// Tiles at least this many pixels on a side may get their own tape.
const SIMPLIFY_TILE: usize = 32;

/// Tiles below [`SIMPLIFY_TILE`] are bounded only when their parent's
/// bounds spanned at most this many grey levels (else bounding them rarely
/// pays: smooth channels vary by many levels over a tile, and a child spans
/// about half its parent's levels, so it is uniform only when the parent
/// spanned very few; with 8 the Bezier cube's leaves were bounded in vain).
const CLOSE_LEVELS: u8 = 2;

/// Grey level of attribute value `s`: `round(255 clamp(s, 0, 1))`, 0 for
/// NaN.
fn grey(s: f32) -> u8 {
    // `max` maps NaN to 0 (as `clamp` and the cast would), so the rounded
    // value is a whole number v in 0..=255; v + 2^23 is exact with v in
    // its low mantissa bits (bit operations that vectorise, unlike the
    // saturating casts).
    let v = (255.0 * s.max(0.0).min(1.0)).round();
    (v + 8_388_608.0).to_bits() as u8
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
            tape: channel_tape(shape, channel),
            known: Arc::default(),
        })
    }

    /// Grey levels of layer `k`, rows top (largest y) first.
    pub fn layer_pixels(&self, shape: &Shape, grid: &SliceGrid, k: usize) -> Vec<u8> {
        self.levels(shape, grid, k).0
    }

    /// [`AttributeStack::layer_pixels`], which tile sizes the probe bands
    /// found worth bounding, and the number of pixels with a level above 0.
    fn levels(&self, shape: &Shape, grid: &SliceGrid, k: usize) -> (Vec<u8>, [bool; 3], u64) {
        let (nx, ny) = (grid.nx, grid.ny);
        let mut pixels = vec![0u8; nx * ny];
        if nx == 0 || ny == 0 {
            return (pixels, [true; 3], 0);
        }
        // Bands of BAND image rows counted from the bottom (j), stored top
        // row first: band b holds rows j0..j0 + h at pixel rows
        // ny - j0 - h .. ny - j0. Cut the buffer from its end.
        let bands: Vec<(usize, &mut [u8])> = {
            let mut out = Vec::new();
            let mut rest = &mut pixels[..];
            let mut j0 = 0;
            while j0 < ny {
                let h = BAND.min(ny - j0);
                let (head, tail) = rest.split_at_mut((ny - j0 - h) * nx);
                out.push((j0, tail));
                rest = head;
                j0 += h;
            }
            out
        };
        // The pixel centres as the reference gives them to the evaluator.
        let xs: Vec<f32> = (0..nx).map(|i| grid.x(i) as f32).collect();
        let z = grid.z(k);
        // The channel's tape with the branches the whole layer decides cut
        // (a slice's fixed z often decides some).
        let tape = {
            let mut iv = IntervalEval::new(&self.tape);
            iv.eval(
                Interval::with_f32_ends(grid.x(0), grid.x(nx - 1)),
                Interval::with_f32_ends(grid.y(0), grid.y(ny - 1)),
                Interval::with_f32_ends(z, z),
            );
            match self.tape.simplify(iv.values(), Simplify::Folded) {
                Some(t) => self.known.get(t),
                None => self.tape.clone(),
            }
        };
        let tiles = nx.div_ceil(TILE);
        let init = || {
            let w = Worker {
                evals: vec![Evals::new(&tape, z as f32)],
                known: &self.known,
                z: z as f32,
            };
            (BandRaster::new(shape), w, Vec::new())
        };
        // Each band is sampled (the shape's value, as `rasterize` samples
        // it) and then graded while its values are in cache.
        type State<'a> = (BandRaster, Worker<'a>, Vec<f32>);
        let band = |(raster, w, values): &mut State<'_>, (j0, rows): (usize, &mut [u8]), stride| {
            let h = rows.len() / nx;
            values.resize(h * nx, 0.0);
            raster.band(grid, z, j0, values);
            let band = Band {
                grid,
                policy: Policy::new(stride),
                z,
                xs: &xs,
                j0,
                h,
                masks: inside_masks(values, nx, tiles),
                tiles,
            };
            for i0 in (0..nx).step_by(TILE) {
                let tw = TILE.min(nx - i0);
                band.tile(w, 0, rows, [i0, j0], [tw, h], true);
            }
            w.finish(rows);
            // The band's pixels with a level, counted while in cache.
            let solid = rows.iter().map(|&v| u64::from(v > 0)).sum::<u64>();
            (band.policy.seen.get(), solid)
        };
        // Probe bands first, one at a time from the middle outwards until
        // one has bounded tiles, bounding every tile they may; then the
        // others in parallel, bounding the sizes that paid there.
        let mid = bands.len() / 2;
        let mut order: Vec<_> = bands.into_iter().enumerate().collect();
        order.sort_by_key(|(b, _)| (b.abs_diff(mid), *b));
        let mut rest = order.into_iter().map(|(_, b)| b);
        let (mut seen, mut solid) = ([Payoff::default(); 3], 0);
        let mut state = init();
        for b in rest.by_ref() {
            let (s, n) = band(&mut state, b, [1; 3]);
            seen = std::array::from_fn(|l| seen[l].add(s[l]));
            solid += n;
            if seen[0].tries + seen[1].tries >= 2 {
                break;
            }
        }
        let stride = seen.map(Payoff::stride);
        solid += rest
            .collect::<Vec<_>>()
            .into_par_iter()
            .map_init(init, |s, b| band(s, b, stride).1)
            .sum::<u64>();
        (pixels, seen.map(Payoff::paid), solid)
    }
}

/// One band of rows being filled.
struct Band<'a> {
    grid: &'a SliceGrid,
    policy: Policy,
    z: f64,
    /// x of each pixel column's centre, in f32.
    xs: &'a [f32],
    /// First image row (from the bottom) and row count of the band.
    j0: usize,
    h: usize,
    /// The band's inside pixels ([`inside_masks`]), `tiles` words a row.
    masks: Vec<u64>,
    tiles: usize,
}

impl Band<'_> {
    /// Index into the band's buffer of the start of image row j.
    fn row(&self, j: usize) -> usize {
        (self.j0 + self.h - 1 - j) * self.grid.nx
    }

    /// The inside pixels of row `j` over columns `cols` (within one
    /// [`TILE`] of columns): bit `i - cols.start` for column `i`.
    fn inside(&self, j: usize, cols: &std::ops::Range<usize>) -> u64 {
        let m = self.masks[(j - self.j0) * self.tiles + cols.start / TILE];
        let w = cols.end - cols.start;
        let keep = if w == 64 { u64::MAX } else { (1u64 << w) - 1 };
        (m >> (cols.start % TILE)) & keep
    }

    /// Fills the tile at pixel `at` of size `size` with evaluator `e` of
    /// `w`. Small tiles are bounded only when `close`: their parent's
    /// bounds spanned few grey levels.
    #[allow(clippy::too_many_arguments)]
    fn tile(
        &self,
        w: &mut Worker,
        e: usize,
        rows: &mut [u8],
        at: [usize; 2],
        size: [usize; 2],
        close: bool,
    ) {
        let cols = at[0]..at[0] + size[0];
        let any_inside = (at[1]..at[1] + size[1]).any(|j| self.inside(j, &cols) != 0);
        if !any_inside {
            return;
        }
        let big = size[0] >= SIMPLIFY_TILE && size[1] >= SIMPLIFY_TILE;
        let level = Payoff::level(size);
        if !(big || close) || !self.policy.worth(level) {
            return self.split_or_sample(w, e, rows, at, size, false);
        }
        let grid = self.grid;
        // The pixel centres' extent, as given to the batch evaluator too.
        let xs = Interval::with_f32_ends(grid.x(at[0]), grid.x(at[0] + size[0] - 1));
        let ys = Interval::with_f32_ends(grid.y(at[1]), grid.y(at[1] + size[1] - 1));
        let ev = &mut w.evals[e];
        let b = ev
            .interval
            .eval(xs, ys, Interval::with_f32_ends(self.z, self.z));
        let inside = || -> u64 {
            (at[1]..at[1] + size[1])
                .map(|j| u64::from(self.inside(j, &cols).count_ones()))
                .sum()
        };
        if let Some(g) = uniform_grey(b) {
            self.policy
                .record(level, ev.cost, inside() * u64::from(ev.cost));
            if g != 0 {
                let all = if size[0] == 64 {
                    u64::MAX
                } else {
                    (1u64 << size[0]) - 1
                };
                for j in at[1]..at[1] + size[1] {
                    let r = self.row(j) + cols.start;
                    let dst = &mut rows[r..r + size[0]];
                    let mut m = self.inside(j, &cols);
                    if m == all {
                        dst.fill(g);
                        continue;
                    }
                    while m != 0 {
                        dst[m.trailing_zeros() as usize] = g;
                        m &= m - 1;
                    }
                }
            }
            return;
        }
        let near = !b.may_be_nan()
            && b.lo <= b.hi
            && grey(b.hi as f32).saturating_sub(grey(b.lo as f32)) <= CLOSE_LEVELS;
        let mut e = e;
        if big && ev.branches {
            let short = ev
                .tape
                .simplify(ev.interval.values(), Simplify::Folded)
                .map(|t| (tape_cost(&t), t))
                .filter(|(c, _)| 10 * c < 8 * ev.cost);
            let saved = short.as_ref().map_or(0, |(c, _)| ev.cost - c);
            self.policy
                .record(level, ev.cost, inside() * u64::from(saved));
            if let Some((_, t)) = short {
                // The same bounds with the shorter tape: go on splitting.
                e = w.find_or_add(t);
            }
        } else {
            self.policy.record(level, ev.cost, 0);
        }
        self.split_or_sample(w, e, rows, at, size, near)
    }

    /// Quarters a tile, or loads a leaf's inside pixels into evaluator `e`
    /// (evaluating its block whenever it fills).
    #[allow(clippy::too_many_arguments)]
    fn split_or_sample(
        &self,
        w: &mut Worker,
        e: usize,
        rows: &mut [u8],
        at: [usize; 2],
        size: [usize; 2],
        close: bool,
    ) {
        if size[0] > LEAF || size[1] > LEAF {
            let hw = size[0].div_ceil(2);
            let hh = size[1].div_ceil(2);
            for (dx, tw) in [(0, hw), (hw, size[0] - hw)] {
                for (dy, th) in [(0, hh), (hh, size[1] - hh)] {
                    if tw > 0 && th > 0 {
                        self.tile(w, e, rows, [at[0] + dx, at[1] + dy], [tw, th], close);
                    }
                }
            }
            return;
        }
        let ev = &mut w.evals[e];
        let cols = at[0]..at[0] + size[0];
        for j in at[1]..at[1] + size[1] {
            let mut m = self.inside(j, &cols);
            if m == 0 {
                continue;
            }
            let count = m.count_ones() as usize;
            if ev.n + count > BLOCK {
                ev.flush(rows);
            }
            let yf = self.grid.y(j) as f32;
            let r = self.row(j) + cols.start;
            let xs = &self.xs[cols.clone()];
            let n = ev.n;
            let (x, y, _) = ev.batch.coords_mut();
            y[n..n + count].fill(yf);
            let (x, idx) = (&mut x[n..n + count], &mut ev.idx[n..n + count]);
            if count == xs.len() {
                // The whole row of the leaf: no bits to walk.
                x.copy_from_slice(xs);
                for (k, iq) in idx.iter_mut().enumerate() {
                    *iq = r + k;
                }
            } else {
                for (xq, iq) in x.iter_mut().zip(idx) {
                    let k = m.trailing_zeros() as usize;
                    *xq = xs[k];
                    *iq = r + k;
                    m &= m - 1;
                }
            }
            ev.n = n + count;
        }
    }
}

/// Bit masks of the inside pixels (value `>= 0`) of the rows of `values`
/// (`nx` a row): for row `r` and tile column `t` (columns `64 t ..`), word
/// `r * tiles + t` with bit `i - 64 t` for column `i`.
fn inside_masks(values: &[f32], nx: usize, tiles: usize) -> Vec<u64> {
    let h = values.len() / nx;
    let mut masks = vec![0u64; h * tiles];
    for (words, row) in masks.chunks_mut(tiles).zip(values.chunks(nx)) {
        for (word, vals) in words.iter_mut().zip(row.chunks(TILE)) {
            let mut m = 0u64;
            if let Ok(full) = <&[f32; TILE]>::try_from(vals) {
                m = tile_mask(full);
            } else {
                for (k, &v) in vals.iter().enumerate() {
                    m |= u64::from(v >= 0.0) << k;
                }
            }
            *word = m;
        }
    }
    masks
}

/// The inside bits of one row of a whole tile: fixed shifts, compiled to
/// vector compares (kept out of line so the loop around it is not
/// vectorised instead, which was slower).
#[inline(never)]
fn tile_mask(vals: &[f32; TILE]) -> u64 {
    let mut m = 0u64;
    for (k, &v) in vals.iter().enumerate() {
        m |= u64::from(v >= 0.0) << k;
    }
    m
}

/// The grey levels of layer `k` the straightforward way, for tests: the
/// shape's value and the channel as the stack evaluates it (its integer
/// powers, shared powers and inverted constant divisors) compiled
/// together, evaluated at every pixel centre.
#[doc(hidden)]
pub fn reference_layer_pixels(
    shape: &Shape,
    grid: &SliceGrid,
    k: usize,
    channel: usize,
) -> Vec<u8> {
    let layer = rasterize(shape, grid, k);
    let (nx, ny) = (grid.nx, grid.ny);
    let both = Tape::with_outputs(&[shape.value().clone(), channel_expr(shape, channel)]);
    let mut ev = BatchEval::new(&both);
    let out = 1;
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
        let (pixels, _, solid) = self.levels(shape, grid, k);
        // The levels go to the encoder as they are (no copy).
        let img = microfrep_io::png::Image {
            width: grid.nx,
            height: grid.ny,
            pixels: microfrep_io::png::Pixels::Grey,
            data: pixels,
        };
        Ok((microfrep_io::png::encode(&img, path)?, solid))
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
                self.layer_name(grid.first + k),
                grid.z(k)
            );
        }
        s.push_str("  ]\n}\n");
        s.into_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::{grey, inside_masks, tile_mask, Evals, Known, Worker, CACHED_TAPES, TILE};
    use microfrep_core::{BatchEval, Expr, Tape, BLOCK};

    /// More shorter tapes than a worker keeps, each with pixels waiting:
    /// finishing stores every pixel's level from its own tape, keeps the
    /// channel's evaluator and the last needed tapes, and a dropped tape is
    /// made anew when needed again (a kept one is found).
    #[test]
    fn workers_flush_every_tape_and_keep_the_last() {
        let x = Expr::x();
        let tapes: Vec<Tape> = (0..CACHED_TAPES + 4)
            .map(|k| Tape::new(&(0.02 * k as f64 + 0.5 * (&x * (1.0 + k as f64)).sin().abs())))
            .collect();
        let root = Tape::new(&(&x * 0.0 + 0.25));
        let known = Known::default();
        let mut w = Worker {
            evals: vec![Evals::new(&root, 0.0)],
            known: &known,
            z: 0.0,
        };
        let mut rows = vec![0u8; (tapes.len() + 1) * BLOCK];
        let mut want = vec![0u8; rows.len()];
        for (k, t) in std::iter::once(&root).chain(&tapes).enumerate() {
            let e = if k == 0 { 0 } else { w.find_or_add(t.clone()) };
            assert_eq!(e, k);
            let ev = &mut w.evals[e];
            let n = 100 + k;
            let xs: Vec<f32> = (0..n).map(|i| -2.0 + 0.037 * i as f32).collect();
            let mut out = vec![0f32; n];
            BatchEval::new(t).eval(&xs, &vec![0.0; n], &vec![0.0; n], &mut out);
            let (cx, _, _) = ev.batch.coords_mut();
            cx[..n].copy_from_slice(&xs);
            for i in 0..n {
                ev.idx[i] = k * BLOCK + i;
                want[k * BLOCK + i] = grey(out[i]);
            }
            ev.n = n;
        }
        w.finish(&mut rows);
        assert_eq!(rows, want);
        assert_eq!(w.evals.len(), 1 + CACHED_TAPES);
        assert!(w.evals.iter().all(|e| e.n == 0));
        let last = tapes.len() - 1;
        assert_eq!(w.find_or_add(tapes[last].clone()), CACHED_TAPES);
        assert_eq!(w.find_or_add(tapes[0].clone()), 1 + CACHED_TAPES);
    }

    /// A channel that varies too fast for any tile bound to fill a tile,
    /// without branches to cut: after the first tries, tiles are bounded
    /// only now and then, and the levels stay those of full evaluation.
    #[test]
    fn bounds_that_never_pay_are_skipped_with_the_same_levels() {
        use super::{reference_layer_pixels, AttributeStack};
        use crate::SliceGrid;
        use microfrep_core::Shape;
        let [x, y, z] = Expr::xyz();
        let ball = 1.0 - (x.square() + y.square() + z.square());
        let wavy = 0.5 + 0.45 * (40.0 * &x).sin() * (40.0 * &y + &z).cos();
        let shape = Shape::new(ball).with_attribute("wavy", wavy);
        let grid = SliceGrid::new([-1.05; 3], [1.05; 3], 0.1, 0.008).unwrap();
        let stack = AttributeStack::new(&shape, 0).unwrap();
        for k in 0..grid.layers {
            let fast = stack.layer_pixels(&shape, &grid, k);
            assert_eq!(
                fast,
                reference_layer_pixels(&shape, &grid, k, 0),
                "layer {k}"
            );
        }
        // The layer through the middle: its probe bands found neither large
        // size worth bounding (small tiles are bounded only below parents
        // near one level, so never here), and the levels are the same.
        let k = grid.layers / 2;
        let (fast, bound, solid) = stack.levels(&shape, &grid, k);
        assert_eq!(bound[..2], [false; 2]);
        assert_eq!(solid, fast.iter().filter(|&&v| v > 0).count() as u64);
        assert_eq!(fast, reference_layer_pixels(&shape, &grid, k, 0));
    }

    /// Bounding a tile size is kept for every tile while the probes tell
    /// nothing or it paid, one in 16 where it saved too little, one in 64
    /// where it saved nothing; and a band bounds just those tiles.
    #[test]
    fn strides_follow_what_bounding_saved() {
        use super::{Payoff, Policy, BOUND_PIXELS};
        let p = |tries, spent, gained| Payoff {
            tries,
            spent,
            gained,
        };
        assert_eq!(p(1, 500, 0).stride(), 1);
        assert_eq!(p(4, 100, 100 * BOUND_PIXELS / 4).stride(), 1);
        assert_eq!(p(4, 100, 100).stride(), 16);
        assert_eq!(p(4, 100, 0).stride(), 64);
        let policy = Policy::new([1, 16, 64]);
        let count = |level| (0..256).filter(|_| policy.worth(level)).count();
        assert_eq!((count(0), count(1), count(2)), (256, 16, 4));
    }

    /// The vectorisable level equals `round(255 clamp(s, 0, 1))` with a
    /// saturating cast (NaN to 0) on every f32 in [-0.5, 1.5] near the
    /// level boundaries and on the special values.
    #[test]
    fn grey_is_the_rounded_clamped_level() {
        let want = |s: f32| (255.0 * s.clamp(0.0, 1.0)).round() as u8;
        let mut specials = vec![
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            1.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
        ];
        // Each half level and its neighbours a few ulps away.
        for k in 0..=512 {
            let b = (k as f32 - 0.5) / 510.0;
            let mut v = b;
            for _ in 0..4 {
                v = f32::from_bits(v.to_bits().wrapping_sub(1));
            }
            for _ in 0..9 {
                specials.push(v);
                v = f32::from_bits(v.to_bits() + 1);
            }
        }
        for &s in &specials {
            assert_eq!(grey(s), want(s), "{s:e} ({:08x})", s.to_bits());
        }
        // And a dense sweep of [-0.5, 1.5].
        for k in 0..1_000_000 {
            let s = -0.5 + k as f32 * 2e-6;
            assert_eq!(grey(s), want(s), "{s:e}");
        }
    }

    /// The bit masks mark exactly the pixels with `v >= 0` (NaN outside,
    /// -0 inside), for rows of whole and partial tiles.
    #[test]
    fn masks_mark_inside_pixels() {
        let nx = 2 * TILE + 7;
        let rows = 5;
        let values: Vec<f32> = (0..nx * rows)
            .map(|i| match (i * 7919) % 11 {
                0 => f32::NAN,
                1 => -0.0,
                2 => f32::INFINITY,
                3 => f32::NEG_INFINITY,
                k if k % 2 == 0 => -(k as f32),
                k => k as f32 * 0.5,
            })
            .collect();
        let tiles = nx.div_ceil(TILE);
        let masks = inside_masks(&values, nx, tiles);
        for r in 0..rows {
            for i in 0..nx {
                let bit = masks[r * tiles + i / TILE] >> (i % TILE) & 1 == 1;
                assert_eq!(bit, values[r * nx + i] >= 0.0, "row {r}, column {i}");
            }
        }
        let all = [1.0f32; TILE];
        assert_eq!(tile_mask(&all), u64::MAX);
    }
}
