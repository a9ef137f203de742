//! A smooth field from samples: the uniform cubic B-spline whose control
//! values are the samples of a grid. It is C2 everywhere (the kinks of a
//! distance field at its medial axis, and its creases, are rounded over
//! about one grid step), reproduces linear functions exactly, and lies
//! within the range of the control values it mixes, which gives sound
//! interval bounds.

use crate::field::{Field, GridError};
use crate::interval::Interval;

/// Control values per side of a block of the min/max table.
const BLOCK: usize = 8;

/// A uniform cubic B-spline over a grid of control values `values`
/// (x fastest) at `min + idx * step`; beyond the grid the edge values
/// repeat.
#[derive(Clone, Debug)]
pub struct SplineField {
    name: String,
    dims: [usize; 3],
    min: [f64; 3],
    step: [f64; 3],
    values: Vec<f64>,
    /// (min, max) of the control values of each block of `BLOCK`^3.
    blocks: Vec<(f64, f64)>,
    nb: [usize; 3],
    range: (f64, f64),
    distance: bool,
}

/// Uniform cubic B-spline weights of the four controls around parameter
/// `t` in [0, 1), and their derivatives.
fn weights(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    let w = [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ];
    let d = [
        -s * s / 2.0,
        (3.0 * t * t - 4.0 * t) / 2.0,
        (-3.0 * t * t + 2.0 * t + 1.0) / 2.0,
        t * t / 2.0,
    ];
    (w, d)
}

impl SplineField {
    /// The spline of `values` (`dims` samples, x fastest) with control `0`
    /// at `min` and spacing `step` per axis.
    ///
    /// # Errors
    /// [`GridError`] for too few or too many samples, a wrong count, a bad
    /// spacing or a value that is not finite.
    pub fn new(
        name: &str,
        dims: [usize; 3],
        min: [f64; 3],
        step: [f64; 3],
        values: Vec<f64>,
    ) -> Result<SplineField, GridError> {
        crate::field::check_samples(dims, &values)?;
        for a in 0..3 {
            if !(min[a].is_finite() && step[a].is_finite() && step[a] > 0.0) {
                return Err(GridError::BadBox(a));
            }
        }
        let nb: [usize; 3] = std::array::from_fn(|a| dims[a].div_ceil(BLOCK));
        let mut blocks = vec![(f64::INFINITY, f64::NEG_INFINITY); nb[0] * nb[1] * nb[2]];
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let v = values[i + dims[0] * (j + dims[1] * k)];
                    let b = &mut blocks[i / BLOCK + nb[0] * (j / BLOCK + nb[1] * (k / BLOCK))];
                    b.0 = b.0.min(v);
                    b.1 = b.1.max(v);
                }
            }
        }
        let range = blocks
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, b| {
                (r.0.min(b.0), r.1.max(b.1))
            });
        Ok(SplineField {
            name: name.to_string(),
            dims,
            min,
            step,
            values,
            blocks,
            nb,
            range,
            distance: false,
        })
    }

    /// Marks the field as (close to) a signed distance.
    pub fn as_distance(mut self) -> SplineField {
        self.distance = true;
        self
    }

    /// The cell and parameter of coordinate `v` on axis `a`.
    fn locate(&self, a: usize, v: f64) -> (isize, f64) {
        let u = (v - self.min[a]) / self.step[a];
        let u = u.clamp(-2.0, self.dims[a] as f64 + 1.0);
        let i = u.floor();
        (i as isize, u - i)
    }

    fn at(&self, i: isize, j: isize, k: isize) -> f64 {
        let c = |v: isize, n: usize| v.clamp(0, n as isize - 1) as usize;
        let (i, j, k) = (c(i, self.dims[0]), c(j, self.dims[1]), c(k, self.dims[2]));
        self.values[i + self.dims[0] * (j + self.dims[1] * k)]
    }

    /// Value and gradient at `p`.
    fn value_grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let (ix, tx) = self.locate(0, p[0]);
        let (iy, ty) = self.locate(1, p[1]);
        let (iz, tz) = self.locate(2, p[2]);
        let (wx, dx) = weights(tx);
        let (wy, dy) = weights(ty);
        let (wz, dz) = weights(tz);
        let (mut v, mut gx, mut gy, mut gz) = (0.0, 0.0, 0.0, 0.0);
        for c in 0..4 {
            for b in 0..4 {
                for a in 0..4 {
                    let s = self.at(
                        ix + a as isize - 1,
                        iy + b as isize - 1,
                        iz + c as isize - 1,
                    );
                    v += s * wx[a] * wy[b] * wz[c];
                    gx += s * dx[a] * wy[b] * wz[c];
                    gy += s * wx[a] * dy[b] * wz[c];
                    gz += s * wx[a] * wy[b] * dz[c];
                }
            }
        }
        // Beyond the clamped band the spline is constant along that axis.
        let inside = |a: usize, x: f64| {
            let u = (x - self.min[a]) / self.step[a];
            (-2.0..=self.dims[a] as f64 + 1.0).contains(&u)
        };
        let g = [
            if inside(0, p[0]) {
                gx / self.step[0]
            } else {
                0.0
            },
            if inside(1, p[1]) {
                gy / self.step[1]
            } else {
                0.0
            },
            if inside(2, p[2]) {
                gz / self.step[2]
            } else {
                0.0
            },
        ];
        (v, g)
    }
}

