//! Regular voxel grids over a box, and the multithreaded occupancy sampler
//! that every measure of the crate builds on.
//!
//! # API (stable: `volume`, `area`, `connectivity` and `thickness` use it)
//! - [`Grid::new`]`(bounds, resolution)` and [`Grid::with_voxel`]`(bounds,
//!   voxel)`: `dims[a]` voxels per axis tiling `bounds = [lo, hi]` exactly,
//!   `resolution` of them on the longest side. Every count is rounded up to
//!   an even number (so the grid coarsens by two); the voxel size per axis is
//!   `step[a] = (hi[a] - lo[a]) / dims[a]`, cubic up to that rounding.
//!   [`Grid::center`] gives voxel centres, [`Grid::node`] voxel corners
//!   (indices `0..=dims[a]`).
//! - Voxel labels: [`OUTSIDE`] (0, outside the region), [`PORE`] (1, in the
//!   region, not solid), [`SOLID`] (2, in the region and solid). Inside is
//!   `f >= 0` for both the model and the region.
//! - [`Sampler::new`]`(&solid, region: Option<&Tape>, grid)`, then
//!   [`Sampler::slab`]`(k0, k1) -> Vec<u8>`: the labels of voxel layers
//!   `k0..k1`, x fastest, then y, then z, sampled at voxel centres with the
//!   batch evaluator on all rayon threads, in column bricks of
//!   [`BRICK`]` x `[`BRICK`] voxels; bricks that interval evaluation proves
//!   full or empty are filled without sampling. [`Sampler::all`] samples the
//!   whole grid (one byte per voxel) in slabs of [`SLAB`] layers, calling
//!   `progress(done_layers, total_layers)` after each.
//! - [`classify_box`]: the interval verdict on a box, shared by the samplers.

use crate::error::{AnalysisError, Result};
use microfrep_core::{BatchEval, Interval, IntervalEval, Shape, Simplify, Tape};
use rayon::prelude::*;

/// Voxel label: outside the region (or outside the bounds).
pub const OUTSIDE: u8 = 0;
/// Voxel label: pore space (inside the region, not solid).
pub const PORE: u8 = 1;
/// Voxel label: solid inside the region.
pub const SOLID: u8 = 2;

/// Voxels per side of the column bricks of the sampler.
pub const BRICK: usize = 16;
/// Layers per slab of [`Sampler::all`].
pub const SLAB: usize = 16;
/// Most voxels on one side of a grid.
pub const MAX_RESOLUTION: usize = 16384;

/// Progress callback: `(done, total)` in units the caller states.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// A regular grid of voxels tiling a box exactly.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Lower corner of the box in model units (millimetres); voxel `(0, 0, 0)`
    /// starts here.
    pub lo: [f64; 3],
    /// Upper corner of the box in model units; `lo[a] + dims[a] * step[a]`
    /// equals it up to rounding.
    pub hi: [f64; 3],
    /// Voxels per axis (even).
    pub dims: [usize; 3],
    /// Voxel size per axis.
    pub step: [f64; 3],
}

