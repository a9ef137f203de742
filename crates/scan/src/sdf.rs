//! From intensities and an iso value to a signed distance grid in mm.
//!
//! 1. Every voxel with a 6-neighbour on the other side of the iso value is
//!    a *seed*. Each seed gets a surface element: the iso surface of the
//!    intensities linearised at the voxel (the gradient taken one-sided
//!    across the nearest iso crossing on each axis that has one, central
//!    elsewhere), i.e. the foot point on that plane and its normal. Along
//!    an axis with a crossing the plane passes exactly through the linearly
//!    interpolated crossing, so the surface position is sub-voxel.
//! 2. An exact Euclidean feature transform over the seed voxels, with the
//!    voxel spacing of each axis: linear sweeps along z, then the lower
//!    envelope of parabolas (Felzenszwalb and Huttenlocher) along y and x,
//!    carrying the nearest seed along. Every voxel learns its nearest seed.
//! 3. The distance of each voxel is its distance to the surface element of
//!    that seed (a disc of about a voxel in the tangent plane); within a
//!    few voxels of the surface the neighbouring seeds' elements are tried
//!    too and the nearest taken. The sign is the voxel's side: positive
//!    where the intensity is at least the iso value.

use crate::error::{Result, ScanError};
use crate::grid::{Lattice, Sample};
use crate::volume::Progress;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// No seed (yet) for this voxel.
pub(crate) const NONE: u32 = u32::MAX;

/// Radius of a surface element, in units of the largest spacing.
const DISC: f64 = 0.6;

/// Voxels closer than this many largest spacings to their nearest seed
/// compare the neighbouring seeds' elements too.
const BAND: f64 = 3.0;

/// Seeds themselves (nearer than this many largest spacings) keep their
/// own element: it is their projection onto the linearised surface.
const INNER: f64 = 0.5;

/// Offsets of the seeds (around the nearest one) whose elements are
/// compared in the band: the seed and its face and edge neighbours.
const NEIGHBOURS: [[i64; 3]; 19] = [
    [0, 0, 0],
    [-1, 0, 0],
    [1, 0, 0],
    [0, -1, 0],
    [0, 1, 0],
    [0, 0, -1],
    [0, 0, 1],
    [-1, -1, 0],
    [1, -1, 0],
    [-1, 1, 0],
    [1, 1, 0],
    [-1, 0, -1],
    [1, 0, -1],
    [-1, 0, 1],
    [1, 0, 1],
    [0, -1, -1],
    [0, 1, -1],
    [0, -1, 1],
    [0, 1, 1],
];

/// A surface element of one seed voxel (local coordinates: mm from the
/// centre of voxel (0, 0, 0)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Surfel {
    /// Foot point on the linearised iso surface.
    p: [f32; 3],
    /// Unit normal (towards the inside), in units of 1/32767.
    n: [i16; 3],
    /// Linear index of the seed voxel.
    v: u32,
}

const NSCALE: f64 = 32767.0;

/// Bytes of one surface element.
pub(crate) const SURFEL_BYTES: u64 = std::mem::size_of::<Surfel>() as u64;

/// Intensity lookup for the transform.
pub(crate) trait Src: Sync {
    fn get(&self, i: usize) -> f64;
}

/// Samples with the volume's scaling.
pub(crate) struct Scaled<'a, T> {
    pub data: &'a [T],
    pub slope: f64,
    pub intercept: f64,
}

impl<T: Sample> Src for Scaled<'_, T> {
    #[inline]
    fn get(&self, i: usize) -> f64 {
        self.data[i].v() * self.slope + self.intercept
    }
}

/// Counts work in planes for the progress callback.
pub(crate) struct Ticker<'a> {
    done: AtomicU64,
    total: u64,
    progress: Progress<'a>,
}

