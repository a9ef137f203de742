//! Volume and surface area of a model from its field, brick by brick.
//!
//! Bricks of [`BRICK`] voxels that interval evaluation proves full or empty
//! count exactly. The others are sampled at the voxel corners with the batch
//! evaluator; each voxel is split into six tetrahedra (Kuhn split along the
//! main diagonal). On each tetrahedron edge where the samples change sign
//! the zero crossing is first estimated linearly, then refined on the field
//! itself by a few Illinois steps, batched over all such edges of a brick
//! (see `crease::roots`). The crossings cut each tetrahedron into
//! an inside polytope and a polygon whose volume and area are taken
//! exactly: planes are exact, and smooth curved surfaces are off only by
//! the polygons' chords, O(h^2) in the curvature, however far the field is
//! from linear between the samples (fields that are not distances, thin
//! features a few voxels across; the linear crossings alone were off by
//! O(h^2) in the field's second derivatives, 10 % on the tori-ball block
//! at 128 voxels). The chords' error in volume is then corrected, without
//! a region, by each polygon's bulge (see `volume::Bulge`): the field at the
//! polygon's centre, one more batch evaluation, over its gradient from the
//! slopes found on the edges. The area is left with the chords' error.
//!
//! Creases (min/max and R-function edges, where the polygons cut across the
//! edge: O(h^2) in volume with the crossings exact, O(h) in area) are found
//! by comparing each surface cell's centre value and corners with their
//! best linear fit (which also flags curvature that the grid barely
//! resolves); those cells, and every cell with a sign change inside them,
//! are halved up to [`MAX_DEPTH`] times. A first, unrefined pass counts the
//! creased cells so that one depth, as deep as a work budget allows, is
//! used for the whole grid.
//!
//! The same samples on every other node give the measures on voxels twice
//! as large, computed the same way; the difference gives the error
//! estimate (see [`Estimate::error`]). Features one or two voxels across
//! are beyond it: the grid and the coarse one can miss them alike.

use crate::crease::{creased, no_nan, sample_centers, split};
use crate::grid::{classify_box, Class, Grid, Progress};
use crate::volume::{measure_leaves, Estimate, Leaf, LEAF_BATCH};
use microfrep_core::{BatchEval, IntervalEval, Shape, Tape};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Voxels per side of a brick (even, so that coarse voxels tile it).
pub const BRICK: usize = 16;

/// Volume and area measures of a model in a grid's box (or in a region).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Measures {
    /// Volume of the solid (inside the region, if any).
    pub volume: Estimate,
    /// Volume of the region (the box's volume without one).
    pub region_volume: Estimate,
    /// Area of the model's zero set inside the box (and the region).
    pub area: Estimate,
    /// Volume of the bricks proven full or empty by intervals, exact.
    pub proven_volume: f64,
    /// The solid volume by one sample at a random point of every block of
    /// 2 x 2 x 2 voxels (stratified Monte Carlo, unbiased however small the
    /// features), and its standard deviation: a check on `volume`, which
    /// misses features that fall between the grid's nodes.
    pub sampled_volume: f64,
    /// Standard deviation of `sampled_volume`, in cubic model units.
    pub sampled_volume_error: f64,
    /// Bricks sampled, of all.
    pub sampled_bricks: usize,
    /// Halvings of the cells around creases (see [`MAX_DEPTH`]).
    pub refine_depth: u32,
    /// Voxels (and coarse voxels) found creased or sharply curved, which
    /// were refined.
    pub creased_cells: usize,
    /// Bricks of the grid in all (sampled ones and those proven full or empty
    /// by intervals).
    pub bricks: usize,
}

pub(crate) use microfrep_core::geom::KUHN_TETS as TETS;

pub(crate) struct Scratch {
    pub(crate) solid_iv: IntervalEval,
    pub(crate) region_iv: Option<IntervalEval>,
    pub(crate) solid_ev: BatchEval,
    pub(crate) region_ev: Option<BatchEval>,
    pub(crate) xs: Vec<f32>,
    pub(crate) ys: Vec<f32>,
    pub(crate) zs: Vec<f32>,
    pub(crate) f: Vec<f32>,
    pub(crate) r: Vec<f32>,
    /// Surface cells whose measures wait for their edges' roots.
    pub(crate) leaves: Vec<Leaf>,
    pub(crate) root_vals: Vec<f32>,
}

