//! [`ScanField`] (signed distance to an iso surface of a scan) and
//! [`IntensityField`] (the scan's own values), both [`Field`]s.

use crate::error::{too_large_field, Result, ScanError};
use crate::grid::{widen, Lattice, Pyramid, Sample};
use crate::sdf::{self, Scaled, Src, Ticker, NONE, SURFEL_BYTES};
use crate::smooth;
use crate::volume::{no_progress, Progress, Samples, Volume, DEFAULT_MEMORY_LIMIT};
use microfrep_core::{Field, Interval};
use rayon::prelude::*;
use std::sync::Arc;

/// Options of [`ScanField::build`].
#[derive(Clone, Debug, PartialEq)]
pub struct ScanOptions {
    /// Iso value: a sample with value `>= iso` is inside (e.g. 300 HU for
    /// bone in CT, 0.5 for occupancy bytes, 0 for a sampled FRep field).
    pub iso: f64,
    /// Standard deviation in mm of a Gaussian applied to the intensities
    /// first (0: none). Smoothing costs a 4-byte copy of the volume.
    pub smooth: f64,
    /// Most bytes the build may allocate on top of the volume.
    pub memory_limit: u64,
    /// Name of the field (for diagnostics).
    pub name: String,
}

impl ScanOptions {
    /// Options for an iso value: no smoothing, the default memory limit,
    /// name `scan`.
    pub fn new(iso: f64) -> ScanOptions {
        ScanOptions {
            iso,
            smooth: 0.0,
            memory_limit: DEFAULT_MEMORY_LIMIT,
            name: "scan".into(),
        }
    }
}

/// The signed distance in mm to the iso surface of a volume, positive
/// inside (intensity `>= iso`), as a [`Field`].
///
/// Inside the voxel box the value is the trilinear interpolation of a grid
/// of distances at the sample centres (see [`ScanField::build`] for how
/// they are computed). The solid is also cut by the box of the voxels
/// (half a voxel beyond the outer sample centres): the value is
/// `min(distance at the clamped point, signed distance to the box)`, so it
/// is negative everywhere outside the box, with a magnitude that never
/// exceeds the true distance to the solid, and meshing and slicing bounds
/// stay finite. Intervals come from a min/max pyramid of the grid (exact
/// for the interpolant up to the block structure) combined with the box.
#[derive(Clone, Debug)]
pub struct ScanField {
    name: String,
    lat: Lattice,
    values: Vec<f32>,
    pyramid: Pyramid,
    lo: [f64; 3],
    hi: [f64; 3],
    seeds: usize,
    iso: f64,
}

/// Bytes [`ScanField::build`] allocates for a volume of `dims` with the
/// given smoothing, not counting the surface elements (one per voxel next
/// to the surface, [`surface_bytes`] each).
pub fn plan_bytes(dims: [usize; 3], spacing: [f64; 3], smooth_mm: f64) -> u64 {
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    let plane = (dims[0] * dims[1]) as u64;
    let smooth = if smooth_mm > 0.0 {
        let r = smooth::radius(smooth_mm, spacing[2], dims[2]) as u64;
        n * 4 + (2 * r + 2) * plane * 4
    } else {
        0
    };
    n * 8 + smooth + Pyramid::bytes(dims)
}

/// Bytes of one surface element (one per voxel next to the surface).
pub fn surface_bytes() -> u64 {
    SURFEL_BYTES
}

impl ScanField {
    /// Builds the field of `vol` at `opts.iso` (see the crate docs for the
    /// method). Errors: a volume with fewer than 2 samples on an axis, a
    /// non-finite sample, an iso value outside the samples' range, or more
    /// memory than `opts.memory_limit`.
    pub fn build(vol: &Volume, opts: &ScanOptions) -> Result<ScanField> {
        ScanField::build_with_progress(vol, opts, &no_progress)
    }

