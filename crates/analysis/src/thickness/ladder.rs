//! Painting one phase of a window within a work budget.
//!
//! Exact painting costs about one row per ball row: `pi D` per ridge ball.
//! That is fine for bounded pores and struts, but a phase of huge balls
//! (the open space around a single convex solid in a box) has millions of
//! ridge balls of radius 100 and more. So the ridge balls are taken
//! smallest first while their rows fit a budget per window voxel
//! ([`WORK_PER_VOXEL`] by default);
//! those are painted exactly. Larger balls are replaced by a ladder of radii
//! (ratio at least [`MIN_RATIO`], at most [`MAX_LEVELS`] rungs, the top rung
//! the largest ball): for each rung `L`, every voxel within `sqrt(L)` of a
//! centre with `D >= L` gets `L`, by one distance transform of the window.
//! Such a value is a lower bound (the voxel lies in a ball of squared radius
//! at least `L`), floored to the rung below the exact value.

use super::edt::edt_squared_by;
use super::local;
use rayon::prelude::*;
use std::ops::Range;

/// Default rows of exact painting allowed per window voxel.
pub const WORK_PER_VOXEL: f64 = 128.0;
/// Most rungs of the ladder.
pub const MAX_LEVELS: usize = 32;
/// Smallest ratio between rungs' radii.
pub const MIN_RATIO: f64 = 1.05;

/// One phase painted over some planes of a window.
pub struct Painted {
    /// Per voxel of the planes, an index + 1 into `values`; 0 off the phase.
    pub out: Vec<u32>,
    /// Squared radii, largest first.
    pub values: Vec<u32>,
    /// Largest squared radius painted exactly when a ladder was used.
    pub exact_up_to: Option<u32>,
    /// Ratio between the ladder's radii (1 without one).
    pub ratio: f64,
}

/// Paints `planes` of the window `d` (squared distances, `dims`) from the
/// ridge balls centred in the planes `centres`, with `work` rows of exact
/// painting per window voxel.
pub fn paint_phase(
    d: &[u32],
    dims: [usize; 3],
    centres: Range<usize>,
    planes: Range<usize>,
    work: f64,
) -> Painted {
    let mut balls = local::ridge(d, dims, centres);
    // The smallest balls first, whole groups of one radius at a time.
    let budget = work * d.len() as f64;
    let mut work = 0.0;
    let mut split = balls.len();
    while split > 0 {
        let v = balls[split - 1].d;
        let mut j = split;
        while j > 0 && balls[j - 1].d == v {
            j -= 1;
        }
        let w = (split - j) as f64 * std::f64::consts::PI * v as f64;
        if work + w > budget {
            break;
        }
        work += w;
        split = j;
    }
    let cut = balls.get(split).map_or(0, |b| b.d);
    let (levels, ratio) = match balls.first() {
        Some(top) if split > 0 => ladder(cut, top.d),
        _ => (Vec::new(), 1.0),
    };
    let exact = &mut balls[split..];
    let mut values = levels.clone();
    for b in exact.iter_mut() {
        if values.last() != Some(&b.d) || values.len() == levels.len() {
            values.push(b.d);
        }
        b.rank = values.len() as u32 - 1;
    }
    let layer = dims[0] * dims[1];
    let mut out = vec![0u32; planes.len() * layer];
    let own = &d[planes.start * layer..planes.end * layer];
    for (j, &l) in levels.iter().enumerate() {
        let e = edt_squared_by(dims, |i| d[i] < l);
        let e = &e[planes.start * layer..planes.end * layer];
        out.par_chunks_mut(1 << 16)
            .zip(e.par_chunks(1 << 16))
            .zip(own.par_chunks(1 << 16))
            .for_each(|((o, e), dd)| {
                for ((o, &e), &dd) in o.iter_mut().zip(e).zip(dd) {
                    if *o == 0 && dd > 0 && e < l {
                        *o = j as u32 + 1;
                    }
                }
            });
    }
    local::paint(d, dims, planes, exact, &mut out);
    Painted {
        out,
        values,
        exact_up_to: (!levels.is_empty()).then_some(cut),
        ratio,
    }
}

/// Rungs (squared radii, largest first) above `cut` up to `top`, and the
/// ratio of their radii.
fn ladder(cut: u32, top: u32) -> (Vec<u32>, f64) {
    let (lo, hi) = (((cut + 1) as f64).sqrt(), (top as f64).sqrt());
    let ratio = (hi / lo).powf(1.0 / MAX_LEVELS as f64).max(MIN_RATIO);
    let mut rungs = vec![top];
    let mut r = lo;
    while r * r < top as f64 {
        let l = ((r * r).ceil() as u32).clamp(cut + 1, top);
        if !rungs.contains(&l) {
            rungs.push(l);
        }
        r *= ratio;
    }
    rungs.sort_unstable_by(|a, b| b.cmp(a));
    (rungs, ratio)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ladder_spans_cut_to_top() {
        let (r, q) = ladder(99, 10_000);
        assert_eq!(r[0], 10_000);
        assert_eq!(*r.last().unwrap(), 100);
        assert!(r.len() <= MAX_LEVELS + 2);
        assert!(r.windows(2).all(|w| w[0] > w[1]));
        assert!(q >= MIN_RATIO);
        for w in r.windows(2) {
            assert!(((w[0] as f64) / (w[1] as f64)).sqrt() <= q * 1.01);
        }
    }
}
