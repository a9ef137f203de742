//! What a fill built, measured on the built model at voxels tied to the
//! structure, never guessed from a coarse grid over the whole part.
//!
//! - **Voxel size.** The thinnest designed feature `f` (the strut diameter
//!   where it is known in closed form, else the 10th percentile of the
//!   wall thickness measured in a pilot cell at a 32nd of the cell) sets
//!   the voxel: `f / voxels_across` (default 14). The skin, measured by
//!   rays, does not; the connectivity grid resolves the thinner of the two.
//! - **Density.** Cubes of one cell side, their centres on a fixed
//!   low-discrepancy sequence over the part's box grown by half a cube, so
//!   every point of the core is equally likely to be covered: the density
//!   is the ratio of the infill's volume to the core's volume over the
//!   cubes, its error twice the ratio estimator's standard error plus the
//!   measurement error of the volumes. Cubes are added (up to
//!   `max_boxes`) until the error is below `target_error`.
//! - **Thinnest wall or strut, pore size.** In the density cubes that lie
//!   wholly inside the core: the thinnest is the 1st percentile of the
//!   inscribed diameters `2 sqrt(D)` on the ridge of the exact distance
//!   transform (a plate of n voxels reads n or n + 1, a cylinder of d
//!   voxels about d - 0.8: within a voxel, so 14 voxels across the
//!   thinnest feature keep it within 7 %), at its place; the 10th percentile and the mean are those of
//!   the local thickness (largest ball containing each voxel, the
//!   convention of BoneJ and PoreSpy).
//! - **Skin.** Rays along the inward normal from points on the part's
//!   surface, through the skin alone, to where it ends (bisected): minimum
//!   and mean over the rays.
//! - **Interconnectivity and components.** The whole part labelled at a
//!   voxel of at most a third of `f` (within a voxel budget; the report
//!   says when the budget made it coarser): solid components, the pore
//!   volume connected to the part's outside, closed pores, and whether the
//!   skin seals the pores in.

use super::{FillError, Filled, Structure};
use crate::load::Progress;
use microfrep_analysis::grid::{Sampler, PORE, SOLID};
use microfrep_analysis::thickness::local_thickness_field;
use microfrep_analysis::Grid;
use microfrep_core::{Interval, Shape};
use std::time::Instant;

/// How thoroughly to measure.
#[derive(Clone, Debug)]
pub struct MeasureOptions {
    /// Voxels across the thinnest designed feature (at least 8).
    pub voxels_across: f64,
    /// Density cubes at least and at most.
    pub min_boxes: usize,
    /// Density cubes at most.
    pub max_boxes: usize,
    /// Stop adding cubes once the density's error is below this.
    pub target_error: f64,
    /// Cubes for the thickness at most.
    pub thickness_boxes: usize,
    /// Voxels of the whole-part connectivity grid at most.
    pub connectivity_voxels: u64,
    /// Rays through the skin.
    pub rays: usize,
}

impl Default for MeasureOptions {
    fn default() -> Self {
        MeasureOptions {
            voxels_across: 14.0,
            min_boxes: 12,
            max_boxes: 48,
            target_error: 0.006,
            thickness_boxes: 6,
            connectivity_voxels: 24_000_000,
            rays: 1500,
        }
    }
}

impl MeasureOptions {
    /// Refuses options that cannot measure anything.
    pub fn check(&self) -> Result<(), FillError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.voxels_across) || !positive(self.target_error) {
            return Err(FillError::Option(
                "the report's voxels across a feature and target error must be positive".into(),
            ));
        }
        if self.min_boxes == 0 || self.max_boxes < self.min_boxes || self.rays == 0 {
            return Err(FillError::Option(
                "the report needs 1 <= min cubes <= max cubes and at least one skin ray".into(),
            ));
        }
        Ok(())
    }
}

/// A measured figure and its error (same units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Figure {
    /// The value.
    pub value: f64,
    /// Its error estimate.
    pub error: f64,
}

/// Local thickness of one phase in the interior cubes.
#[derive(Clone, Debug)]
pub struct ThicknessFigure {
    /// Thinnest (millimetres, error one voxel).
    pub min: f64,
    /// Where the thinnest voxel is.
    pub at: [f64; 3],
    /// 10th percentile.
    pub p10: f64,
    /// Mean.
    pub mean: f64,
}

