//! Trilinear interpolation on a sample lattice and a min/max pyramid for
//! sound, tight interval bounds over boxes of any size.

use microfrep_core::Interval;
use rayon::prelude::*;

/// A sample type the lattice can interpolate.
pub(crate) trait Sample: Copy + Send + Sync + 'static {
    fn v(self) -> f64;
}

macro_rules! sample {
    ($($t:ty),*) => {$(impl Sample for $t {
        #[inline]
        fn v(self) -> f64 {
            self as f64
        }
    })*};
}
sample!(u8, i8, u16, i16, f32);

/// Where the samples are: sample `(i, j, k)` at `origin + idx * spacing`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Lattice {
    pub dims: [usize; 3],
    pub origin: [f64; 3],
    pub spacing: [f64; 3],
}

impl Lattice {
    /// Cell index and local coordinate in [0, 1] on one axis, clamped to
    /// the samples; the flag says whether `v` was strictly inside (the
    /// derivative along the axis is then the cell's).
    #[inline]
    fn locate(&self, a: usize, v: f64) -> (usize, f64, bool) {
        let n = self.dims[a];
        let t = (v - self.origin[a]) / self.spacing[a];
        if t.is_nan() || t <= 0.0 {
            return (0, 0.0, false);
        }
        if t >= (n - 1) as f64 {
            return (n - 2, 1.0, false);
        }
        let i = (t.floor() as usize).min(n - 2);
        (i, t - i as f64, true)
    }

    /// Trilinear value and gradient of `data` at `p` (coordinates clamped
    /// to the sample box; the gradient is 0 along a clamped axis).
    #[inline]
    pub fn trilinear<T: Sample>(&self, data: &[T], p: [f64; 3]) -> (f64, [f64; 3]) {
        let (i, u, du) = self.locate(0, p[0]);
        let (j, v, dv) = self.locate(1, p[1]);
        let (k, w, dw) = self.locate(2, p[2]);
        let [nx, ny, _] = self.dims;
        let b = i + nx * (j + ny * k);
        let (sy, sz) = (nx, nx * ny);
        let c000 = data[b].v();
        let c100 = data[b + 1].v();
        let c010 = data[b + sy].v();
        let c110 = data[b + sy + 1].v();
        let c001 = data[b + sz].v();
        let c101 = data[b + sz + 1].v();
        let c011 = data[b + sz + sy].v();
        let c111 = data[b + sz + sy + 1].v();
        let lerp = |a: f64, b: f64, t: f64| a + (b - a) * t;
        let c00 = lerp(c000, c100, u);
        let c10 = lerp(c010, c110, u);
        let c01 = lerp(c001, c101, u);
        let c11 = lerp(c011, c111, u);
        let c0 = lerp(c00, c10, v);
        let c1 = lerp(c01, c11, v);
        let val = lerp(c0, c1, w);
        let gx = if du {
            let d0 = lerp(c100 - c000, c110 - c010, v);
            let d1 = lerp(c101 - c001, c111 - c011, v);
            lerp(d0, d1, w) / self.spacing[0]
        } else {
            0.0
        };
        let gy = if dv {
            lerp(c10 - c00, c11 - c01, w) / self.spacing[1]
        } else {
            0.0
        };
        let gz = if dw { (c1 - c0) / self.spacing[2] } else { 0.0 };
        (val, [gx, gy, gz])
    }

    /// Inclusive sample index range whose cells meet the box (clamped to
    /// the samples) on each axis.
    pub fn node_range(&self, b: [Interval; 3]) -> [[usize; 2]; 3] {
        std::array::from_fn(|a| {
            let n = self.dims[a] - 1;
            let t = |v: f64| ((v - self.origin[a]) / self.spacing[a]).clamp(0.0, n as f64);
            let lo = t(b[a].lo).floor() as usize;
            let hi = (t(b[a].hi).ceil() as usize).min(n);
            [lo.min(hi), hi]
        })
    }
}

/// Cells per block side at the finest pyramid level.
const BLOCK: usize = 4;

/// Min/max of the samples over blocks of `BLOCK * 2^level` cells, each
/// block holding its corner samples too (so it bounds the interpolant over
/// its cells).
#[derive(Clone, Debug)]
pub(crate) struct Pyramid {
    levels: Vec<Level>,
}

#[derive(Clone, Debug)]
struct Level {
    /// Blocks per axis.
    nb: [usize; 3],
    /// Cells per block side.
    side: usize,
    lo: Vec<f32>,
    hi: Vec<f32>,
}

impl Pyramid {
    /// Bytes a pyramid over `dims` samples takes (for memory planning).
    pub fn bytes(dims: [usize; 3]) -> u64 {
        let mut nb: [usize; 3] = std::array::from_fn(|a| (dims[a] - 1).div_ceil(BLOCK).max(1));
        let mut total = 0u64;
        loop {
            total += nb.iter().product::<usize>() as u64 * 8;
            if nb.iter().all(|&n| n == 1) {
                return total;
            }
            nb = nb.map(|n| n.div_ceil(2));
        }
    }

