//! Dithering material fractions to one material per voxel, for printers
//! that deposit one material per voxel (material jetting).
//!
//! The voxel grid is `nx x ny` voxels per layer (row-major, row 0 at the
//! lowest y) and `layers` layers, streamed bottom to top: a source callback
//! fills, for layer `k`, `materials` fractions per voxel and the inside
//! mask; a sink receives each finished layer as one byte per voxel, the
//! material index, or [`OUTSIDE`]. Memory holds three layers of fractions (one
//! being computed while the one two below is dithered) and two of
//! diffusion error, whatever the layer count.
//!
//! Fractions are read as follows: the first `materials - 1` are clamped to
//! `[0, 1]` (NaN counts as 0) and scaled down if they sum to more than 1;
//! the last material takes the remainder `1 - sum` (the value the source
//! wrote for it is ignored). The integrals reported are of these values.
//!
//! Methods ([`Method`]), all deterministic (the same input and seed give
//! the same bytes, whatever the thread count):
//!
//! - **Error diffusion** (default): vector error diffusion in 3D. Each
//!   inside voxel takes the material with the largest demand (its fraction
//!   plus the error diffused to it); the error vector (demand minus the
//!   choice) goes to seven forward neighbours, weights in sixteenths, `+1`
//!   in `x` being the scan direction: in the same layer `(+1, 0)` 4,
//!   `(-1, +1)` 2, `(0, +1)` 3, `(+1, +1)` 1; in the next layer `(0, 0)` 4,
//!   `(+1, 0)` 1, `(0, +1)` 1.
//!   Rows run serpentine (direction alternating with row and layer), so
//!   there are no directional streaks. Weights to neighbours outside the grid
//!   or the mask are renormalised over the inside ones; error with nowhere
//!   to go is carried to the next inside voxel in scan order, so every
//!   material's volume is preserved to within one voxel over the whole part.
//! - **Stochastic** (OpenVCAD's material inkjet behaviour): each voxel draws
//!   a uniform number from a counter-based hash of `(seed, x, y, layer)` and
//!   takes the material whose cumulative fraction interval holds it.
//! - **Ordered**: the same selection against a 3D Bayer threshold of period
//!   8 on each axis (512 levels): a constant fraction is met exactly over
//!   every aligned 8x8x8 block, a smooth two-material field within 0.5 %.
//!   With three or more materials, material `m` takes the thresholds in
//!   `[C_(m-1), C_m)` (cumulative fractions); where the fractions before it
//!   vary, that window slides over the pattern and its volume can be off by
//!   one or two percent (tested within 2 %). Use error diffusion where
//!   volumes matter.

use crate::error::{Error, Result};
use rayon::prelude::*;

/// Byte of a voxel outside the part.
pub const OUTSIDE: u8 = u8::MAX;

/// Most materials (indices `0..=254`; 255 is [`OUTSIDE`]).
pub const MAX_MATERIALS: usize = 255;

/// Default limit on the dithering buffers (bytes).
pub const DEFAULT_MEMORY_LIMIT: u64 = 8 << 30;

/// The layer source: `source(k, fractions, inside)` fills layer `k`'s
/// fractions (`materials` per voxel) and inside mask. Layers are asked for
/// in order, one at a time, while the layers below are dithered on another
/// thread (hence `Send`).
pub type LayerSource<'a> = dyn FnMut(usize, &mut [f32], &mut [bool]) + Send + 'a;

/// How fractions become one material per voxel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// 3D vector error diffusion (volume-preserving, no banding).
    #[default]
    ErrorDiffusion,
    /// Independent random choice per voxel with this seed.
    Stochastic {
        /// Seed of the counter-based generator.
        seed: u64,
    },
    /// 3D Bayer threshold (period 8).
    Ordered,
}

impl Method {
    /// Short name for manifests and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Method::ErrorDiffusion => "error-diffusion",
            Method::Stochastic { .. } => "stochastic",
            Method::Ordered => "ordered",
        }
    }
}

/// Size of a dithering job.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Voxels along x.
    pub nx: usize,
    /// Voxels along y.
    pub ny: usize,
    /// Layers along z.
    pub layers: usize,
    /// Number of materials (1 to 255).
    pub materials: usize,
}