impl<'a> Ticker<'a> {
    pub(crate) fn new(total: u64, progress: Progress<'a>) -> Ticker<'a> {
        Ticker {
            done: AtomicU64::new(0),
            total,
            progress,
        }
    }
    pub(crate) fn tick(&self, n: u64) {
        let d = self.done.fetch_add(n, Ordering::Relaxed) + n;
        (self.progress)(d.min(self.total), self.total);
    }
}

/// Checks the samples: all finite, and the iso value between the extremes.
pub(crate) fn check_samples<S: Src>(src: &S, lat: &Lattice, iso: f64) -> Result<()> {
    let [nx, ny, nz] = lat.dims;
    let plane = nx * ny;
    let parts: Vec<(f64, f64, Option<usize>)> = (0..nz)
        .into_par_iter()
        .map(|k| {
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for i in k * plane..(k + 1) * plane {
                let v = src.get(i);
                if !v.is_finite() {
                    return (lo, hi, Some(i));
                }
                lo = lo.min(v);
                hi = hi.max(v);
            }
            (lo, hi, None)
        })
        .collect();
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for (l, h, bad) in parts {
        if let Some(i) = bad {
            return Err(ScanError::NotFinite {
                index: [i % nx, (i / nx) % ny, i / plane],
                value: src.get(i) as f32,
            });
        }
        lo = lo.min(l);
        hi = hi.max(h);
    }
    if !(hi >= iso && lo < iso) {
        return Err(ScanError::NoSurface {
            iso,
            min: lo,
            max: hi,
        });
    }
    Ok(())
}

/// Number of seed voxels per z plane.
pub(crate) fn count_seeds<S: Src>(src: &S, lat: &Lattice, iso: f64, t: &Ticker) -> Vec<usize> {
    let [nx, ny, nz] = lat.dims;
    (0..nz)
        .into_par_iter()
        .map(|k| {
            let mut c = 0;
            for j in 0..ny {
                for i in 0..nx {
                    if is_seed(src, lat.dims, iso, [i, j, k]) {
                        c += 1;
                    }
                }
            }
            t.tick(1);
            c
        })
        .collect()
}

#[inline]
fn is_seed<S: Src>(src: &S, dims: [usize; 3], iso: f64, p: [usize; 3]) -> bool {
    let [nx, ny, _] = dims;
    let i = p[0] + nx * (p[1] + ny * p[2]);
    let inside = src.get(i) >= iso;
    let strides = [1, nx, nx * ny];
    for a in 0..3 {
        if p[a] > 0 && (src.get(i - strides[a]) >= iso) != inside {
            return true;
        }
        if p[a] + 1 < dims[a] && (src.get(i + strides[a]) >= iso) != inside {
            return true;
        }
    }
    false
}

/// The surface element of seed voxel `p`.
fn surfel<S: Src>(src: &S, lat: &Lattice, iso: f64, p: [usize; 3]) -> Surfel {
    let [nx, ny, _] = lat.dims;
    let strides = [1, nx, nx * ny];
    let i = p[0] + nx * (p[1] + ny * p[2]);
    let v0 = src.get(i) - iso;
    let inside = v0 >= 0.0;
    let mut g = [0.0f64; 3];
    for a in 0..3 {
        let h = lat.spacing[a];
        let lo = (p[a] > 0).then(|| src.get(i - strides[a]) - iso);
        let hi = (p[a] + 1 < lat.dims[a]).then(|| src.get(i + strides[a]) - iso);
        // Nearest crossing on this axis: one-sided difference across it.
        let mut best: Option<(f64, f64)> = None;
        for (vn, dir) in [(lo, -1.0), (hi, 1.0)] {
            if let Some(vn) = vn {
                if (vn >= 0.0) != inside {
                    let t = v0 / (v0 - vn);
                    let ga = (vn - v0) / (dir * h);
                    if best.is_none_or(|(bt, _)| t < bt) {
                        best = Some((t, ga));
                    }
                }
            }
        }
        g[a] = match (best, lo, hi) {
            (Some((_, ga)), _, _) => ga,
            (None, Some(l), Some(u)) => (u - l) / (2.0 * h),
            (None, Some(l), None) => (v0 - l) / h,
            (None, None, Some(u)) => (u - v0) / h,
            (None, None, None) => 0.0,
        };
    }
    let g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
    let x: [f64; 3] = std::array::from_fn(|a| p[a] as f64 * lat.spacing[a]);
    // A seed has a crossing on some axis, so g2 > 0; guard anyway.
    let (s, n) = if g2 > 0.0 && g2.is_finite() {
        let len = g2.sqrt();
        (
            std::array::from_fn(|a| x[a] - v0 * g[a] / g2),
            g.map(|c| c / len),
        )
    } else {
        (x, [0.0; 3])
    };
    Surfel {
        p: s.map(|c| c as f32),
        n: n.map(|c| (c * NSCALE).round() as i16),
        v: i as u32,
    }
}

/// The surface elements of all seeds, plane by plane (deterministic order),
/// and the feature array with each seed's element index (`NONE` elsewhere).
pub(crate) fn surfels<S: Src>(
    src: &S,
    lat: &Lattice,
    iso: f64,
    counts: &[usize],
    feat: &mut [u32],
    t: &Ticker,
) -> Vec<Surfel> {
    let [nx, ny, _] = lat.dims;
    let plane = nx * ny;
    let mut offsets = Vec::with_capacity(counts.len());
    let mut total = 0;
    for &c in counts {
        offsets.push(total);
        total += c;
    }
    let mut out = vec![
        Surfel {
            p: [0.0; 3],
            n: [0; 3],
            v: 0
        };
        total
    ];
    // Split the output by plane.
    let mut parts: Vec<&mut [Surfel]> = Vec::with_capacity(counts.len());
    let mut rest = &mut out[..];
    for &c in counts {
        let (a, b) = rest.split_at_mut(c);
        parts.push(a);
        rest = b;
    }
    feat.par_chunks_mut(plane)
        .zip(parts.into_par_iter())
        .enumerate()
        .for_each(|(k, (fp, part))| {
            let mut m = 0;
            for j in 0..ny {
                for i in 0..nx {
                    let o = i + nx * j;
                    if is_seed(src, lat.dims, iso, [i, j, k]) {
                        part[m] = surfel(src, lat, iso, [i, j, k]);
                        fp[o] = (offsets[k] + m) as u32;
                        m += 1;
                    } else {
                        fp[o] = NONE;
                    }
                }
            }
            t.tick(1);
        });
    out
}

/// The exact feature transform: on return `feat[i]` is the nearest seed's
/// element and `d2[i]` the squared distance (mm^2) between the centres.
pub(crate) fn feature_transform(lat: &Lattice, feat: &mut [u32], d2: &mut [f32], t: &Ticker) {
    let [nx, ny, nz] = lat.dims;
    let plane = nx * ny;
    const CHUNK: usize = 4096;
    // Along z: forward then backward linear sweeps, counting voxels.
    for k in 0..nz {
        let (fdone, frest) = feat.split_at_mut(k * plane);
        let (ddone, drest) = d2.split_at_mut(k * plane);
        let fprev = if k > 0 {
            &fdone[(k - 1) * plane..]
        } else {
            &[][..]
        };
        let dprev = if k > 0 {
            &ddone[(k - 1) * plane..]
        } else {
            &[][..]
        };
        frest[..plane]
            .par_chunks_mut(CHUNK)
            .zip(drest[..plane].par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (f, d))| {
                let i0 = c * CHUNK;
                for m in 0..f.len() {
                    if f[m] != NONE {
                        d[m] = 0.0;
                    } else if k > 0 && fprev[i0 + m] != NONE {
                        f[m] = fprev[i0 + m];
                        d[m] = dprev[i0 + m] + 1.0;
                    } else {
                        d[m] = f32::INFINITY;
                    }
                }
            });
    }
    for k in (0..nz.saturating_sub(1)).rev() {
        let (fcur, fnext) = feat.split_at_mut((k + 1) * plane);
        let (dcur, dnext) = d2.split_at_mut((k + 1) * plane);
        fcur[k * plane..]
            .par_chunks_mut(CHUNK)
            .zip(dcur[k * plane..].par_chunks_mut(CHUNK))
            .zip(
                fnext[..plane]
                    .par_chunks(CHUNK)
                    .zip(dnext[..plane].par_chunks(CHUNK)),
            )
            .for_each(|((f, d), (fnx, dnx))| {
                for m in 0..f.len() {
                    if fnx[m] != NONE && dnx[m] + 1.0 < d[m] {
                        f[m] = fnx[m];
                        d[m] = dnx[m] + 1.0;
                    }
                }
            });
    }
    let hz2 = (lat.spacing[2] * lat.spacing[2]) as f32;
    d2.par_chunks_mut(plane).for_each(|p| {
        for v in p {
            if v.is_finite() {
                *v = *v * *v * hz2;
            }
        }
    });
    t.tick(nz as u64);
    // Along y, within each plane.
    let hy2 = lat.spacing[1] * lat.spacing[1];
    d2.par_chunks_mut(plane)
        .zip(feat.par_chunks_mut(plane))
        .for_each_init(
            || Envelope::new(ny),
            |e, (dp, fp)| {
                for i in 0..nx {
                    for j in 0..ny {
                        e.f[j] = dp[i + nx * j] as f64;
                        e.feat[j] = fp[i + nx * j];
                    }
                    e.transform(ny, hy2);
                    for j in 0..ny {
                        dp[i + nx * j] = e.out[j] as f32;
                        fp[i + nx * j] = e.out_feat[j];
                    }
                }
                t.tick(1);
            },
        );
    // Along x, row by row.
    let hx2 = lat.spacing[0] * lat.spacing[0];
    d2.par_chunks_mut(plane)
        .zip(feat.par_chunks_mut(plane))
        .for_each_init(
            || Envelope::new(nx),
            |e, (dp, fp)| {
                for (dr, fr) in dp.chunks_mut(nx).zip(fp.chunks_mut(nx)) {
                    for i in 0..nx {
                        e.f[i] = dr[i] as f64;
                        e.feat[i] = fr[i];
                    }
                    e.transform(nx, hx2);
                    for i in 0..nx {
                        dr[i] = e.out[i] as f32;
                        fr[i] = e.out_feat[i];
                    }
                }
                t.tick(1);
            },
        );
}