    /// [`ScanField::build`] with a progress callback (work units done,
    /// total).
    pub fn build_with_progress(
        vol: &Volume,
        opts: &ScanOptions,
        progress: Progress,
    ) -> Result<ScanField> {
        if vol.dims.iter().any(|&d| d < 2) {
            return Err(ScanError::Invalid(format!(
                "a scan field needs at least 2 samples on each axis, the volume has {:?}",
                vol.dims
            )));
        }
        if vol.len() >= u32::MAX as usize {
            return Err(ScanError::Invalid(format!(
                "volume dims {:?} are too large for a scan field",
                vol.dims
            )));
        }
        if !opts.iso.is_finite() {
            return Err(ScanError::Invalid(format!(
                "iso value must be finite, got {}",
                opts.iso
            )));
        }
        smooth::check_width(opts.smooth, vol.dims, vol.spacing).map_err(ScanError::Invalid)?;
        let need = plan_bytes(vol.dims, vol.spacing, opts.smooth);
        if need > opts.memory_limit {
            return Err(too_large_field(vol, need, opts.memory_limit));
        }
        let lat = Lattice {
            dims: vol.dims,
            origin: vol.origin,
            spacing: vol.spacing,
        };
        let nz = vol.dims[2] as u64;
        let stages = if opts.smooth > 0.0 { 9 } else { 6 };
        let t = Ticker::new(stages * nz, progress);
        let (values, seeds) = if opts.smooth > 0.0 {
            let mut f = vol.to_f32();
            smooth::gaussian(&mut f, vol.dims, vol.spacing, opts.smooth, &|_| t.tick(nz));
            let src = Scaled {
                data: &f[..],
                slope: 1.0,
                intercept: 0.0,
            };
            distances(&src, &lat, opts, need, &t)?
        } else {
            let (s, b) = (vol.slope, vol.intercept);
            match &vol.samples {
                Samples::U8(d) => distances(&scaled(d, s, b), &lat, opts, need, &t)?,
                Samples::I8(d) => distances(&scaled(d, s, b), &lat, opts, need, &t)?,
                Samples::U16(d) => distances(&scaled(d, s, b), &lat, opts, need, &t)?,
                Samples::I16(d) => distances(&scaled(d, s, b), &lat, opts, need, &t)?,
                Samples::F32(d) => distances(&scaled(d, s, b), &lat, opts, need, &t)?,
            }
        };
        let pyramid = Pyramid::new(&lat, &values);
        t.tick(nz);
        let [lo, hi] = vol.bounds();
        Ok(ScanField {
            name: opts.name.clone(),
            lat,
            values,
            pyramid,
            lo,
            hi,
            seeds,
            iso: opts.iso,
        })
    }

    /// Samples per axis of the distance grid (the volume's).
    pub fn dims(&self) -> [usize; 3] {
        self.lat.dims
    }

    /// Centre of sample (0, 0, 0), mm.
    pub fn origin(&self) -> [f64; 3] {
        self.lat.origin
    }

    /// Sample spacing, mm.
    pub fn spacing(&self) -> [f64; 3] {
        self.lat.spacing
    }

    /// Signed distances (mm) at the sample centres, x fastest.
    pub fn distances(&self) -> &[f32] {
        &self.values
    }

    /// The box of the voxels, `[min, max]` mm; the field is negative
    /// outside it.
    pub fn bounds(&self) -> [[f64; 3]; 2] {
        [self.lo, self.hi]
    }

    /// Voxels next to the surface (those that carry a surface element).
    pub fn surface_voxels(&self) -> usize {
        self.seeds
    }

    /// The iso value the field was built at.
    pub fn iso(&self) -> f64 {
        self.iso
    }

    /// Bytes the field holds.
    pub fn bytes(&self) -> u64 {
        self.values.len() as u64 * 4 + Pyramid::bytes(self.lat.dims)
    }

    /// As a shared [`Field`], ready for `Expr::field`.
    pub fn into_field(self) -> Arc<dyn Field> {
        Arc::new(self)
    }

    #[inline]
    fn value_grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|v| v.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let (d, gd) = self.lat.trilinear(&self.values, p);
        let (b, gb) = box_distance(p, self.lo, self.hi);
        if b < d {
            (b, gb)
        } else {
            (d, gd)
        }
    }
}

