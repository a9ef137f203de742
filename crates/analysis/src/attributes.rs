//! Attribute channels over the solid: for every channel of a shape (a
//! material fraction, a density), its integral over the solid, mean,
//! minimum and maximum.
//!
//! The integral is the midpoint rule on the grid's voxel centres (the
//! voxels whose centre is inside the solid, and the region if given), the
//! same sampling as layer images at the grid's pixel size, so a grey-level
//! stack of the channel sums to this integral. Its error estimate is the
//! difference to the same sum on the grid coarsened by two.

use crate::grid::Grid;
use microfrep_core::{BatchEval, Shape};
use rayon::prelude::*;

/// The figures of one attribute channel.
#[derive(Clone, Debug, PartialEq)]
pub struct AttributeStats {
    /// Channel name (`s1`, ... for HyperFun's `s[]`).
    pub name: String,
    /// Integral over the solid (model units cubed).
    pub integral: f64,
    /// Estimated error of the integral.
    pub error: f64,
    /// Integral divided by the solid's volume on the same grid.
    pub mean: f64,
    /// Smallest and largest value at a voxel centre in the solid (NaN with
    /// no solid).
    pub min: f64,
    /// See `min`.
    pub max: f64,
}

/// Per channel: (sum fine, sum coarse, min, max), plus the inside counts.
type Acc = (Vec<[f64; 4]>, u64, u64);

/// The statistics of every attribute channel of `shape` over its solid
/// (inside `region` if given) on `grid`; empty when the shape has none.
pub fn attributes(shape: &Shape, region: Option<&Shape>, grid: &Grid) -> Vec<AttributeStats> {
    let n = shape.attributes().len();
    if n == 0 {
        return Vec::new();
    }
    let tape = shape.outputs();
    let outs: Vec<usize> = (0..n).map(|k| shape.attribute_output(k)).collect();
    let [nx, ny, nz] = grid.dims;
    let zero = || {
        (
            vec![[0.0, 0.0, f64::INFINITY, f64::NEG_INFINITY]; n],
            0u64,
            0u64,
        )
    };
    let acc: Acc = (0..nz)
        .into_par_iter()
        .fold(
            || {
                (
                    zero(),
                    BatchEval::new(tape),
                    region.map(|r| BatchEval::new(r.tape())),
                )
            },
            |(mut acc, mut ev, mut rev), k| {
                let m = nx * ny;
                let (mut x, mut y, mut z) = (vec![0f32; m], vec![0f32; m], vec![0f32; m]);
                for j in 0..ny {
                    for i in 0..nx {
                        let c = grid.center([i, j, k]);
                        let q = i + nx * j;
                        (x[q], y[q], z[q]) = (c[0] as f32, c[1] as f32, c[2] as f32);
                    }
                }
                let mut value = vec![0f32; m];
                ev.eval_output(0, &x, &y, &z, &mut value);
                let mut inside: Vec<bool> = value.iter().map(|&v| v >= 0.0).collect();
                if let Some(r) = rev.as_mut() {
                    let mut rv = vec![0f32; m];
                    r.eval(&x, &y, &z, &mut rv);
                    for (a, &b) in inside.iter_mut().zip(&rv) {
                        *a &= b >= 0.0;
                    }
                }
                let mut chan = vec![0f32; m];
                for (c, &o) in outs.iter().enumerate() {
                    ev.eval_output(o, &x, &y, &z, &mut chan);
                    for q in 0..m {
                        if !inside[q] || chan[q].is_nan() {
                            continue;
                        }
                        let v = chan[q] as f64;
                        let s = &mut acc.0[c];
                        s[0] += v;
                        // The coarse grid: every other voxel on each axis.
                        if (q % nx) % 2 == 0 && (q / nx) % 2 == 0 && k % 2 == 0 {
                            s[1] += v;
                        }
                        s[2] = s[2].min(v);
                        s[3] = s[3].max(v);
                    }
                }
                for q in 0..m {
                    if inside[q] {
                        acc.1 += 1;
                        if (q % nx) % 2 == 0 && (q / nx) % 2 == 0 && k % 2 == 0 {
                            acc.2 += 1;
                        }
                    }
                }
                (acc, ev, rev)
            },
        )
        .map(|(a, _, _)| a)
        .reduce(zero, |mut a, b| {
            for (x, y) in a.0.iter_mut().zip(&b.0) {
                x[0] += y[0];
                x[1] += y[1];
                x[2] = x[2].min(y[2]);
                x[3] = x[3].max(y[3]);
            }
            (a.0, a.1 + b.1, a.2 + b.2)
        });
    let dv = grid.voxel_volume();
    shape
        .attributes()
        .iter()
        .zip(&acc.0)
        .map(|(a, s)| {
            let integral = s[0] * dv;
            let coarse = s[1] * dv * 8.0;
            let volume = acc.1 as f64 * dv;
            AttributeStats {
                name: a.name.clone(),
                integral,
                error: (integral - coarse).abs(),
                mean: if volume > 0.0 {
                    integral / volume
                } else {
                    f64::NAN
                },
                min: if acc.1 > 0 { s[2] } else { f64::NAN },
                max: if acc.1 > 0 { s[3] } else { f64::NAN },
            }
        })
        .collect()
}
