//! Local thickness of the solid (strut and wall thickness) and of the pore
//! space (pore size), on a voxel grid, with an exact Euclidean distance
//! transform.
//!
//! # API (stable)
//! - [`thickness`]`(&Sampler, &ThicknessOptions, progress) -> Result<Thickness>`:
//!   samples the grid itself (in slabs when it must) and measures both
//!   phases: solid = [`SOLID`] voxels, pore = [`PORE`] voxels; every other
//!   voxel (the other phase, or [`crate::grid::OUTSIDE`] the region) bounds
//!   a phase. `progress(done, total)` is called as work proceeds (units:
//!   layers sampled plus layers measured per phase).
//! - [`thickness_of_labels`]`(labels, dims, voxel, &opts)`: the same on
//!   labels already in memory (x fastest, then y, then z).
//! - [`local_thickness_field`]`(labels, dims, phase)`: the per-voxel
//!   diameter field, in voxels (0 off the phase), whole grid at once, always
//!   exact (no work budget).
//! - [`edt::edt_squared`]: the exact squared distance transform.
//! - Options ([`ThicknessOptions`]): histogram bin width, memory limit,
//!   which phases, work budget. Results ([`Thickness`], [`PhaseThickness`],
//!   [`ThicknessStats`]): diameters in model units, with the slab cap and
//!   the ladder (below) stated.
//!
//! # Definitions
//! The local thickness at a voxel is the diameter of the largest ball that
//! contains it and fits in the phase (Hildebrand and Rüegsegger). On the
//! grid: a centre `c` has the squared distance `D(c)` (voxel units, between
//! voxel centres) to the nearest voxel of the grid not in the phase; its
//! ball holds the voxels `|p - c|^2 < D(c)`; diameter `2 sqrt(D) * voxel`,
//! the convention of PoreSpy (which returns the radius, floored to whole
//! voxels) and BoneJ. This reads thin features up to one voxel thick (a
//! plate of n voxel layers reads n or n + 1 voxels). Space beyond the grid
//! is not a wall: pores open at the bounds are measured as if they
//! continued (PoreSpy's default too). A phase that fills the whole grid has
//! no finite thickness: [`PhaseThickness::Unbounded`].
//!
//! # Work
//! Exact: the distance transform (linear), the ridge (26 neighbours per
//! voxel) and the painting of the ridge balls, about `pi D` row tests per
//! ball. When those rows would exceed [`ThicknessOptions::work_per_voxel`]
//! per voxel (huge balls everywhere, e.g. the open space around one convex
//! part in a box), the largest balls are replaced by a ladder of at most 32
//! radii, one distance transform each: values above
//! [`ThicknessStats::exact_up_to`] are then lower bounds floored to the
//! ladder ([`ThicknessStats::ladder_ratio`] apart, at least 5 %).
//!
//! # Memory
//! Working arrays: 9 bytes per voxel of a window (labels, distances, and a
//! ladder rung's distances) + 5 per voxel of the slab painted in it (result
//! and a bitmap) + 16 bytes per ridge centre, planned as 4 bytes per window
//! voxel (measured: 26 % of the pore voxels of the tori-ball block are
//! ridge centres, so 4.2 bytes per voxel). When the whole grid fits
//! [`ThicknessOptions::memory_limit`] it is one window and the result is
//! exact. Otherwise it is cut into slabs of `S = 2H` layers painted from
//! windows of `S + 4H` layers (`H` as large as the limit allows, at least
//! [`MIN_HALO`]): distances and balls up to radius `H` voxels are exact; a
//! voxel covered by a larger ball is counted at the cap diameter `2H`
//! ([`Thickness::diameter_cap`], [`ThicknessStats::capped_voxels`]), and
//! voxels near such a large ball may read low. Grids whose layers are too
//! large for the limit are refused with [`AnalysisError::Memory`].

pub mod edt;
mod histogram;
mod ladder;
mod local;

pub use histogram::{Histogram, ThicknessStats};

use crate::error::{AnalysisError, Result};
use crate::grid::{Progress, Sampler, PORE, SOLID};
use edt::{edt_squared, INF, MAX_SIDE};
use histogram::summarize;
use ladder::paint_phase;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Smallest slab halo, in voxels, before the grid is refused.
pub const MIN_HALO: usize = 4;

/// Bytes per window voxel (labels 1, distances 4, a ladder rung's
/// distances 4, and 4 for ridge centres: 16 bytes each, typically a
/// quarter of the voxels or fewer) and per painted voxel.
const WINDOW_BYTES: u64 = 13;
const SLAB_BYTES: u64 = 5;