/// Scratch of the 1D lower envelope of parabolas.
struct Envelope {
    f: Vec<f64>,
    feat: Vec<u32>,
    scaled: Vec<f64>,
    apex: Vec<usize>,
    bound: Vec<f64>,
    out: Vec<f64>,
    out_feat: Vec<u32>,
}

impl Envelope {
    fn new(n: usize) -> Envelope {
        Envelope {
            f: vec![0.0; n],
            feat: vec![NONE; n],
            scaled: vec![0.0; n],
            apex: vec![0; n],
            bound: vec![0.0; n + 1],
            out: vec![0.0; n],
            out_feat: vec![NONE; n],
        }
    }

    /// `out[u] = min_q h2 (u - q)^2 + f[q]` over the finite `f[q]`, with
    /// `out_feat[u]` the minimiser's feature.
    fn transform(&mut self, n: usize, h2: f64) {
        let mut k: isize = -1;
        for q in 0..n {
            if !self.f[q].is_finite() {
                continue;
            }
            let fq = self.f[q] / h2;
            self.scaled[q] = fq;
            let qf = q as f64;
            loop {
                if k < 0 {
                    k = 0;
                    self.apex[0] = q;
                    self.bound[0] = f64::NEG_INFINITY;
                    break;
                }
                let p = self.apex[k as usize];
                let pf = p as f64;
                let s = ((fq + qf * qf) - (self.scaled[p] + pf * pf)) / (2.0 * (qf - pf));
                if s <= self.bound[k as usize] {
                    k -= 1;
                    continue;
                }
                k += 1;
                self.apex[k as usize] = q;
                self.bound[k as usize] = s;
                break;
            }
        }
        if k < 0 {
            self.out[..n].fill(f64::INFINITY);
            self.out_feat[..n].fill(NONE);
            return;
        }
        let k = k as usize;
        self.bound[k + 1] = f64::INFINITY;
        let mut j = 0;
        for u in 0..n {
            let uf = u as f64;
            while self.bound[j + 1] < uf {
                j += 1;
            }
            let p = self.apex[j];
            let du = uf - p as f64;
            self.out[u] = (du * du + self.scaled[p]) * h2;
            self.out_feat[u] = self.feat[p];
        }
    }
}