impl Field for SplineField {
    fn name(&self) -> &str {
        &self.name
    }

    fn is_signed_distance(&self) -> bool {
        self.distance
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        if p.iter().any(|c| c.is_nan()) {
            return f64::NAN;
        }
        self.value_grad(p).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|c| c.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        self.value_grad(p)
    }

    /// The values lie between the smallest and largest control value the
    /// box's points mix (the weights are non-negative and sum to 1): taken
    /// from the blocks those controls fall in.
    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter()
            .any(|i| i.is_nan() || !i.lo.is_finite() || !i.hi.is_finite())
        {
            if b.iter().any(|i| i.is_nan()) {
                return Interval::new(f64::NAN, f64::NAN);
            }
            return Interval::new(self.range.0, self.range.1);
        }
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        for a in 0..3 {
            let (i0, _) = self.locate(a, b[a].lo);
            let (i1, _) = self.locate(a, b[a].hi);
            let n = self.dims[a] as isize - 1;
            lo[a] = ((i0 - 1).clamp(0, n) as usize) / BLOCK;
            hi[a] = ((i1 + 2).clamp(0, n) as usize) / BLOCK;
        }
        let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    let (a, c) = self.blocks[i + self.nb[0] * (j + self.nb[1] * k)];
                    mn = mn.min(a);
                    mx = mx.max(c);
                }
            }
        }
        Interval::new(mn, mx)
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            out[i] = self.eval([x[i] as f64, y[i] as f64, z[i] as f64]) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field_check::{check_field, FieldCheck};

    fn linear() -> SplineField {
        let dims = [6, 5, 7];
        let mut v = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = [i as f64 * 0.5, -1.0 + j as f64 * 0.25, k as f64];
                    v.push(2.0 * p[0] - p[1] + 0.5 * p[2] + 1.0);
                }
            }
        }
        SplineField::new("lin", dims, [0.0, -1.0, 0.0], [0.5, 0.25, 1.0], v).unwrap()
    }

    #[test]
    fn linear_functions_are_reproduced_inside_the_grid() {
        let f = linear();
        // Where all four controls per axis exist (a cell from the edge).
        for p in [[1.1, -0.6, 2.3], [0.6, -0.3, 4.9], [1.5, -0.5, 3.0]] {
            let want = 2.0 * p[0] - p[1] + 0.5 * p[2] + 1.0;
            let (v, g) = f.grad(p);
            assert!((v - want).abs() < 1e-12, "{p:?}: {v} vs {want}");
            assert!((g[0] - 2.0).abs() < 1e-12 && (g[1] + 1.0).abs() < 1e-12);
            assert!((g[2] - 0.5).abs() < 1e-12);
        }
    }

    #[test]
    fn the_spline_passes_the_four_mode_check() {
        let f: std::sync::Arc<dyn Field> = std::sync::Arc::new(linear());
        // Inside and a little beyond the controls (the edge values repeat).
        let c = FieldCheck::new([[-0.9, -1.4, -1.9], [3.4, 0.4, 7.9]]);
        check_field(&f, &c).unwrap();
    }
}
