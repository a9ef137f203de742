//! Relative density (volume fraction) control: the level of a TPMS or the
//! radius of a strut lattice for a target volume fraction, bisection on any
//! model parameter, and a level(density) table that turns a density field
//! into a per-point level.
//!
//! Volume fractions come from [`LevelField`]: the field is sampled once on
//! a grid over the unit cell and the volume of `{g <= t}` is taken from its
//! piecewise-linear interpolant with Richardson extrapolation, so it is
//! deterministic and continuous in `t`, and a table of many densities costs
//! one sampling.

use crate::error::{Error, Result};
use crate::sampling::{sample_levels, LevelField};
use crate::struts::{StrutLattice, MAX_RADIUS};
use crate::tpms::{Solid, Tpms};
use microfrep_core::{Expr, Tape};

mod near;

/// Grid cells per axis of the unit cell for the TPMS level solve: the
/// extrapolated volume is within about 5e-5 of the exact one (measured
/// against the analysis crate: 5e-4 relative at worst, Neovius sheet at 0.1).
pub const TPMS_CELLS: usize = 96;
/// Grid cells per axis for strut radii: thin struts and the creases where
/// struts meet need a finer grid.
pub const STRUT_CELLS: usize = 128;

/// Bisection steps of [`solve_param`]: the bracket shrinks to 1e-12 of its
/// width.
const STEPS: usize = 40;
/// [`solve_param`] stops early once the fraction is this close (relative)
/// to the target.
const REL_TOL: f64 = 1e-6;

/// The value of the parameter `param` of `model` in `[lo, hi]` at which the
/// volume fraction of `model >= 0` in the box `[min, max]` (measured on a
/// grid of `n` cells per axis, see [`LevelField`]) is `target`. The
/// fraction must be monotone in the parameter (either way). Each step
/// samples the model anew; for a threshold `t - g` use [`LevelField::solve`].
pub fn solve_param(
    model: &Expr,
    param: &str,
    (lo, hi): (f64, f64),
    target: f64,
    (min, max): ([f64; 3], [f64; 3]),
    n: usize,
) -> Result<f64> {
    if !(target > 0.0 && target < 1.0) {
        return Err(Error::OutOfRange {
            what: "target volume fraction",
            value: target,
            expected: "strictly between 0 and 1",
        });
    }
    // Sublevel set {-model <= 0} is the solid.
    let tape = Tape::new(&(-model));
    let idx = tape
        .param_index(param)
        .ok_or_else(|| Error::NoParam(param.to_string()))?;
    let frac = |v: f64| {
        Ok::<f64, Error>(sample_levels(&tape, &[(idx, v)], min, max, n)?.fraction_below(0.0))
    };
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

/// Solves the level (TPMS) or radius (struts) of one unit-cell family for
/// any number of target densities from one sampling of its field: the solid
/// is `{g <= t}` with `g` the TPMS function (network) or the distance to the
/// nearest strut axis, or `{-t <= g <= t}` for a TPMS sheet.
#[derive(Clone, Debug)]
pub struct DensitySolver {
    field: LevelField,
    bracket: (f64, f64),
    /// Sheet: the solid is the band `{-t <= g <= t}` of the TPMS function.
    band: bool,
}

impl DensitySolver {
    /// For the TPMS solid `kind`/`solid` (cell size 1), on `n` (even) grid
    /// cells per axis.
    pub fn tpms(kind: Tpms, solid: Solid, n: usize) -> Result<DensitySolver> {
        let f = kind.field(&Expr::xyz(), 1.0);
        let field = sample_levels(&Tape::new(&f), &[], [0.0; 3], [1.0; 3], n)?;
        let band = solid == Solid::Sheet;
        let lo = if band { 0.0 } else { -kind.bound() };
        Ok(DensitySolver {
            field,
            bracket: (lo, kind.bound()),
            band,
        })
    }

    /// For the strut lattice `kind` (radius in cell units up to
    /// [`MAX_RADIUS`]), on `n` (even) grid cells per axis. The distance to
    /// the struts is computed in f64 from the lattice's own segments.
    pub fn struts(kind: StrutLattice, n: usize) -> Result<DensitySolver> {
        // Values beyond `cap` cannot reach a cell that the largest radius
        // cuts (the distance changes by at most a coarse cell's diagonal
        // across it), so farther struts are left out.
        let cap = MAX_RADIUS + 4.0 * 3f64.sqrt() / n.max(1) as f64;
        let near = near::NearStruts::new(kind, cap);
        let field = LevelField::from_fn([0.0; 3], [1.0; 3], n, |p| near.distance(p))?;
        Ok(DensitySolver {
            field,
            bracket: (0.0, MAX_RADIUS),
            band: false,
        })
    }

    /// The level (or radius) giving volume fraction `target`.
    pub fn solve(&self, target: f64) -> Result<f64> {
        if self.band {
            self.field.solve_band(target, self.bracket)
        } else {
            self.field.solve(target, self.bracket)
        }
    }

    /// The volume fraction at level (or radius) `t`.
    pub fn fraction(&self, t: f64) -> f64 {
        if self.band {
            self.field.fraction_between(-t, t)
        } else {
            self.field.fraction_below(t)
        }
    }
}

/// The TPMS level giving volume fraction `target` on one unit cell,
/// measured on a grid of `n` (even) cells per axis ([`TPMS_CELLS`] is
/// accurate to about 5e-5).
pub fn tpms_level(kind: Tpms, solid: Solid, target: f64, n: usize) -> Result<f64> {
    DensitySolver::tpms(kind, solid, n)?.solve(target)
}

/// The strut radius (cell units) giving volume fraction `target` on one
/// unit cell, measured on a grid of `n` (even) cells per axis
/// ([`STRUT_CELLS`] is the default).
pub fn strut_radius(kind: StrutLattice, target: f64, n: usize) -> Result<f64> {
    DensitySolver::struts(kind, n)?.solve(target)
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

    /// The densities of the table, increasing.
    pub fn density(&self) -> &[f64] {
        &self.density
    }

    /// The solved level (or radius) at each density, in the same order.
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