fn scaled<T>(data: &[T], slope: f64, intercept: f64) -> Scaled<'_, T> {
    Scaled {
        data,
        slope,
        intercept,
    }
}

/// Runs the transform on one source and returns the distances and seed count.
fn distances<S: Src>(
    src: &S,
    lat: &Lattice,
    opts: &ScanOptions,
    planned: u64,
    t: &Ticker,
) -> Result<(Vec<f32>, usize)> {
    sdf::check_samples(src, lat, opts.iso)?;
    let counts = sdf::count_seeds(src, lat, opts.iso, t);
    let seeds: usize = counts.iter().sum();
    let need = planned + seeds as u64 * SURFEL_BYTES;
    if need > opts.memory_limit {
        return Err(ScanError::TooLarge {
            what: format!(
                "the distance transform of {} x {} x {} voxels with {seeds} surface voxels",
                lat.dims[0], lat.dims[1], lat.dims[2]
            ),
            need,
            limit: opts.memory_limit,
            hint: "crop or downsample the volume (ReadOptions::crop, ::step), or raise the limit"
                .into(),
        });
    }
    let n = lat.dims.iter().product::<usize>();
    let mut feat = vec![NONE; n];
    let surfels = sdf::surfels(src, lat, opts.iso, &counts, &mut feat, t);
    let mut d2 = vec![0f32; n];
    sdf::feature_transform(lat, &mut feat, &mut d2, t);
    sdf::signed_distances(src, lat, opts.iso, &feat, &surfels, &mut d2, t);
    Ok((d2, seeds))
}

