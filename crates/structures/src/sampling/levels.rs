//! Volume of the sublevel sets `{g <= t}` of a field sampled once on the
//! nodes of a regular grid, for any threshold `t` without resampling.
//!
//! Each grid cell is split into six tetrahedra (the Kuhn split along the
//! cell's main diagonal); on each, `g` is replaced by the linear
//! interpolant of its corner values, whose sublevel volume has a closed
//! form. For a smooth surface `{g = t}` the interpolant's volume is off by
//! `C h^2` (the chords of the curved surface), so the volume on every other
//! node (cells of size `2h`, error `4 C h^2`) gives the Richardson
//! estimate `(4 V_h - V_2h) / 3`, accurate to a higher order.
//!
//! Sums are taken over fixed chunks in a fixed order, so results do not
//! depend on the number of threads.

use super::cells::{Active, Level, CHUNK};
use crate::error::{check_resolution, Error, Result};
use rayon::prelude::*;
use std::sync::OnceLock;

/// Largest number of cells per axis (the node values take `4 (n + 1)^3`
/// bytes: 540 MB at this size).
pub const MAX_CELLS: usize = 512;

/// Most root-finding steps of a solve (it takes about ten).
const MAX_STEPS: usize = 100;
/// A solve stops once the fraction is this close (relative) to the target,
/// far below the error of the estimate itself.
const STOP: f64 = 1e-9;

/// Node values of a field `g` on an `n x n x n` cell grid (`n` even).
#[derive(Clone, Debug)]
pub struct LevelField {
    n: usize,
    /// `(n + 1)^3` values, x fastest.
    g: Vec<f32>,
    min: f64,
    max: f64,
    /// The coarse grid's node values sorted, and their magnitudes sorted
    /// (for bands), made on the first solve: their quantiles give a narrow
    /// starting bracket.
    sorted: [OnceLock<Vec<f32>>; 2],
}

