//! Distance to the nearest strut axis of a lattice, in f64, with the struts
//! culled per bucket of the unit cell so each point tests only the few
//! that can come within a cap distance of it.

use crate::struts::StrutLattice;

/// Buckets per axis of the unit cell.
const BUCKETS: usize = 16;

/// A segment: start, direction (end - start) and its squared length.
#[derive(Clone, Copy, Debug)]
struct Segment {
    a: [f64; 3],
    e: [f64; 3],
    e2: f64,
}

impl Segment {
    fn distance2(&self, p: [f64; 3]) -> f64 {
        let d: [f64; 3] = std::array::from_fn(|i| p[i] - self.a[i]);
        let h =
            ((d[0] * self.e[0] + d[1] * self.e[1] + d[2] * self.e[2]) / self.e2).clamp(0.0, 1.0);
        (0..3).map(|i| (d[i] - h * self.e[i]).powi(2)).sum::<f64>()
    }
}

/// The struts of a lattice sorted into buckets of `[0, 1]^3`.
pub(super) struct NearStruts {
    segments: Vec<Segment>,
    /// Per bucket (x fastest), the segments within the cap of it.
    buckets: Vec<Vec<u32>>,
    cap: f64,
}

impl NearStruts {
    /// Keeps, per bucket, the struts that come within `cap` of it.
    pub(super) fn new(kind: StrutLattice, cap: f64) -> NearStruts {
        let segments: Vec<Segment> = kind
            .struts()
            .into_iter()
            .map(|(a, b)| {
                let e: [f64; 3] = std::array::from_fn(|i| b[i] - a[i]);
                Segment {
                    a,
                    e,
                    e2: e.iter().map(|c| c * c).sum(),
                }
            })
            .collect();
        let w = 1.0 / BUCKETS as f64;
        // A bucket's points are within half its diagonal of its centre.
        let reach = cap + 0.5 * w * 3f64.sqrt() + 1e-9;
        let buckets = (0..BUCKETS.pow(3))
            .map(|q| {
                let c = [
                    q % BUCKETS,
                    (q / BUCKETS) % BUCKETS,
                    q / (BUCKETS * BUCKETS),
                ]
                .map(|i| (i as f64 + 0.5) * w);
                (0..segments.len() as u32)
                    .filter(|&s| segments[s as usize].distance2(c) <= reach * reach)
                    .collect()
            })
            .collect();
        NearStruts {
            segments,
            buckets,
            cap,
        }
    }

    /// Distance from `p` (in `[0, 1]^3`) to the nearest strut axis, or
    /// `cap` where that is farther.
    pub(super) fn distance(&self, p: [f64; 3]) -> f64 {
        let b = p.map(|c| ((c * BUCKETS as f64) as usize).min(BUCKETS - 1));
        self.buckets[b[0] + BUCKETS * (b[1] + BUCKETS * b[2])]
            .iter()
            .map(|&s| self.segments[s as usize].distance2(p))
            .fold(self.cap * self.cap, f64::min)
            .sqrt()
    }
}