/// Bricks measured per step of [`measure`]: their results are summed (in
/// brick order) and dropped, so the memory does not grow with the grid.
const CHUNK: usize = 4096;

/// Peak bytes of [`measure`] on `grid` beyond the model: a bit per brick
/// (which need refining), a chunk of brick results, and each thread's
/// buffers (a brick's samples and a batch of cells waiting to be
/// measured, with their edges' roots).
pub fn predict_bytes(grid: &Grid) -> f64 {
    let nb: f64 = grid
        .dims
        .iter()
        .map(|&d| d.div_ceil(BRICK) as f64)
        .product();
    let nodes = ((BRICK + 1) as f64).powi(3);
    let per_thread = nodes * (3.0 * 4.0 + 2.0 * 4.0 + 2.0 * 24.0)
        + LEAF_BATCH as f64 * (std::mem::size_of::<Leaf>() as f64 + 19.0 * 2.0 * (4.0 + 40.0));
    nb / 8.0
        + CHUNK as f64 * std::mem::size_of::<Part>() as f64
        + rayon::current_num_threads() as f64 * per_thread
        + 16e6
}

/// Measures the solid `f >= 0` (inside `region >= 0` when given) on `grid`.
/// `progress(done, total)` counts bricks.
pub fn measure(solid: &Shape, region: Option<&Shape>, grid: &Grid, progress: Progress) -> Measures {
    let (solid, region) = (solid.tape(), region.map(|r| r.tape()));
    let nb = grid.dims.map(|d| d.div_ceil(BRICK));
    let total = nb[0] * nb[1] * nb[2];
    let mut m = Measures {
        bricks: total,
        ..Measures::default()
    };
    let add = |m: &mut Measures, p: &Part| {
        m.volume.add(p.volume);
        m.region_volume.add(p.region);
        m.area.add(p.area);
        if p.sampled {
            m.sampled_bricks += 1;
        } else {
            m.proven_volume += p.region.value;
        }
    };
    // First pass: measure the bricks without creased cells, count the
    // creased cells of the others (marked in `redo`); then measure those
    // at the deepest depth the budget allows (one depth for the whole grid
    // keeps the fine and coarse estimates comparable).
    let mut redo = vec![0u64; total.div_ceil(64)];
    let (mut creased, mut nodes) = (0usize, 0usize);
    for start in (0..total).step_by(CHUNK) {
        let which: Vec<usize> = (start..(start + CHUNK).min(total)).collect();
        let parts = pass(solid, region, grid, 0, true, true, &which, &|d, _| {
            progress(start + d, 2 * total)
        });
        for (&b, p) in which.iter().zip(&parts) {
            creased += p.creased;
            nodes += p.nodes;
            m.sampled_volume += p.jitter[0];
            m.sampled_volume_error += p.jitter[1];
            if p.creased > 0 {
                redo[b / 64] |= 1 << (b % 64);
            } else {
                add(&mut m, p);
            }
        }
    }
    let budget = REFINE_BUDGET * nodes as f64;
    let mut depth = 0;
    let mut cost = 0.0;
    for d in (1..=MAX_DEPTH).filter(|_| creased > 0) {
        // Each halving level below a creased cell splits up to 4^(d-1)
        // cells (a surface through it).
        cost += (SPLIT_POINTS + 4.0 * LEAF_POINTS) * 4f64.powi(d as i32 - 1) * creased as f64;
        if cost > budget {
            break;
        }
        depth = d;
    }
    // Bricks without creased cells measure the same at any depth.
    let is_redo = |b: usize| redo[b / 64] >> (b % 64) & 1 == 1;
    for start in (0..total).step_by(CHUNK) {
        let which: Vec<usize> = (start..(start + CHUNK).min(total))
            .filter(|&b| is_redo(b))
            .collect();
        if which.is_empty() {
            continue;
        }
        let parts = pass(solid, region, grid, depth, false, false, &which, &|_, _| {});
        for p in &parts {
            add(&mut m, p);
        }
        progress(total + (start + CHUNK).min(total), 2 * total);
    }
    progress(2 * total, 2 * total);
    m.sampled_volume_error = m.sampled_volume_error.sqrt();
    m.refine_depth = depth;
    m.creased_cells = creased;
    m
}