/// Squared distance from `x` to a surface element (a disc of radius `r`).
#[inline]
fn disc2(x: [f64; 3], s: &Surfel, r: f64) -> f64 {
    let d = [
        x[0] - s.p[0] as f64,
        x[1] - s.p[1] as f64,
        x[2] - s.p[2] as f64,
    ];
    // The quantised normal is unit length within 1e-4.
    let n = s.n.map(|c| c as f64 * (1.0 / NSCALE));
    let dn = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
    let all = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let lat2 = all - dn * dn;
    if lat2 <= r * r {
        return dn * dn;
    }
    let e = lat2.sqrt() - r;
    dn * dn + e * e
}

/// Turns the feature transform into signed distances, in place in `d2`.
pub(crate) fn signed_distances<S: Src>(
    src: &S,
    lat: &Lattice,
    iso: f64,
    feat: &[u32],
    surfels: &[Surfel],
    d2: &mut [f32],
    t: &Ticker,
) {
    let [nx, ny, _] = lat.dims;
    let plane = nx * ny;
    let hmax = lat.spacing.iter().cloned().fold(0.0, f64::max);
    let r = DISC * hmax;
    let band2 = (BAND * hmax).powi(2);
    let inner2 = (INNER * hmax).powi(2);
    let diag = (0..3)
        .map(|a| (lat.dims[a] as f64 * lat.spacing[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    let is_seed_at = |q: [usize; 3]| -> Option<&Surfel> {
        let l = q[0] + nx * (q[1] + ny * q[2]);
        let f = feat[l];
        if f == NONE {
            return None;
        }
        let s = &surfels[f as usize];
        (s.v as usize == l).then_some(s)
    };
    d2.par_chunks_mut(plane).enumerate().for_each(|(k, dp)| {
        for j in 0..ny {
            for i in 0..nx {
                let o = i + nx * j;
                let idx = k * plane + o;
                let x = [
                    i as f64 * lat.spacing[0],
                    j as f64 * lat.spacing[1],
                    k as f64 * lat.spacing[2],
                ];
                let f = feat[idx];
                let mut best = if f == NONE {
                    diag * diag
                } else {
                    disc2(x, &surfels[f as usize], r)
                };
                if f != NONE && (dp[o] as f64) <= band2 && (dp[o] as f64) > inner2 {
                    let l = surfels[f as usize].v as usize;
                    let c = [l % nx, (l / nx) % ny, l / plane];
                    for off in NEIGHBOURS {
                        let q = [
                            c[0] as i64 + off[0],
                            c[1] as i64 + off[1],
                            c[2] as i64 + off[2],
                        ];
                        if (0..3).any(|a| q[a] < 0 || q[a] >= lat.dims[a] as i64) {
                            continue;
                        }
                        if let Some(s) = is_seed_at(q.map(|v| v as usize)) {
                            best = best.min(disc2(x, s, r));
                        }
                    }
                }
                let best = best.sqrt() as f32;
                dp[o] = if src.get(idx) >= iso { best } else { -best };
            }
        }
        t.tick(1);
    });
}
