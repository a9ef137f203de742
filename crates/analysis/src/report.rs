//! The whole analysis of a model in one call: volume, area, connectivity
//! and thickness on one grid, with the accuracy of each figure.

use crate::connectivity::{self, connectivity, Connectivity};
use crate::error::{AnalysisError, Result};
use crate::grid::{Grid, Sampler};
use crate::measure::{measure, Measures};
use crate::thickness::{thickness, Thickness, ThicknessOptions};
use microfrep_core::Shape;
use std::time::Instant;

/// What to compute, and within which memory.
#[derive(Clone, Debug)]
pub struct AnalyzeOptions {
    /// Label connected components of solid and pore space and compute the
    /// Euler characteristic ([`Report::connectivity`]); on by default.
    pub connectivity: bool,
    /// Compute the local thickness of solid and pores
    /// ([`Report::thickness`]); on by default, and the most expensive stage.
    pub thickness: bool,
    /// Options of the thickness stage (bin width, memory, phases, work budget).
    pub thickness_options: ThicknessOptions,
    /// Most bytes the voxel stages may use; jobs predicted to need more are
    /// refused before they start.
    pub memory_limit: u64,
}

impl Default for AnalyzeOptions {
    fn default() -> Self {
        AnalyzeOptions {
            connectivity: true,
            thickness: true,
            thickness_options: ThicknessOptions::default(),
            memory_limit: 4 << 30,
        }
    }
}

/// The stage a progress report is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Volume and area, counted in bricks.
    Measure,
    /// Component labelling, counted in voxel layers.
    Connectivity,
    /// Local thickness, in the thickness module's units.
    Thickness,
}

impl Stage {
    /// The stage's name for progress messages, in lower case
    /// (for example `"volume and area"`).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Measure => "volume and area",
            Stage::Connectivity => "connectivity",
            Stage::Thickness => "thickness",
        }
    }
}

/// Results of [`analyze`].
#[derive(Clone, Debug)]
pub struct Report {
    /// The grid all figures were computed on (box in model units, voxels per
    /// axis and voxel size).
    pub grid: Grid,
    /// Whether the figures are inside a region model (else the bounds).
    pub region: bool,
    /// Volume, region volume and area with their coarse-grid estimates, and
    /// the random-sample check on the volume.
    pub measures: Measures,
    /// Components and Euler characteristic; `None` when not asked for.
    pub connectivity: Option<Connectivity>,
    /// Local thickness of solid and pores; `None` when not asked for.
    pub thickness: Option<Thickness>,
    /// Every attribute channel's integral, mean, minimum and maximum over
    /// the solid (empty for shapes without channels).
    pub attributes: Vec<crate::attributes::AttributeStats>,
    /// Wall-clock seconds of the measure, connectivity and thickness stages.
    pub seconds: [f64; 3],
}

impl Report {
    /// Solid volume (inside the region, if any).
    pub fn volume(&self) -> f64 {
        self.measures.volume.value
    }

    /// The volume's error estimate: the Richardson estimate, or where the
    /// volume misses part of the sampled volume (features between the
    /// nodes, see [`Report::missed_volume`]) that difference plus three of
    /// the sampling's standard deviations.
    pub fn volume_error(&self) -> f64 {
        let r = self.measures.volume.error();
        match self.missed_volume() {
            Some(d) => r.max(d.abs() + 3.0 * self.measures.sampled_volume_error),
            None => r,
        }
    }

    /// Where the measured volume and the volume sampled at random points
    /// (see [`Measures::sampled_volume`]) differ by more than three of the
    /// sampling's standard deviations and the Richardson error together:
    /// sampled minus measured. Features smaller than a voxel were missed by
    /// the fine and the coarse grid alike.
    pub fn missed_volume(&self) -> Option<f64> {
        let m = &self.measures;
        let d = m.sampled_volume - m.volume.value;
        (d.abs() > 3.0 * m.sampled_volume_error + m.volume.error()
            && d.abs() > 1e-9 * m.region_volume.value.abs())
        .then_some(d)
    }

