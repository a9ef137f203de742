//! Data-driven fields: sampled data that behaves like any other graph node.
//!
//! A [`Field`] gives the four evaluation modes for a function of three
//! coordinates. The graph calls it at mapped coordinates, so a field composes
//! with transforms, set operations and as a parameter of other operations.

use crate::interval::Interval;
use std::fmt::Debug;

/// A scalar function of space backed by data (grids, meshes, images, ...).
pub trait Field: Send + Sync + Debug {
    /// Short name for diagnostics.
    fn name(&self) -> &str;
    /// Whether the value is a signed distance (in model units, positive
    /// inside) to the field's zero set, at least near it: a mesh's or a
    /// scan's distance. Consumers that need a depth below the surface
    /// (a skin, a grading) take such a value as it is and estimate one
    /// otherwise. The default: no.
    fn is_signed_distance(&self) -> bool {
        false
    }
    /// Reference value.
    fn eval(&self, p: [f64; 3]) -> f64;
    /// Value and gradient.
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]);
    /// Bounds of the value over a box; must contain every `eval` in the box.
    fn interval(&self, b: [Interval; 3]) -> Interval;
    /// Bounds of the partial derivatives over a box. The default knows nothing.
    fn grad_interval(&self, _b: [Interval; 3]) -> [Interval; 3] {
        [Interval::ENTIRE; 3]
    }
    /// Values for a batch (f32, the hot path). Override for speed.
    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            out[i] = self.eval([x[i] as f64, y[i] as f64, z[i] as f64]) as f32;
        }
    }
    /// Where the ray `origin + t dir`, `t` in `range`, first enters the
    /// inside (`f >= 0`), for a field that can find that directly (a mesh
    /// by intersecting its triangles) instead of by sampling. A ray caster
    /// of a model that is this field alone may use the answer in place of
    /// its own search. The default: [`RayEntry::Unknown`].
    fn ray_entry(&self, _origin: [f64; 3], _dir: [f64; 3], _range: [f64; 2]) -> RayEntry {
        RayEntry::Unknown
    }
}

/// What [`Field::ray_entry`] knows about a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RayEntry {
    /// Nothing: the caller searches the ray itself.
    Unknown,
    /// The ray stays outside over its whole range.
    Miss,
    /// The ray is outside before this depth and meets the surface there,
    /// entering the inside.
    Enter(f64),
}

/// Regular grid of samples over a box with trilinear interpolation; outside
/// the box the coordinates are clamped to it (the nearest boundary sample).
#[derive(Clone, Debug)]
pub struct GridField {
    name: String,
    dims: [usize; 3],
    min: [f64; 3],
    max: [f64; 3],
    /// x fastest, then y, then z.
    values: Vec<f64>,
    /// (min, max) of the 8 samples of each cell, for interval bounds.
    cell_range: Vec<(f64, f64)>,
    range: (f64, f64),
    /// The samples are a signed distance ([`GridField::as_distance`]).
    distance: bool,
}

/// Errors when building a grid field.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GridError {
    /// Fewer than two samples on some axis (no cell to interpolate in).
    #[error("grid needs at least 2 samples on each axis, got {0:?}")]
    TooSmall([usize; 3]),
    /// More samples than [`MAX_SAMPLES`] (or the count overflows).
    #[error("grid of {0:?} samples exceeds the limit of {MAX_SAMPLES}")]
    TooLarge([usize; 3]),
    /// The value array does not have one value per sample.
    #[error("grid has {got} values, dims {dims:?} need {want}")]
    WrongLength {
        /// Samples per axis.
        dims: [usize; 3],
        /// Length of the value array given.
        got: usize,
        /// Length the dimensions need.
        want: usize,
    },
    /// `min` is not below `max`, or not finite, on the given axis.
    #[error("grid box is empty or not finite on axis {0}")]
    BadBox(usize),
    /// A sample is NaN or infinite.
    #[error("grid value {index} is not finite")]
    NotFinite {
        /// Position in the value array.
        index: usize,
    },
}

