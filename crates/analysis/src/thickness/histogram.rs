//! Summary of a thickness distribution: voxel counts per distinct squared
//! radius turned into diameters in model units, a histogram, the mean and
//! percentiles.

use std::collections::BTreeMap;

/// Voxel counts per diameter bin: bin `i` holds diameters in
/// `[edges[i], edges[i + 1])` (the last bin also holds its upper edge).
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// Bin edges in model units, `counts.len() + 1` of them, from 0.
    pub edges: Vec<f64>,
    /// Voxels per bin.
    pub counts: Vec<u64>,
}

/// Distribution of the local thickness over the voxels of one phase, in
/// model units. Percentiles are nearest-rank over the voxels (so
/// volume-weighted) and are attained diameters.
#[derive(Clone, Debug, PartialEq)]
pub struct ThicknessStats {
    /// Voxels of the phase.
    pub voxels: u64,
    /// Mean diameter over the phase's voxels (volume-weighted), model units.
    pub mean: f64,
    /// Smallest diameter of any voxel, model units.
    pub min: f64,
    /// 10th percentile of the diameters (nearest rank), model units.
    pub p10: f64,
    /// Median diameter (50th percentile, nearest rank), model units.
    pub median: f64,
    /// 90th percentile of the diameters (nearest rank), model units.
    pub p90: f64,
    /// Largest diameter of any voxel (at most the cap), model units.
    pub max: f64,
    /// Voxel counts per diameter bin.
    pub histogram: Histogram,
    /// Voxels whose ball reached the slab halo: their diameter is only known
    /// to be at least the cap (see [`super::Thickness::diameter_cap`]); they
    /// are counted at the cap. 0 when the whole grid was one slab.
    pub capped_voxels: u64,
    /// `None`: every value is exact. Otherwise the phase had balls too many
    /// and too large to paint exactly within the work budget: diameters up
    /// to this one (model units) are exact, larger ones are lower bounds
    /// floored to a ladder of diameters `ladder_ratio` apart.
    pub exact_up_to: Option<f64>,
    /// Ratio between the ladder's diameters; 1 when exact.
    pub ladder_ratio: f64,
}

/// Diameter of the ball of squared radius `d` voxels, in model units.
pub fn diameter(d: u32, voxel: f64) -> f64 {
    2.0 * (d as f64).sqrt() * voxel
}

/// Stats of `counts` (squared radius -> voxels; not empty). Squared radii
/// above `cap` count as capped. Bins are `bin_width` wide.
pub fn summarize(
    counts: &BTreeMap<u32, u64>,
    voxel: f64,
    bin_width: f64,
    cap: u32,
) -> ThicknessStats {
    let n: u64 = counts.values().sum();
    let dia = |d: u32| diameter(d.min(cap), voxel);
    let mut sum = 0.0;
    for (&d, &c) in counts {
        sum += dia(d) * c as f64;
    }
    let pct = |q: f64| {
        let want = ((q * n as f64).ceil() as u64).clamp(1, n);
        let mut seen = 0;
        for (&d, &c) in counts {
            seen += c;
            if seen >= want {
                return dia(d);
            }
        }
        dia(*counts.keys().next_back().expect("not empty"))
    };
    let max = dia(*counts.keys().next_back().expect("not empty"));
    let bins = (max / bin_width).floor() as usize + 1;
    let mut hist = vec![0u64; bins];
    for (&d, &c) in counts {
        let b = ((dia(d) / bin_width).floor() as usize).min(bins - 1);
        hist[b] += c;
    }
    ThicknessStats {
        voxels: n,
        mean: sum / n as f64,
        min: dia(*counts.keys().next().expect("not empty")),
        p10: pct(0.1),
        median: pct(0.5),
        p90: pct(0.9),
        max,
        histogram: Histogram {
            edges: (0..=bins).map(|i| i as f64 * bin_width).collect(),
            counts: hist,
        },
        capped_voxels: counts.range(cap.saturating_add(1)..).map(|(_, &c)| c).sum(),
        exact_up_to: None,
        ladder_ratio: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_are_nearest_rank() {
        // 10 voxels of radius 1, 10 of radius 2 (voxel 0.5).
        let counts = BTreeMap::from([(1, 10), (4, 10)]);
        let s = summarize(&counts, 0.5, 0.5, u32::MAX);
        assert_eq!(s.voxels, 20);
        assert_eq!(s.min, 1.0);
        assert_eq!(s.p10, 1.0);
        assert_eq!(s.median, 1.0);
        assert_eq!(s.p90, 2.0);
        assert_eq!(s.max, 2.0);
        assert!((s.mean - 1.5).abs() < 1e-12);
        assert_eq!(s.histogram.counts, vec![0, 0, 10, 0, 10]);
        assert_eq!(s.histogram.edges.len(), 6);
    }
}