impl Grid {
    /// Grid with `resolution` voxels on the longest side of `bounds`
    /// (rounded up to even); the other sides get the count nearest to cubic
    /// voxels.
    pub fn new(bounds: [[f64; 3]; 2], resolution: usize) -> Result<Grid> {
        let [lo, hi] = bounds;
        let ext: [f64; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        if lo.iter().chain(hi.iter()).any(|v| !v.is_finite()) || ext.iter().any(|&e| e <= 0.0) {
            return Err(AnalysisError::Input(format!(
                "bounds {lo:?}..{hi:?} must be finite with min < max on every axis"
            )));
        }
        if resolution == 0 || resolution > MAX_RESOLUTION {
            return Err(AnalysisError::Input(format!(
                "resolution {resolution} must be between 1 and {MAX_RESOLUTION}"
            )));
        }
        let longest = ext.iter().cloned().fold(0.0, f64::max);
        let h = longest / resolution as f64;
        let dims: [usize; 3] = std::array::from_fn(|a| {
            let n = (ext[a] / h).round().max(1.0) as usize;
            n + n % 2
        });
        let step: [f64; 3] = std::array::from_fn(|a| ext[a] / dims[a] as f64);
        // f32 samples must resolve the voxels everywhere in the box.
        let finest = step.iter().cloned().fold(f64::INFINITY, f64::min);
        microfrep_io::precision::check_grid(lo, hi, finest).map_err(|e| {
            AnalysisError::Input(format!("cannot sample at resolution {resolution}: {e}"))
        })?;
        Ok(Grid { lo, hi, dims, step })
    }

    /// Grid whose voxels are at most `voxel` on a side.
    pub fn with_voxel(bounds: [[f64; 3]; 2], voxel: f64) -> Result<Grid> {
        let longest = (0..3)
            .map(|a| bounds[1][a] - bounds[0][a])
            .fold(0.0, f64::max);
        if !(voxel > 0.0 && voxel.is_finite()) {
            return Err(AnalysisError::Input(format!(
                "voxel size {voxel} must be a number > 0"
            )));
        }
        let n = (longest / voxel).ceil();
        if !(n >= 1.0 && n <= MAX_RESOLUTION as f64) {
            return Err(AnalysisError::Input(format!(
                "voxel size {voxel} gives {n} voxels on the longest side (limit {MAX_RESOLUTION})"
            )));
        }
        Grid::new(bounds, n as usize)
    }

    /// Number of voxels.
    pub fn voxels(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    /// Volume of one voxel.
    pub fn voxel_volume(&self) -> f64 {
        self.step.iter().product()
    }

    /// Volume of the box.
    pub fn box_volume(&self) -> f64 {
        (0..3).map(|a| self.hi[a] - self.lo[a]).product()
    }

    /// Centre of voxel `i`.
    pub fn center(&self, i: [usize; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.lo[a] + self.step[a] * (i[a] as f64 + 0.5))
    }

    /// Corner node `i` (indices `0..=dims[a]`).
    pub fn node(&self, i: [usize; 3]) -> [f64; 3] {
        std::array::from_fn(|a| {
            if i[a] == self.dims[a] {
                self.hi[a]
            } else {
                self.lo[a] + self.step[a] * i[a] as f64
            }
        })
    }

    /// Largest voxel side.
    pub fn voxel_size(&self) -> f64 {
        self.step.iter().cloned().fold(0.0, f64::max)
    }
}

/// What interval evaluation proves about a function on a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// `f < 0` everywhere.
    Empty,
    /// `f >= 0` everywhere.
    Full,
    /// Undecided: the box must be sampled.
    Mixed,
}

/// The interval verdict on the box `[lo, hi]`.
pub fn classify_box(ev: &mut IntervalEval, lo: [f64; 3], hi: [f64; 3]) -> Class {
    let iv = |a: usize| Interval::new(lo[a], hi[a]);
    let r = ev.eval(iv(0), iv(1), iv(2));
    if r.is_nan() || r.may_be_nan() {
        Class::Mixed
    } else if r.hi < 0.0 {
        Class::Empty
    } else if r.lo >= 0.0 {
        Class::Full
    } else {
        Class::Mixed
    }
}

/// Voxel-centre occupancy of a model, optionally inside a region.
pub struct Sampler {
    solid: Tape,
    region: Option<Tape>,
    /// The grid whose voxel centres are sampled.
    pub grid: Grid,
}

/// A brick's result: one label for all its voxels, or one per voxel.
enum Fill {
    Same(u8),
    Each(Vec<u8>),
}

struct Scratch {
    solid_iv: IntervalEval,
    region_iv: Option<IntervalEval>,
    solid_ev: BatchEval,
    region_ev: Option<BatchEval>,
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    vals: Vec<f32>,
}

impl Sampler {
    /// Occupancy of `solid` (inside `region`, if given) on `grid`.
    pub fn new(solid: &Shape, region: Option<&Shape>, grid: Grid) -> Sampler {
        Sampler {
            solid: solid.tape().clone(),
            region: region.map(|r| r.tape().clone()),
            grid,
        }
    }

    /// Labels of voxel layers `k0..k1` (x fastest, then y, then z).
    pub fn slab(&self, k0: usize, k1: usize) -> Vec<u8> {
        let [nx, ny, _] = self.grid.dims;
        let mut out = vec![OUTSIDE; nx * ny * k1.saturating_sub(k0)];
        self.slab_into(k0, k1, &mut out);
        out
    }

