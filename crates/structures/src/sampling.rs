//! Volume fraction by sampling: the solid's share (`f >= 0`) of sample
//! points in a box, either the centres of an `n^3` grid of cells or a
//! quasi-random point set; and, accurate to far below a point count's
//! error, the volume of a field's sublevel sets from its grid node values
//! ([`LevelField`], module `levels`).
//!
//! The quasi-random set is Roberts' R3 Kronecker sequence `frac(i alpha)`.
//! Its low discrepancy avoids the aliasing of a regular grid with periodic
//! structures (struts along grid lines, cells commensurate with the grid),
//! so its error falls about as `1/count` rather than `1/count^(1/3)`.

use crate::error::{check_box, check_resolution, Error, Result};
use microfrep_core::{BatchEval, Expr, Tape, BLOCK};
use rayon::prelude::*;

mod cells;
mod levels;
pub use levels::{LevelField, MAX_CELLS};
pub use microfrep_analysis::volume::tet_fraction;

/// Largest accepted number of sample points (memory: 12 bytes a point).
pub const MAX_POINTS: usize = 1 << 24;

/// Sample points, coordinates by axis.
#[derive(Clone, Debug)]
pub struct Samples {
    /// x coordinates.
    pub x: Vec<f32>,
    /// y coordinates.
    pub y: Vec<f32>,
    /// z coordinates.
    pub z: Vec<f32>,
}

impl Samples {
    /// Centres of the cells of an `n x n x n` grid on `[min, max]`.
    pub fn grid(min: [f64; 3], max: [f64; 3], n: usize) -> Result<Samples> {
        check_box(min, max)?;
        check_resolution("sample grid", n, 1, 256)?;
        let c =
            |i: usize, k: usize| (min[i] + (max[i] - min[i]) * (k as f64 + 0.5) / n as f64) as f32;
        let mut s = Samples::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    s.push(c(0, i), c(1, j), c(2, k));
                }
            }
        }
        Ok(s)
    }

    /// `count` points of the R3 sequence on `[min, max]`.
    pub fn quasi_random(min: [f64; 3], max: [f64; 3], count: usize) -> Result<Samples> {
        check_box(min, max)?;
        check_resolution("quasi-random sample count", count, 1, MAX_POINTS)?;
        // alpha_k = phi^-k with phi the real root of x^4 = x + 1 (for 3-D points).
        let phi = 1.220_744_084_605_759_5_f64;
        let alpha = [1.0 / phi, 1.0 / (phi * phi), 1.0 / (phi * phi * phi)];
        let c = |a: usize, i: usize| {
            let u = (0.5 + alpha[a] * (i + 1) as f64).fract();
            (min[a] + u * (max[a] - min[a])) as f32
        };
        let mut s = Samples::with_capacity(count);
        for i in 0..count {
            s.push(c(0, i), c(1, i), c(2, i));
        }
        Ok(s)
    }

    fn with_capacity(n: usize) -> Samples {
        Samples {
            x: Vec::with_capacity(n),
            y: Vec::with_capacity(n),
            z: Vec::with_capacity(n),
        }
    }

    fn push(&mut self, x: f32, y: f32, z: f32) {
        self.x.push(x);
        self.y.push(y);
        self.z.push(z);
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Share of the points where the tape's value is `>= 0`, with the
    /// parameters `(index, value)` set. A NaN or infinite value is an error
    /// naming the first such point.
    pub fn fraction(&self, tape: &Tape, params: &[(usize, f64)]) -> Result<f64> {
        if self.is_empty() {
            return Ok(0.0);
        }
        const CHUNK: usize = BLOCK * 16;
        let chunks: Vec<(usize, Option<Error>)> = self
            .x
            .par_chunks(CHUNK)
            .enumerate()
            .map_init(
                || {
                    let mut ev = BatchEval::new(tape);
                    for &(i, v) in params {
                        ev.set_param(i, v);
                    }
                    (ev, vec![0.0f32; CHUNK])
                },
                |(ev, out), (ci, xs)| {
                    let s = ci * CHUNK;
                    let e = s + xs.len();
                    let out = &mut out[..xs.len()];
                    ev.eval(xs, &self.y[s..e], &self.z[s..e], out);
                    let bad = out
                        .iter()
                        .position(|v| !v.is_finite())
                        .map(|k| Error::NotFinite {
                            value: out[k] as f64,
                            x: self.x[s + k] as f64,
                            y: self.y[s + k] as f64,
                            z: self.z[s + k] as f64,
                        });
                    (out.iter().filter(|v| **v >= 0.0).count(), bad)
                },
            )
            .collect();
        let mut inside = 0;
        for (count, bad) in chunks {
            if let Some(e) = bad {
                return Err(e);
            }
            inside += count;
        }
        Ok(inside as f64 / self.len() as f64)
    }
}

/// Volume fraction of `f` in `[min, max]` on the centres of an `n^3` grid.
pub fn volume_fraction(f: &Expr, min: [f64; 3], max: [f64; 3], n: usize) -> Result<f64> {
    Samples::grid(min, max, n)?.fraction(&Tape::new(f), &[])
}

/// Volume fraction of `f` in `[min, max]` on `count` quasi-random points.
pub fn volume_fraction_qmc(f: &Expr, min: [f64; 3], max: [f64; 3], count: usize) -> Result<f64> {
    Samples::quasi_random(min, max, count)?.fraction(&Tape::new(f), &[])
}

/// The values of the tape (parameters `(index, value)` set) at the nodes
/// of a grid of `n` cells per axis on `[min, max]`, for sublevel volumes;
/// evaluated in f32 batches, z layers in parallel.
pub fn sample_levels(
    tape: &Tape,
    params: &[(usize, f64)],
    min: [f64; 3],
    max: [f64; 3],
    n: usize,
) -> Result<LevelField> {
    check_box(min, max)?;
    check_resolution("level grid cells per axis", n, 2, MAX_CELLS)?;
    let r = n + 1;
    let c = |a: usize, i: usize| (min[a] + (max[a] - min[a]) * i as f64 / n as f64) as f32;
    let mut vals = vec![0.0f32; r * r * r];
    vals.par_chunks_mut(r * r).enumerate().for_each_init(
        || {
            let mut ev = BatchEval::new(tape);
            for &(i, v) in params {
                ev.set_param(i, v);
            }
            let xs: Vec<f32> = (0..r * r).map(|q| c(0, q % r)).collect();
            let ys: Vec<f32> = (0..r * r).map(|q| c(1, q / r)).collect();
            (ev, xs, ys)
        },
        |(ev, xs, ys), (k, layer)| {
            let zs = vec![c(2, k); r * r];
            ev.eval(xs, ys, &zs, layer);
        },
    );
    // Node coordinates of a bad value, mapped from the unit grid to the box.
    LevelField::from_values(n, vals).map_err(|e| match e {
        Error::NotFinite { value, x, y, z } => {
            let m = |a: usize, u: f64| min[a] + (max[a] - min[a]) * u;
            Error::NotFinite {
                value,
                x: m(0, x),
                y: m(1, y),
                z: m(2, z),
            }
        }
        e => e,
    })
}

/// Volume fraction of `f >= 0` in `[min, max]` from the linear interpolant
/// of its values on a grid of `n` (even) cells per axis, extrapolated from
/// the grids of `n` and `n / 2` cells (see [`LevelField`]).
pub fn volume_fraction_fine(f: &Expr, min: [f64; 3], max: [f64; 3], n: usize) -> Result<f64> {
    let tape = Tape::new(&(-f));
    Ok(sample_levels(&tape, &[], min, max, n)?.fraction_below(0.0))
}
