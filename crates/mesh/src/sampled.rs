//! The model's volume sampled independently of the mesh, to catch what the
//! mesh lost: features thinner than a cell fall between the grid nodes and
//! vanish from the surface, but a sample placed at random in every cell
//! still lands in them in proportion to their volume.
//!
//! Bricks proven full count whole, bricks proven empty count nothing, and
//! every cell of the other bricks gets one sample at a pseudo-random
//! (hashed, so deterministic) position inside it: stratified Monte Carlo,
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

/// Per brick: cells proven inside, samples inside, pairs of neighbouring
/// samples that disagree, samples taken.
type Counts = [u64; 4];

/// Samples the volume of `plan`'s (clipped) model, one point per cell of
/// every brick interval analysis could not decide.
pub fn sampled_volume(plan: &Plan) -> SampledVolume {
    let g = &plan.grid;
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
                        for k in 0..cells[2] {
                            for j in 0..cells[1] {
                                for i in 0..cells[0] {
                                    let c = [lo[0] + i, lo[1] + j, lo[2] + k];
                                    let u = jitter(g.node_index(c));
                                    let p: [f64; 3] = std::array::from_fn(|a| {
                                        g.origin[a] + g.h * (c[a] as f64 + u[a])
                                    });
                                    xs.push(p[0] as f32);
                                    ys.push(p[1] as f32);
                                    zs.push(p[2] as f32);
                                }
                            }
                        }
                        let mut v = vec![0.0f32; xs.len()];
                        ev.eval(xs, ys, zs, &mut v);
                        let inside = v.iter().filter(|&&f| f >= 0.0).count() as u64;
                        // Pairs of cells along x: (2i, 2i + 1).
                        let mut differ = 0u64;
                        for row in v.chunks(cells[0]) {
                            for pair in row.chunks_exact(2) {
                                differ += ((pair[0] >= 0.0) != (pair[1] >= 0.0)) as u64;
                            }
                        }
                        [0, inside, differ, total]
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
        // Each disagreeing pair contributes a variance of about 1/2 per
        // cell pair in units of cells (two Bernoulli samples, p near 1/2).
        error: (sum[2] as f64 * 0.5).sqrt() * cell,
        samples: sum[3],
    }
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
    use microfrep_core::{prims, Expr, Shape};

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