/// Measures the bricks `which` with creased cells halved `depth` times.
pub(crate) fn pass(
    solid: &Tape,
    region: Option<&Tape>,
    grid: &Grid,
    depth: u32,
    survey: bool,
    sample: bool,
    which: &[usize],
    progress: Progress,
) -> Vec<Part> {
    let nb = grid.dims.map(|d| d.div_ceil(BRICK));
    let total = which.len();
    let done = AtomicUsize::new(0);
    which
        .par_iter()
        .map_init(
            || Scratch {
                solid_iv: IntervalEval::new(solid),
                region_iv: region.map(IntervalEval::new),
                solid_ev: BatchEval::new(solid),
                region_ev: region.map(BatchEval::new),
                xs: Vec::new(),
                ys: Vec::new(),
                zs: Vec::new(),
                f: Vec::new(),
                r: Vec::new(),
                leaves: Vec::new(),
                root_vals: Vec::new(),
            },
            |s, &b| {
                let bi = [b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])];
                let lo = bi.map(|v| v * BRICK);
                let hi: [usize; 3] = std::array::from_fn(|a| (lo[a] + BRICK).min(grid.dims[a]));
                let part = brick(grid, s, lo, hi, depth, survey, sample);
                let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                if d & 63 == 0 {
                    progress(d, total);
                }
                part
            },
        )
        .collect()
}

#[derive(Default)]
pub(crate) struct Part {
    pub(crate) volume: Estimate,
    pub(crate) region: Estimate,
    pub(crate) area: Estimate,
    /// The solid volume by one random sample per block of 2^3 voxels (see
    /// [`Measures::sampled_volume`]), and that estimate's variance.
    pub(crate) jitter: [f64; 2],
    pub(crate) sampled: bool,
    /// Top-level cells found creased, and points sampled.
    pub(crate) creased: usize,
    pub(crate) nodes: usize,
}

/// Measures of the voxels `lo..hi`.
/// With `survey`, bricks with creased cells are only counted (their
/// measures are left for a second pass); the others are measured. With
/// `sample`, the brick's sampled volume ([`Part::jitter`]) is measured too.
fn brick(
    g: &Grid,
    s: &mut Scratch,
    lo: [usize; 3],
    hi: [usize; 3],
    max_depth: u32,
    survey: bool,
    sample: bool,
) -> Part {
    let p0 = g.node(lo);
    let p1 = g.node(hi);
    let bv: f64 = (0..3).map(|a| p1[a] - p0[a]).product();
    let region = match &mut s.region_iv {
        Some(ev) => classify_box(ev, p0, p1),
        None => Class::Full,
    };
    if region == Class::Empty {
        return Part::default();
    }
    let solid = classify_box(&mut s.solid_iv, p0, p1);
    if region == Class::Full && solid != Class::Mixed {
        let v = if solid == Class::Full { bv } else { 0.0 };
        return Part {
            volume: Estimate::exact(v),
            region: Estimate::exact(bv),
            jitter: [v, 0.0],
            ..Part::default()
        };
    }
    let jitter = if sample {
        jitter_volume(g, s, lo, hi, solid, region)
    } else {
        [0.0; 2]
    };
    // Sample the (n+1)^3 nodes.
    let nn: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a] + 1);
    s.xs.clear();
    s.ys.clear();
    s.zs.clear();
    for k in 0..nn[2] {
        for j in 0..nn[1] {
            for i in 0..nn[0] {
                let p = g.node([lo[0] + i, lo[1] + j, lo[2] + k]);
                s.xs.push(p[0] as f32);
                s.ys.push(p[1] as f32);
                s.zs.push(p[2] as f32);
            }
        }
    }
    let len = s.xs.len();
    s.f.resize(len, 0.0);
    s.r.resize(len, 1.0);
    match solid {
        Class::Mixed => s.solid_ev.eval(&s.xs, &s.ys, &s.zs, &mut s.f),
        Class::Full => s.f.fill(f32::INFINITY),
        Class::Empty => s.f.fill(f32::NEG_INFINITY),
    }
    match (&mut s.region_ev, region) {
        (Some(ev), Class::Mixed) => ev.eval(&s.xs, &s.ys, &s.zs, &mut s.r),
        _ => s.r.fill(f32::INFINITY),
    }
    no_nan(&mut s.f);
    no_nan(&mut s.r);
    let mut ctx = Ctx {
        s,
        with_region: region == Class::Mixed,
        eval_solid: solid == Class::Mixed,
        solid_const: if solid == Class::Full {
            f32::INFINITY
        } else {
            f32::NEG_INFINITY
        },
        max_depth,
        creased: 0,
        refined: false,
        survey,
        slot: 0,
        slots: Vec::new(),
    };
    let n: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a] + 1);
    let centers = sample_centers(g, &mut ctx, lo, n);
    let mut part = cells(g, &mut ctx, lo, n, &centers);
    if survey && ctx.creased == 0 {
        ctx.survey = false;
        part = cells(g, &mut ctx, lo, n, &centers);
    }
    part.creased = ctx.creased;
    part.nodes = len;
    part.jitter = jitter;
    part
}