/// The skin measured along normals.
#[derive(Clone, Debug)]
pub struct SkinFigure {
    /// Thinnest over the rays.
    pub min: f64,
    /// Where the thinnest ray starts.
    pub at: [f64; 3],
    /// Mean over the rays.
    pub mean: f64,
    /// Rays cast (that found the skin's inner side).
    pub rays: usize,
    /// Rays that did not leave the skin within three designed thicknesses
    /// (the skin is solid there: no core below it).
    pub unbounded: usize,
    /// Accuracy of each ray's length.
    pub error: f64,
}

/// Connectivity of the whole filled part.
#[derive(Clone, Debug)]
pub struct ConnectivityFigure {
    /// Voxel size of the grid.
    pub voxel: f64,
    /// Whether the voxel resolves the thinnest feature (at most half of it).
    pub resolved: bool,
    /// Solid components (26-connected).
    pub solid_components: usize,
    /// Fraction of the solid volume outside the largest component.
    pub loose_fraction: f64,
    /// Fraction of the pore volume inside the part connected to its outside.
    pub open_fraction: f64,
    /// Pores with no way out.
    pub closed_pores: usize,
    /// Percolation of the pores between opposite faces of the box.
    pub percolates: [bool; 3],
    /// Volume of the part (its solid and its pores) on the grid.
    pub part_volume: f64,
}

/// What [`measure`](super::Filled::measure) found.
#[derive(Clone, Debug)]
pub struct FillReport {
    /// Infill volume fraction inside the core.
    pub density: Figure,
    /// Surface of the infill per volume of the core in the density cubes
    /// (1/mm): with the part's volume, what sizes a mesh before it is made.
    pub area_per_volume: f64,
    /// The thinnest designed feature of the infill, which the voxels were
    /// sized from.
    pub feature: f64,
    /// Voxel size of the density and thickness cubes.
    pub voxel: f64,
    /// Side of the cubes.
    pub box_side: f64,
    /// Side of the cubes the walls and pores were measured in (the density
    /// cubes', or a half or quarter of it in a thin part).
    pub thickness_side: f64,
    /// Cubes measured for the density.
    pub boxes: usize,
    /// Cubes (wholly inside the core) measured for the thickness.
    pub thickness_boxes: usize,
    /// Wall or strut thickness.
    pub thinnest: Option<ThicknessFigure>,
    /// Pore size.
    pub pores: Option<ThicknessFigure>,
    /// The skin.
    pub skin: Option<SkinFigure>,
    /// Whole-part connectivity.
    pub connectivity: Option<ConnectivityFigure>,
    /// Whether a skin seals the pores in (no pore volume open to the
    /// outside); `None` without a skin.
    pub sealed: Option<bool>,
    /// Warnings (a structure that falls apart, an unresolved grid, ...).
    pub notes: Vec<String>,
    /// Seconds the measuring took.
    pub seconds: f64,
}

fn err(e: impl std::fmt::Display) -> FillError {
    FillError::Build(format!("measuring the fill: {e}"))
}

/// Measures `f` (see the module docs).
pub fn measure(
    f: &Filled,
    opts: &MeasureOptions,
    progress: Progress,
) -> Result<FillReport, FillError> {
    let mut r = measure_local(f, opts, progress)?;
    add_connectivity(f, &mut r, opts, progress)?;
    Ok(r)
}

