//! Separable Gaussian smoothing of a volume in place, with the width in mm
//! (so anisotropic voxels get per-axis kernels), edges replicated.

use rayon::prelude::*;

/// Widths below this many voxels leave the samples as they are.
const MIN_SIGMA: f64 = 0.05;

/// Beyond this many voxels every kernel is the same in f32 (its inner
/// weights are below 1e-15 of its tails), so wider ones are computed as
/// this wide.
const MAX_SIGMA: f64 = 1e15;

/// Radius in voxels of the kernel of a Gaussian of `sigma` voxels on a line
/// of `n` samples: `ceil(3 sigma)`, but at most `n - 1`. With the edges
/// replicated, a tap farther than `n - 1` from any sample of the line reads
/// an end sample, just as the tap at `n - 1` does, so its weight can be
/// added to that tap's and the result is the same. This bounds the kernel,
/// the work and the memory by the line, whatever the width asked for.
pub(crate) fn radius(sigma_mm: f64, spacing: f64, n: usize) -> usize {
    let sigma = sigma_mm / spacing;
    if !(sigma > MIN_SIGMA) || n < 2 {
        return 0;
    }
    let r = (3.0 * sigma.min(MAX_SIGMA)).ceil();
    if r >= (n - 1) as f64 {
        n - 1
    } else {
        r as usize
    }
}

/// The error function, to within 1.5e-7 (Abramowitz and Stegun 7.1.26).
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let y = 1.0 - poly * (-x * x).exp();
    if x < 0.0 {
        -y
    } else {
        y
    }
}

/// Sum of `exp(-i^2 / (2 sigma^2))` for `i` in `a..=b` (0 <= a): directly
/// for short runs, else as the integral from `a - 1/2` to `b + 1/2` (a run
/// this long has sigma above 10^4, where sum and integral agree to f64
/// precision but for the error function's).
fn tail_sum(sigma: f64, a: f64, b: f64) -> f64 {
    if b < a {
        return 0.0;
    }
    if b - a < 100_000.0 {
        let (a, b) = (a as u64, b as u64);
        return (a..=b)
            .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
            .sum();
    }
    let s = sigma * std::f64::consts::SQRT_2;
    sigma * (std::f64::consts::PI / 2.0).sqrt() * (erf((b + 0.5) / s) - erf((a - 0.5) / s))
}

/// Kernel of a Gaussian of `sigma_mm` along an axis of `n` samples
/// `spacing` apart: cut at 3 sigma, folded at [`radius`], normalised to sum
/// 1; `None` when it would change nothing.
fn kernel(sigma_mm: f64, spacing: f64, n: usize) -> Option<Vec<f32>> {
    let rr = radius(sigma_mm, spacing, n);
    if rr == 0 {
        return None;
    }
    let sigma = (sigma_mm / spacing).min(MAX_SIGMA);
    let r = (3.0 * sigma).ceil();
    let rr_i = rr as i64;
    let mut w: Vec<f64> = (-rr_i..=rr_i)
        .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let tail = tail_sum(sigma, rr as f64 + 1.0, r);
    w[0] += tail;
    w[2 * rr] += tail;
    let s: f64 = w.iter().sum();
    Some(w.iter().map(|v| (v / s) as f32).collect())
}