/// The solid volume of the voxels `lo..hi` (inside the region) by one
/// sample at a hashed random point of every block of 2 x 2 x 2 voxels, and
/// its variance (from pairs of neighbouring blocks that disagree): a
/// measure that no feature escapes by lying between the nodes, against
/// which [`crate::report::Report::notes`] checks the volume.
fn jitter_volume(
    g: &Grid,
    s: &mut Scratch,
    lo: [usize; 3],
    hi: [usize; 3],
    solid: Class,
    region: Class,
) -> [f64; 2] {
    let blocks: [usize; 3] = std::array::from_fn(|a| (hi[a] - lo[a]).div_ceil(2));
    s.xs.clear();
    s.ys.clear();
    s.zs.clear();
    let mut vol = Vec::with_capacity(blocks.iter().product());
    for k in 0..blocks[2] {
        for j in 0..blocks[1] {
            for i in 0..blocks[0] {
                let v0 = [lo[0] + 2 * i, lo[1] + 2 * j, lo[2] + 2 * k];
                let n: [usize; 3] = std::array::from_fn(|a| 2.min(hi[a] - v0[a]));
                let key = (v0[0] as u64) | (v0[1] as u64) << 21 | (v0[2] as u64) << 42;
                let u = hash3(key);
                let p: [f64; 3] = std::array::from_fn(|a| {
                    g.lo[a] + g.step[a] * (v0[a] as f64 + u[a] * n[a] as f64)
                });
                s.xs.push(p[0] as f32);
                s.ys.push(p[1] as f32);
                s.zs.push(p[2] as f32);
                vol.push((0..3).map(|a| n[a] as f64 * g.step[a]).product::<f64>());
            }
        }
    }
    let len = s.xs.len();
    s.f.resize(len, 0.0);
    s.r.resize(len, 1.0);
    match solid {
        Class::Mixed => s.solid_ev.eval(&s.xs, &s.ys, &s.zs, &mut s.f),
        Class::Full => s.f.fill(1.0),
        Class::Empty => s.f.fill(-1.0),
    }
    match (&mut s.region_ev, region) {
        (Some(ev), Class::Mixed) => ev.eval(&s.xs, &s.ys, &s.zs, &mut s.r),
        _ => s.r.fill(1.0),
    }
    let inside = |q: usize| s.f[q] >= 0.0 && s.r[q] >= 0.0;
    let total: f64 = (0..len).filter(|&q| inside(q)).map(|q| vol[q]).sum();
    // Blocks paired (2i, 2i + 1) along each axis in turn; a disagreeing
    // pair adds about half the product of their volumes to the variance.
    // The largest of the three axes (a surface parallel to an axis shows
    // only in the pairs across it).
    let idx = |c: [usize; 3]| c[0] + blocks[0] * (c[1] + blocks[1] * c[2]);
    let mut var = 0.0f64;
    for axis in 0..3 {
        let mut sum = 0.0;
        for k in 0..blocks[2] {
            for j in 0..blocks[1] {
                for i in 0..blocks[0] {
                    let c = [i, j, k];
                    if c[axis] % 2 == 1 {
                        let mut o = c;
                        o[axis] -= 1;
                        let (a, b) = (idx(c), idx(o));
                        if inside(a) != inside(b) {
                            sum += 0.5 * vol[a] * vol[b];
                        }
                    }
                }
            }
        }
        var = var.max(sum);
    }
    [total, var]
}

