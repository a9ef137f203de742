//! The model's volume sampled independently of the mesh, to catch what the
//! mesh lost: features thinner than a cell fall between the grid nodes and
//! vanish from the surface, but a sample placed at random in every cell
//! still lands in them in proportion to their volume.
//!
//! Bricks proven full count whole, bricks proven empty count nothing, and
//! every cell (or block of cells, for large grids) of the other bricks
//! gets one sample at a pseudo-random (hashed, so deterministic) position
//! inside it: stratified Monte Carlo,
//! unbiased whatever the features' size or alignment with the grid (node
//! counts are not: a face on a node plane counts half a cell too much).
//! The error is estimated from neighbouring cells' disagreement.

use crate::classify::BrickClass;
use crate::Plan;
use microfrep_core::BatchEval;
use rayon::prelude::*;

/// The sampled volume of a plan's model in its box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledVolume {
    /// Estimated volume.
    pub value: f64,
    /// One standard deviation of `value` (stratified sampling, estimated
    /// from pairs of neighbouring cells; an overestimate where the surface
    /// is resolved).
    pub error: f64,
    /// Samples evaluated.
    pub samples: u64,
}

/// Per brick: cells proven inside, cells of the strata sampled inside,
/// disagreeing neighbour pairs (weighted), samples taken.
type Counts = [u64; 4];

/// Most samples [`sampled_volume`] takes: past this, one sample stands for
/// a block of `s^3` cells (at a resolution where that block is a small
/// fraction of any feature the mesh keeps), so the check costs a small
/// part of the meshing.
pub const MAX_SAMPLES: f64 = 4.0 * 1024.0 * 1024.0;

/// Samples the volume of `plan`'s (clipped) model: one point per cell, or
/// per block of cells past [`MAX_SAMPLES`], of every brick interval
/// analysis could not decide.
pub fn sampled_volume(plan: &Plan) -> SampledVolume {
    let g = &plan.grid;
    let undecided = plan.surface_bricks() as f64 * (g.brick as f64).powi(3);
    // Cells per side of a stratum.
    let s = ((undecided / MAX_SAMPLES).cbrt().ceil() as usize).clamp(1, g.brick);
    // Integer sums: the total does not depend on the order of the bricks.
    let sum = (0..g.brick_count())
        .into_par_iter()
        .map_init(
            || {
                (
                    BatchEval::new(&plan.tape),
                    Vec::new(),
                    Vec::new(),
                    Vec::new(),
                )
            },
            |(ev, xs, ys, zs), b| {
                let (lo, n) = g.brick_nodes(g.brick_coords(b));
                let cells = [n[0] - 1, n[1] - 1, n[2] - 1];
                let total = (cells[0] * cells[1] * cells[2]) as u64;
                match plan.classes[b] {
                    BrickClass::Empty => [0; 4],
                    BrickClass::Full => [total, 0, 0, 0],
                    BrickClass::Surface => {
                        xs.clear();
                        ys.clear();
                        zs.clear();
                        // Strata of s^3 cells (fewer at the brick's far
                        // sides); each sample counts for its stratum's cells.
                        let strata = cells.map(|c| c.div_ceil(s));
                        let mut weight = Vec::new();
                        for k in 0..strata[2] {
                            for j in 0..strata[1] {
                                for i in 0..strata[0] {
                                    let c0 = [i * s, j * s, k * s];
                                    let ext: [usize; 3] =
                                        std::array::from_fn(|a| s.min(cells[a] - c0[a]));
                                    let c: [usize; 3] = std::array::from_fn(|a| lo[a] + c0[a]);
                                    let u = jitter(g.node_index(c));
                                    let p: [f64; 3] = std::array::from_fn(|a| {
                                        g.origin[a] + g.h * (c[a] as f64 + u[a] * ext[a] as f64)
                                    });
                                    xs.push(p[0] as f32);
                                    ys.push(p[1] as f32);
                                    zs.push(p[2] as f32);
                                    weight.push((ext[0] * ext[1] * ext[2]) as u64);
                                }
                            }
                        }
                        let mut v = vec![0.0f32; xs.len()];
                        ev.eval(xs, ys, zs, &mut v);
                        let inside: u64 = v
                            .iter()
                            .zip(&weight)
                            .filter(|(&f, _)| f >= 0.0)
                            .map(|(_, &w)| w)
                            .sum();
                        let ins: Vec<bool> = v.iter().map(|&f| f >= 0.0).collect();
                        let differ = pair_variance(&ins, &weight, strata);
                        [0, inside, differ, v.len() as u64]
                    }
                }
            },
        )
        .reduce(
            || [0; 4],
            |mut s: Counts, c: Counts| {
                for k in 0..4 {
                    s[k] += c[k];
                }
                s
            },
        );
    let cell = g.h * g.h * g.h;
    SampledVolume {
        value: (sum[0] + sum[1]) as f64 * cell,
        // Each disagreeing pair of strata of w cells contributes a variance
        // of about w^2 / 2 cells^2 (two Bernoulli samples, p near 1/2).
        error: (sum[2] as f64 * 0.5).sqrt() * cell,
        samples: sum[3],
    }
}