/// Everything [`measure`] measures but the whole part's connectivity
/// (`connectivity` and `sealed` stay `None`): the figures that decide how
/// the part is written, so that [`add_connectivity`] can run beside the
/// writing.
pub fn measure_local(
    f: &Filled,
    opts: &MeasureOptions,
    progress: Progress,
) -> Result<FillReport, FillError> {
    opts.check()?;
    let t0 = Instant::now();
    let cell = f.options.cell;
    let mut notes = Vec::new();
    // Where the cubes go: candidates on a Halton sequence, kept if the
    // core may be inside them.
    let side = cell;
    let feature = designed_feature(f, side)?;
    let across = opts.voxels_across.max(8.0);
    let mut voxel = (feature / across).min(side / 16.0);
    // At most 128^3 voxels a cube.
    voxel = voxel.max(side / 128.0);
    let achieved = feature / voxel;
    if achieved < across - 1e-9 {
        notes.push(format!(
            "the thinnest designed feature ({feature:.4}) is {achieved:.1} voxels across in the \
             measuring cubes (asked {across}); figures of that size are less accurate"
        ));
    }
    // The volumes are measured by cutting each voxel at the field's roots
    // (accurate to a fraction of a percent for features 3 voxels across),
    // so the density cubes take a coarser voxel than the thickness.
    let density_voxel = (feature / 4.0).min(side / 16.0).max(side / 96.0);
    let boxes = place_boxes(f, side, opts.max_boxes * 4);
    if boxes.is_empty() {
        return Err(err("no cube of one cell fits the part's core"));
    }
    let quiet = |_: usize, _: usize| {};
    let mut inf = Vec::new();
    let mut core = Vec::new();
    let mut area = 0.0;
    let mut meas_err = 0.0;
    let mut estimate = (f64::NAN, f64::INFINITY);
    let mut interior = Vec::new();
    for (k, b) in boxes.iter().enumerate() {
        progress("measuring the density", k as u64, opts.max_boxes as u64);
        let grid = Grid::with_voxel(*b, density_voxel).map_err(err)?;
        let m = microfrep_analysis::measure(&f.infill, Some(&f.core), &grid, &quiet);
        if m.region_volume.value <= 0.0 {
            continue;
        }
        inf.push(m.volume.value);
        core.push(m.region_volume.value);
        area += m.area.value;
        meas_err += m.volume.error() + m.region_volume.error();
        if interior.len() < opts.thickness_boxes && wholly_inside(&f.core, &grown(b, 0.25)) {
            interior.push(*b);
        }
        if inf.len() >= opts.min_boxes {
            estimate = ratio(&inf, &core, meas_err);
            if estimate.1 <= opts.target_error || inf.len() >= opts.max_boxes {
                break;
            }
        }
    }
    if inf.len() < opts.min_boxes {
        estimate = ratio(&inf, &core, meas_err);
    }
    // A thin part (a pelvis, a plate) may hold no cube of a whole cell:
    // then the walls are measured in the halves and quarters of the
    // density cubes that it holds.
    let mut thickness_side = side;
    for k in [2usize, 4] {
        if !interior.is_empty() {
            break;
        }
        thickness_side = side / k as f64;
        'cubes: for b in boxes.iter().take(opts.max_boxes * 4) {
            for i in 0..k * k * k {
                let o = [i % k, (i / k) % k, i / (k * k)];
                let lo: [f64; 3] = std::array::from_fn(|a| b[0][a] + o[a] as f64 * thickness_side);
                let sub = [lo, lo.map(|v| v + thickness_side)];
                if wholly_inside(&f.core, &grown(&sub, 0.25)) {
                    interior.push(sub);
                    if interior.len() >= opts.thickness_boxes {
                        break 'cubes;
                    }
                }
            }
        }
    }
    let (thinnest, pores) = thickness(f, &interior, voxel, progress)?;
    if interior.is_empty() {
        notes.push(
            "no cube of a quarter cell lies wholly inside the core: wall and pore sizes not \
             measured"
                .into(),
        );
    } else if thickness_side < side {
        notes.push(format!(
            "walls and pores measured in cubes of {thickness_side:.4} (no cube of one cell lies \
             wholly inside the core): pores larger than that read small"
        ));
    }
    let skin = match (&f.skin, f.options.skin) {
        (Some(s), Some(t)) => Some(skin_rays(f, s, t, opts.rays)?),
        _ => None,
    };
    if let Some(s) = &skin {
        if s.unbounded > 0 {
            notes.push(format!(
                "{} of {} rays found no core below the skin within three skin thicknesses",
                s.unbounded,
                s.rays + s.unbounded
            ));
        }
    }
    Ok(FillReport {
        density: Figure {
            value: estimate.0,
            error: estimate.1,
        },
        area_per_volume: area / core.iter().sum::<f64>(),
        feature,
        voxel,
        box_side: side,
        thickness_side,
        boxes: inf.len(),
        thickness_boxes: interior.len(),
        thinnest,
        pores,
        skin,
        connectivity: None,
        sealed: None,
        notes,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Measures the whole part's connectivity into `r` (from
/// [`measure_local`]): components, open and closed pores, whether the
/// skin seals them, with their notes; its time is added to `r.seconds`.
pub fn add_connectivity(
    f: &Filled,
    r: &mut FillReport,
    opts: &MeasureOptions,
    progress: Progress,
) -> Result<(), FillError> {
    opts.check()?;
    let t0 = Instant::now();
    let feature = r.feature;
    let notes = &mut r.notes;
    // The connectivity grid must resolve the skin too (it decides whether
    // the skin seals the pores).
    let resolve = f.options.skin.map_or(feature, |t| feature.min(t));
    let connectivity = connectivity(f, resolve, opts.connectivity_voxels, progress)?;
    let sealed = f.skin.as_ref().map(|_| connectivity.open_fraction < 1e-3);
    if !connectivity.resolved {
        notes.push(format!(
            "connectivity measured at {:.4} voxels, more than half the thinnest feature \
             ({resolve:.4}): the part is too large for a finer grid within the budget",
            connectivity.voxel
        ));
    }
    if connectivity.solid_components > 1 && connectivity.loose_fraction > 1e-3 {
        notes.push(format!(
            "the solid falls apart into {} pieces ({:.2} % of its volume outside the largest): \
             loose pieces cannot be printed",
            connectivity.solid_components,
            100.0 * connectivity.loose_fraction
        ));
    }
    r.connectivity = Some(connectivity);
    r.sealed = sealed;
    r.seconds += t0.elapsed().as_secs_f64();
    Ok(())
}

/// Ratio estimate `sum a / sum b` with twice its standard error plus the
/// measurement error `m` (of the volumes, summed) relative to `sum b`.
fn ratio(a: &[f64], b: &[f64], m: f64) -> (f64, f64) {
    let n = a.len() as f64;
    let (sa, sb): (f64, f64) = (a.iter().sum(), b.iter().sum());
    let r = sa / sb;
    let var = if n > 1.0 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - r * y).powi(2))
            .sum::<f64>()
            / (n - 1.0)
    } else {
        f64::INFINITY
    };
    let se = (var / n).sqrt() / (sb / n);
    (r, 2.0 * se + m / sb)
}

