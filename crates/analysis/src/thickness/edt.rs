//! Exact squared Euclidean distance transform of a 3D voxel set.
//!
//! For every voxel of the set, the squared distance (in voxel units, between
//! voxel centres) to the nearest voxel centre outside the set; 0 outside the
//! set. Space beyond the array counts as neither: distances reach only voxels
//! of the array ("open" border, as scipy's and PoreSpy's transforms do). A
//! voxel with no outside voxel anywhere gets [`INF`].
//!
//! Separable: the distance along z first (two linear sweeps, plane by plane),
//! then the lower envelope of parabolas along y and along x (the exact 1D
//! transform of Felzenszwalb and Huttenlocher, with Meijster's integer
//! intersection), all in integers, so the result is exact. Lines run in
//! parallel on the rayon pool.

use rayon::prelude::*;

/// Marks "no voxel outside the set on this line / in the array".
pub const INF: u32 = u32::MAX;

/// Largest side the transform accepts: squared distances `3 * n^2` must fit
/// a `u32` below [`INF`].
pub const MAX_SIDE: usize = 32767;

/// Squared distances for the voxels `inside(label)` of `labels` (x fastest,
/// then y, then z; `dims = [nx, ny, nz]`).
pub fn edt_squared(
    labels: &[u8],
    dims: [usize; 3],
    inside: impl Fn(u8) -> bool + Sync,
) -> Vec<u32> {
    assert_eq!(
        labels.len(),
        dims.iter().product::<usize>(),
        "label array length"
    );
    edt_squared_by(dims, |i| inside(labels[i]))
}

/// Squared distances for the voxels whose index `i` has `inside(i)`.
pub fn edt_squared_by(dims: [usize; 3], inside: impl Fn(usize) -> bool + Sync) -> Vec<u32> {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    assert!(dims.iter().all(|&d| d <= MAX_SIDE), "side over {MAX_SIDE}");
    let mut d = vec![0u32; plane * nz];
    if plane == 0 || nz == 0 {
        return d;
    }
    along_z(&mut d, plane, &inside);
    d.par_chunks_mut(plane).for_each_init(
        || Lines::new(ny),
        |s, p| {
            for i in 0..nx {
                for j in 0..ny {
                    s.f[j] = p[i + nx * j];
                }
                s.transform(ny);
                for j in 0..ny {
                    p[i + nx * j] = s.out[j];
                }
            }
        },
    );
    d.par_chunks_mut(nx).for_each_init(
        || Lines::new(nx),
        |s, row| {
            s.f[..nx].copy_from_slice(row);
            s.transform(nx);
            row.copy_from_slice(&s.out[..nx]);
        },
    );
    d
}

/// Linear distance along z to the nearest outside voxel, squared; planes
/// in order, each plane's voxels in parallel.
fn along_z(d: &mut [u32], plane: usize, inside: &(impl Fn(usize) -> bool + Sync)) {
    const CHUNK: usize = 4096;
    // Forward: distance to the nearest outside voxel below.
    for k in 0..d.len() / plane {
        let (done, rest) = d.split_at_mut(k * plane);
        let prev = if k > 0 {
            &done[(k - 1) * plane..]
        } else {
            &[][..]
        };
        let cur = &mut rest[..plane];
        cur.par_chunks_mut(CHUNK).enumerate().for_each(|(c, o)| {
            let i0 = c * CHUNK;
            for (j, o) in o.iter_mut().enumerate() {
                *o = if !inside(k * plane + i0 + j) {
                    0
                } else if k == 0 || prev[i0 + j] == INF {
                    INF
                } else {
                    prev[i0 + j] + 1
                };
            }
        });
    }
    // Backward: the nearer of below and above.
    for k in (0..d.len() / plane - 1).rev() {
        let (cur, next) = d.split_at_mut((k + 1) * plane);
        let cur = &mut cur[k * plane..];
        let next = &next[..plane];
        cur.par_chunks_mut(CHUNK)
            .zip(next.par_chunks(CHUNK))
            .for_each(|(o, n)| {
                for (o, &n) in o.iter_mut().zip(n) {
                    if n != INF && n + 1 < *o {
                        *o = n + 1;
                    }
                }
            });
    }
    d.par_chunks_mut(CHUNK).for_each(|c| {
        for v in c {
            if *v != INF {
                *v *= *v;
            }
        }
    });
}

/// Scratch of the 1D transform for lines up to a given length.
struct Lines {
    f: Vec<u32>,
    out: Vec<u32>,
    /// Apex positions of the parabolas on the envelope.
    apex: Vec<usize>,
    /// Where each envelope parabola starts to be the lowest.
    start: Vec<i64>,
}

impl Lines {
    fn new(n: usize) -> Lines {
        Lines {
            f: vec![0; n],
            out: vec![0; n],
            apex: vec![0; n],
            start: vec![0; n],
        }
    }

    /// `out[u] = min_i (u - i)^2 + f[i]` over the finite `f[i]`, for the
    /// first `n` entries; [`INF`] where every `f[i]` is.
    fn transform(&mut self, n: usize) {
        let f = &self.f[..n];
        let (apex, start) = (&mut self.apex, &mut self.start);
        let value = |u: i64, i: usize| (u - i as i64).pow(2) + f[i] as i64;
        // First abscissa where parabola `u` is at most parabola `i` (i < u).
        let sep = |i: usize, u: usize| {
            let (ii, uu) = (i as i64, u as i64);
            let num = uu * uu - ii * ii + f[u] as i64 - f[i] as i64;
            num.div_euclid(2 * (uu - ii)) + 1
        };
        let mut q: isize = -1;
        for (u, &fu) in f.iter().enumerate() {
            if fu == INF {
                continue;
            }
            while q >= 0 {
                let qi = q as usize;
                if value(start[qi], apex[qi]) > value(start[qi], u) {
                    q -= 1;
                } else {
                    break;
                }
            }
            if q < 0 {
                q = 0;
                apex[0] = u;
                start[0] = 0;
            } else {
                let w = sep(apex[q as usize], u);
                if w < n as i64 {
                    q += 1;
                    apex[q as usize] = u;
                    start[q as usize] = w;
                }
            }
        }
        let out = &mut self.out[..n];
        if q < 0 {
            out.fill(INF);
            return;
        }
        for u in (0..n).rev() {
            let qi = q as usize;
            out[u] = value(u as i64, apex[qi]) as u32;
            if u as i64 == start[qi] {
                q -= 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_transform_matches_brute_force() {
        let f = [INF, 4, INF, 0, 9, INF, INF, 1, INF, INF];
        let mut s = Lines::new(f.len());
        s.f.copy_from_slice(&f);
        s.transform(f.len());
        for u in 0..f.len() {
            let want = (0..f.len())
                .filter(|&i| f[i] != INF)
                .map(|i| (u as i64 - i as i64).pow(2) + f[i] as i64)
                .min()
                .unwrap();
            assert_eq!(s.out[u] as i64, want, "u = {u}");
        }
    }
}