/// Most samples a grid may hold (2 GiB of f64), so that a bad size is an
/// error rather than an allocation failure.
pub const MAX_SAMPLES: usize = 1 << 28;

/// Number of samples for `dims`, checked against the limits.
fn sample_count(dims: [usize; 3]) -> Result<usize, GridError> {
    if dims.iter().any(|&d| d < 2) {
        return Err(GridError::TooSmall(dims));
    }
    dims.iter()
        .try_fold(1usize, |n, &d| n.checked_mul(d))
        .filter(|&n| n <= MAX_SAMPLES)
        .ok_or(GridError::TooLarge(dims))
}

/// Checks `values` as the samples of a grid of `dims` (x fastest): the
/// sizes, the count, and that every value is finite.
pub(crate) fn check_samples(dims: [usize; 3], values: &[f64]) -> Result<(), GridError> {
    let want = sample_count(dims)?;
    if values.len() != want {
        return Err(GridError::WrongLength {
            dims,
            got: values.len(),
            want,
        });
    }
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(GridError::NotFinite { index }),
        None => Ok(()),
    }
}

impl GridField {
    /// A grid of `dims` samples spanning the box `min`..`max` (samples on the
    /// box corners), `values` with x fastest, then y, then z.
    /// The cell bounds for interval evaluation are computed here.
    ///
    /// # Errors
    ///
    /// [`GridError`] when a size is too small or too large, the value count
    /// does not match, the box is empty or not finite, or a value is not finite.
    pub fn new(
        name: &str,
        dims: [usize; 3],
        min: [f64; 3],
        max: [f64; 3],
        values: Vec<f64>,
    ) -> Result<GridField, GridError> {
        check_samples(dims, &values)?;
        for a in 0..3 {
            if !min[a].is_finite() || !max[a].is_finite() || min[a] >= max[a] {
                return Err(GridError::BadBox(a));
            }
        }
        let [nx, ny, nz] = dims;
        let mut cell_range = Vec::with_capacity((nx - 1) * (ny - 1) * (nz - 1));
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let mut lo = f64::INFINITY;
                    let mut hi = f64::NEG_INFINITY;
                    for c in 0..8 {
                        let v =
                            values[(i + (c & 1)) + nx * ((j + (c >> 1 & 1)) + ny * (k + (c >> 2)))];
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                    cell_range.push((lo, hi));
                }
            }
        }
        let range = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        Ok(GridField {
            name: name.to_string(),
            dims,
            min,
            max,
            values,
            cell_range,
            range,
            distance: false,
        })
    }

    /// This grid declared a signed distance (see
    /// [`Field::is_signed_distance`]), for samples of one.
    pub fn as_distance(mut self) -> GridField {
        self.distance = true;
        self
    }

    /// Samples a function on the grid nodes.
    pub fn sample(
        name: &str,
        dims: [usize; 3],
        min: [f64; 3],
        max: [f64; 3],
        f: impl Fn([f64; 3]) -> f64,
    ) -> Result<GridField, GridError> {
        let mut v = Vec::with_capacity(sample_count(dims)?);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let idx = [i, j, k];
                    let p: [f64; 3] = std::array::from_fn(|a| {
                        min[a] + (max[a] - min[a]) * idx[a] as f64 / (dims[a] - 1) as f64
                    });
                    v.push(f(p));
                }
            }
        }
        GridField::new(name, dims, min, max, v)
    }

    fn spacing(&self, a: usize) -> f64 {
        (self.max[a] - self.min[a]) / (self.dims[a] - 1) as f64
    }

    /// Cell index and local coordinate in [0, 1] on one axis, clamped; the
    /// flag says whether the coordinate was inside the box (derivative nonzero).
    fn locate(&self, a: usize, v: f64) -> (usize, f64, bool) {
        let n = self.dims[a];
        let t = (v - self.min[a]) / self.spacing(a);
        if t.is_nan() || t <= 0.0 {
            return (0, 0.0, false);
        }
        if t >= (n - 1) as f64 {
            return (n - 2, 1.0, false);
        }
        let i = (t.floor() as usize).min(n - 2);
        (i, t - i as f64, true)
    }

    fn at(&self, i: usize, j: usize, k: usize) -> f64 {
        self.values[i + self.dims[0] * (j + self.dims[1] * k)]
    }

    /// Index range of cells whose closed extent meets [lo, hi] on one axis.
    fn cell_span(&self, a: usize, iv: Interval) -> (usize, usize) {
        let h = self.spacing(a);
        let n = self.dims[a] - 1;
        let f = |v: f64| ((v - self.min[a]) / h).floor().clamp(0.0, (n - 1) as f64) as usize;
        (f(iv.lo), f(iv.hi))
    }
}