/// The thinnest designed feature of the infill: the strut diameter, or the
/// 10th percentile of the walls in a pilot cell.
fn designed_feature(f: &Filled, side: f64) -> Result<f64, FillError> {
    let feat = match (f.options.structure, f.design.strut_radius) {
        (Structure::Struts(_), Some(r)) => 2.0 * r,
        _ => {
            let b = place_boxes(f, side, 64)
                .into_iter()
                .find(|b| wholly_inside(&f.core, b))
                .or_else(|| place_boxes(f, side, 1).first().copied());
            let Some(b) = b else {
                return Err(err("no cube of one cell fits the part's core"));
            };
            let grid = Grid::with_voxel(b, side / 32.0).map_err(err)?;
            let labels = Sampler::new(&f.infill, None, grid.clone()).all(&|_, _| {});
            let t = local_thickness_field(&labels, grid.dims, SOLID).map_err(err)?;
            let mut v: Vec<f32> = t
                .into_iter()
                .filter(|&x| x > 0.0 && x.is_finite())
                .collect();
            if v.is_empty() {
                side
            } else {
                v.sort_by(f32::total_cmp);
                v[v.len() / 10] as f64 * grid.voxel_size()
            }
        }
    };
    Ok(feat.max(side / 128.0))
}

/// Cubes of side `side` whose centres follow a Halton sequence over the
/// box grown by half a side, kept where the core may reach into them (by
/// intervals): each point of the core is covered alike.
fn place_boxes(f: &Filled, side: f64, max: usize) -> Vec<[[f64; 3]; 2]> {
    let b = f.bounds;
    let mut iv = f.core.interval();
    let mut out = Vec::new();
    for k in 1..=(64 * max as u64) {
        let u = super::part::halton3(k);
        let c: [f64; 3] =
            std::array::from_fn(|a| b.min[a] - 0.5 * side + u[a] * (b.max[a] - b.min[a] + side));
        let lo: [f64; 3] = std::array::from_fn(|a| c[a] - 0.5 * side);
        let hi: [f64; 3] = std::array::from_fn(|a| c[a] + 0.5 * side);
        let r = iv.eval(
            Interval::new(lo[0], hi[0]),
            Interval::new(lo[1], hi[1]),
            Interval::new(lo[2], hi[2]),
        );
        if r.hi >= 0.0 || r.may_be_nan() {
            out.push([lo, hi]);
            if out.len() == max {
                break;
            }
        }
    }
    out
}