/// Signed distance to the box `[lo, hi]`, positive inside, and its gradient.
#[inline]
fn box_distance(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> (f64, [f64; 3]) {
    let mut q = [0.0f64; 3];
    let mut dq = [0.0f64; 3];
    let mut outside = false;
    for a in 0..3 {
        if p[a] < lo[a] {
            q[a] = lo[a] - p[a];
            dq[a] = -1.0;
            outside = true;
        } else if p[a] > hi[a] {
            q[a] = p[a] - hi[a];
            dq[a] = 1.0;
            outside = true;
        }
    }
    if outside {
        let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
        let g = std::array::from_fn(|a| -q[a] / len * dq[a]);
        return (-len, g);
    }
    let mut best = f64::INFINITY;
    let mut g = [0.0; 3];
    for a in 0..3 {
        let (l, h) = (p[a] - lo[a], hi[a] - p[a]);
        if l < best {
            best = l;
            g = [0.0; 3];
            g[a] = 1.0;
        }
        if h < best {
            best = h;
            g = [0.0; 3];
            g[a] = -1.0;
        }
    }
    (best, g)
}

/// Bounds of [`box_distance`] over a box: the least corner value below (it
/// is concave), the nearest-face distance at the point nearest the centre
/// above.
fn box_interval(b: [Interval; 3], lo: [f64; 3], hi: [f64; 3]) -> Interval {
    let mut low = f64::INFINITY;
    for c in 0..8 {
        let p: [f64; 3] = std::array::from_fn(|a| if c >> a & 1 == 0 { b[a].lo } else { b[a].hi });
        low = low.min(box_distance(p, lo, hi).0);
    }
    let mut up = f64::INFINITY;
    for a in 0..3 {
        let c = 0.5 * (lo[a] + hi[a]);
        let x = c.clamp(b[a].lo, b[a].hi);
        up = up.min((x - lo[a]).min(hi[a] - x));
    }
    let (l, u) = widen(low, up);
    Interval::new(l, u)
}

impl Field for ScanField {
    fn name(&self) -> &str {
        &self.name
    }

    fn is_signed_distance(&self) -> bool {
        true
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.value_grad(p).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.value_grad(p)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let r = self.lat.node_range(b);
        let (dl, dh) = self.pyramid.range(self.lat.dims, &self.values, r);
        let (dl, dh) = widen(dl, dh);
        let bi = box_interval(b, self.lo, self.hi);
        Interval::new(dl.min(bi.lo), dh.min(bi.hi))
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        let n = out.len();
        let one = |i: usize| self.value_grad([x[i] as f64, y[i] as f64, z[i] as f64]).0 as f32;
        if n >= 1 << 14 {
            out.par_chunks_mut(4096).enumerate().for_each(|(c, o)| {
                for (m, v) in o.iter_mut().enumerate() {
                    *v = one(c * 4096 + m);
                }
            });
        } else {
            for (i, v) in out.iter_mut().enumerate() {
                *v = one(i);
            }
        }
    }
}

/// The volume's own values (scaled), trilinear between sample centres and
/// clamped to the nearest boundary sample outside, as a [`Field`]. For
/// models that threshold the scan themselves (`I(p) - 300` is bone, and
/// combine it with the volume's box to keep it bounded). Holds the volume
/// (shared) and a min/max pyramid; no copy of the samples.
#[derive(Clone, Debug)]
pub struct IntensityField {
    name: String,
    vol: Arc<Volume>,
    lat: Lattice,
    pyramid: Pyramid,
}

impl IntensityField {
    /// The field of `vol`; its samples must be finite and at least 2 per
    /// axis.
    pub fn new(name: &str, vol: Arc<Volume>) -> Result<IntensityField> {
        if vol.dims.iter().any(|&d| d < 2) {
            return Err(ScanError::Invalid(format!(
                "an intensity field needs at least 2 samples on each axis, the volume has {:?}",
                vol.dims
            )));
        }
        if let (_, _, Some(i)) = vol.range() {
            return Err(ScanError::NotFinite {
                index: vol.unindex(i),
                value: vol.value_at(i) as f32,
            });
        }
        let lat = Lattice {
            dims: vol.dims,
            origin: vol.origin,
            spacing: vol.spacing,
        };
        let pyramid = match &vol.samples {
            Samples::U8(d) => Pyramid::new(&lat, d),
            Samples::I8(d) => Pyramid::new(&lat, d),
            Samples::U16(d) => Pyramid::new(&lat, d),
            Samples::I16(d) => Pyramid::new(&lat, d),
            Samples::F32(d) => Pyramid::new(&lat, d),
        };
        Ok(IntensityField {
            name: name.to_string(),
            vol,
            lat,
            pyramid,
        })
    }

    /// The volume.
    pub fn volume(&self) -> &Arc<Volume> {
        &self.vol
    }

    fn raw<T: Sample>(&self, d: &[T], p: [f64; 3]) -> (f64, [f64; 3]) {
        let (v, g) = self.lat.trilinear(d, p);
        let s = self.vol.slope;
        (v * s + self.vol.intercept, g.map(|c| c * s))
    }

    #[inline]
    fn value_grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|v| v.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        match &self.vol.samples {
            Samples::U8(d) => self.raw(d, p),
            Samples::I8(d) => self.raw(d, p),
            Samples::U16(d) => self.raw(d, p),
            Samples::I16(d) => self.raw(d, p),
            Samples::F32(d) => self.raw(d, p),
        }
    }
}

impl Field for IntensityField {
    fn name(&self) -> &str {
        &self.name
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.value_grad(p).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.value_grad(p)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let r = self.lat.node_range(b);
        let dims = self.lat.dims;
        let (l, h) = match &self.vol.samples {
            Samples::U8(d) => self.pyramid.range(dims, d, r),
            Samples::I8(d) => self.pyramid.range(dims, d, r),
            Samples::U16(d) => self.pyramid.range(dims, d, r),
            Samples::I16(d) => self.pyramid.range(dims, d, r),
            Samples::F32(d) => self.pyramid.range(dims, d, r),
        };
        let (l, h) = widen(l, h);
        let (s, c) = (self.vol.slope, self.vol.intercept);
        let (a, b) = (l * s + c, h * s + c);
        Interval::new(a.min(b), a.max(b))
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for (i, v) in out.iter_mut().enumerate() {
            *v = self.value_grad([x[i] as f64, y[i] as f64, z[i] as f64]).0 as f32;
        }
    }
}