impl LevelField {
    /// Wraps `(n + 1)^3` node values (x fastest) of a grid of `n` cells per
    /// axis; `n` must be even (2 to [`MAX_CELLS`]) and the values finite.
    pub fn from_values(n: usize, g: Vec<f32>) -> Result<LevelField> {
        check_resolution("level grid cells per axis", n, 2, MAX_CELLS)?;
        if !n.is_multiple_of(2) {
            return Err(Error::BadResolution {
                what: "level grid cells per axis (must be even)",
                n,
                lo: 2,
                hi: MAX_CELLS,
            });
        }
        let r = n + 1;
        if g.len() != r * r * r {
            return Err(Error::OutOfRange {
                what: "node value count",
                value: g.len() as f64,
                expected: "(n + 1)^3 values",
            });
        }
        if let Some(k) = g.iter().position(|v| !v.is_finite()) {
            let (i, j, l) = (k % r, (k / r) % r, k / (r * r));
            let c = |i: usize| i as f64 / n as f64;
            return Err(Error::NotFinite {
                value: g[k] as f64,
                x: c(i),
                y: c(j),
                z: c(l),
            });
        }
        let (min, max) = g
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v as f64), b.max(v as f64))
            });
        Ok(LevelField {
            n,
            g,
            min,
            max,
            sorted: Default::default(),
        })
    }

    /// Samples `g` at the nodes of the grid of `n` cells per axis on the box
    /// `[min, max]` (z layers in parallel); non-finite values are an error.
    pub fn from_fn(
        min: [f64; 3],
        max: [f64; 3],
        n: usize,
        g: impl Fn([f64; 3]) -> f64 + Sync,
    ) -> Result<LevelField> {
        crate::error::check_box(min, max)?;
        check_resolution("level grid cells per axis", n, 2, MAX_CELLS)?;
        let r = n + 1;
        let c = |a: usize, i: usize| min[a] + (max[a] - min[a]) * i as f64 / n as f64;
        let mut vals = vec![0.0f32; r * r * r];
        vals.par_chunks_mut(r * r)
            .enumerate()
            .for_each(|(k, layer)| {
                for (q, v) in layer.iter_mut().enumerate() {
                    *v = g([c(0, q % r), c(1, q / r), c(2, k)]) as f32;
                }
            });
        LevelField::from_values(n, vals)
    }

    /// Cells per axis.
    pub fn cells(&self) -> usize {
        self.n
    }

    /// Smallest and largest node value.
    pub fn range(&self) -> (f64, f64) {
        (self.min, self.max)
    }

    fn level(&self, stride: usize) -> Level<'_> {
        Level::new(&self.g, self.n, stride)
    }

    /// Richardson estimate of the volume fraction of `{g <= t}` in the box.
    pub fn fraction_below(&self, t: f64) -> f64 {
        let part = |stride: usize| {
            let lv = self.level(stride);
            let cells = lv.cells().pow(3);
            let sums: Vec<f64> = (0..cells.div_ceil(CHUNK))
                .into_par_iter()
                .map(|c| {
                    (c * CHUNK..((c + 1) * CHUNK).min(cells))
                        .map(|q| lv.cell_fraction(lv.base(q), t))
                        .sum::<f64>()
                })
                .collect();
            sums.iter().sum::<f64>() / cells as f64
        };
        (4.0 * part(1) - part(2)) / 3.0
    }

    /// Richardson estimate of the volume fraction of `{lo <= g <= hi}`:
    /// the difference of two sublevel volumes, so a band around a surface
    /// (a TPMS sheet) is measured from the smooth `g`, not from `|g|`,
    /// whose crease at `g = 0` the interpolant would cut.
    pub fn fraction_between(&self, lo: f64, hi: f64) -> f64 {
        self.fraction_below(hi) - self.fraction_below(lo)
    }

    /// The threshold `t` in `[lo, hi]` where [`Self::fraction_below`] is
    /// `target` (strictly between 0 and 1), by bisection; cells whose
    /// values lie wholly on one side of the shrinking bracket are counted
    /// once and dropped, so each step costs only the cells it can change.
    pub fn solve(&self, target: f64, bracket: (f64, f64)) -> Result<f64> {
        self.bisect(target, bracket, false)
    }

    /// The half width `t` in `[lo, hi]` (`lo >= 0`) where the band
    /// `{-t <= g <= t}` has volume fraction `target`, as [`Self::solve`].
    pub fn solve_band(&self, target: f64, bracket: (f64, f64)) -> Result<f64> {
        if bracket.0.is_nan() || bracket.0 < 0.0 {
            return Err(Error::OutOfRange {
                what: "band half width",
                value: bracket.0,
                expected: ">= 0",
            });
        }
        self.bisect(target, bracket, true)
    }

    fn bisect(&self, target: f64, (lo, hi): (f64, f64), band: bool) -> Result<f64> {
        if !(target > 0.0 && target < 1.0) {
            return Err(Error::OutOfRange {
                what: "target volume fraction",
                value: target,
                expected: "strictly between 0 and 1",
            });
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(Error::OutOfRange {
                what: "threshold bracket",
                value: hi - lo,
                expected: "finite with lo < hi",
            });
        }
        // First the bracket that the node values' quantiles suggest (a
        // node count is within a few per cent of the volume); the whole
        // one where that bracket misses the target.
        let (qa, qb) = self.quantile_bracket(target, band);
        let (qa, qb) = (qa.max(lo), qb.min(hi));
        let tries = [(qa, qb), (lo, hi)];
        let mut found = None;
        for (a, b) in tries.into_iter().filter(|(a, b)| a < b) {
            let upper = Sublevel::new(self, a, b);
            // For a band, the lower threshold -t runs over [-b, -a].
            let lower = band.then(|| Sublevel::new(self, -b, -a));
            let (f_a, f_b) = (
                band_fraction(self, &upper, &lower, a),
                band_fraction(self, &upper, &lower, b),
            );
            if target >= f_a && target <= f_b {
                found = Some((a, b, f_a, f_b, upper, lower));
                break;
            }
            if (a, b) == (lo, hi) {
                return Err(Error::Unreachable {
                    target,
                    lo: f_a,
                    hi: f_b,
                });
            }
        }
        let Some((mut a, mut b, f_a, f_b, mut upper, mut lower)) = found else {
            return Err(Error::OutOfRange {
                what: "threshold bracket",
                value: hi - lo,
                expected: "finite with lo < hi",
            });
        };
        let frac = |upper: &Sublevel, lower: &Option<Sublevel>, t: f64| {
            band_fraction(self, upper, lower, t)
        };
        // Regula falsi with the Illinois halving: the fraction is smooth in
        // `t`, so a handful of steps suffice (each costs the active cells).
        let (mut fa, mut fb) = (f_a - target, f_b - target);
        let mut side = 0;
        for _ in 0..MAX_STEPS {
            if fa == 0.0 {
                return Ok(a);
            }
            if fb == 0.0 || b - a <= 1e-12 * (hi - lo) {
                return Ok(b);
            }
            let secant = b - fb * (b - a) / (fb - fa);
            let m = if secant > a && secant < b {
                secant
            } else {
                0.5 * (a + b)
            };
            let fm = frac(&upper, &lower, m) - target;
            if fm.abs() <= STOP * target {
                return Ok(m);
            }
            if fm < 0.0 {
                (a, fa) = (m, fm);
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                (b, fb) = (m, fm);
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
            upper.narrow(self, a, b);
            if let Some(l) = lower.as_mut() {
                l.narrow(self, -b, -a);
            }
        }
        Ok(if fa.abs() < fb.abs() { a } else { b })
    }
}