/// A point of the unit cube from a key (splitmix64): deterministic.
fn hash3(key: u64) -> [f64; 3] {
    let mut z = key.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x2545_F491_4F6C_DD1D;
    std::array::from_fn(|_| {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut x = z;
        x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        x ^= x >> 31;
        (x >> 11) as f64 / (1u64 << 53) as f64
    })
}

/// Measures of the sampled brick's cells (node counts `n`), each coarse cell
/// with its eight fine cells; `centers` from
/// [`crate::crease::sample_centers`].
fn cells(g: &Grid, ctx: &mut Ctx, lo: [usize; 3], n: [usize; 3], centers: &[[f64; 2]]) -> Part {
    let mut part = Part {
        sampled: true,
        ..Part::default()
    };
    let idx = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
    let h = g.step;
    let h2 = h.map(|v| 2.0 * v);
    let slot = |i: usize, j: usize, k: usize, step: usize| {
        let fine = (n[0] - 1) * (n[1] - 1) * (n[2] - 1);
        if step == 1 {
            i + (n[0] - 1) * (j + (n[1] - 1) * k)
        } else {
            fine + i / 2 + (n[0] / 2) * (j / 2 + (n[1] / 2) * (k / 2))
        }
    };
    // Per coarse cell: its measures (slot 2g), its fine cells' (2g + 1),
    // and whether it was refined, and found creased.
    ctx.slots.clear();
    let mut groups: Vec<(bool, bool)> = Vec::new();
    ctx.s.leaves.clear();
    for k in (0..n[2] - 1).step_by(2) {
        for j in (0..n[1] - 1).step_by(2) {
            for i in (0..n[0] - 1).step_by(2) {
                let group = groups.len();
                let creased_before = ctx.creased;
                ctx.slots.extend([[0.0; 3]; 2]);
                let corners = |s: &Scratch, i: usize, j: usize, k: usize, step: usize| {
                    let at = |c: usize| {
                        idx(
                            i + step * (c & 1),
                            j + step * ((c >> 1) & 1),
                            k + step * ((c >> 2) & 1),
                        )
                    };
                    let f: [f64; 8] = std::array::from_fn(|c| s.f[at(c)] as f64);
                    let r: [f64; 8] = std::array::from_fn(|c| s.r[at(c)] as f64);
                    (f, r)
                };
                let origin = g.node([lo[0] + i, lo[1] + j, lo[2] + k]);
                let (f, r) = corners(ctx.s, i, j, k, 2);
                ctx.refined = false;
                let c = centers[slot(i, j, k, 2)];
                ctx.slot = 2 * group;
                let coarse = cell(ctx, origin, h2, &f, &r, c, 0);
                ctx.slot = 2 * group + 1;
                let mut fine = [0.0; 3];
                for c in 0..8 {
                    let o = [c & 1, (c >> 1) & 1, (c >> 2) & 1];
                    let (f, r) = corners(ctx.s, i + o[0], j + o[1], k + o[2], 1);
                    let p: [f64; 3] = std::array::from_fn(|a| origin[a] + h[a] * o[a] as f64);
                    let c = centers[slot(i + o[0], j + o[1], k + o[2], 1)];
                    let m = cell(ctx, p, h, &f, &r, c, 0);
                    for q in 0..3 {
                        fine[q] += m[q];
                    }
                }
                for q in 0..3 {
                    ctx.slots[2 * group][q] += coarse[q];
                    ctx.slots[2 * group + 1][q] += fine[q];
                }
                groups.push((ctx.refined, ctx.creased > creased_before));
            }
        }
    }
    if !ctx.survey {
        measure_leaves(ctx);
    }
    for (g, &(refined, creased)) in groups.iter().enumerate() {
        let (mut coarse, mut fine) = (ctx.slots[2 * g], ctx.slots[2 * g + 1]);
        // A cell holds no less than no solid and no more than its region
        // (the curvature corrections of features below the voxel size can
        // overshoot either way).
        for m in [&mut coarse, &mut fine] {
            m[0] = m[0].clamp(0.0, m[1].max(0.0));
        }
        for (q, e) in [&mut part.volume, &mut part.region, &mut part.area]
            .into_iter()
            .enumerate()
        {
            e.value += fine[q];
            e.coarse += coarse[q];
            // Volumes cut at exact crossings are of second order at
            // creases; areas, of first.
            if refined || (q == 2 && creased) {
                e.kink_diff += fine[q] - coarse[q];
            }
        }
    }
    part
}