    /// Volume of the region, or of the bounds.
    pub fn region_volume(&self) -> f64 {
        self.measures.region_volume.value
    }

    /// Error estimate of [`Report::region_volume`] (cubic model units), from
    /// the difference between the fine and the coarse grid.
    pub fn region_volume_error(&self) -> f64 {
        self.measures.region_volume.error()
    }

    /// Solid volume over region volume (relative density); NaN
    /// (undefined) when the region is empty.
    pub fn volume_fraction(&self) -> f64 {
        let r = self.region_volume();
        if r > 0.0 {
            self.volume() / r
        } else {
            f64::NAN
        }
    }

    /// Error bound of [`Report::volume_fraction`], propagated from the volume
    /// and region-volume errors (dimensionless); NaN for an empty region.
    pub fn volume_fraction_error(&self) -> f64 {
        let r = self.region_volume();
        if r > 0.0 {
            (self.volume_error() + self.volume_fraction() * self.region_volume_error()) / r
        } else {
            f64::NAN
        }
    }

    /// `1 - volume_fraction` (NaN, undefined, for an empty region).
    pub fn porosity(&self) -> f64 {
        1.0 - self.volume_fraction()
    }

    /// Area of the solid's surface `f = 0` inside the bounds (and region);
    /// faces cut by the bounds or the region are not counted.
    pub fn area(&self) -> f64 {
        self.measures.area.value
    }

    /// Error estimate of [`Report::area`] in square model units: a third of the
    /// smooth fine-minus-coarse difference plus the whole difference from
    /// cells around creases.
    pub fn area_error(&self) -> f64 {
        self.measures.area.error()
    }

    /// Area over solid volume; NaN (undefined) without solid.
    pub fn specific_surface(&self) -> f64 {
        if self.volume() > 0.0 {
            self.area() / self.volume()
        } else {
            f64::NAN
        }
    }

    /// Error bound of [`Report::specific_surface`] (per model unit), from the
    /// relative errors of area and volume added; NaN without solid.
    pub fn specific_surface_error(&self) -> f64 {
        let (a, v) = (self.area(), self.volume());
        if v > 0.0 {
            self.specific_surface()
                * (self.area_error() / a.max(f64::MIN_POSITIVE) + self.volume_error() / v)
        } else {
            f64::NAN
        }
    }

    /// Why some figures are undefined or the result is empty, for people:
    /// an empty region, no solid, or solid everywhere.
    pub fn notes(&self) -> Vec<String> {
        let mut out = Vec::new();
        let within = if self.region {
            "inside the region"
        } else {
            "in the box"
        };
        if self.region_volume() <= 0.0 {
            out.push(if self.region {
                "the region is empty inside the box: volume fraction, porosity and specific \
                 surface are undefined (check --region and --bounds)"
                    .to_string()
            } else {
                "the box has no volume: every figure is undefined".to_string()
            });
        } else if self.volume() <= 0.0 {
            out.push(format!(
                "no solid {within} at this resolution (voxels of {}): specific surface and \
                 thickness are undefined; a model thinner than a voxel needs a finer grid",
                microfrep_io::text::sig(self.grid.voxel_size(), 4)
            ));
        } else if self.volume() >= self.region_volume() && self.area() <= 0.0 {
            out.push(format!("solid everywhere {within}: no pores, no surface"));
        }
        if let Some(d) = self.missed_volume() {
            let m = &self.measures;
            out.push(format!(
                "the volume differs from the model sampled at a random point of every 2^3 \
                 voxels ({} ± {}) by {} %: features smaller than a voxel ({}) were missed \
                 (the area, connectivity and thickness miss them too); the volume's ± \
                 includes the difference; use a finer --resolution",
                microfrep_io::text::sig(m.sampled_volume, 5),
                microfrep_io::text::sig(m.sampled_volume_error, 2),
                microfrep_io::text::sig(100.0 * d / m.sampled_volume.max(f64::MIN_POSITIVE), 3),
                microfrep_io::text::sig(self.grid.voxel_size(), 4)
            ));
        }
        out
    }
}