/// The cube `b` grown by `k` of its side on every face (the padded grid
/// the thickness is measured on).
fn grown(b: &[[f64; 3]; 2], k: f64) -> [[f64; 3]; 2] {
    let pad = k * (b[1][0] - b[0][0]);
    [
        std::array::from_fn(|a| b[0][a] - pad),
        std::array::from_fn(|a| b[1][a] + pad),
    ]
}

/// Whether the core holds the whole cube (all of a 5^3 lattice of its
/// points inside, with the interval bound where it is tight).
fn wholly_inside(core: &Shape, b: &[[f64; 3]; 2]) -> bool {
    let r = core.interval().eval(
        Interval::new(b[0][0], b[1][0]),
        Interval::new(b[0][1], b[1][1]),
        Interval::new(b[0][2], b[1][2]),
    );
    if r.lo > 0.0 && !r.may_be_nan() {
        return true;
    }
    let mut ev = core.point();
    for i in 0..125 {
        let t = [i % 5, (i / 5) % 5, i / 25];
        let p: [f64; 3] =
            std::array::from_fn(|a| b[0][a] + (b[1][a] - b[0][a]) * t[a] as f64 / 4.0);
        if !(ev.eval(p) > 0.0) {
            return false;
        }
    }
    true
}

/// Local thickness of the model's solid and pores in the interior cubes.
fn thickness(
    f: &Filled,
    boxes: &[[[f64; 3]; 2]],
    voxel: f64,
    progress: Progress,
) -> Result<(Option<ThicknessFigure>, Option<ThicknessFigure>), FillError> {
    let mut phases = [Phase::default(), Phase::default()];
    for (k, b) in boxes.iter().enumerate() {
        progress("measuring walls and pores", k as u64, boxes.len() as u64);
        // Measured in the cube grown by a quarter cell, kept in the cube:
        // a wall cut by the grid's edge reads thin there (its largest
        // balls are centred outside).
        let grid = Grid::with_voxel(grown(b, 0.25), voxel).map_err(err)?;
        let labels = Sampler::new(&f.model, None, grid.clone()).all(&|_, _| {});
        for (slot, phase) in [(0, SOLID), (1, PORE)] {
            phases[slot].add(&grid, &labels, phase, b)?;
        }
    }
    let [a, b] = phases;
    Ok((a.figure(), b.figure()))
}

/// One phase's measurements over the cubes.
#[derive(Default)]
struct Phase {
    /// Local thickness (largest ball) of every voxel, mm.
    local: Vec<f32>,
    /// Inscribed diameters on the ridge of the distance transform, mm,
    /// with their places.
    ridge: Vec<(f32, [f64; 3])>,
}