    /// Builds the pyramid of `data` (raw values) on `lat`.
    pub fn new<T: Sample>(lat: &Lattice, data: &[T]) -> Pyramid {
        let d = lat.dims;
        let nb0: [usize; 3] = std::array::from_fn(|a| (d[a] - 1).div_ceil(BLOCK).max(1));
        let plane0 = nb0[0] * nb0[1];
        let mut lo = vec![0f32; plane0 * nb0[2]];
        let mut hi = vec![0f32; plane0 * nb0[2]];
        lo.par_chunks_mut(plane0)
            .zip(hi.par_chunks_mut(plane0))
            .enumerate()
            .for_each(|(bk, (lp, hp))| {
                for bj in 0..nb0[1] {
                    for bi in 0..nb0[0] {
                        let r = block_nodes(d, [bi, bj, bk], BLOCK);
                        let (l, h) = scan(d, data, r);
                        lp[bi + nb0[0] * bj] = l as f32;
                        hp[bi + nb0[0] * bj] = h as f32;
                    }
                }
            });
        let mut levels = vec![Level {
            nb: nb0,
            side: BLOCK,
            lo,
            hi,
        }];
        loop {
            let prev = levels.last().expect("level 0");
            if prev.nb.iter().all(|&n| n == 1) {
                break;
            }
            let nb = prev.nb.map(|n| n.div_ceil(2));
            let mut lo = vec![f32::INFINITY; nb.iter().product()];
            let mut hi = vec![f32::NEG_INFINITY; lo.len()];
            for k in 0..prev.nb[2] {
                for j in 0..prev.nb[1] {
                    for i in 0..prev.nb[0] {
                        let s = i + prev.nb[0] * (j + prev.nb[1] * k);
                        let t = i / 2 + nb[0] * (j / 2 + nb[1] * (k / 2));
                        lo[t] = lo[t].min(prev.lo[s]);
                        hi[t] = hi[t].max(prev.hi[s]);
                    }
                }
            }
            let side = prev.side * 2;
            levels.push(Level { nb, side, lo, hi });
        }
        Pyramid { levels }
    }

    /// Min and max of `data` over the inclusive node range `r`.
    pub fn range<T: Sample>(&self, dims: [usize; 3], data: &[T], r: [[usize; 2]; 3]) -> (f64, f64) {
        let count: usize = r.iter().map(|[a, b]| b - a + 1).product();
        if count <= 512 {
            return scan(dims, data, r);
        }
        let mut acc = (f64::INFINITY, f64::NEG_INFINITY);
        let top = self.levels.len() - 1;
        let nb = self.levels[top].nb;
        for k in 0..nb[2] {
            for j in 0..nb[1] {
                for i in 0..nb[0] {
                    self.visit(top, [i, j, k], dims, data, r, &mut acc);
                }
            }
        }
        acc
    }

    fn visit<T: Sample>(
        &self,
        level: usize,
        b: [usize; 3],
        dims: [usize; 3],
        data: &[T],
        r: [[usize; 2]; 3],
        acc: &mut (f64, f64),
    ) {
        let l = &self.levels[level];
        let nodes = block_nodes(dims, b, l.side);
        let mut inter = [[0usize; 2]; 3];
        let mut inside = true;
        for a in 0..3 {
            let lo = nodes[a][0].max(r[a][0]);
            let hi = nodes[a][1].min(r[a][1]);
            if lo > hi {
                return;
            }
            inter[a] = [lo, hi];
            inside &= nodes[a] == inter[a];
        }
        let idx = b[0] + l.nb[0] * (b[1] + l.nb[1] * b[2]);
        let (bl, bh) = (l.lo[idx] as f64, l.hi[idx] as f64);
        if bl >= acc.0 && bh <= acc.1 {
            return; // cannot widen the result
        }
        if inside {
            acc.0 = acc.0.min(bl);
            acc.1 = acc.1.max(bh);
            return;
        }
        if level == 0 {
            let (sl, sh) = scan(dims, data, inter);
            acc.0 = acc.0.min(sl);
            acc.1 = acc.1.max(sh);
            return;
        }
        let child = &self.levels[level - 1];
        for dk in 0..2 {
            for dj in 0..2 {
                for di in 0..2 {
                    let c = [2 * b[0] + di, 2 * b[1] + dj, 2 * b[2] + dk];
                    if c[0] < child.nb[0] && c[1] < child.nb[1] && c[2] < child.nb[2] {
                        self.visit(level - 1, c, dims, data, r, acc);
                    }
                }
            }
        }
    }
}

/// Inclusive node range of block `b` of `side` cells.
fn block_nodes(dims: [usize; 3], b: [usize; 3], side: usize) -> [[usize; 2]; 3] {
    std::array::from_fn(|a| {
        let lo = (b[a] * side).min(dims[a] - 1);
        [lo, (lo + side).min(dims[a] - 1)]
    })
}

/// Min and max over an inclusive node range, directly.
fn scan<T: Sample>(dims: [usize; 3], data: &[T], r: [[usize; 2]; 3]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for k in r[2][0]..=r[2][1] {
        for j in r[1][0]..=r[1][1] {
            let row = dims[0] * (j + dims[1] * k);
            for &v in &data[row + r[0][0]..=row + r[0][1]] {
                let v = v.v();
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    (lo, hi)
}

/// Widens `[lo, hi]` for the rounding of trilinear interpolation (a few
/// ulps of the largest magnitude).
pub(crate) fn widen(lo: f64, hi: f64) -> (f64, f64) {
    let m = lo.abs().max(hi.abs());
    let e = m * 4.0 * f64::EPSILON + f64::MIN_POSITIVE;
    (lo - e, hi + e)
}