/// How the local thickness is measured: histogram bins, the memory and
/// work allowed, and which phases. The default measures both phases
/// exactly where the work budget allows, within 2 GiB.
#[derive(Clone, Debug)]
pub struct ThicknessOptions {
    /// Histogram bin width in model units; `None`: one voxel.
    pub bin_width: Option<f64>,
    /// Most bytes for the working arrays (see the module docs).
    pub memory_limit: u64,
    /// Which phases to measure (both by default); a phase left out is
    /// [`PhaseThickness::Skipped`].
    pub measure_solid: bool,
    /// Measure the pore space (pore size distribution); on by default.
    pub measure_pore: bool,
    /// Rows of exact ball painting allowed per voxel (see
    /// [`ThicknessStats::exact_up_to`]); `f64::INFINITY`: always exact.
    pub work_per_voxel: f64,
}

impl Default for ThicknessOptions {
    fn default() -> Self {
        ThicknessOptions {
            bin_width: None,
            memory_limit: 2 << 30,
            measure_solid: true,
            measure_pore: true,
            work_per_voxel: ladder::WORK_PER_VOXEL,
        }
    }
}

/// The thickness distribution of one phase.
#[derive(Clone, Debug, PartialEq)]
pub enum PhaseThickness {
    /// Not asked for ([`ThicknessOptions::measure_solid`], `measure_pore`).
    Skipped,
    /// The phase has no voxels.
    Empty,
    /// The phase fills the grid: no wall anywhere, no finite thickness.
    Unbounded {
        /// Voxels of the phase (the whole grid).
        voxels: u64,
    },
    /// The phase's diameter distribution.
    Measured(ThicknessStats),
}

impl PhaseThickness {
    /// The distribution when the phase was measured, else `None`.
    pub fn stats(&self) -> Option<&ThicknessStats> {
        match self {
            PhaseThickness::Measured(s) => Some(s),
            _ => None,
        }
    }
}

/// Local thickness of the solid and the pore space.
#[derive(Clone, Debug, PartialEq)]
pub struct Thickness {
    /// Voxel side used for the diameters (the largest of the grid's steps).
    pub voxel: f64,
    /// Voxels per axis of the grid the distribution was taken on.
    pub dims: [usize; 3],
    /// Strut and wall thickness.
    pub solid: PhaseThickness,
    /// Pore size.
    pub pore: PhaseThickness,
    /// Slabs the grid was processed in (1: exact).
    pub slabs: usize,
    /// With more than one slab: the diameter (model units) above which
    /// values are capped; `None` when exact.
    pub diameter_cap: Option<f64>,
    /// Planned bytes of the working arrays (window and slab, without ridge
    /// centres).
    pub working_bytes: u64,
}

/// How the grid is cut: slabs of `slab` layers, halo `halo` (0: one window).
#[derive(Clone, Copy, Debug)]
struct Plan {
    slab: usize,
    halo: usize,
}

fn plan(dims: [usize; 3], limit: u64) -> Result<(Plan, u64)> {
    let [nx, ny, nz] = dims;
    if let Some(a) = (0..3).find(|&a| dims[a] > MAX_SIDE) {
        return Err(AnalysisError::Input(format!(
            "thickness: {} voxels on axis {a} exceed the limit of {MAX_SIDE}",
            dims[a]
        )));
    }
    let layer = (nx * ny) as u64;
    let whole = layer * nz as u64 * (WINDOW_BYTES + SLAB_BYTES);
    if whole <= limit {
        return Ok((Plan { slab: nz, halo: 0 }, whole));
    }
    // Slabs of 2H layers in windows of 6H: layer * H * (6 * 13 + 2 * 5).
    let per_halo = layer * (6 * WINDOW_BYTES + 2 * SLAB_BYTES);
    let halo = (limit / per_halo) as usize;
    if halo < MIN_HALO {
        return Err(AnalysisError::Memory(format!(
            "thickness: layers of {nx} x {ny} voxels need {} MiB for slabs with a halo of \
             {MIN_HALO} voxels, over the limit of {} MiB; lower the resolution or raise the limit",
            (per_halo * MIN_HALO as u64) >> 20,
            limit >> 20
        )));
    }
    let slab = (2 * halo).min(nz);
    let bytes =
        layer * ((slab + 4 * halo).min(nz) as u64 * WINDOW_BYTES + slab as u64 * SLAB_BYTES);
    Ok((Plan { slab, halo }, bytes))
}

/// Both phases of the grid of `sampler`, sampled by it.
pub fn thickness(
    sampler: &Sampler,
    opts: &ThicknessOptions,
    progress: Progress,
) -> Result<Thickness> {
    let grid = &sampler.grid;
    run(
        grid.dims,
        grid.voxel_size(),
        opts,
        progress,
        &|k0, k1, out| sampler.slab_into(k0, k1, out),
    )
}