impl Phase {
    fn add(
        &mut self,
        grid: &Grid,
        labels: &[u8],
        phase: u8,
        keep: &[[f64; 3]; 2],
    ) -> Result<(), FillError> {
        use microfrep_analysis::thickness::edt::{edt_squared, INF};
        let h = grid.voxel_size();
        let [nx, ny, nz] = grid.dims;
        let inside = |i: usize| {
            let c = grid.center([i % nx, (i / nx) % ny, i / (nx * ny)]);
            (0..3).all(|a| c[a] >= keep[0][a] && c[a] <= keep[1][a])
        };
        let t = local_thickness_field(labels, grid.dims, phase).map_err(err)?;
        for (i, &v) in t.iter().enumerate() {
            if v > 0.0 && v.is_finite() && inside(i) {
                self.local.push((v as f64 * h) as f32);
            }
        }
        // The ridge: voxels whose squared distance to the other phase is
        // at least their 26 neighbours'. There the inscribed ball's
        // diameter is 2 sqrt(D) voxels (a plate of n voxels reads n or
        // n + 1, a cylinder of d voxels about d - 0.8), without the
        // largest-ball rule's readings of one or two voxels at curved
        // surfaces and edges.
        let d = edt_squared(labels, grid.dims, |l| l == phase);
        let at = |x: usize, y: usize, z: usize| d[x + nx * (y + ny * z)];
        for z in 1..nz.saturating_sub(1) {
            for y in 1..ny - 1 {
                for x in 1..nx - 1 {
                    let v = at(x, y, z);
                    if v == 0 || v == INF {
                        continue;
                    }
                    let i = x + nx * (y + ny * z);
                    let mut top = true;
                    'n: for dz in 0..3 {
                        for dy in 0..3 {
                            for dx in 0..3 {
                                if at(x + dx - 1, y + dy - 1, z + dz - 1) > v {
                                    top = false;
                                    break 'n;
                                }
                            }
                        }
                    }
                    if top && inside(i) {
                        let dia = 2.0 * (v as f64).sqrt() * h;
                        self.ridge.push((dia as f32, grid.center([x, y, z])));
                    }
                }
            }
        }
        Ok(())
    }

    /// The thinnest (the 1st percentile of the ridge diameters, at its
    /// place), and the 10th percentile and mean of the local thickness.
    fn figure(mut self) -> Option<ThicknessFigure> {
        if self.local.is_empty() || self.ridge.is_empty() {
            return None;
        }
        self.local.sort_by(f32::total_cmp);
        self.ridge.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mean = self.local.iter().map(|&v| v as f64).sum::<f64>() / self.local.len() as f64;
        let (m, at) = self.ridge[self.ridge.len() / 100];
        let p10 = self.local[self.local.len() / 10] as f64;
        // The ridge reads a polyhedral pore whole where the largest balls
        // of its corners are smaller: the thinnest is never above the
        // 10th percentile.
        Some(ThicknessFigure {
            min: (m as f64).min(p10),
            at,
            p10,
            mean,
        })
    }
}