impl Field for GridField {
    fn name(&self) -> &str {
        &self.name
    }

    fn is_signed_distance(&self) -> bool {
        self.distance
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.grad(p).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|v| v.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let (i, u, du) = self.locate(0, p[0]);
        let (j, v, dv) = self.locate(1, p[1]);
        let (k, w, dw) = self.locate(2, p[2]);
        let c = |a: usize, b: usize, c: usize| self.at(i + a, j + b, k + c);
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c00 = lerp(c(0, 0, 0), c(1, 0, 0), u);
        let c10 = lerp(c(0, 1, 0), c(1, 1, 0), u);
        let c01 = lerp(c(0, 0, 1), c(1, 0, 1), u);
        let c11 = lerp(c(0, 1, 1), c(1, 1, 1), u);
        let c0 = lerp(c00, c10, v);
        let c1 = lerp(c01, c11, v);
        let val = lerp(c0, c1, w);
        let gx = {
            let d00 = c(1, 0, 0) - c(0, 0, 0);
            let d10 = c(1, 1, 0) - c(0, 1, 0);
            let d01 = c(1, 0, 1) - c(0, 0, 1);
            let d11 = c(1, 1, 1) - c(0, 1, 1);
            lerp(lerp(d00, d10, v), lerp(d01, d11, v), w) / self.spacing(0)
        };
        let gy = lerp(c10 - c00, c11 - c01, w) / self.spacing(1);
        let gz = (c1 - c0) / self.spacing(2);
        let g = [
            if du { gx } else { 0.0 },
            if dv { gy } else { 0.0 },
            if dw { gz } else { 0.0 },
        ];
        (val, g)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        // Trilinear interpolation stays within the range of each cell's corners.
        let (i0, i1) = self.cell_span(0, b[0]);
        let (j0, j1) = self.cell_span(1, b[1]);
        let (k0, k1) = self.cell_span(2, b[2]);
        let cells = (i1 - i0 + 1) * (j1 - j0 + 1) * (k1 - k0 + 1);
        if cells > 4096 {
            return Interval::new(self.range.0, self.range.1);
        }
        let (nx, ny) = (self.dims[0] - 1, self.dims[1] - 1);
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for k in k0..=k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let (l, h) = self.cell_range[i + nx * (j + ny * k)];
                    lo = lo.min(l);
                    hi = hi.max(h);
                }
            }
        }
        // Interpolation rounding can leave the corner range by an ulp.
        Interval::new(lo.next_down(), hi.next_up())
    }

    /// The value alone (no gradient; the same bits as [`Field::eval`]):
    /// the hot path of meshing and analysis over a cached part.
    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        // In chunks: first every point's cell and weights (a branch-free
        // loop the compiler vectorises), then the eight corners of each.
        // The clamps give `locate`'s cells and weights bit for bit (NaN
        // and anything below the box go to cell 0 at weight 0, anything
        // above to the last cell at weight 1).
        const CHUNK: usize = 64;
        let h: [f64; 3] = std::array::from_fn(|a| self.spacing(a));
        let top: [f64; 3] = std::array::from_fn(|a| (self.dims[a] - 1) as f64);
        let last: [f64; 3] = std::array::from_fn(|a| (self.dims[a] - 2) as f64);
        let [nx, ny, _] = self.dims;
        let (sx, sy, sz) = (1, nx, nx * ny);
        let v = &self.values;
        debug_assert!(self.dims.iter().all(|&n| n >= 2));
        let n = out.len().min(x.len()).min(y.len()).min(z.len());
        let mut base = [0usize; CHUNK];
        let mut wt = [[0.0f64; CHUNK]; 3];
        for start in (0..n).step_by(CHUNK) {
            let m = CHUNK.min(n - start);
            let coords = [
                &x[start..start + m],
                &y[start..start + m],
                &z[start..start + m],
            ];
            let mut cell = [[0.0f64; CHUNK]; 3];
            for a in 0..3 {
                for q in 0..m {
                    // `max` drops a NaN.
                    let t = ((coords[a][q] as f64 - self.min[a]) / h[a])
                        .max(0.0)
                        .min(top[a]);
                    let i = t.floor().min(last[a]);
                    cell[a][q] = i;
                    wt[a][q] = t - i;
                }
            }
            for q in 0..m {
                base[q] =
                    cell[0][q] as usize * sx + cell[1][q] as usize * sy + cell[2][q] as usize * sz;
            }
            for q in 0..m {
                let b = base[q];
                // Every cell index is at most dims - 2, so the far corner
                // `b + sx + sy + sz` is inside `values`.
                debug_assert!(b + sx + sy + sz < v.len());
                let at = |o: usize| unsafe { *v.get_unchecked(b + o) };
                let lerp = |a: f64, c: f64, t: f64| a + (c - a) * t;
                let (u, w1, w2) = (wt[0][q], wt[1][q], wt[2][q]);
                let c00 = lerp(at(0), at(sx), u);
                let c10 = lerp(at(sy), at(sy + sx), u);
                let c01 = lerp(at(sz), at(sz + sx), u);
                let c11 = lerp(at(sz + sy), at(sz + sy + sx), u);
                let r = lerp(lerp(c00, c10, w1), lerp(c01, c11, w1), w2) as f32;
                let nan = coords[0][q].is_nan() || coords[1][q].is_nan() || coords[2][q].is_nan();
                out[start + q] = if nan { f32::NAN } else { r };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The batch path of a grid gives the bits of the point path (rounded
    /// to f32), inside, on the edges, outside and for NaN.
    #[test]
    fn grid_batch_values_are_the_point_values() {
        let g = GridField::sample("g", [7, 5, 9], [-1.0, 0.5, -2.0], [2.0, 1.5, 3.0], |p| {
            (3.0 * p[0]).sin() + p[1] * p[2] - 0.25 * p[2] * p[2]
        })
        .unwrap();
        let mut s = 7u64;
        let mut r = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut pts: Vec<[f32; 3]> = (0..5000)
            .map(|_| {
                [
                    (-1.5 + 4.0 * r()) as f32,
                    (0.2 + 1.6 * r()) as f32,
                    (-2.5 + 6.0 * r()) as f32,
                ]
            })
            .collect();
        pts.extend([
            [-1.0, 0.5, -2.0],
            [2.0, 1.5, 3.0],
            [f32::NAN, 1.0, 0.0],
            [0.5, 1.0, 9.0],
        ]);
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
            pts.iter().map(|p| p[0]).collect(),
            pts.iter().map(|p| p[1]).collect(),
            pts.iter().map(|p| p[2]).collect(),
        );
        let mut out = vec![0.0f32; pts.len()];
        g.eval_batch(&x, &y, &z, &mut out);
        for (p, o) in pts.iter().zip(&out) {
            let want = g.eval(p.map(|c| c as f64)) as f32;
            assert!(
                want.to_bits() == o.to_bits() || (want.is_nan() && o.is_nan()),
                "{p:?}: {o} vs {want}"
            );
        }
    }
}
