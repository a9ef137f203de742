//! Bernstein-Bezier data fields (Park et al. §2.3, §3.1): the tensor-product
//! polynomial of degrees `(l, m, n)` on a box, and the barycentric polynomial
//! of degree `m` on a tetrahedron, both as [`microfrep_core::Field`]s with
//! exact gradients and sound interval bounds.
//!
//! **Tensor product** ([`BezierBox`]):
//! `P(p) = sum_{i,j,k} W_ijk B_i^l(u) B_j^m(v) B_k^n(w)` with
//! `(u, v, w) = (p - min) / (max - min)` and `B_i^l(u) = C(l, i) u^i (1-u)^(l-i)`.
//! Weights are stored with `i` (x) fastest, then `j`, then `k`:
//! `W[i + (l+1) (j + (m+1) k)]`. Outside the box the coordinates are clamped
//! to it (as for the core's `GridField`), so the field is continuous and
//! bounded everywhere and its partial along a clamped axis is 0.
//! [`BezierBox::interpolate`] finds the weights that make `P` pass through
//! samples on the regular grid of `(l+1)(m+1)(n+1)` points of the box (nodes
//! `u = a/l`, ...): the collocation is separable, so it is one small
//! `(l+1) x (l+1)` solve per axis; [`BezierBox::conditioning`] reports the
//! 1-norm condition number of each axis matrix (the tensor problem's is
//! their product): 1, 1, 2.5, 6 and 17.5 for degrees 0 to 4, growing
//! about 2.7 times per degree (5.9e3 at degree 10), fine for the small
//! degrees data sets use (Park's 4 x 4 x 4 grid: 6 per axis, 216 in all).
//!
//! **Barycentric** ([`BezierTet`]): for a tetrahedron `v0, v1, v2, v3` and a
//! point `p = v0 + x (v1 - v0) + y (v2 - v0) + z (v3 - v0)` (so `x`, `y`, `z`
//! are the barycentric coordinates of `v1`, `v2`, `v3` and `1 - x - y - z`
//! that of `v0`), `P(p) = sum W_ijk m!/(i! j! k! l!) x^i y^j z^k (1-x-y-z)^l`
//! with `l = m - i - j - k`, Park's formula on the unit tetrahedron. Weights
//! are in Park's summation order: lexicographic in `(i, j, k)`, `k` fastest,
//! i.e. `(0,0,0), (0,0,1), ..., (0,0,m), (0,1,0), ..., (m,0,0)`;
//! [`tet_index`] gives the position of `(i, j, k)`. There are
//! `(m+1)(m+2)(m+3)/6` of them. Weight `(i, j, k)` sits at the domain point
//! `v0 + (i (v1-v0) + j (v2-v0) + k (v3-v0)) / m`. Outside the tetrahedron
//! the polynomial simply continues.
//!
//! **Intervals.** Over a box, the tensor field's bound is the range of the
//! control net of the sub-box (de Casteljau subdivision of the net to the
//! box clamped into the domain; convex hull property), widened by a few
//! rounding units; its gradient bounds come the same way from the
//! derivative nets. The tetrahedral field's bound evaluates the Bernstein
//! form in interval arithmetic on the (affine, so exactly bounded)
//! barycentric coordinates, intersected with the weight range where the box
//! lies inside the tetrahedron.
//!
//! ```
//! use microfrep_graded::bezier::BezierBox;
//! use microfrep_core::Field;
//! // Degree 1 in x, 0 in y and z: the linear ramp from 2 to 4 over [0, 1].
//! let f = BezierBox::new("ramp", [0.0; 3], [1.0; 3], [1, 0, 0], vec![2.0, 4.0]).unwrap();
//! assert_eq!(f.eval([0.25, 0.7, 0.1]), 2.5);
//! assert_eq!(f.grad([0.25, 0.7, 0.1]).1, [2.0, 0.0, 0.0]);
//! ```

use crate::error::{Error, Result};
use microfrep_core::{Field, Interval};

/// Largest degree on any axis (tensor) or of a tetrahedral field: the
/// collocation's condition number at degree 16 is about 2e6.
pub const MAX_DEGREE: usize = 16;

/// `B_i^n(t)` for `i = 0..=n` into `out[..=n]` (de Casteljau's triangle,
/// stable), and with `d` the derivatives `dB_i^n/dt` into `d[..=n]`.
fn bernstein(n: usize, t: f64, out: &mut [f64], mut d: Option<&mut [f64]>) {
    let s = 1.0 - t;
    out[0] = 1.0;
    if let Some(d) = d.as_deref_mut() {
        d[0] = 0.0;
    }
    for level in 1..=n {
        if level == n {
            if let Some(d) = d.as_deref_mut() {
                // out holds B^{n-1}: dB_i^n = n (B_{i-1}^{n-1} - B_i^{n-1}).
                let nf = n as f64;
                for (i, di) in d.iter_mut().enumerate().take(n + 1) {
                    let left = if i > 0 { out[i - 1] } else { 0.0 };
                    let right = if i < n { out[i] } else { 0.0 };
                    *di = nf * (left - right);
                }
            }
        }
        out[level] = t * out[level - 1];
        for i in (1..level).rev() {
            out[i] = s * out[i] + t * out[i - 1];
        }
        out[0] *= s;
    }
}

/// The tensor-product Bernstein-Bezier polynomial on a box.
#[derive(Clone, Debug)]
pub struct BezierBox {
    name: String,
    min: [f64; 3],
    max: [f64; 3],
    deg: [usize; 3],
    w: Vec<f64>,
    /// Derivative nets along each axis (degree one lower on that axis),
    /// already divided by the box side.
    dw: [Vec<f64>; 3],
    range: (f64, f64),
    /// Rounding allowance of the interval bounds.
    tol: f64,
    dtol: [f64; 3],
    cond: Option<[f64; 3]>,
    /// Tags this field's rows in the per-thread [`RowCache`] (clones have
    /// the same weights, so they share it).
    id: u64,
}