/// Most halvings of a creased cell.
pub const MAX_DEPTH: u32 = 4;
/// Refinement may evaluate about this many times the points of the
/// sampled bricks; the depth is lowered until it fits (models with creases
/// or unresolved detail everywhere get less refinement, and larger error
/// estimates).
pub(crate) const REFINE_BUDGET: f64 = 8.0;

pub(crate) struct Ctx<'a> {
    pub(crate) s: &'a mut Scratch,
    pub(crate) with_region: bool,
    pub(crate) eval_solid: bool,
    /// The solid's value where it is not evaluated (proven full or empty):
    /// infinite, so that `min(solid, region)` is the region's value or
    /// empty. Likewise the region is `+inf` where it is not evaluated.
    pub(crate) solid_const: f32,
    /// Halvings of creased cells (and of every cell with a sign change
    /// inside them).
    pub(crate) max_depth: u32,
    /// Cells found creased at the top level.
    pub(crate) creased: usize,
    /// Whether the current coarse cell was refined anywhere.
    pub(crate) refined: bool,
    /// Only count creased cells, measure nothing.
    pub(crate) survey: bool,
    /// Where the measures of cells left for later go (see [`Leaf`]).
    pub(crate) slot: usize,
    /// Measures per slot.
    pub(crate) slots: Vec<[f64; 3]>,
}

/// Points evaluated per halving of a cell (27 nodes, 8 centres).
pub(crate) const SPLIT_POINTS: f64 = 35.0;
/// Points evaluated, about, to measure a cell with a sign change: the
/// refinement of the crossings on its edges (some 6 edges,
/// [`crate::crease::ROOT_STEPS`] evaluations each) and the centres of its
/// polygons (some 4). A halving leaves about 4 such cells.
pub(crate) const LEAF_POINTS: f64 = 22.0;

/// Solid volume, region volume and area of the cell at `p0` with sides `h`
/// and corner values `f` (solid) and `r` (region); creased cells are halved
/// (and `ctx.refined` set) up to `ctx.max_depth` times.
pub(crate) fn cell(
    ctx: &mut Ctx,
    p0: [f64; 3],
    h: [f64; 3],
    f: &[f64; 8],
    r: &[f64; 8],
    center: [f64; 2],
    depth: u32,
) -> [f64; 3] {
    let m: [f64; 8] = std::array::from_fn(|c| f[c].min(r[c]));
    let inside = |v: &[f64; 8]| v.iter().filter(|&&x| x >= 0.0).count();
    let (nm, nf, nr) = (inside(&m), inside(f), inside(r));
    let mixed = |n: usize| n != 0 && n != 8;
    let cv = h[0] * h[1] * h[2];
    if !mixed(nm) && !mixed(nr) && !mixed(nf) {
        return [cv * (nm / 8) as f64, cv * (nr / 8) as f64, 0.0];
    }
    let split_here = depth > 0
        || (mixed(nf) && creased(f, center[0]))
        || (mixed(nr) && creased(r, center[1]))
        || (mixed(nm) && creased(&m, center[0].min(center[1])));
    if split_here && depth == 0 {
        ctx.creased += 1;
    }
    if ctx.survey {
        return [0.0; 3];
    }
    if split_here && depth < ctx.max_depth {
        ctx.refined = true;
        return split(ctx, p0, h, f, r, depth);
    }
    // Measured later, with the other cells of the brick.
    ctx.s.leaves.push(Leaf {
        p0,
        h,
        f: *f,
        r: *r,
        slot: ctx.slot,
    });
    if ctx.s.leaves.len() >= LEAF_BATCH {
        measure_leaves(ctx);
    }
    [0.0; 3]
}