/// Both phases of `labels` (x fastest, then y, then z), voxels of side
/// `voxel`.
pub fn thickness_of_labels(
    labels: &[u8],
    dims: [usize; 3],
    voxel: f64,
    opts: &ThicknessOptions,
) -> Result<Thickness> {
    check_labels(labels, dims)?;
    let plane = dims[0] * dims[1];
    run(dims, voxel, opts, &|_, _| {}, &|k0, k1, out| {
        out.copy_from_slice(&labels[k0 * plane..k1 * plane])
    })
}

fn check_labels(labels: &[u8], dims: [usize; 3]) -> Result<()> {
    let n = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    if n != Some(labels.len()) {
        return Err(AnalysisError::Input(format!(
            "thickness: {} labels for a grid of {dims:?}",
            labels.len()
        )));
    }
    Ok(())
}

/// Local thickness (diameter, in voxels) of every voxel labelled `phase`,
/// 0 elsewhere; [`f32::INFINITY`] if `phase` fills the grid. One window:
/// needs about 20 bytes per voxel (with the returned field).
pub fn local_thickness_field(labels: &[u8], dims: [usize; 3], phase: u8) -> Result<Vec<f32>> {
    check_labels(labels, dims)?;
    plan(dims, u64::MAX)?;
    let d = edt_squared(labels, dims, |l| l == phase);
    if d.contains(&INF) {
        return Ok(d
            .iter()
            .map(|&v| if v > 0 { f32::INFINITY } else { 0.0 })
            .collect());
    }
    let p = paint_phase(&d, dims, 0..dims[2], 0..dims[2], f64::INFINITY);
    let dia: Vec<f32> = p.values.iter().map(|&v| 2.0 * (v as f32).sqrt()).collect();
    Ok(p.out
        .iter()
        .zip(&d)
        .map(|(&r, &own)| match r {
            0 if own > 0 => 2.0 * (own as f32).sqrt(),
            0 => 0.0,
            r => dia[r as usize - 1],
        })
        .collect())
}

/// Per-phase accumulation over slabs.
#[derive(Default)]
struct Acc {
    counts: BTreeMap<u32, u64>,
    unbounded: u64,
    /// Smallest exact limit (squared radius) of the windows that used a
    /// ladder, and the largest ratio.
    exact_up_to: Option<u32>,
    ratio: f64,
}

type Fill<'a> = &'a (dyn Fn(usize, usize, &mut [u8]) + Sync);

fn run(
    dims: [usize; 3],
    voxel: f64,
    opts: &ThicknessOptions,
    progress: Progress,
    fill: Fill,
) -> Result<Thickness> {
    if !(voxel.is_finite() && voxel > 0.0) {
        return Err(AnalysisError::Input(format!(
            "thickness: voxel size {voxel} must be > 0"
        )));
    }
    let bin_width = opts.bin_width.unwrap_or(voxel);
    if opts.work_per_voxel.is_nan() || opts.work_per_voxel <= 0.0 {
        return Err(AnalysisError::Input(format!(
            "thickness: work per voxel {} must be > 0",
            opts.work_per_voxel
        )));
    }
    if !(bin_width.is_finite() && bin_width > 0.0) {
        return Err(AnalysisError::Input(format!(
            "thickness: bin width {bin_width} must be > 0"
        )));
    }
    let (p, working_bytes) = plan(dims, opts.memory_limit)?;
    let [nx, ny, nz] = dims;
    let layer = nx * ny;
    let exact = p.halo == 0;
    let cap = if exact {
        u32::MAX
    } else {
        (p.halo * p.halo) as u32
    };
    let mut acc = [Acc::default(), Acc::default()];
    let mut slabs = 0;
    let mut labels = Vec::new();
    let wanted = [opts.measure_solid, opts.measure_pore];
    // Progress in layers: sampling, then each phase measured.
    let total = nz * (1 + wanted.iter().filter(|&&w| w).count());
    let mut done = 0;
    for z0 in (0..nz).step_by(p.slab.max(1)) {
        let z1 = (z0 + p.slab).min(nz);
        let (w0, w1) = (z0.saturating_sub(2 * p.halo), (z1 + 2 * p.halo).min(nz));
        labels.clear();
        labels.resize((w1 - w0) * layer, 0);
        // Sample in runs of 16 layers, reporting each in one-window mode.
        for k in (w0..w1).step_by(16) {
            let k1 = (k + 16).min(w1);
            fill(k, k1, &mut labels[(k - w0) * layer..(k1 - w0) * layer]);
            if exact {
                done += k1 - k;
                progress(done, total);
            }
        }
        if !exact {
            done += z1 - z0;
            progress(done, total);
        }
        let wdims = [nx, ny, w1 - w0];
        let centres = z0.saturating_sub(p.halo) - w0..(z1 + p.halo).min(nz) - w0;
        for ((acc, phase), _) in acc
            .iter_mut()
            .zip([SOLID, PORE])
            .zip(wanted)
            .filter(|(_, w)| *w)
        {
            let job = Job {
                labels: &labels,
                dims: wdims,
                cap,
                centres: centres.clone(),
                paint: z0 - w0..z1 - w0,
                work: opts.work_per_voxel,
            };
            measure(&job, phase, acc)?;
            done += z1 - z0;
            progress(done, total);
        }
        slabs += 1;
    }
    let mut wanted = [opts.measure_solid, opts.measure_pore].into_iter();
    let [solid, pore] = acc.map(|a| {
        if !wanted.next().unwrap_or(false) {
            PhaseThickness::Skipped
        } else if a.unbounded > 0 {
            PhaseThickness::Unbounded {
                voxels: a.unbounded,
            }
        } else if a.counts.is_empty() {
            PhaseThickness::Empty
        } else {
            let mut s = summarize(&a.counts, voxel, bin_width, cap);
            s.exact_up_to = a.exact_up_to.map(|c| histogram::diameter(c, voxel));
            s.ladder_ratio = a.exact_up_to.map_or(1.0, |_| a.ratio);
            PhaseThickness::Measured(s)
        }
    });
    Ok(Thickness {
        voxel,
        dims,
        solid,
        pore,
        slabs,
        diameter_cap: (!exact).then_some(2.0 * p.halo as f64 * voxel),
        working_bytes,
    })
}

