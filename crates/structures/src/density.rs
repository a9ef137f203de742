//! Relative density (volume fraction) control: bisection on a model
//! parameter against the sampled volume fraction, and a level(density)
//! table that turns a density field into a per-point level.

use crate::error::{Error, Result};
use crate::sampling::Samples;
use crate::struts::{strut_cell, StrutLattice, MAX_RADIUS};
use crate::tpms::{tpms, Solid, Tpms};
use microfrep_core::{Expr, Tape};

/// Most bisection steps: the bracket shrinks below 1e-12 of its width, far
/// finer than the steps of a sampled fraction.
const STEPS: usize = 40;
/// Bisection stops early once the sampled fraction is this close (relative)
/// to the target.
const REL_TOL: f64 = 2e-4;

/// The value of the parameter `param` of `model` in `[lo, hi]` at which the
/// volume fraction on the sample points is `target`. The fraction must be
/// monotone in the parameter (either way).
pub fn solve_param(
    model: &Expr,
    param: &str,
    (lo, hi): (f64, f64),
    target: f64,
    samples: &Samples,
) -> Result<f64> {
    if !(target > 0.0 && target < 1.0) {
        return Err(Error::OutOfRange {
            what: "target volume fraction",
            value: target,
            expected: "strictly between 0 and 1",
        });
    }
    let tape = Tape::new(model);
    let idx = tape
        .param_index(param)
        .ok_or_else(|| Error::NoParam(param.to_string()))?;
    let frac = |v: f64| samples.fraction(&tape, &[(idx, v)]);
    let (f_lo, f_hi) = (frac(lo)?, frac(hi)?);
    let (reach_lo, reach_hi) = (f_lo.min(f_hi), f_lo.max(f_hi));
    if target < reach_lo || target > reach_hi {
        return Err(Error::Unreachable {
            target,
            lo: reach_lo,
            hi: reach_hi,
        });
    }
    let increasing = f_hi >= f_lo;
    let (mut a, mut b) = (lo, hi);
    for _ in 0..STEPS {
        let m = 0.5 * (a + b);
        let fm = frac(m)?;
        if (fm - target).abs() <= REL_TOL * target {
            return Ok(m);
        }
        if (fm < target) == increasing {
            a = m;
        } else {
            b = m;
        }
    }
    Ok(0.5 * (a + b))
}

/// The TPMS level giving volume fraction `target` on one unit cell,
/// measured on `count` quasi-random points.
pub fn tpms_level(kind: Tpms, solid: Solid, target: f64, count: usize) -> Result<f64> {
    let level = Expr::param("level", 0.0);
    let model = tpms(kind, solid, &Expr::xyz(), 1.0, level);
    let lo = match solid {
        Solid::Network => -kind.bound(),
        Solid::Sheet => 0.0,
    };
    let samples = Samples::quasi_random([0.0; 3], [1.0; 3], count)?;
    solve_param(&model, "level", (lo, kind.bound()), target, &samples)
}

/// The strut radius (cell units) giving volume fraction `target` on one
/// unit cell, measured on `count` quasi-random points.
pub fn strut_radius(kind: StrutLattice, target: f64, count: usize) -> Result<f64> {
    let model = strut_cell(kind, &Expr::xyz(), Expr::param("radius", 0.1));
    let samples = Samples::quasi_random([0.0; 3], [1.0; 3], count)?;
    solve_param(&model, "radius", (0.0, MAX_RADIUS), target, &samples)
}

/// Levels (or radii) solved at increasing densities, for a density that
/// varies in space.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelTable {
    density: Vec<f64>,
    level: Vec<f64>,
}

impl LevelTable {
    /// Solves `solve(density)` at each of the increasing `densities`.
    pub fn build(densities: &[f64], solve: impl Fn(f64) -> Result<f64>) -> Result<LevelTable> {
        if densities.is_empty() {
            return Err(Error::OutOfRange {
                what: "table size",
                value: 0.0,
                expected: "at least one density",
            });
        }
        for w in densities.windows(2) {
            if w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater) {
                return Err(Error::OutOfRange {
                    what: "table density",
                    value: w[1],
                    expected: "strictly increasing densities",
                });
            }
        }
        let level = densities.iter().map(|&d| solve(d)).collect::<Result<_>>()?;
        Ok(LevelTable {
            density: densities.to_vec(),
            level,
        })
    }

    pub fn density(&self) -> &[f64] {
        &self.density
    }

    pub fn level(&self) -> &[f64] {
        &self.level
    }

    /// Piecewise-linear level of a density field (held constant beyond the
    /// table's ends), as a chain of selects.
    pub fn piecewise(&self, density: &Expr) -> Expr {
        let (d, l) = (&self.density, &self.level);
        let last = d.len() - 1;
        let mut out = Expr::constant(l[last]);
        for i in (0..last).rev() {
            let t = (density - d[i]) / (d[i + 1] - d[i]);
            let seg = l[i] + (l[i + 1] - l[i]) * t;
            out = Expr::select(density.lt(d[i + 1]), seg, out);
        }
        Expr::select(density.lt(d[0]), Expr::constant(l[0]), out)
    }

    /// Least-squares polynomial coefficients (constant first) of the level
    /// in the density, of the given degree (below the table size).
    pub fn fit_polynomial(&self, degree: usize) -> Result<Vec<f64>> {
        let m = degree + 1;
        if m > self.density.len() {
            return Err(Error::OutOfRange {
                what: "polynomial degree",
                value: degree as f64,
                expected: "below the number of table entries",
            });
        }
        // Normal equations, solved by Gaussian elimination with pivoting.
        let mut a = vec![vec![0.0; m + 1]; m];
        for (&x, &y) in self.density.iter().zip(&self.level) {
            for (r, row) in a.iter_mut().enumerate() {
                for (c, v) in row[..m].iter_mut().enumerate() {
                    *v += x.powi((r + c) as i32);
                }
                row[m] += y * x.powi(r as i32);
            }
        }
        for col in 0..m {
            let piv = (col..m)
                .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
                .unwrap_or(col);
            a.swap(col, piv);
            if a[col][col].abs() < 1e-300 {
                return Err(Error::OutOfRange {
                    what: "polynomial degree",
                    value: degree as f64,
                    expected: "a table with enough distinct densities",
                });
            }
            let pivot = a[col].clone();
            for (r, row) in a.iter_mut().enumerate() {
                if r != col {
                    let k = row[col] / pivot[col];
                    for (v, p) in row.iter_mut().zip(&pivot).skip(col) {
                        *v -= k * p;
                    }
                }
            }
        }
        Ok((0..m).map(|i| a[i][m] / a[i][i]).collect())
    }
}

/// `sum_i c_i d^i` by Horner's rule.
pub fn polynomial(coeffs: &[f64], d: &Expr) -> Expr {
    coeffs
        .iter()
        .rev()
        .fold(Expr::constant(0.0), |acc, &c| acc * d + c)
}