impl Layout {
    /// Bytes of the buffers [`dither`] allocates.
    pub fn memory(&self) -> u128 {
        let plane = (self.nx as u128) * (self.ny as u128);
        let n = self.materials as u128;
        let c = n.saturating_sub(1).max(1);
        // Three layers of fractions and masks (one being loaded while the
        // one two below is dithered), two of error, one of output.
        plane * (3 * (4 * n + 1) + 2 * 4 * c + 1)
    }

    fn check(&self, limit: u64) -> Result<()> {
        if self.nx == 0 || self.ny == 0 || self.layers == 0 {
            return Err(Error::Invalid(format!(
                "empty voxel grid {} x {} x {}",
                self.nx, self.ny, self.layers
            )));
        }
        if !(1..=MAX_MATERIALS).contains(&self.materials) {
            return Err(Error::Invalid(format!(
                "dithering needs 1 to {MAX_MATERIALS} materials, got {}",
                self.materials
            )));
        }
        let bytes = self.memory();
        if bytes > limit as u128 {
            return Err(Error::TooLarge {
                what: format!(
                    "dithering {} x {} voxels per layer with {} materials",
                    self.nx, self.ny, self.materials
                ),
                bytes,
                limit: limit as u128,
            });
        }
        Ok(())
    }
}

/// What a dithering run produced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DitherReport {
    /// Voxels assigned to each material.
    pub counts: Vec<u64>,
    /// Sum over inside voxels of each material's (normalised) fraction.
    pub integrals: Vec<f64>,
    /// Inside voxels.
    pub inside: u64,
}

/// A layer's input: fractions (`materials` per voxel) and the mask.
struct Slot {
    frac: Vec<f32>,
    mask: Vec<bool>,
}