/// One window to measure: its labels and `dims`, the squared distance
/// `cap` (`u32::MAX`: one window, exact), the planes of ball centres and of
/// painted voxels, the work budget.
struct Job<'a> {
    labels: &'a [u8],
    dims: [usize; 3],
    cap: u32,
    centres: std::ops::Range<usize>,
    paint: std::ops::Range<usize>,
    work: f64,
}

/// Adds the thickness counts of the planes `paint` of one window for
/// `phase` to `acc`. Squared distances over `cap` are clamped to `cap + 1`.
fn measure(job: &Job, phase: u8, acc: &mut Acc) -> Result<()> {
    let Job {
        labels,
        dims,
        cap,
        ref centres,
        ref paint,
        work,
    } = *job;
    let (centres, paint) = (centres.clone(), paint.clone());
    let layer = dims[0] * dims[1];
    let mut d = edt_squared(labels, dims, |l| l == phase);
    if cap == u32::MAX {
        // One window: INF means no wall anywhere in the grid.
        let n = d.par_iter().filter(|&&v| v == INF).count() as u64;
        if n > 0 {
            acc.unbounded += n;
            return Ok(());
        }
    } else {
        d.par_iter_mut().for_each(|v| *v = (*v).min(cap + 1));
    }
    let p = paint_phase(&d, dims, centres, paint.clone(), work);
    if let Some(cut) = p.exact_up_to {
        acc.exact_up_to = Some(acc.exact_up_to.map_or(cut, |c: u32| c.min(cut)));
        acc.ratio = acc.ratio.max(p.ratio);
    }
    let ranks = p.out;
    let distinct = p.values.len();
    let own = &d[paint.start * layer..paint.end * layer];
    let (per_rank, missed) = ranks
        .par_chunks(1 << 16)
        .zip(own.par_chunks(1 << 16))
        .fold(
            || (vec![0u64; distinct], Vec::new()),
            |(mut c, mut m), (r, o)| {
                for (&r, &o) in r.iter().zip(o) {
                    if r > 0 {
                        c[r as usize - 1] += 1;
                    } else if o > 0 {
                        m.push(o);
                    }
                }
                (c, m)
            },
        )
        .reduce(
            || (vec![0u64; distinct], Vec::new()),
            |(mut a, mut m), (b, n)| {
                a.iter_mut().zip(&b).for_each(|(a, b)| *a += b);
                m.extend(n);
                (a, m)
            },
        );
    // Every phase voxel lies in a ridge ball, so exact painting misses
    // none; under a ladder a voxel may fall between rungs and the exact
    // balls. Its own ball is a valid lower bound.
    debug_assert!(
        p.exact_up_to.is_some() || missed.is_empty(),
        "{} voxels unpainted",
        missed.len()
    );
    for v in missed {
        *acc.counts.entry(v).or_default() += 1;
    }
    for (c, &d) in per_rank.into_iter().zip(&p.values) {
        if c > 0 {
            *acc.counts.entry(d).or_default() += c;
        }
    }
    Ok(())
}
