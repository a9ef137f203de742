//! Separable Gaussian smoothing of a volume in place, with the width in mm
//! (so anisotropic voxels get per-axis kernels), edges replicated.

use rayon::prelude::*;

/// Kernel of a Gaussian of `sigma` voxels, radius `ceil(3 sigma)`,
/// normalised to sum 1; `None` when sigma is too small to matter.
fn kernel(sigma: f64) -> Option<Vec<f32>> {
    if !(sigma > 0.05) {
        return None;
    }
    let r = (3.0 * sigma).ceil() as i64;
    let w: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let s: f64 = w.iter().sum();
    Some(w.iter().map(|v| (v / s) as f32).collect())
}

/// Radius in voxels of the kernel along one axis (0 for none).
pub(crate) fn radius(sigma_mm: f64, spacing: f64) -> usize {
    kernel(sigma_mm / spacing).map_or(0, |k| k.len() / 2)
}

/// Convolves one line (`src`, length n) into `dst` with edge replication.
fn convolve(src: &[f32], dst: &mut [f32], k: &[f32]) {
    let n = src.len() as i64;
    let r = (k.len() / 2) as i64;
    for (i, d) in dst.iter_mut().enumerate() {
        let mut acc = 0.0f32;
        for (t, &w) in k.iter().enumerate() {
            let j = (i as i64 + t as i64 - r).clamp(0, n - 1);
            acc += w * src[j as usize];
        }
        *d = acc;
    }
}

/// Smooths `v` (dims, x fastest) with a Gaussian of `sigma_mm` in place.
/// Extra memory: a few lines per thread and `2 r + 1` planes.
pub(crate) fn gaussian(
    v: &mut [f32],
    dims: [usize; 3],
    spacing: [f64; 3],
    sigma_mm: f64,
    tick: &(dyn Fn(u64) + Sync),
) {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    if let Some(k) = kernel(sigma_mm / spacing[0]) {
        v.par_chunks_mut(nx).for_each_init(
            || vec![0f32; nx],
            |line, row| {
                line.copy_from_slice(row);
                convolve(line, row, &k);
            },
        );
    }
    tick(1);
    if let Some(k) = kernel(sigma_mm / spacing[1]) {
        v.par_chunks_mut(plane).for_each_init(
            || (vec![0f32; ny], vec![0f32; ny]),
            |(a, b), p| {
                for i in 0..nx {
                    for j in 0..ny {
                        a[j] = p[i + nx * j];
                    }
                    convolve(a, b, &k);
                    for j in 0..ny {
                        p[i + nx * j] = b[j];
                    }
                }
            },
        );
    }
    tick(1);
    if let Some(k) = kernel(sigma_mm / spacing[2]) {
        // Plane by plane, keeping the original planes of the window.
        let r = k.len() / 2;
        let mut window: std::collections::VecDeque<Vec<f32>> = Default::default();
        let orig = |z: i64, v: &[f32]| {
            let z = z.clamp(0, nz as i64 - 1) as usize;
            v[z * plane..(z + 1) * plane].to_vec()
        };
        for t in -(r as i64)..=(r as i64) {
            window.push_back(orig(t, v));
        }
        const CHUNK: usize = 4096;
        for z in 0..nz {
            let out = &mut v[z * plane..(z + 1) * plane];
            let win = &window;
            out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, o)| {
                let base = c * CHUNK;
                for (i, d) in o.iter_mut().enumerate() {
                    let mut acc = 0.0f32;
                    for (t, &w) in k.iter().enumerate() {
                        acc += w * win[t][base + i];
                    }
                    *d = acc;
                }
            });
            // Slide: drop plane z - r, add original plane z + r + 1 (not
            // yet overwritten, or replicated past the end).
            window.pop_front();
            let next = z as i64 + r as i64 + 1;
            let add = if next < nz as i64 {
                v[next as usize * plane..(next as usize + 1) * plane].to_vec()
            } else {
                window.back().cloned().unwrap_or_default()
            };
            window.push_back(add);
        }
    }
    tick(1);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothing_keeps_constants_and_linear_ramps() {
        let dims = [9, 8, 11];
        let n = dims.iter().product::<usize>();
        let mut c = vec![3.5f32; n];
        gaussian(&mut c, dims, [1.0, 0.5, 2.0], 1.0, &|_| {});
        assert!(c.iter().all(|&x| (x - 3.5).abs() < 1e-5));
        // A linear ramp in z stays linear away from the ends (symmetric kernel).
        let mut r: Vec<f32> = (0..n).map(|i| (i / 72) as f32).collect();
        gaussian(&mut r, dims, [1.0, 1.0, 1.0], 1.0, &|_| {});
        for z in 4..7 {
            assert!(
                (r[z * 72 + 5] - z as f32).abs() < 1e-4,
                "z {z}: {}",
                r[z * 72 + 5]
            );
        }
        // A delta spreads into a normalised kernel.
        let mut d = vec![0f32; n];
        d[4 + 9 * (4 + 8 * 5)] = 1.0;
        gaussian(&mut d, dims, [1.0; 3], 0.8, &|_| {});
        let s: f32 = d.iter().sum();
        assert!((s - 1.0).abs() < 1e-4, "sum {s}");
    }
}