/// Dithers `layout.layers` layers from `source` into `sink` with `method`;
/// `progress(done, total)` after each layer. Buffers are checked against
/// `memory_limit` bytes before anything is allocated.
pub fn dither(
    layout: Layout,
    method: Method,
    memory_limit: u64,
    source: &mut LayerSource<'_>,
    sink: &mut dyn FnMut(usize, &[u8]) -> Result<()>,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<DitherReport> {
    dither_with(layout, method, memory_limit, source, sink, progress, true)
}

/// [`dither`], with or without the diffusion's fast path for voxels whose
/// taps all land inside (the same bits either way; tested).
fn dither_with(
    layout: Layout,
    method: Method,
    memory_limit: u64,
    source: &mut LayerSource<'_>,
    sink: &mut dyn FnMut(usize, &[u8]) -> Result<()>,
    progress: &(dyn Fn(u64, u64) + Sync),
    fast: bool,
) -> Result<DitherReport> {
    layout.check(memory_limit)?;
    let Layout {
        nx,
        ny,
        layers,
        materials: n,
    } = layout;
    let plane = nx * ny;
    let c = n - 1;
    let mut slots = [0, 1, 2].map(|_| Slot {
        frac: vec![0.0; plane * n],
        mask: vec![false; plane],
    });
    let mut out = vec![OUTSIDE; plane];
    let mut report = DitherReport {
        counts: vec![0; n],
        integrals: vec![0.0; n],
        inside: 0,
    };
    let mut ed = match method {
        Method::ErrorDiffusion if c > 0 => Some(Diffuser {
            fast,
            ..Diffuser::new(nx, ny, c)
        }),
        _ => None,
    };
    // Layer k is dithered while layer k + 2 is loaded: slot k % 3 holds
    // layer k; the diffusion reads the next layer's mask.
    for (k, slot) in slots.iter_mut().enumerate().take(layers.min(2)) {
        let sums = load(slot, k, n, source);
        add(&mut report.integrals, sums);
    }
    for k in 0..layers {
        let (cur, next, far) = {
            let [a, b, d] = &mut slots;
            match k % 3 {
                0 => (&*a, &*b, d),
                1 => (&*b, &*d, a),
                _ => (&*d, &*a, b),
            }
        };
        let next_mask = (k + 1 < layers).then_some(&next.mask[..]);
        let dither_layer = |ed: &mut Option<Diffuser>, out: &mut [u8]| match (method, ed.as_mut()) {
            (_, _) if c == 0 => {
                for (o, &m) in out.iter_mut().zip(&cur.mask) {
                    *o = if m { 0 } else { OUTSIDE };
                }
            }
            (Method::ErrorDiffusion, Some(d)) => d.layer(k, cur, next_mask, out),
            (Method::Stochastic { seed }, _) => select_layer(k, cur, nx, n, out, |i, j| {
                uniform(seed, i as u64, j as u64, k as u64)
            }),
            _ => select_layer(k, cur, nx, n, out, |i, j| bayer(i, j, k)),
        };
        let (_, sums) = rayon::join(
            || dither_layer(&mut ed, &mut out),
            || (k + 2 < layers).then(|| load(far, k + 2, n, &mut *source)),
        );
        if let Some(s) = sums {
            add(&mut report.integrals, s);
        }
        for &m in &out {
            if m != OUTSIDE {
                report.counts[m as usize] += 1;
            }
        }
        sink(k, &out)?;
        progress(k as u64 + 1, layers as u64);
    }
    report.inside = report.counts.iter().sum();
    Ok(report)
}

/// Calls the source for layer `k` on cleared buffers, then normalises the
/// fractions of inside voxels (the only ones read); returns their sums per
/// material for each block of rows, in order (so the totals do not depend
/// on the thread count).
fn load(slot: &mut Slot, k: usize, n: usize, source: &mut LayerSource<'_>) -> Vec<Vec<f64>> {
    slot.frac.iter_mut().for_each(|v| *v = 0.0);
    slot.mask.iter_mut().for_each(|v| *v = false);
    source(k, &mut slot.frac, &mut slot.mask);
    let row = 4096usize;
    slot.frac
        .par_chunks_mut(row * n)
        .zip(slot.mask.par_chunks(row))
        .map(|(f, m)| {
            let mut s = vec![0.0f64; n];
            for (v, &inside) in f.chunks_mut(n).zip(m) {
                if inside {
                    normalise(v);
                    for (a, &b) in s.iter_mut().zip(v.iter()) {
                        *a += b as f64;
                    }
                }
            }
            s
        })
        .collect()
}

/// Adds the block sums of [`load`] to the integrals, in order.
fn add(integrals: &mut [f64], sums: Vec<Vec<f64>>) {
    for s in sums {
        for (a, b) in integrals.iter_mut().zip(s) {
            *a += b;
        }
    }
}

/// The documented reading of one voxel's fractions, in place.
fn normalise(v: &mut [f32]) {
    let c = v.len() - 1;
    let mut sum = 0.0f32;
    for x in &mut v[..c] {
        *x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
        sum += *x;
    }
    if sum > 1.0 {
        for x in &mut v[..c] {
            *x /= sum;
        }
        sum = v[..c].iter().sum::<f32>().min(1.0);
    }
    v[c] = 1.0 - sum;
}

/// Picks, per voxel, the material whose cumulative interval holds `t(i, j)`.
fn select_layer(
    _k: usize,
    cur: &Slot,
    nx: usize,
    n: usize,
    out: &mut [u8],
    t: impl Fn(usize, usize) -> f32 + Sync,
) {
    out.par_chunks_mut(nx)
        .zip(cur.frac.par_chunks(nx * n))
        .zip(cur.mask.par_chunks(nx))
        .enumerate()
        .for_each(|(j, ((o, f), m))| {
            for i in 0..nx {
                if !m[i] {
                    o[i] = OUTSIDE;
                    continue;
                }
                let r = t(i, j);
                let v = &f[i * n..(i + 1) * n];
                let mut acc = 0.0f32;
                let mut pick = n - 1;
                for (a, &x) in v[..n - 1].iter().enumerate() {
                    acc += x;
                    if r < acc {
                        pick = a;
                        break;
                    }
                }
                o[i] = pick as u8;
            }
        });
}

/// Uniform in `[0, 1)` from `(seed, i, j, k)` (splitmix64 finaliser).
fn uniform(seed: u64, i: u64, j: u64, k: u64) -> f32 {
    let mut z = seed
        ^ i.wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ j.wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ k.wrapping_mul(0x1656_67b1_9e37_79f9);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}

/// Order of the 2x2x2 corners: antipodal pairs follow each other, so the
/// first two, four and six levels are spread as far as they can be.
const BAYER2: [[[u16; 2]; 2]; 2] = {
    // Index [x][y][z] -> rank.
    let mut t = [[[0u16; 2]; 2]; 2];
    let order = [
        (0, 0, 0),
        (1, 1, 1),
        (1, 1, 0),
        (0, 0, 1),
        (0, 1, 1),
        (1, 0, 0),
        (1, 0, 1),
        (0, 1, 0),
    ];
    let mut r = 0;
    while r < 8 {
        let (x, y, z) = order[r];
        t[x][y][z] = r as u16;
        r += 1;
    }
    t
};

/// The 3D Bayer threshold at voxel `(i, j, k)`, in `(0, 1)`: rank
/// `sum_b 8^(2-b) BAYER2[bit b of i, j, k]` over the three low bits, centred
/// in its 1/512 step.
pub fn bayer(i: usize, j: usize, k: usize) -> f32 {
    let mut rank = 0u32;
    for b in 0..3 {
        let r = BAYER2[(i >> b) & 1][(j >> b) & 1][(k >> b) & 1] as u32;
        rank += r << (3 * (2 - b));
    }
    (rank as f32 + 0.5) / 512.0
}

/// State of the 3D error diffusion across layers.
struct Diffuser {
    nx: usize,
    ny: usize,
    /// Channels (materials - 1).
    c: usize,
    cur: Vec<f32>,
    next: Vec<f32>,
    carry: Vec<f32>,
    demand: Vec<f32>,
    /// Whether voxels whose taps all land inside skip the general case.
    fast: bool,
}

/// Taps `(dx in scan direction, dy, dz, weight / 16)`.
const TAPS: [(isize, usize, usize, f32); 7] = [
    (1, 0, 0, 4.0),
    (-1, 1, 0, 2.0),
    (0, 1, 0, 3.0),
    (1, 1, 0, 1.0),
    (0, 0, 1, 4.0),
    (1, 0, 1, 1.0),
    (0, 1, 1, 1.0),
];

impl Diffuser {
    fn new(nx: usize, ny: usize, c: usize) -> Diffuser {
        Diffuser {
            nx,
            ny,
            c,
            cur: vec![0.0; nx * ny * c],
            next: vec![0.0; nx * ny * c],
            carry: vec![0.0; c],
            demand: vec![0.0; c + 1],
            fast: true,
        }
    }

    fn layer(&mut self, k: usize, slot: &Slot, next_mask: Option<&[bool]>, out: &mut [u8]) {
        // Fixed channel counts unroll the per-material loops.
        match self.c {
            1 => self.scan::<1>(k, slot, next_mask, out),
            2 => self.scan::<2>(k, slot, next_mask, out),
            3 => self.scan::<3>(k, slot, next_mask, out),
            _ => self.scan::<0>(k, slot, next_mask, out),
        }
        std::mem::swap(&mut self.cur, &mut self.next);
        self.next.iter_mut().for_each(|v| *v = 0.0);
    }

    /// One layer; `C` is the channel count, or 0 for "read `self.c`".
    fn scan<const C: usize>(
        &mut self,
        k: usize,
        slot: &Slot,
        next_mask: Option<&[bool]>,
        out: &mut [u8],
    ) {
        let (nx, ny) = (self.nx, self.ny);
        let c = if C == 0 { self.c } else { C };
        let n = c + 1;
        for j in 0..ny {
            let row = j * nx..(j + 1) * nx;
            if !slot.mask[row.clone()].iter().any(|&m| m) {
                out[row].fill(OUTSIDE);
                continue;
            }
            let forward = (j + k) & 1 == 0;
            for step in 0..nx {
                let i = if forward { step } else { nx - 1 - step };
                let idx = j * nx + i;
                if !slot.mask[idx] {
                    out[idx] = OUTSIDE;
                    continue;
                }
                // Demands: fraction + diffused error + carried error.
                let f = &slot.frac[idx * n..idx * n + n];
                let e = &mut self.cur[idx * c..idx * c + c];
                let mut sum = 0.0f32;
                for m in 0..c {
                    let d = f[m] + e[m] + self.carry[m];
                    self.demand[m] = d;
                    sum += d;
                    self.carry[m] = 0.0;
                }
                self.demand[c] = 1.0 - sum;
                let mut pick = 0;
                for m in 1..n {
                    if self.demand[m] > self.demand[pick] {
                        pick = m;
                    }
                }
                out[idx] = pick as u8;
                if pick < c {
                    self.demand[pick] -= 1.0;
                }
                // Every tap inside the grid and the part (most voxels): the
                // weights sum to 16, as the general case below finds.
                if let Some(nm) =
                    next_mask.filter(|_| self.fast && i >= 1 && i + 1 < nx && j + 1 < ny)
                {
                    let s = if forward { 1 } else { -1 };
                    let q = |di: isize, dj: usize| (j + dj) * nx + i.wrapping_add_signed(di);
                    let qs = [
                        q(s, 0),
                        q(-s, 1),
                        q(0, 1),
                        q(s, 1),
                        q(0, 0),
                        q(s, 0),
                        q(0, 1),
                    ];
                    if qs[..4].iter().all(|&q| slot.mask[q]) && qs[4..].iter().all(|&q| nm[q]) {
                        let scale = 1.0f32 / 16.0;
                        for (t, &q) in qs.iter().enumerate() {
                            let buf = if t < 4 { &mut self.cur } else { &mut self.next };
                            let wt = TAPS[t].3 * scale;
                            let dst = &mut buf[q * c..q * c + c];
                            for (d, &e) in dst.iter_mut().zip(&self.demand[..c]) {
                                *d += wt * e;
                            }
                        }
                        continue;
                    }
                }
                // Targets and weights of the taps that land inside.
                let mut total = 0.0f32;
                let mut live = [(usize::MAX, false, 0.0f32); 7];
                for (t, &(dx, dy, dz, w)) in TAPS.iter().enumerate() {
                    let ii = if forward {
                        i as isize + dx
                    } else {
                        i as isize - dx
                    };
                    let jj = j + dy;
                    if ii < 0 || ii >= nx as isize || jj >= ny {
                        continue;
                    }
                    let q = jj * nx + ii as usize;
                    let inside = if dz == 0 {
                        slot.mask[q]
                    } else {
                        next_mask.is_some_and(|m| m[q])
                    };
                    if inside {
                        live[t] = (q, dz == 0, w);
                        total += w;
                    }
                }
                if total == 0.0 {
                    for m in 0..c {
                        self.carry[m] += self.demand[m];
                    }
                    continue;
                }
                let scale = 1.0 / total;
                for &(q, same, w) in &live {
                    if q == usize::MAX {
                        continue;
                    }
                    let buf = if same { &mut self.cur } else { &mut self.next };
                    let wt = w * scale;
                    let dst = &mut buf[q * c..q * c + c];
                    for (d, &e) in dst.iter_mut().zip(&self.demand[..c]) {
                        *d += wt * e;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Error diffusion of a holed, graded block with 2, 3 and 5 materials,
    /// with and without the fast path: the same voxels.
    #[test]
    fn fast_path_keeps_every_voxel() {
        let (nx, ny, layers) = (37, 29, 11);
        for n in [2usize, 3, 5] {
            let layout = Layout {
                nx,
                ny,
                layers,
                materials: n,
            };
            let run = |fast: bool| {
                let mut all = Vec::new();
                let report = dither_with(
                    layout,
                    Method::ErrorDiffusion,
                    1 << 30,
                    &mut |k, frac, mask| {
                        for j in 0..ny {
                            for i in 0..nx {
                                let q = j * nx + i;
                                let (x, y) = (i as f32 - 18.0, j as f32 - 14.0);
                                // Outside: a round hole and a notch.
                                mask[q] = x * x + y * y > 20.0 && (i + 2 * k) % 13 != 0;
                                for m in 0..n {
                                    let t = 0.3 + 0.25 * ((i + 3 * m) as f32 * 0.21).sin();
                                    frac[q * n + m] = t * (1.0 + (j + k) as f32 / 40.0) / n as f32;
                                }
                            }
                        }
                    },
                    &mut |_, layer| {
                        all.extend_from_slice(layer);
                        Ok(())
                    },
                    &|_, _| {},
                    fast,
                )
                .unwrap();
                (report, all)
            };
            let (fast, slow) = (run(true), run(false));
            assert_eq!(fast.1, slow.1, "{n} materials");
            assert_eq!(fast.0, slow.0);
            // Several materials in use, and holes.
            let used = (0..n).filter(|&m| fast.0.counts[m] > 100).count();
            assert!(
                used >= 2 && fast.1.contains(&OUTSIDE),
                "{:?}",
                fast.0.counts
            );
        }
    }
}