/// Twice the variance, in cells^2, that neighbouring strata disagreeing
/// reveal: strata paired (2i, 2i + 1) along each axis in turn, each
/// disagreeing pair of strata of `w` cells adding `w^2`; the largest of
/// the three axes (a surface parallel to an axis shows only in the pairs
/// across it).
fn pair_variance(inside: &[bool], w: &[u64], strata: [usize; 3]) -> u64 {
    let idx = |i: usize, j: usize, k: usize| i + strata[0] * (j + strata[1] * k);
    let mut best = 0;
    for axis in 0..3 {
        let mut sum = 0u64;
        for k in 0..strata[2] {
            for j in 0..strata[1] {
                for i in 0..strata[0] {
                    let c = [i, j, k];
                    if c[axis] % 2 == 1 {
                        let mut o = c;
                        o[axis] -= 1;
                        let (a, b) = (idx(i, j, k), idx(o[0], o[1], o[2]));
                        if inside[a] != inside[b] {
                            sum += w[a] * w[b];
                        }
                    }
                }
            }
        }
        best = best.max(sum);
    }
    best
}

/// A point in the unit cube from a cell's index (splitmix64 with a fixed
/// seed): the same cell always gets the same sample.
fn jitter(cell: u64) -> [f64; 3] {
    let mut z = cell.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut x = z;
        x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        x ^= x >> 31;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    [next(), next(), next()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MeshOptions;
    use microfrep_core::{Expr, Shape};
    use microfrep_shapes as prims;

    #[test]
    fn sampled_volumes_of_a_ball_and_a_thin_plate_are_right() {
        let ball = prims::sphere(&Expr::xyz(), &prims::v3([0.05, 0.0, -0.1]), 0.8);
        let plan = Plan::new(
            &Shape::from(&ball),
            &MeshOptions::new([[-1.0; 3], [1.0; 3]], 40),
        )
        .unwrap();
        let v = sampled_volume(&plan);
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.512;
        assert!((v.value - exact).abs() < 4.0 * v.error, "{v:?} vs {exact}");
        assert!(v.error < 0.01 * exact, "{v:?}");
        // A plate a third of a cell thick: invisible to the nodes, not to
        // the samples (volume 4 * 0.01).
        let z = Expr::z();
        let plate = 0.005 - (&z - 0.0123).abs();
        let plan = Plan::new(
            &Shape::from(&plate),
            &MeshOptions::new([[-1.0; 3], [1.0; 3]], 64),
        )
        .unwrap();
        let v = sampled_volume(&plan);
        assert!((v.value - 0.04).abs() < 4.0 * v.error + 1e-4, "{v:?}");
        assert!(v.error < 0.1 * 0.04, "{v:?}");
    }
}