fn check_box(min: [f64; 3], max: [f64; 3]) -> Result<()> {
    for a in 0..3 {
        if !(min[a].is_finite() && max[a].is_finite() && min[a] < max[a]) {
            return Err(Error::Bezier(format!(
                "box on axis {a} must be finite with min < max, got {} .. {}",
                min[a], max[a]
            )));
        }
    }
    Ok(())
}

fn check_degrees(deg: [usize; 3]) -> Result<usize> {
    if let Some(a) = (0..3).find(|&a| deg[a] > MAX_DEGREE) {
        return Err(Error::Bezier(format!(
            "degree {} on axis {a} exceeds the limit of {MAX_DEGREE}",
            deg[a]
        )));
    }
    Ok((deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1))
}

fn check_finite(w: &[f64], what: &str) -> Result<()> {
    match w.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(Error::Bezier(format!(
            "{what} {i} is {}, not a finite number",
            w[i]
        ))),
        None => Ok(()),
    }
}

fn range_of(w: &[f64]) -> (f64, f64) {
    w.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        })
}

/// Rounding allowance for values of a net: the evaluation and the
/// subdivision are convex combinations over `steps` levels, each off by at
/// most an ulp of the largest weight.
fn allowance(w: &[f64], steps: usize) -> f64 {
    let big = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    4.0 * (steps + 4) as f64 * f64::EPSILON * big + f64::MIN_POSITIVE
}

/// Collocation matrix `M[a][i] = B_i^n(a/n)` (row `a` is the node).
fn collocation(n: usize) -> Vec<Vec<f64>> {
    let mut b = vec![0.0; n + 1];
    (0..=n)
        .map(|a| {
            let t = if n == 0 { 0.0 } else { a as f64 / n as f64 };
            bernstein(n, t, &mut b, None);
            b.clone()
        })
        .collect()
}

/// Inverse by Gauss-Jordan elimination with partial pivoting.
fn invert(m: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = m.len();
    let mut a: Vec<Vec<f64>> = m.to_vec();
    let mut inv: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect();
    for c in 0..n {
        let p = (c..n).max_by(|&x, &y| a[x][c].abs().total_cmp(&a[y][c].abs()))?;
        if a[p][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, p);
        inv.swap(c, p);
        let d = a[c][c];
        for j in 0..n {
            a[c][j] /= d;
            inv[c][j] /= d;
        }
        for r in 0..n {
            if r != c && a[r][c] != 0.0 {
                let f = a[r][c];
                for j in 0..n {
                    a[r][j] -= f * a[c][j];
                    inv[r][j] -= f * inv[c][j];
                }
            }
        }
    }
    Some(inv)
}