    /// Like [`Sampler::slab`], into `out` of length `nx * ny * (k1 - k0)`.
    pub fn slab_into(&self, k0: usize, k1: usize, out: &mut [u8]) {
        let [nx, ny, nz] = self.grid.dims;
        assert!(k0 <= k1 && k1 <= nz, "layers {k0}..{k1} outside 0..{nz}");
        assert_eq!(out.len(), nx * ny * (k1 - k0), "slab buffer length");
        if k0 == k1 {
            return;
        }
        let (bx, by) = (nx.div_ceil(BRICK), ny.div_ceil(BRICK));
        let fills: Vec<Fill> = (0..bx * by)
            .into_par_iter()
            .map_init(
                || self.scratch(),
                |s, b| {
                    let lo = [(b % bx) * BRICK, (b / bx) * BRICK, k0];
                    let hi = [(lo[0] + BRICK).min(nx), (lo[1] + BRICK).min(ny), k1];
                    self.brick(s, lo, hi)
                },
            )
            .collect();
        for (b, fill) in fills.iter().enumerate() {
            let lo = [(b % bx) * BRICK, (b / bx) * BRICK];
            let w = BRICK.min(nx - lo[0]);
            let h = BRICK.min(ny - lo[1]);
            for k in 0..k1 - k0 {
                for j in 0..h {
                    let o = lo[0] + nx * (lo[1] + j + ny * k);
                    match fill {
                        Fill::Same(v) => out[o..o + w].fill(*v),
                        Fill::Each(d) => {
                            let s = w * (j + h * k);
                            out[o..o + w].copy_from_slice(&d[s..s + w]);
                        }
                    }
                }
            }
        }
    }

    /// The whole grid, one byte per voxel, sampled in slabs of [`SLAB`]
    /// layers; `progress(done_layers, total_layers)` after each slab.
    pub fn all(&self, progress: Progress) -> Vec<u8> {
        let [nx, ny, nz] = self.grid.dims;
        let layer = nx * ny;
        let mut out = vec![OUTSIDE; layer * nz];
        for k0 in (0..nz).step_by(SLAB) {
            let k1 = (k0 + SLAB).min(nz);
            self.slab_into(k0, k1, &mut out[k0 * layer..k1 * layer]);
            progress(k1, nz);
        }
        out
    }

    fn scratch(&self) -> Scratch {
        Scratch {
            solid_iv: IntervalEval::new(&self.solid),
            region_iv: self.region.as_ref().map(IntervalEval::new),
            solid_ev: BatchEval::new(&self.solid),
            region_ev: self.region.as_ref().map(BatchEval::new),
            xs: Vec::new(),
            ys: Vec::new(),
            zs: Vec::new(),
            vals: Vec::new(),
        }
    }

    /// Labels of the voxels `lo..hi` (x fastest).
    fn brick(&self, s: &mut Scratch, lo: [usize; 3], hi: [usize; 3]) -> Fill {
        let g = &self.grid;
        let p0 = g.center(lo);
        let p1 = g.center(std::array::from_fn(|a| hi[a] - 1));
        let region = match &mut s.region_iv {
            Some(ev) => classify_box(ev, p0, p1),
            None => Class::Full,
        };
        if region == Class::Empty {
            return Fill::Same(OUTSIDE);
        }
        let solid = classify_box(&mut s.solid_iv, p0, p1);
        if region == Class::Full && solid != Class::Mixed {
            return Fill::Same(if solid == Class::Full { SOLID } else { PORE });
        }
        s.xs.clear();
        s.ys.clear();
        s.zs.clear();
        for k in lo[2]..hi[2] {
            for j in lo[1]..hi[1] {
                for i in lo[0]..hi[0] {
                    let c = g.center([i, j, k]);
                    s.xs.push(c[0] as f32);
                    s.ys.push(c[1] as f32);
                    s.zs.push(c[2] as f32);
                }
            }
        }
        let n = s.xs.len();
        let mut labels = vec![
            match solid {
                Class::Full => SOLID,
                Class::Empty => PORE,
                Class::Mixed => OUTSIDE,
            };
            n
        ];
        s.vals.resize(n, 0.0);
        if solid == Class::Mixed {
            // Where the brick's intervals decide a branch of a set
            // operation, the shorter tape gives the same bits for less
            // (deep in a part's core its distance is cut away).
            let mut local = self
                .solid
                .simplify(s.solid_iv.values(), Simplify::Exact)
                .filter(|t| 10 * t.len() < 7 * self.solid.len())
                .map(|t| BatchEval::new(&t));
            let ev = local.as_mut().unwrap_or(&mut s.solid_ev);
            ev.eval(&s.xs, &s.ys, &s.zs, &mut s.vals);
            for (l, &v) in labels.iter_mut().zip(&s.vals) {
                *l = if v >= 0.0 { SOLID } else { PORE };
            }
        }
        if region == Class::Mixed {
            if let Some(ev) = &mut s.region_ev {
                ev.eval(&s.xs, &s.ys, &s.zs, &mut s.vals);
                for (l, &v) in labels.iter_mut().zip(&s.vals) {
                    if v.is_nan() || v < 0.0 {
                        *l = OUTSIDE;
                    }
                }
            }
        }
        Fill::Each(labels)
    }
}