/// Volume fraction of `{g <= t}`, less that of `{g < -t}` for a band.
fn band_fraction(f: &LevelField, upper: &Sublevel, lower: &Option<Sublevel>, t: f64) -> f64 {
    upper.fraction(f, t) - lower.as_ref().map_or(0.0, |l| l.fraction(f, -t))
}

impl LevelField {
    /// Thresholds whose coarse-node counts are the target less and plus a
    /// margin: they almost always bracket the volume's threshold.
    fn quantile_bracket(&self, target: f64, band: bool) -> (f64, f64) {
        let sorted = self.sorted[band as usize].get_or_init(|| {
            // Every other node on each axis.
            let (r, row) = (self.n / 2 + 1, self.n + 1);
            let mut v: Vec<f32> = (0..r * r * r)
                .map(|q| {
                    let (i, j, k) = (q % r, (q / r) % r, q / (r * r));
                    let g = self.g[2 * (i + row * (j + row * k))];
                    if band {
                        g.abs()
                    } else {
                        g
                    }
                })
                .collect();
            v.sort_unstable_by(f32::total_cmp);
            v
        });
        let at = |p: f64| {
            let k = (p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64).round() as usize;
            sorted[k] as f64
        };
        let margin = 0.02 + 0.1 * target;
        (at(target - margin), at(target + margin))
    }
}

/// The sublevel volume for thresholds in a bracket, on both grids.
struct Sublevel {
    fine: Active,
    coarse: Active,
}

impl Sublevel {
    fn new(f: &LevelField, a: f64, b: f64) -> Sublevel {
        Sublevel {
            fine: Active::new(&f.level(1), a, b),
            coarse: Active::new(&f.level(2), a, b),
        }
    }

    fn fraction(&self, f: &LevelField, t: f64) -> f64 {
        (4.0 * self.fine.fraction(&f.level(1), t) - self.coarse.fraction(&f.level(2), t)) / 3.0
    }

    fn narrow(&mut self, f: &LevelField, a: f64, b: f64) {
        self.fine.narrow(&f.level(1), a, b);
        self.coarse.narrow(&f.level(2), a, b);
    }
}