fn norm1(m: &[Vec<f64>]) -> f64 {
    let n = m.len();
    (0..n)
        .map(|j| (0..n).map(|i| m[i][j].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// 1-norm condition number of the degree-`n` collocation matrix.
pub fn collocation_condition(n: usize) -> f64 {
    let m = collocation(n);
    let inv = invert(&m).expect("Bernstein collocation at distinct nodes is invertible");
    norm1(&m) * norm1(&inv)
}

/// Applies the matrix `m` (size `deg[axis] + 1`) along `axis` of a net.
fn apply_along(net: &mut [f64], deg: [usize; 3], axis: usize, m: &[Vec<f64>]) {
    let dims = deg.map(|d| d + 1);
    let stride = match axis {
        0 => 1,
        1 => dims[0],
        _ => dims[0] * dims[1],
    };
    let n = dims[axis];
    let mut line = vec![0.0; n];
    for base in 0..net.len() {
        // Visit each line once, from its first element.
        if (base / stride) % n != 0 {
            continue;
        }
        for (t, l) in line.iter_mut().enumerate() {
            *l = net[base + t * stride];
        }
        for (r, row) in m.iter().enumerate() {
            net[base + r * stride] = row.iter().zip(&line).map(|(a, b)| a * b).sum();
        }
    }
}

/// Nets up to this many weights are bounded in buffers on the stack.
const SMALL_NET: usize = 128;

/// The lines of `net` (dimensions `dims`) along `axis` gathered into
/// `buf`, coefficient-major: `buf[k * count + q]` is coefficient `k` of line
/// `q`, for `count = net.len() / dims[axis]` lines (so the de Casteljau
/// steps below run over all lines at once, in lanes).
fn gather_lines(net: &[f64], dims: [usize; 3], axis: usize, buf: &mut [f64]) -> usize {
    let n = dims[axis];
    let stride = [1, dims[0], dims[0] * dims[1]][axis];
    let count = net.len() / n;
    for q in 0..count {
        // Line q starts at its offset within one slab plus whole slabs.
        let f = (q % stride) + (q / stride) * stride * n;
        for k in 0..n {
            buf[k * count + q] = net[f + k * stride];
        }
    }
    count
}

/// [`gather_lines`] in reverse.
fn scatter_lines(buf: &[f64], dims: [usize; 3], axis: usize, net: &mut [f64]) {
    let n = dims[axis];
    let stride = [1, dims[0], dims[0] * dims[1]][axis];
    let count = net.len() / n;
    for q in 0..count {
        let f = (q % stride) + (q / stride) * stride * n;
        for k in 0..n {
            net[f + k * stride] = buf[k * count + q];
        }
    }
}

/// The value at `t` of each line gathered in `buf` ([`gather_lines`]: `n`
/// coefficients of `count` lines) into `buf[..count]`, by de Casteljau's
/// algorithm (convex combinations only).
fn casteljau_lines(buf: &mut [f64], n: usize, count: usize, t: f64) {
    let s = 1.0 - t;
    for level in 1..n {
        for i in 0..n - level {
            let (lo, hi) = buf.split_at_mut((i + 1) * count);
            for (a, &b) in lo[i * count..].iter_mut().zip(&hi[..count]) {
                *a = s * *a + t * b;
            }
        }
    }
}

/// The net `net` (dimensions `dims`) at coordinate `t` of `axis`: the net
/// of one fewer dimension (that axis of length 1, same layout), the values
/// [`net_range`] collapses it to.
fn collapse(net: &[f64], dims: [usize; 3], axis: usize, t: f64) -> Vec<f64> {
    let mut buf = vec![0.0; net.len()];
    let count = gather_lines(net, dims, axis, &mut buf);
    casteljau_lines(&mut buf, dims[axis], count, t);
    buf.truncate(count);
    buf
}

/// The Bernstein coefficients on `[a, b]` (within `[0, 1]`) of each line
/// gathered in `buf` ([`gather_lines`]: `n` coefficients of `count` lines),
/// in place: de Casteljau at `b` gives the left part on `[0, b]`, then at
/// `a / b` its right part.
fn subdivide_lines(buf: &mut [f64], n: usize, count: usize, a: f64, b: f64) {
    let deg = n - 1;
    if deg == 0 || (a == 0.0 && b == 1.0) {
        return;
    }
    let buf = &mut buf[..n * count];
    if b <= 0.0 {
        let (first, rest) = buf.split_at_mut(count);
        for r in rest.chunks_mut(count) {
            r.copy_from_slice(first);
        }
        return;
    }
    if b < 1.0 {
        for level in 1..=deg {
            for i in (level..=deg).rev() {
                let (lo, hi) = buf.split_at_mut(i * count);
                for (c, &p) in hi[..count].iter_mut().zip(&lo[(i - 1) * count..]) {
                    *c = (1.0 - b) * p + b * *c;
                }
            }
        }
    }
    let s = (a / b).clamp(0.0, 1.0);
    if s > 0.0 {
        for level in 1..=deg {
            for i in 0..=deg - level {
                let (lo, hi) = buf.split_at_mut((i + 1) * count);
                for (c, &q) in lo[i * count..].iter_mut().zip(&hi[..count]) {
                    *c = (1.0 - s) * *c + s * q;
                }
            }
        }
    }
}

/// Nets collapsed at a flat axis, per thread: `(field id, axis, coordinate
/// bits, net)`, most recent last. The boxes of one slice's tiles share
/// their z, so its net is collapsed once per slice and thread.
type FlatNets = Vec<(u64, usize, u64, Vec<f64>)>;

thread_local! {
    static FLAT: std::cell::RefCell<FlatNets> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Flat nets kept per thread.
const CACHED_FLAT: usize = 4;

/// Range of the net `w` (degrees `deg`) over the unit sub-box `u[a]`.
fn net_range(w: &[f64], deg: [usize; 3], u: [(f64, f64); 3]) -> (f64, f64) {
    if u.iter().all(|&(a, b)| a == 0.0 && b == 1.0) {
        return range_of(w);
    }
    // The net and scratch for its lines, on the stack when small.
    let (mut small, mut spare) = ([0.0; SMALL_NET], [0.0; SMALL_NET]);
    let (mut big, mut big_spare);
    let (mut net, mut buf): (&mut [f64], &mut [f64]) = if w.len() <= SMALL_NET {
        (&mut small[..w.len()], &mut spare[..w.len()])
    } else {
        big = vec![0.0; w.len()];
        big_spare = vec![0.0; w.len()];
        (&mut big[..], &mut big_spare[..])
    };
    net.copy_from_slice(w);
    let mut dims = deg.map(|d| d + 1);
    // Axes of zero width (a slice's fixed z) first: the net collapses to
    // its values at that coordinate (one slice across the axis), and the
    // other axes subdivide only that slice.
    let mut order = [0, 1, 2];
    order.sort_by_key(|&a| u[a].0 != u[a].1);
    for axis in order {
        let (a, b) = u[axis];
        let n = dims[axis];
        if (a == 0.0 && b == 1.0) || n == 1 {
            continue;
        }
        let count = gather_lines(net, dims, axis, buf);
        if a == b {
            casteljau_lines(buf, n, count, a);
            // Coefficient 0 of every line is the collapsed net.
            std::mem::swap(&mut net, &mut buf);
            net = &mut net[..count];
            buf = &mut buf[..count];
            dims[axis] = 1;
        } else {
            subdivide_lines(buf, n, count, a, b);
            scatter_lines(buf, dims, axis, net);
        }
    }
    range_of(net)
}

impl BezierBox {
    /// A field from its control weights (`x` fastest), degrees and box.
    pub fn new(
        name: &str,
        min: [f64; 3],
        max: [f64; 3],
        degrees: [usize; 3],
        weights: Vec<f64>,
    ) -> Result<BezierBox> {
        check_box(min, max)?;
        let want = check_degrees(degrees)?;
        if weights.len() != want {
            return Err(Error::Bezier(format!(
                "degrees {degrees:?} need (l+1)(m+1)(n+1) = {want} weights, got {}",
                weights.len()
            )));
        }
        check_finite(&weights, "weight")?;
        Ok(BezierBox::build(name, min, max, degrees, weights, None))
    }

    fn build(
        name: &str,
        min: [f64; 3],
        max: [f64; 3],
        deg: [usize; 3],
        w: Vec<f64>,
        cond: Option<[f64; 3]>,
    ) -> BezierBox {
        let dims = deg.map(|d| d + 1);
        let dw: [Vec<f64>; 3] = std::array::from_fn(|axis| {
            if deg[axis] == 0 {
                return Vec::new();
            }
            let mut dd = dims;
            dd[axis] -= 1;
            let scale = deg[axis] as f64 / (max[axis] - min[axis]);
            let mut out = Vec::with_capacity(dd[0] * dd[1] * dd[2]);
            for k in 0..dd[2] {
                for j in 0..dd[1] {
                    for i in 0..dd[0] {
                        let mut hi = [i, j, k];
                        hi[axis] += 1;
                        let at = |q: [usize; 3]| w[q[0] + dims[0] * (q[1] + dims[1] * q[2])];
                        out.push(scale * (at(hi) - at([i, j, k])));
                    }
                }
            }
            out
        });
        let steps = deg.iter().sum::<usize>() + 3;
        let tol = allowance(&w, 2 * steps);
        let dtol = std::array::from_fn(|a| allowance(&dw[a], 2 * steps));
        BezierBox {
            name: name.to_string(),
            min,
            max,
            deg,
            range: range_of(&w),
            w,
            dw,
            tol,
            dtol,
            cond,
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        }
    }

    /// The polynomial that passes through `samples` taken on the regular
    /// grid of `(l+1)(m+1)(n+1)` points spanning the box (x fastest; the
    /// grid point `(a, b, c)` is `min + (a/l, b/m, c/n) (max - min)`).
    pub fn interpolate(
        name: &str,
        min: [f64; 3],
        max: [f64; 3],
        degrees: [usize; 3],
        samples: &[f64],
    ) -> Result<BezierBox> {
        check_box(min, max)?;
        let want = check_degrees(degrees)?;
        if samples.len() != want {
            return Err(Error::Bezier(format!(
                "degrees {degrees:?} need (l+1)(m+1)(n+1) = {want} samples, got {}",
                samples.len()
            )));
        }
        check_finite(samples, "sample")?;
        let mut w = samples.to_vec();
        let mut cond = [1.0; 3];
        for axis in 0..3 {
            let m = collocation(degrees[axis]);
            let inv = invert(&m).expect("Bernstein collocation at distinct nodes is invertible");
            cond[axis] = norm1(&m) * norm1(&inv);
            apply_along(&mut w, degrees, axis, &inv);
        }
        check_finite(&w, "solved weight")?;
        Ok(BezierBox::build(name, min, max, degrees, w, Some(cond)))
    }

    /// Degrees `(l, m, n)`.
    pub fn degrees(&self) -> [usize; 3] {
        self.deg
    }

    /// Control weights, `x` fastest.
    pub fn weights(&self) -> &[f64] {
        &self.w
    }

    /// The box `(min, max)`.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.min, self.max)
    }

    /// For an interpolating field, the 1-norm condition number of each
    /// axis's collocation matrix (the 3D problem's is their product).
    pub fn conditioning(&self) -> Option<[f64; 3]> {
        self.cond
    }

    /// Value and, with `want_grad`, gradient.
    fn value_grad(&self, p: [f64; 3], want_grad: bool) -> (f64, [f64; 3]) {
        let mut b = [[0.0; MAX_DEGREE + 1]; 3];
        let mut db = [[0.0; MAX_DEGREE + 1]; 3];
        let mut live = [false; 3];
        for a in 0..3 {
            let side = self.max[a] - self.min[a];
            let u = (p[a] - self.min[a]) / side;
            live[a] = (0.0..=1.0).contains(&u);
            let u = u.clamp(0.0, 1.0);
            let n = self.deg[a];
            if want_grad {
                bernstein(n, u, &mut b[a], Some(&mut db[a]));
                for v in &mut db[a][..=n] {
                    *v /= side;
                }
            } else {
                bernstein(n, u, &mut b[a], None);
            }
        }
        let [l, m, n] = self.deg;
        // The value as the batch evaluation computes it (see `row_coeffs`).
        let mut c = [0.0; MAX_DEGREE + 1];
        self.row_coeffs(&b[1], &b[2], &mut c);
        let mut val = -0.0;
        for i in 0..=l {
            val += b[0][i] * c[i];
        }
        let mut g = [0.0; 3];
        if want_grad {
            for i in 0..=l {
                g[0] += db[0][i] * c[i];
            }
            for k in 0..=n {
                let (mut sy, mut sz) = (0.0, 0.0);
                for j in 0..=m {
                    let row = &self.w[(l + 1) * (j + (m + 1) * k)..][..=l];
                    let r: f64 = row.iter().zip(&b[0][..=l]).map(|(w, b)| w * b).sum();
                    sy += db[1][j] * r;
                    sz += b[1][j] * r;
                }
                g[1] += b[2][k] * sy;
                g[2] += db[2][k] * sz;
            }
        }
        for a in 0..3 {
            if !live[a] && !p[a].is_nan() {
                g[a] = 0.0;
            }
        }
        (val, g)
    }

    /// The polynomial's coefficients along x for fixed y and z: `c[i] =
    /// sum_k B_k(w) sum_j B_j(v) w_ijk` from the Bernstein values `by`, `bz`,
    /// so the value is `sum_i B_i(u) c[i]`. A row of points with the same y
    /// and z shares them (one cubic in u per point instead of the whole
    /// tensor sum); point and batch evaluation both sum in this order, so
    /// they give the same bits.
    fn row_coeffs(&self, by: &[f64], bz: &[f64], c: &mut [f64; MAX_DEGREE + 1]) {
        let [l, m, n] = self.deg;
        for (i, ci) in c.iter_mut().enumerate().take(l + 1) {
            let mut acc = -0.0;
            for k in 0..=n {
                let mut t = -0.0;
                for j in 0..=m {
                    t += by[j] * self.w[i + (l + 1) * (j + (m + 1) * k)];
                }
                acc += bz[k] * t;
            }
            *ci = acc;
        }
    }

    /// Unit sub-box of `b` clamped into the domain, and per axis whether
    /// `b` reaches outside the box (where the clamped partial is 0).
    fn unit_box(&self, b: [Interval; 3]) -> ([(f64, f64); 3], [bool; 3]) {
        let mut u = [(0.0, 1.0); 3];
        let mut out = [false; 3];
        for a in 0..3 {
            let side = self.max[a] - self.min[a];
            let lo = (b[a].lo - self.min[a]) / side;
            let hi = (b[a].hi - self.min[a]) / side;
            out[a] = lo < 0.0 || hi > 1.0;
            u[a] = (lo.clamp(0.0, 1.0), hi.clamp(0.0, 1.0));
        }
        (u, out)
    }
}

impl Field for BezierBox {
    fn name(&self) -> &str {
        &self.name
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.value_grad(p, false).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.value_grad(p, true)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let (u, _) = self.unit_box(b);
        let flat = (0..3).find(|&a| u[a].0 == u[a].1 && self.deg[a] > 0);
        let (lo, hi) = if u.iter().all(|&(a, b)| a == 0.0 && b == 1.0) {
            self.range
        } else if let Some(a) = flat {
            // The net at the flat coordinate (the same values `net_range`
            // would collapse it to), then the other axes.
            let t = u[a].0;
            let key = (self.id, a, t.to_bits());
            let mut d = self.deg;
            d[a] = 0;
            let mut rest = u;
            rest[a] = (0.0, 1.0);
            let cached = FLAT.with(|c| {
                let c = c.try_borrow().ok()?;
                let e = c.iter().find(|e| (e.0, e.1, e.2) == key)?;
                Some(net_range(&e.3, d, rest))
            });
            cached.unwrap_or_else(|| {
                let net = collapse(&self.w, self.deg.map(|d| d + 1), a, t);
                let r = net_range(&net, d, rest);
                FLAT.with(|c| {
                    if let Ok(mut c) = c.try_borrow_mut() {
                        if c.len() >= CACHED_FLAT {
                            c.remove(0);
                        }
                        c.push((key.0, key.1, key.2, net));
                    }
                });
                r
            })
        } else {
            net_range(&self.w, self.deg, u)
        };
        Interval::new(lo - self.tol, hi + self.tol)
    }

    fn grad_interval(&self, b: [Interval; 3]) -> [Interval; 3] {
        if b.iter().any(|i| i.is_nan()) {
            return [Interval::nan(); 3];
        }
        let (u, out) = self.unit_box(b);
        std::array::from_fn(|a| {
            if self.deg[a] == 0 {
                return Interval::point(0.0);
            }
            let mut d = self.deg;
            d[a] -= 1;
            let (mut lo, mut hi) = net_range(&self.dw[a], d, u);
            if out[a] {
                lo = lo.min(0.0);
                hi = hi.max(0.0);
            }
            Interval::new(lo - self.dtol[a], hi + self.dtol[a])
        })
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        // Lanes of points through the same f64 operations in the same order
        // as `value_grad`, so each result has the same bits as `eval`. Lanes
        // that share y and z (rows of a slice or grid) share the
        // coefficients along x, computed once per row.
        let [l, m, n] = self.deg;
        let param = |a: usize, c: f32| {
            ((c as f64 - self.min[a]) / (self.max[a] - self.min[a])).clamp(0.0, 1.0)
        };
        // The coefficients of rows met before on this thread (rows of a
        // slice band recur in every tile along it); without the cache (it
        // is busy) only the last row's.
        let mut cache = ROWS.with(|r| r.try_borrow_mut().ok().map(|mut c| std::mem::take(&mut *c)));
        let mut row: Option<(u32, u32)> = None;
        let mut shared = [0.0f64; MAX_DEGREE + 1];
        // Scratch lanes: each group writes the entries it reads first.
        let mut b0 = [[0.0f64; LANES]; MAX_DEGREE + 1];
        let mut c = [[0.0f64; LANES]; MAX_DEGREE + 1];
        let mut by = [[0.0f64; LANES]; MAX_DEGREE + 1];
        let mut bz = [[0.0f64; LANES]; MAX_DEGREE + 1];
        let mut q = 0;
        while q < out.len() {
            let len = LANES.min(out.len() - q);
            let (ys, zs) = (&y[q..q + len], &z[q..q + len]);
            let mut t = [0.0f64; LANES];
            for (t, &c) in t.iter_mut().zip(&x[q..q + len]) {
                *t = param(0, c);
            }
            bernstein_lanes(l, &t, &mut b0);
            let key = (ys[0].to_bits(), zs[0].to_bits());
            let same =
                ys.iter().all(|v| v.to_bits() == key.0) && zs.iter().all(|v| v.to_bits() == key.1);
            let mut val = [-0.0f64; LANES];
            if same {
                if row != Some(key) {
                    let hit = cache.as_ref().and_then(|c| c.get(self.id, key));
                    if let Some(h) = hit {
                        shared = h;
                    } else {
                        let mut by = [0.0; MAX_DEGREE + 1];
                        let mut bz = [0.0; MAX_DEGREE + 1];
                        bernstein(m, param(1, ys[0]), &mut by, None);
                        bernstein(n, param(2, zs[0]), &mut bz, None);
                        self.row_coeffs(&by, &bz, &mut shared);
                        if let Some(c) = cache.as_mut() {
                            c.put(self.id, key, &shared);
                        }
                    }
                    row = Some(key);
                }
                for i in 0..=l {
                    for e in 0..LANES {
                        val[e] += b0[i][e] * shared[i];
                    }
                }
            } else {
                for (a, cs, bs) in [(1, ys, &mut by), (2, zs, &mut bz)] {
                    let mut t = [0.0f64; LANES];
                    for (t, &c) in t.iter_mut().zip(cs) {
                        *t = param(a, c);
                    }
                    bernstein_lanes(self.deg[a], &t, bs);
                }
                for (i, ci) in c.iter_mut().enumerate().take(l + 1) {
                    let mut acc = [-0.0f64; LANES];
                    for k in 0..=n {
                        let mut s = [-0.0f64; LANES];
                        for j in 0..=m {
                            let w = self.w[i + (l + 1) * (j + (m + 1) * k)];
                            for e in 0..LANES {
                                s[e] += by[j][e] * w;
                            }
                        }
                        for e in 0..LANES {
                            acc[e] += bz[k][e] * s[e];
                        }
                    }
                    *ci = acc;
                }
                for i in 0..=l {
                    for e in 0..LANES {
                        val[e] += b0[i][e] * c[i][e];
                    }
                }
            }
            for (o, v) in out[q..q + len].iter_mut().zip(val) {
                *o = v as f32;
            }
            q += len;
        }
        if let Some(c) = cache {
            ROWS.with(|r| {
                if let Ok(mut r) = r.try_borrow_mut() {
                    *r = c;
                }
            });
        }
    }
}

/// Rows kept by [`RowCache`] (a power of two).
const CACHED_ROWS: usize = 256;

/// The x coefficients ([`BezierBox::row_coeffs`]) of recently evaluated
/// rows, per thread: direct-mapped by the row's y and z bits, tagged with
/// the field's id, so a hit has exactly the bits a fresh computation gives.
#[derive(Default)]
struct RowCache {
    /// `(field id, y bits, z bits, coefficients)`; id 0 is empty.
    rows: Vec<(u64, (u32, u32), [f64; MAX_DEGREE + 1])>,
}

impl RowCache {
    fn slot(key: (u32, u32)) -> usize {
        let h = (key.0 as u64 | (key.1 as u64) << 32).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        (h >> (64 - CACHED_ROWS.trailing_zeros())) as usize
    }

    fn get(&self, id: u64, key: (u32, u32)) -> Option<[f64; MAX_DEGREE + 1]> {
        let e = self.rows.get(Self::slot(key))?;
        (e.0 == id && e.1 == key).then_some(e.2)
    }

    fn put(&mut self, id: u64, key: (u32, u32), c: &[f64; MAX_DEGREE + 1]) {
        if self.rows.is_empty() {
            self.rows = vec![(0, (0, 0), [0.0; MAX_DEGREE + 1]); CACHED_ROWS];
        }
        self.rows[Self::slot(key)] = (id, key, *c);
    }
}

thread_local! {
    static ROWS: std::cell::RefCell<RowCache> = std::cell::RefCell::new(RowCache::default());
}

/// Source of [`BezierBox`] ids (0 marks an empty [`RowCache`] slot).
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Points evaluated together by [`BezierBox`]'s batch evaluation.
const LANES: usize = 8;

/// [`bernstein`] (without derivatives) for `LANES` parameters at once, the
/// same operations per lane: `out[i][e]` is `B_i^n(t[e])`.
fn bernstein_lanes(n: usize, t: &[f64; LANES], out: &mut [[f64; LANES]; MAX_DEGREE + 1]) {
    // Low degrees with their loops unrolled (the same operations).
    match n {
        1 => bernstein_lanes_of::<1>(t, out),
        2 => bernstein_lanes_of::<2>(t, out),
        3 => bernstein_lanes_of::<3>(t, out),
        4 => bernstein_lanes_of::<4>(t, out),
        5 => bernstein_lanes_of::<5>(t, out),
        _ => bernstein_lanes_of_any(n, t, out),
    }
}

#[inline(always)]
fn bernstein_lanes_of<const N: usize>(t: &[f64; LANES], out: &mut [[f64; LANES]; MAX_DEGREE + 1]) {
    bernstein_lanes_of_any(N, t, out)
}

#[inline(always)]
fn bernstein_lanes_of_any(n: usize, t: &[f64; LANES], out: &mut [[f64; LANES]; MAX_DEGREE + 1]) {
    let mut s = [0.0f64; LANES];
    for e in 0..LANES {
        s[e] = 1.0 - t[e];
    }
    out[0] = [1.0; LANES];
    for level in 1..=n {
        for e in 0..LANES {
            out[level][e] = t[e] * out[level - 1][e];
        }
        for i in (1..level).rev() {
            for e in 0..LANES {
                out[i][e] = s[e] * out[i][e] + t[e] * out[i - 1][e];
            }
        }
        for e in 0..LANES {
            out[0][e] *= s[e];
        }
    }
}

/// Number of weights of a degree-`m` tetrahedral field.
pub fn tet_weight_count(m: usize) -> usize {
    (m + 1) * (m + 2) * (m + 3) / 6
}

/// Position of weight `(i, j, k)` (`i + j + k <= m`) in the documented order.
pub fn tet_index(m: usize, i: usize, j: usize, k: usize) -> usize {
    // Weights before i: those with first index < i; then before j; then k.
    let before_i: usize = (0..i).map(|a| (m - a + 1) * (m - a + 2) / 2).sum();
    let before_j: usize = (0..j).map(|b| m - i - b + 1).sum();
    before_i + before_j + k
}

/// Arithmetic shared by point and interval evaluation of the tetrahedral
/// polynomial, so both perform the same operations in the same order (the
/// interval then bounds the rounded point values: IEEE operations round
/// monotonically).
trait Num: Copy {
    fn c(v: f64) -> Self;
    fn add(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
}

impl Num for f64 {
    fn c(v: f64) -> f64 {
        v
    }
    fn add(self, o: f64) -> f64 {
        self + o
    }
    fn mul(self, o: f64) -> f64 {
        self * o
    }
}

impl Num for Interval {
    fn c(v: f64) -> Interval {
        Interval::point(v)
    }
    fn add(self, o: Interval) -> Interval {
        Interval::add(self, o)
    }
    fn mul(self, o: Interval) -> Interval {
        Interval::mul(self, o)
    }
}

/// The barycentric Bernstein-Bezier polynomial on a tetrahedron.
#[derive(Clone, Debug)]
pub struct BezierTet {
    name: String,
    v0: [f64; 3],
    deg: usize,
    w: Vec<f64>,
    /// Exponents `[e0, e1, e2, e3]` of `lambda_0 .. lambda_3` per weight.
    exps: Vec<[usize; 4]>,
    /// `w * multinomial` per weight.
    wc: Vec<f64>,
    /// Rows: gradients of `lambda_0 .. lambda_3`.
    glam: [[f64; 3]; 4],
    range: (f64, f64),
    tol: f64,
}

impl BezierTet {
    /// A field on the tetrahedron `vertices` (non-degenerate) of degree `m`
    /// with weights in the documented order.
    pub fn new(
        name: &str,
        vertices: [[f64; 3]; 4],
        m: usize,
        weights: Vec<f64>,
    ) -> Result<BezierTet> {
        if m > MAX_DEGREE {
            return Err(Error::Bezier(format!(
                "degree {m} exceeds the limit of {MAX_DEGREE}"
            )));
        }
        let want = tet_weight_count(m);
        if weights.len() != want {
            return Err(Error::Bezier(format!(
                "degree {m} needs (m+1)(m+2)(m+3)/6 = {want} weights, got {}",
                weights.len()
            )));
        }
        check_finite(&weights, "weight")?;
        if let Some(i) = vertices.iter().flatten().position(|v| !v.is_finite()) {
            return Err(Error::Bezier(format!(
                "vertex coordinate {i} is {}, not finite",
                vertices[i / 3][i % 3]
            )));
        }
        let v0 = vertices[0];
        let e: [[f64; 3]; 3] =
            std::array::from_fn(|r| std::array::from_fn(|c| vertices[r + 1][c] - v0[c]));
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let det = dot(e[0], cross(e[1], e[2]));
        let scale = e.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        if det.is_nan() || det.abs() <= 1e-12 * scale.powi(3) {
            return Err(Error::Bezier(format!(
                "tetrahedron {vertices:?} is degenerate (volume {:e})",
                det / 6.0
            )));
        }
        // The matrix with columns e[0], e[1], e[2] maps (lambda_1..3) to
        // p - v0; the rows of its inverse, grad lambda_1..3, are the cross
        // products of the other two edges over the determinant.
        let r1 = cross(e[1], e[2]).map(|v| v / det);
        let r2 = cross(e[2], e[0]).map(|v| v / det);
        let r3 = cross(e[0], e[1]).map(|v| v / det);
        let r0 = std::array::from_fn(|c| -(r1[c] + r2[c] + r3[c]));
        let fact = |n: usize| (1..=n).map(|v| v as f64).product::<f64>();
        let mut exps = Vec::with_capacity(want);
        let mut wc = Vec::with_capacity(want);
        for i in 0..=m {
            for j in 0..=m - i {
                for k in 0..=m - i - j {
                    let l = m - i - j - k;
                    let idx = exps.len();
                    exps.push([l, i, j, k]);
                    let multi = fact(m) / (fact(i) * fact(j) * fact(k) * fact(l));
                    wc.push(weights[idx] * multi);
                }
            }
        }
        let tol = allowance(&weights, 4 * (m + 4));
        Ok(BezierTet {
            name: name.to_string(),
            v0,
            deg: m,
            range: range_of(&weights),
            w: weights,
            exps,
            wc,
            glam: [r0, r1, r2, r3],
            tol,
        })
    }

    /// The degree `m`.
    pub fn degree(&self) -> usize {
        self.deg
    }

    /// The weights in the documented order.
    pub fn weights(&self) -> &[f64] {
        &self.w
    }

    /// Barycentric coordinates `(lambda_0, .., lambda_3)` of `p`, each an
    /// affine function evaluated in a fixed order.
    fn lambdas<T: Num>(&self, p: [T; 3]) -> [T; 4] {
        let d: [T; 3] = std::array::from_fn(|c| p[c].add(T::c(-self.v0[c])));
        std::array::from_fn(|r| {
            let g = self.glam[r];
            let lin = d[0]
                .mul(T::c(g[0]))
                .add(d[1].mul(T::c(g[1])))
                .add(d[2].mul(T::c(g[2])));
            if r == 0 {
                T::c(1.0).add(lin)
            } else {
                lin
            }
        })
    }

    /// `P` and its partials in the four barycentric coordinates.
    fn poly<T: Num>(&self, lam: [T; 4], want_partials: bool) -> (T, [T; 4]) {
        let m = self.deg;
        let mut pw = vec![[T::c(1.0); 4]; m + 1];
        for e in 1..=m {
            for a in 0..4 {
                pw[e][a] = pw[e - 1][a].mul(lam[a]);
            }
        }
        let mut val = T::c(0.0);
        let mut part = [T::c(0.0); 4];
        for (ex, &wc) in self.exps.iter().zip(&self.wc) {
            let term = T::c(wc)
                .mul(pw[ex[0]][0])
                .mul(pw[ex[1]][1])
                .mul(pw[ex[2]][2])
                .mul(pw[ex[3]][3]);
            val = val.add(term);
            if want_partials {
                for a in 0..4 {
                    if ex[a] == 0 {
                        continue;
                    }
                    let mut t = T::c(wc * ex[a] as f64);
                    for b in 0..4 {
                        let e = if b == a { ex[b] - 1 } else { ex[b] };
                        t = t.mul(pw[e][b]);
                    }
                    part[a] = part[a].add(t);
                }
            }
        }
        (val, part)
    }

    fn gradient<T: Num>(&self, part: [T; 4]) -> [T; 3] {
        std::array::from_fn(|c| {
            (0..4).fold(T::c(0.0), |s, a| s.add(part[a].mul(T::c(self.glam[a][c]))))
        })
    }
}

impl Field for BezierTet {
    fn name(&self) -> &str {
        &self.name
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.poly(self.lambdas(p), false).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let (v, part) = self.poly(self.lambdas(p), true);
        (v, self.gradient(part))
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let lam = self.lambdas(b);
        let (v, _) = self.poly(lam, false);
        if lam.iter().all(|l| l.lo >= 0.0 && l.hi <= 1.0) {
            // Inside the tetrahedron: also within the weights (convex hull).
            let (lo, hi) = (self.range.0 - self.tol, self.range.1 + self.tol);
            return Interval::new(v.lo.max(lo), v.hi.min(hi));
        }
        v
    }

    fn grad_interval(&self, b: [Interval; 3]) -> [Interval; 3] {
        if b.iter().any(|i| i.is_nan()) {
            return [Interval::nan(); 3];
        }
        let (_, part) = self.poly(self.lambdas(b), true);
        self.gradient(part)
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            out[i] = self.eval([x[i] as f64, y[i] as f64, z[i] as f64]) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::BezierBox;
    use microfrep_core::Field;

    /// Rows of a grid (lanes sharing y and z, the path that reuses the
    /// coefficients along x), rows that change inside a group of lanes, and
    /// points outside the box or at NaN: every result has the bits of the
    /// point evaluation rounded to f32.
    #[test]
    fn shared_rows_have_point_bits() {
        let deg = [3, 2, 4];
        let count = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
        let w: Vec<f64> = (0..count)
            .map(|i| ((i * 29 % 13) as f64 - 6.0) / 5.0)
            .collect();
        let f = BezierBox::new("b", [-1.0, 0.0, 0.5], [1.0, 2.0, 1.5], deg, w).unwrap();
        let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
        // Rows of 13 points (not a multiple of the lane count), y and z
        // stepping inside and beyond the box.
        for r in 0..40 {
            for i in 0..13 {
                xs.push(-1.3 + 0.2 * i as f32);
                ys.push(-0.2 + 0.06 * r as f32);
                zs.push(0.4 + 0.03 * (r / 3) as f32);
            }
        }
        ys[100] = f32::NAN;
        zs[200] = f32::NAN;
        xs[300] = f32::NAN;
        for len in [8usize, 13, 16, 100, xs.len()] {
            let mut out = vec![0f32; len];
            f.eval_batch(&xs[..len], &ys[..len], &zs[..len], &mut out);
            for i in 0..len {
                let want = f.eval([xs[i] as f64, ys[i] as f64, zs[i] as f64]) as f32;
                assert!(
                    out[i].to_bits() == want.to_bits() || (out[i].is_nan() && want.is_nan()),
                    "point {i} of {len}: {} vs {want}",
                    out[i]
                );
            }
        }
        let mut out = vec![0f32; xs.len()];
        f.eval_batch(&xs, &ys, &zs, &mut out);
        assert!(out[100].is_nan() && out[200].is_nan() && out[300].is_nan());
        assert!(out[..100].iter().all(|v| v.is_finite()));
    }

    /// Interval bounds over boxes flat along one or two axes (a slice's
    /// fixed z, the path that keeps one slice of the net) contain the
    /// values at points of the box, and are tight: the flat box's bounds
    /// are no wider than the full box's. Nets of 60 weights (bounded in
    /// stack buffers) and of 336 (on the heap).
    #[test]
    fn flat_boxes_bound_their_values() {
        for deg in [[3, 2, 4], [6, 5, 7]] {
            flat_boxes_bound_values_of(deg);
        }
    }

    fn flat_boxes_bound_values_of(deg: [usize; 3]) {
        use microfrep_core::Interval;
        let count = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
        let w: Vec<f64> = (0..count)
            .map(|i| ((i * 29 % 13) as f64 - 6.0) / 5.0)
            .collect();
        let f = BezierBox::new("b", [-1.0, 0.0, 0.5], [1.0, 2.0, 1.5], deg, w).unwrap();
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f64 / (1u64 << 24) as f64
        };
        for case in 0..300 {
            let lo = [-1.2 + 2.2 * next(), -0.2 + 2.2 * next(), 0.4 + 1.2 * next()];
            let wide = [0.5 * next(), 0.5 * next(), 0.5 * next()];
            let mut b = [Interval::point(0.0); 3];
            for a in 0..3 {
                // Flat along z always, along y in every third case.
                let flat = a == 2 || (a == 1 && case % 3 == 0);
                b[a] = Interval::new(lo[a], lo[a] + if flat { 0.0 } else { wide[a] });
            }
            let iv = f.interval(b);
            let full = f.interval([b[0], b[1], Interval::new(lo[2] - 0.1, lo[2] + 0.1)]);
            assert!(
                iv.lo >= full.lo - 1e-12 && iv.hi <= full.hi + 1e-12,
                "{iv:?} vs {full:?}"
            );
            for _ in 0..50 {
                let p: [f64; 3] = std::array::from_fn(|a| b[a].lo + (b[a].hi - b[a].lo) * next());
                let v = f.eval(p);
                assert!(
                    iv.lo <= v && v <= iv.hi,
                    "case {case}: {v} outside {iv:?} at {p:?}"
                );
            }
        }
    }
}

#[cfg(test)]
mod cache_tests {
    use super::{net_range, BezierBox, CACHED_ROWS};
    use microfrep_core::{Field, Interval};

    /// Two fields of the same degrees and box but different weights.
    fn pair() -> (BezierBox, BezierBox) {
        let deg = [3, 3, 2];
        let n = 4 * 4 * 3;
        let w1: Vec<f64> = (0..n).map(|i| ((i * 7 % 11) as f64) / 10.0).collect();
        let w2: Vec<f64> = (0..n).map(|i| 1.0 - ((i * 5 % 13) as f64) / 12.0).collect();
        let lo = [-1.0, -1.0, 0.0];
        let hi = [1.0, 1.0, 1.0];
        (
            BezierBox::new("a", lo, hi, deg, w1).unwrap(),
            BezierBox::new("b", lo, hi, deg, w2).unwrap(),
        )
    }

    /// Rows evaluated by two fields in turn, and more rows than the
    /// per-thread row cache holds (so slots are reused by other rows): every
    /// batch value has the bits of the field's own point evaluation, and a
    /// clone (which shares the cache entries) agrees with the original.
    #[test]
    fn cached_rows_belong_to_their_field() {
        let (a, b) = pair();
        let a2 = a.clone();
        let rows = 3 * CACHED_ROWS;
        for pass in 0..2 {
            for r in 0..rows {
                let y = -1.0 + 2.0 * r as f32 / rows as f32;
                let z = 0.25 + 0.5 * (r % 3) as f32;
                let x: Vec<f32> = (0..40).map(|i| -1.1 + 0.055 * i as f32).collect();
                let (ys, zs) = (vec![y; x.len()], vec![z; x.len()]);
                for f in [&a, &b, &a2] {
                    let mut out = vec![0f32; x.len()];
                    f.eval_batch(&x, &ys, &zs, &mut out);
                    for (i, &o) in out.iter().enumerate() {
                        let want = f.eval([x[i] as f64, y as f64, z as f64]) as f32;
                        assert_eq!(o.to_bits(), want.to_bits(), "pass {pass} row {r} lane {i}");
                    }
                }
            }
        }
    }

    /// Bounds over boxes flat in z, asked of two fields in turn at more z
    /// than the per-thread cache of collapsed nets holds: each equals the
    /// bound computed from the field's own net without the cache.
    #[test]
    fn cached_flat_nets_belong_to_their_field() {
        let (a, b) = pair();
        for pass in 0..2 {
            for k in 0..12 {
                let z = 0.05 + 0.08 * k as f64;
                let bx = [
                    Interval::new(-0.3, 0.1),
                    Interval::new(0.2, 0.45),
                    Interval::point(z),
                ];
                // The second round finds both nets cached.
                for f in [&a, &b, &a, &b] {
                    let got = f.interval(bx);
                    let (u, _) = f.unit_box(bx);
                    let (lo, hi) = net_range(&f.w, f.deg, u);
                    assert_eq!(
                        (got.lo, got.hi),
                        (lo - f.tol, hi + f.tol),
                        "pass {pass} z {z}"
                    );
                }
            }
        }
    }
}