/// Skin thickness along inward normals from points on the part's surface.
fn skin_rays(f: &Filled, skin: &Shape, t: f64, rays: usize) -> Result<SkinFigure, FillError> {
    let part = &f.part;
    let b = f.bounds;
    let mut pe = part.point();
    let mut ge = part.grad();
    let mut se = skin.point();
    // Surface points: Halton points near the surface projected onto it by
    // Newton steps along the gradient.
    let band = t.max(f.options.cell * 0.25);
    let mut starts = Vec::new();
    let mut depth = Shape::new(f.depth.clone()).point();
    for k in 1..=(400 * rays as u64) {
        let u = super::part::halton3(k);
        let mut p: [f64; 3] = std::array::from_fn(|a| b.min[a] + u[a] * (b.max[a] - b.min[a]));
        // (`>=`: a cached part's depth is clamped, at no less than the band.)
        if depth.eval(p).abs() >= band {
            continue;
        }
        let mut ok = false;
        for _ in 0..8 {
            let (v, g) = ge.eval(p);
            let n2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
            if !(n2 > 0.0) || !v.is_finite() {
                break;
            }
            p = std::array::from_fn(|a| p[a] - v * g[a] / n2);
            if pe.eval(p).abs() < 1e-9 * (1.0 + t) {
                ok = true;
                break;
            }
        }
        if !ok {
            continue;
        }
        let (_, g) = ge.eval(p);
        let n = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        if !(n > 0.0) {
            continue;
        }
        starts.push((p, [g[0] / n, g[1] / n, g[2] / n]));
        if starts.len() == rays {
            break;
        }
    }
    if starts.is_empty() {
        return Err(err(
            "found no point on the part's surface to measure the skin from",
        ));
    }
    let reach = 3.0 * t;
    let steps = 96;
    let dt = reach / steps as f64;
    let tol = t * 1e-4;
    let mut lengths = Vec::new();
    let mut unbounded = 0;
    let mut min = (f64::INFINITY, [0.0; 3]);
    for (p, n) in &starts {
        let at = |s: f64| -> [f64; 3] { std::array::from_fn(|a| p[a] + s * n[a]) };
        // Just inside the surface the skin is solid; find where it ends.
        let mut prev = dt * 0.01;
        let mut end = None;
        for i in 1..=steps {
            let s = i as f64 * dt;
            if !(se.eval(at(s)) >= 0.0) {
                end = Some((prev, s));
                break;
            }
            prev = s;
        }
        let Some((mut lo, mut hi)) = end else {
            unbounded += 1;
            continue;
        };
        while hi - lo > tol {
            let mid = 0.5 * (lo + hi);
            if se.eval(at(mid)) >= 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let len = 0.5 * (lo + hi);
        if len < min.0 {
            min = (len, *p);
        }
        lengths.push(len);
    }
    let mean = if lengths.is_empty() {
        f64::NAN
    } else {
        lengths.iter().sum::<f64>() / lengths.len() as f64
    };
    Ok(SkinFigure {
        min: if lengths.is_empty() { reach } else { min.0 },
        at: min.1,
        mean: if lengths.is_empty() { reach } else { mean },
        rays: lengths.len(),
        unbounded,
        error: tol,
    })
}

/// Components and open pores of the whole part.
fn connectivity(
    f: &Filled,
    feature: f64,
    budget: u64,
    progress: Progress,
) -> Result<ConnectivityFigure, FillError> {
    let b = f.bounds;
    let size = b.size();
    let vol: f64 = size.iter().product();
    let want = feature / 3.0;
    let floor = (vol / budget as f64).cbrt();
    let voxel = want.max(floor);
    // Pad by two voxels so the part's outside surrounds it.
    let lo: [f64; 3] = std::array::from_fn(|a| b.min[a] - 2.0 * voxel);
    let hi: [f64; 3] = std::array::from_fn(|a| b.max[a] + 2.0 * voxel);
    let grid = Grid::with_voxel([lo, hi], voxel).map_err(err)?;
    let sampler = Sampler::new(&f.model, Some(&f.part), grid.clone());
    let c = microfrep_analysis::connectivity(&sampler, &|d, n| {
        progress("measuring connectivity", d as u64, n as u64)
    })
    .map_err(err)?;
    let total: f64 = c.solid_volumes.iter().sum();
    let largest = c.solid_volumes.iter().copied().fold(0.0, f64::max);
    Ok(ConnectivityFigure {
        voxel: grid.voxel_size(),
        resolved: grid.voxel_size() <= 0.5 * feature,
        solid_components: c.solid_components,
        loose_fraction: if total > 0.0 {
            1.0 - largest / total
        } else {
            0.0
        },
        open_fraction: if c.pore_volume > 0.0 {
            c.open_pore_fraction()
        } else {
            0.0
        },
        closed_pores: c.closed_pores,
        percolates: c.percolates,
        part_volume: total + c.pore_volume,
    })
}

/// Shells (connected pieces of surface: triangles sharing a vertex) of the
/// mesh file at `path`, its vertices welded where they coincide exactly.
pub fn mesh_shells(path: &std::path::Path) -> Result<usize, FillError> {
    let is_3mf = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("3mf"));
    if is_3mf {
        let meshes = microfrep_3mf::read_meshes(path).map_err(err)?;
        return Ok(meshes
            .iter()
            .map(|m| {
                let t = microfrep_meshfield::TriMesh::new(m.vertices.clone(), m.triangles.clone());
                t.map(|t| {
                    let (w, _) = t.weld(0.0);
                    shell_count(w.vertices.len(), &w.triangles)
                })
                .unwrap_or(0)
            })
            .sum());
    }
    let m = microfrep_meshfield::read::read_mesh(path).map_err(err)?;
    let (m, _) = m.weld(0.0);
    Ok(shell_count(m.vertices.len(), &m.triangles))
}