/// Why a smoothing width cannot be used on a volume, if it cannot.
pub(crate) fn check_width(
    sigma_mm: f64,
    dims: [usize; 3],
    spacing: [f64; 3],
) -> Result<(), String> {
    if !(sigma_mm.is_finite() && sigma_mm >= 0.0) {
        return Err(format!(
            "smoothing must be a non-negative width in mm, got {sigma_mm}"
        ));
    }
    let extent = (0..3)
        .map(|a| dims[a].saturating_sub(1) as f64 * spacing[a])
        .fold(0.0f64, f64::max);
    if sigma_mm > extent {
        return Err(format!(
            "smooth={sigma_mm} mm is wider than the whole scan ({extent} mm across its longest \
             side): it would blur the scan into about one value; use a width well below {extent} mm \
             (a voxel or two, {} mm, is typical)",
            spacing.iter().fold(f64::INFINITY, |m, &s| m.min(s))
        ));
    }
    Ok(())
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
/// Extra memory: a few lines per thread and `2 r + 1` planes, `r` the
/// z [`radius`] (below `nz`); work: `2 r + 1` taps per sample and axis.
pub(crate) fn gaussian(
    v: &mut [f32],
    dims: [usize; 3],
    spacing: [f64; 3],
    sigma_mm: f64,
    tick: &(dyn Fn(u64) + Sync),
) {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    if let Some(k) = kernel(sigma_mm, spacing[0], nx) {
        v.par_chunks_mut(nx).for_each_init(
            || vec![0f32; nx],
            |line, row| {
                line.copy_from_slice(row);
                convolve(line, row, &k);
            },
        );
    }
    tick(1);
    if let Some(k) = kernel(sigma_mm, spacing[1], ny) {
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
    if let Some(k) = kernel(sigma_mm, spacing[2], nz) {
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

    /// Edge-replicated convolution with the whole (unfolded) kernel of
    /// `sigma` voxels, cut at 3 sigma: the reference for the folded one.
    fn reference(src: &[f64], sigma: f64) -> Vec<f64> {
        let r = (3.0 * sigma).ceil() as i64;
        let w: Vec<f64> = (-r..=r)
            .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
            .collect();
        let s: f64 = w.iter().sum();
        let n = src.len() as i64;
        (0..n)
            .map(|i| {
                (-r..=r)
                    .map(|t| w[(t + r) as usize] / s * src[(i + t).clamp(0, n - 1) as usize])
                    .sum()
            })
            .collect()
    }

    #[test]
    fn folded_kernels_equal_the_whole_kernel_on_every_line() {
        let mut seed = 0x1234_5678_u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..300 {
            let n = 1 + (next() * 14.0) as usize;
            let sigma = 0.06 + next() * next() * 60.0;
            let src: Vec<f64> = (0..n).map(|_| next() * 10.0 - 5.0).collect();
            let want = reference(&src, sigma);
            let got = match kernel(sigma, 1.0, n) {
                None => src.iter().map(|&v| v as f32).collect::<Vec<_>>(),
                Some(k) => {
                    assert!(
                        k.len() <= 2 * n - 1,
                        "n {n}, sigma {sigma}: {} taps",
                        k.len()
                    );
                    let s32: Vec<f32> = src.iter().map(|&v| v as f32).collect();
                    let mut d = vec![0f32; n];
                    convolve(&s32, &mut d, &k);
                    d
                }
            };
            for i in 0..n {
                assert!(
                    (got[i] as f64 - want[i]).abs() < 1e-4,
                    "n {n}, sigma {sigma}, sample {i}: {} vs {}",
                    got[i],
                    want[i]
                );
            }
        }
    }

    #[test]
    fn any_width_gives_a_small_normalised_kernel() {
        for sigma_mm in [1e3, 1e9, 1e20, 1e300, f64::MAX] {
            for spacing in [1e-300, 1e-3, 1.0, 1e300] {
                for n in [1usize, 2, 7, 300] {
                    let r = radius(sigma_mm, spacing, n);
                    assert!(r < n.max(1), "{sigma_mm} {spacing} {n}: {r}");
                    if let Some(k) = kernel(sigma_mm, spacing, n) {
                        assert_eq!(k.len(), 2 * r + 1);
                        let s: f32 = k.iter().sum();
                        assert!(k.iter().all(|w| w.is_finite() && *w >= 0.0));
                        assert!((s - 1.0).abs() < 1e-5, "{sigma_mm} {spacing} {n}: {s}");
                    }
                }
            }
        }
        // Infinitely wide: half the weight on each end of the line.
        let k = kernel(1e20, 1.0, 7).unwrap();
        assert!(
            (k[0] - 0.5).abs() < 1e-5 && (k[12] - 0.5).abs() < 1e-5,
            "{k:?}"
        );
        // The integral form of a long tail against the plain sum.
        let (sigma, a, b) = (5e4, 7.0, 1.5e5);
        let plain: f64 = (7..=150_000u64)
            .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
            .sum();
        let fast = tail_sum(sigma, a, b);
        assert!((fast - plain).abs() < 1e-6 * plain, "{fast} vs {plain}");
        assert!((erf(0.5) - 0.520_499_877_8).abs() < 2e-7);
    }

    #[test]
    fn widths_beyond_the_scan_are_refused_with_the_reason() {
        let dims = [10, 10, 3];
        let h = [0.5, 0.5, 2.0];
        assert!(check_width(4.0, dims, h).is_ok());
        for w in [4.6, 1e9, 1e20, f64::MAX] {
            let e = check_width(w, dims, h).unwrap_err();
            assert!(
                e.contains("wider than the whole scan") && e.contains("4.5 mm"),
                "{e}"
            );
        }
        for w in [-1.0, f64::NAN, f64::INFINITY] {
            assert!(check_width(w, dims, h)
                .unwrap_err()
                .contains("non-negative"));
        }
    }

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