/// Analyses the solid `f >= 0` of `solid` (inside `region >= 0` when given)
/// on `grid`. `progress(stage, done, total)`.
pub fn analyze(
    solid: &Shape,
    region: Option<&Shape>,
    grid: Grid,
    opts: &AnalyzeOptions,
    progress: &(dyn Fn(Stage, usize, usize) + Sync),
) -> Result<Report> {
    check_precision(solid, &grid, "the model")?;
    if let Some(r) = region {
        check_precision(r, &grid, "the region")?;
    }
    let need = crate::measure::predict_bytes(&grid);
    if need > opts.memory_limit as f64 {
        return Err(AnalysisError::Memory(format!(
            "measuring a grid of {:?} voxels needs about {:.0} MiB, over the limit of {:.0} MiB; \
             lower the resolution",
            grid.dims,
            need / MIB,
            opts.memory_limit as f64 / MIB
        )));
    }
    let sampler = Sampler::new(solid, region, grid.clone());
    if opts.connectivity {
        let need = connectivity::predict_bytes(&sampler);
        if need > opts.memory_limit as f64 {
            return Err(AnalysisError::Memory(format!(
                "connectivity on a grid of {:?} voxels needs about {:.0} MiB, over the limit \
                 of {:.0} MiB; lower the resolution",
                grid.dims,
                need / MIB,
                opts.memory_limit as f64 / MIB
            )));
        }
    }
    let t = Instant::now();
    let measures = measure(solid, region, &grid, &|d, n| progress(Stage::Measure, d, n));
    let mut seconds = [t.elapsed().as_secs_f64(), 0.0, 0.0];
    let connectivity = if opts.connectivity {
        let t = Instant::now();
        let c = connectivity(&sampler, &|d, n| progress(Stage::Connectivity, d, n))?;
        seconds[1] = t.elapsed().as_secs_f64();
        Some(c)
    } else {
        None
    };
    let thickness = if opts.thickness {
        let t = Instant::now();
        let mut topts = opts.thickness_options.clone();
        topts.memory_limit = topts.memory_limit.min(opts.memory_limit);
        let th = thickness(&sampler, &topts, &|d, n| progress(Stage::Thickness, d, n))?;
        seconds[2] = t.elapsed().as_secs_f64();
        Some(th)
    } else {
        None
    };
    let attributes = crate::attributes::attributes(solid, region, &grid);
    Ok(Report {
        grid,
        region: region.is_some(),
        attributes,
        measures,
        connectivity,
        thickness,
        seconds,
    })
}

const MIB: f64 = 1024.0 * 1024.0;

/// Refuses a model whose f32 batch values disagree with its f64 values in
/// the grid's box (see [`microfrep_io::precision::check_agreement`]).
fn check_precision(shape: &Shape, grid: &Grid, what: &str) -> Result<()> {
    use microfrep_io::precision::{check_agreement, probe_points, PROBE_POINTS};
    let pts = probe_points(grid.lo, grid.hi, PROBE_POINTS);
    let axis = |a: usize| -> Vec<f32> { pts.iter().map(|p| p[a] as f32).collect() };
    let mut v32 = vec![0.0f32; pts.len()];
    shape.batch().eval(&axis(0), &axis(1), &axis(2), &mut v32);
    let mut pe = shape.point();
    let v64: Vec<f64> = pts.iter().map(|p| pe.eval(*p)).collect();
    check_agreement(&pts, &v32, &v64)
        .map_err(|e| AnalysisError::Input(format!("cannot analyse {what}: {e}")))
}
