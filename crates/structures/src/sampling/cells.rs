//! The cells of a node grid (or of its every-other-node coarsening) and the
//! sublevel volume of the linear interpolant on their Kuhn tetrahedra.

use microfrep_analysis::volume::tet_fraction;
use microfrep_core::geom::KUHN_TETS as TETS;
use rayon::prelude::*;

/// Cells summed per task: fixed, so sums are deterministic.
pub(super) const CHUNK: usize = 4096;

/// One of the two grids: cells of `stride` node spacings.
pub(super) struct Level<'a> {
    g: &'a [f32],
    /// Node index offset of each of the eight corners.
    corner: [usize; 8],
    /// Cells per axis on this level.
    m: usize,
    /// Node row length `n + 1`.
    row: usize,
    stride: usize,
}

impl<'a> Level<'a> {
    /// The cells of `stride` (1 or 2) node spacings of the grid of `n`
    /// cells per axis with node values `g`.
    pub(super) fn new(g: &'a [f32], n: usize, stride: usize) -> Level<'a> {
        let row = n + 1;
        let corner = std::array::from_fn(|c| {
            stride * ((c & 1) + row * ((c >> 1) & 1) + row * row * ((c >> 2) & 1))
        });
        Level {
            g,
            corner,
            m: n / stride,
            row,
            stride,
        }
    }

    /// Cells per axis.
    pub(super) fn cells(&self) -> usize {
        self.m
    }

    /// Node index of the low corner of cell `q` (x fastest).
    pub(super) fn base(&self, q: usize) -> usize {
        let m = self.m;
        let (i, j, k) = (q % m, (q / m) % m, q / (m * m));
        self.stride * (i + self.row * (j + self.row * k))
    }

    fn corners(&self, base: usize) -> [f64; 8] {
        self.corner.map(|o| self.g[base + o] as f64)
    }

    fn bounds(&self, base: usize) -> (f64, f64) {
        self.corners(base)
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            })
    }

    /// Fraction of the cell where the interpolant is `<= t`.
    pub(super) fn cell_fraction(&self, base: usize, t: f64) -> f64 {
        let u = self.corners(base).map(|g| t - g);
        if u.iter().all(|&v| v >= 0.0) {
            return 1.0;
        }
        if u.iter().all(|&v| v < 0.0) {
            return 0.0;
        }
        TETS.iter()
            .map(|tet| tet_fraction(tet.map(|c| u[c])))
            .sum::<f64>()
            / 6.0
    }
}

/// Cells of one level that a bracket `[a, b]` of thresholds can still
/// change, and the count of those full for every threshold in it.
pub(super) struct Active {
    full: f64,
    cells: Vec<u32>,
}

impl Active {
    pub(super) fn new(lv: &Level<'_>, a: f64, b: f64) -> Active {
        let total = lv.m * lv.m * lv.m;
        let parts: Vec<(f64, Vec<u32>)> = (0..total.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut full = 0.0;
                let mut keep = Vec::new();
                for q in c * CHUNK..((c + 1) * CHUNK).min(total) {
                    let base = lv.base(q);
                    let (lo, hi) = lv.bounds(base);
                    if hi <= a {
                        full += 1.0;
                    } else if lo <= b {
                        keep.push(base as u32);
                    }
                }
                (full, keep)
            })
            .collect();
        let mut out = Active {
            full: 0.0,
            cells: Vec::new(),
        };
        for (f, keep) in parts {
            out.full += f;
            out.cells.extend(keep);
        }
        out
    }

    pub(super) fn narrow(&mut self, lv: &Level<'_>, a: f64, b: f64) {
        let mut full = 0.0;
        self.cells.retain(|&base| {
            let (lo, hi) = lv.bounds(base as usize);
            if hi <= a {
                full += 1.0;
                false
            } else {
                lo <= b
            }
        });
        self.full += full;
    }

    pub(super) fn fraction(&self, lv: &Level<'_>, t: f64) -> f64 {
        let sums: Vec<f64> = self
            .cells
            .par_chunks(CHUNK)
            .map(|cs| {
                cs.iter()
                    .map(|&base| lv.cell_fraction(base as usize, t))
                    .sum::<f64>()
            })
            .collect();
        (self.full + sums.iter().sum::<f64>()) / (lv.m * lv.m * lv.m) as f64
    }
}
