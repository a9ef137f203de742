//! What a scan holds, to choose an iso value: the value range, a
//! histogram, Otsu's threshold, and the volume a threshold keeps.

use crate::volume::Volume;
use rayon::prelude::*;

/// Samples per parallel chunk.
const CHUNK: usize = 1 << 16;

/// A histogram of a volume's finite values: `counts[b]` samples in
/// `[lo + b w, lo + (b + 1) w)` with `w = (hi - lo) / bins` (the last bin
/// also holds `hi`).
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Smallest finite value.
    pub lo: f64,
    /// Largest finite value.
    pub hi: f64,
    /// Samples per bin.
    pub counts: Vec<u64>,
    /// Samples that are NaN or infinite (in no bin).
    pub non_finite: u64,
}

impl Histogram {
    /// The histogram of `vol` in `bins` bins over its finite range.
    pub fn of(vol: &Volume, bins: usize) -> Histogram {
        let bins = bins.max(1);
        let (lo, hi, _) = vol.range();
        let n = vol.len();
        let width = hi - lo;
        let empty = || (vec![0u64; bins], 0u64);
        let (counts, non_finite) = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let (mut h, mut bad) = empty();
                for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                    let v = vol.value_at(i);
                    if !v.is_finite() {
                        bad += 1;
                        continue;
                    }
                    h[bin(v, lo, width, bins)] += 1;
                }
                (h, bad)
            })
            .reduce(empty, |(mut a, x), (b, y)| {
                a.iter_mut().zip(b).for_each(|(p, q)| *p += q);
                (a, x + y)
            });
        Histogram {
            lo,
            hi,
            counts,
            non_finite,
        }
    }

    /// Width of one bin.
    pub fn width(&self) -> f64 {
        (self.hi - self.lo) / self.counts.len() as f64
    }

    /// Lower edge of bin `b`.
    pub fn edge(&self, b: usize) -> f64 {
        self.lo + b as f64 * self.width()
    }

    /// Otsu's threshold: the bin edge that maximises the between-class
    /// variance of the samples below and at-or-above it. `None` when all
    /// finite values are equal (nothing to separate).
    pub fn otsu(&self) -> Option<f64> {
        let bins = self.counts.len();
        if !(self.hi > self.lo) || bins < 2 {
            return None;
        }
        let total: f64 = self.counts.iter().map(|&c| c as f64).sum();
        let centre = |b: usize| self.lo + (b as f64 + 0.5) * self.width();
        let sum_all: f64 = (0..bins).map(|b| self.counts[b] as f64 * centre(b)).sum();
        let (mut w0, mut s0) = (0.0, 0.0);
        let mut best: Option<(f64, usize)> = None;
        // Threshold at the lower edge of bin t: class 0 is bins < t.
        for t in 1..bins {
            w0 += self.counts[t - 1] as f64;
            s0 += self.counts[t - 1] as f64 * centre(t - 1);
            let w1 = total - w0;
            if w0 == 0.0 || w1 == 0.0 {
                continue;
            }
            let d = s0 / w0 - (sum_all - s0) / w1;
            let between = w0 * w1 * d * d;
            if best.is_none_or(|(b, _)| between > b) {
                best = Some((between, t));
            }
        }
        best.map(|(_, t)| self.edge(t))
    }
}

fn bin(v: f64, lo: f64, width: f64, bins: usize) -> usize {
    if width > 0.0 {
        (((v - lo) / width * bins as f64) as usize).min(bins - 1)
    } else {
        0
    }
}

/// Samples whose value is at or above `iso` (inside, as [`crate::ScanField`]
/// takes it).
pub fn count_at_or_above(vol: &Volume, iso: f64) -> u64 {
    let n = vol.len();
    (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            (c * CHUNK..((c + 1) * CHUNK).min(n))
                .filter(|&i| vol.value_at(i) >= iso)
                .count() as u64
        })
        .sum()
}

/// Whether the values look like CT in Hounsfield units: air (about
/// -1000 HU) is present and the range reaches bone (300 HU and more).
pub fn looks_like_ct(h: &Histogram) -> bool {
    h.lo <= -900.0 && h.lo >= -3100.0 && h.hi >= 300.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Samples;

    fn vol(values: Vec<f32>, dims: [usize; 3]) -> Volume {
        Volume::new(dims, [0.5, 0.5, 2.0], [0.0; 3], Samples::F32(values)).unwrap()
    }

    #[test]
    fn histogram_counts_every_finite_sample_once() {
        let v: Vec<f32> = (0..1000)
            .map(|i| (i % 10) as f32)
            .chain([f32::NAN])
            .collect();
        let h = Histogram::of(&vol(v, [1001, 1, 1]), 10);
        assert_eq!((h.lo, h.hi, h.non_finite), (0.0, 9.0, 1));
        assert_eq!(h.counts, vec![100; 10]);
    }

    /// Otsu against a brute force over every threshold between two values.
    #[test]
    fn otsu_matches_a_brute_force_and_splits_two_levels() {
        // Two noisy levels, 30 % at 100 and 70 % at 900.
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f64 / (1u64 << 24) as f64
        };
        let v: Vec<f32> = (0..20000)
            .map(|i| {
                let base = if i % 10 < 3 { 100.0 } else { 900.0 };
                (base + 200.0 * (rnd() - 0.5)) as f32
            })
            .collect();
        let volume = vol(v.clone(), [20000, 1, 1]);
        let h = Histogram::of(&volume, 256);
        let t = h.otsu().unwrap();
        assert!(t > 200.0 && t < 800.0, "{t}");
        // Brute force on the raw samples at every bin edge.
        let score = |t: f64| {
            let (a, b): (Vec<f64>, Vec<f64>) = v.iter().map(|&x| x as f64).partition(|&x| x < t);
            if a.is_empty() || b.is_empty() {
                return 0.0;
            }
            let m = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
            let d = m(&a) - m(&b);
            a.len() as f64 * b.len() as f64 * d * d
        };
        let best = (1..256)
            .map(|b| h.edge(b))
            .max_by(|&p, &q| score(p).total_cmp(&score(q)))
            .unwrap();
        // Any threshold in the empty gap between the levels is as good.
        assert_eq!(score(t), score(best), "{t} vs {best}");
        // The volume it keeps: the 70 % at 900, in mm^3.
        assert_eq!(count_at_or_above(&volume, t), 14000);
        // A constant volume has nothing to split.
        assert_eq!(
            Histogram::of(&vol(vec![3.0; 8], [2, 2, 2]), 16).otsu(),
            None
        );
    }

    #[test]
    fn ct_is_recognised_by_its_range() {
        let ct = Histogram::of(&vol(vec![-1000.0, 0.0, 1200.0], [3, 1, 1]), 4);
        assert!(looks_like_ct(&ct));
        let occ = Histogram::of(&vol(vec![0.0, 1.0], [2, 1, 1]), 4);
        assert!(!looks_like_ct(&occ));
    }
}