/// Connected components of triangles joined through shared vertices (the
/// mesher's census, see [`microfrep_mesh::check::ShellCensus`]; a triangle
/// naming a vertex past `vertices` counts as no shell).
pub fn shell_count(vertices: usize, triangles: &[[u32; 3]]) -> usize {
    let mut c = microfrep_mesh::check::ShellCensus::new();
    c.vertices(vertices);
    c.triangles(triangles);
    c.finish().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measure_options_that_cannot_measure_are_refused() {
        assert!(MeasureOptions::default().check().is_ok());
        let d = MeasureOptions::default;
        for bad in [
            MeasureOptions {
                voxels_across: 0.0,
                ..d()
            },
            MeasureOptions {
                target_error: f64::NAN,
                ..d()
            },
            MeasureOptions {
                min_boxes: 0,
                ..d()
            },
            MeasureOptions {
                max_boxes: 3,
                min_boxes: 4,
                ..d()
            },
            MeasureOptions { rays: 0, ..d() },
        ] {
            assert!(matches!(bad.check(), Err(FillError::Option(_))), "{bad:?}");
        }
    }

    #[test]
    fn shells_count_separate_pieces() {
        // Two triangles sharing a vertex, and a third apart.
        let t = [[0, 1, 2], [2, 3, 4], [5, 6, 7]];
        assert_eq!(shell_count(9, &t), 2);
        assert_eq!(shell_count(3, &[[0, 1, 2]]), 1);
    }

    #[test]
    fn ratio_error_shrinks_with_agreeing_samples() {
        let (r, e) = ratio(&[1.0, 1.0, 1.0], &[2.0, 2.0, 2.0], 0.0);
        assert_eq!(r, 0.5);
        assert_eq!(e, 0.0);
        let (r, e) = ratio(&[1.0, 0.0], &[2.0, 2.0], 0.0);
        assert_eq!(r, 0.25);
        assert!(e > 0.2);
    }
}

impl FillReport {
    /// The surface a mesh of the fill will carry (mm^2): the infill's
    /// surface per core volume times the part's volume (the skin's own
    /// surfaces, a small share of a dense fill's, left out). An estimate
    /// for sizing, not a figure to print.
    pub fn surface_estimate(&self) -> Option<f64> {
        let c = self.connectivity.as_ref()?;
        Some(self.area_per_volume * c.part_volume)
    }

    /// The report as JSON, with the keys `microfrep fill --json` prints
    /// (and `analyze --json` where they overlap: `volume_fraction`); what
    /// an output wrote is the caller's to add.
    pub fn to_json(&self, f: &Filled) -> serde_json::Value {
        self.to_json_with(f, &super::cli_option)
    }

    /// [`FillReport::to_json`] with the notes' option names spelled by
    /// `name`, as a front end spells them (see [`super::with_option_names`]).
    pub fn to_json_with(&self, f: &Filled, name: &dyn Fn(&str) -> String) -> serde_json::Value {
        use serde_json::json;
        let thickness = |t: &Option<ThicknessFigure>| {
            t.as_ref().map(|t| {
                json!({ "min": t.min, "at": t.at, "p10": t.p10, "mean": t.mean, "error": self.voxel })
            })
        };
        let target = match &f.options.density {
            super::Density::Constant(v) => json!(v),
            _ => serde_json::Value::Null,
        };
        let c = self.connectivity.as_ref();
        json!({
            "structure": f.options.structure.name(),
            "cell": f.options.cell,
            "density": { "target": target, "measured": self.density.value, "error": self.density.error },
            "volume_fraction": self.density.value,
            "volume_fraction_error": self.density.error,
            "skin": self.skin.as_ref().map(|s| json!({
                "target": f.options.skin, "min": s.min, "at": s.at, "mean": s.mean,
                "rays": s.rays, "error": s.error, "unbounded_rays": s.unbounded,
            })),
            "thinnest": thickness(&self.thinnest),
            "pore_size": thickness(&self.pores),
            "connectivity": c.map(|c| json!({
                "voxel": c.voxel, "resolved": c.resolved,
                "solid_components": c.solid_components, "loose_fraction": c.loose_fraction,
                "open_pore_fraction": c.open_fraction, "closed_pores": c.closed_pores,
                "percolates": c.percolates, "sealed_by_skin": self.sealed,
            })),
            "measured": {
                "voxel": self.voxel, "cube": self.box_side, "cubes": self.boxes,
                "thickness_cubes": self.thickness_boxes, "thickness_cube": self.thickness_side,
                "feature": self.feature,
                "seconds": self.seconds,
            },
            "notes": f.notes.iter().chain(&self.notes)
                .map(|n| super::with_option_names(n, name))
                .collect::<Vec<_>>(),
        })
    }
}
