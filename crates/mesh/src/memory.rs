//! Predicting the peak memory of a meshing job before the dense work, from
//! a coarse sampling of the model: surface cells scale with the square of
//! the resolution.

use crate::{CellMethod, Plan};
use microfrep_core::eval_grid_par;

/// Triangles and vertices per surface cell of marching tetrahedra on the
/// Kuhn split (measured on a sphere: about 5.9 and 3.0; rounded up), and of
/// marching cubes (2.9 times fewer of both on the tori-ball; rounded up).
const TRIS_PER_CELL: f64 = 6.2;
const VERTS_PER_CELL: f64 = 3.1;
const CUBES_TRIS_PER_CELL: f64 = 2.2;
const CUBES_VERTS_PER_CELL: f64 = 1.1;
/// Bytes per triangle at the peak, which comes in the mesh check after the
/// mesh is made: the mesh (12), the checker's half-edges (24) and sorted
/// copy (12), plus slack. Calibrated on the 512^3 tori-ball (92 M
/// triangles): 5.3 GiB measured with the check, 6.3 GiB predicted.
const BYTES_PER_TRI: f64 = 76.0;
/// Bytes per vertex: brick copy, key, final copy, normal, checker's copy.
const BYTES_PER_VERT: f64 = 64.0;
/// Coarse grid used to count surface cells.
const COARSE: usize = 64;

#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    pub triangles: f64,
    pub vertices: f64,
    pub bytes: f64,
}

/// Estimated output size and peak bytes of `plan`.
pub fn estimate(plan: &Plan) -> Estimate {
    let g = &plan.grid;
    let n = g.cells.iter().copied().max().unwrap_or(1);
    let m = COARSE.min(n);
    let scale = n as f64 / m as f64;
    let step = g.h * scale;
    let dims = g
        .cells
        .map(|c| ((c as f64 / scale).ceil() as usize).max(1) + 1);
    let v = eval_grid_par(&plan.tape, dims, g.origin, [step; 3]);
    let idx = |i: usize, j: usize, k: usize| i + dims[0] * (j + dims[1] * k);
    let mut surface = 0usize;
    for k in 0..dims[2] - 1 {
        for j in 0..dims[1] - 1 {
            for i in 0..dims[0] - 1 {
                let mut inside = 0;
                for c in 0..8 {
                    let f = v[idx(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))];
                    inside += (f >= 0.0) as usize;
                }
                surface += (inside != 0 && inside != 8) as usize;
            }
        }
    }
    let cells = surface as f64 * scale * scale;
    let (tpc, vpc) = match plan.cells {
        CellMethod::Tetrahedra => (TRIS_PER_CELL, VERTS_PER_CELL),
        CellMethod::Cubes => (CUBES_TRIS_PER_CELL, CUBES_VERTS_PER_CELL),
    };
    let triangles = cells * tpc;
    let vertices = cells * vpc;
    let scratch = scratch_bytes(plan);
    Estimate {
        triangles,
        vertices,
        bytes: triangles * BYTES_PER_TRI + vertices * BYTES_PER_VERT + scratch + 64e6,
    }
}

/// Bytes per triangle and per vertex held by the pipeline while it works:
/// the brick's triangles and their global copy (12 + 12); per vertex its
/// position, key, two correction sums and final copy (12 + 12 + 40 + 12).
const WINDOW_BYTES_PER_TRI: f64 = 24.0;
const WINDOW_BYTES_PER_VERT: f64 = 76.0;

/// Estimated peak bytes of `plan` streamed to disk: the pipeline holds
/// three groups of z-slabs of bricks at a time, never the whole mesh.
pub fn streaming_bytes(plan: &Plan, e: &Estimate) -> f64 {
    let slabs = plan.grid.bricks[2] as f64;
    let held = ((3 * plan.slabs_per_group()) as f64).min(slabs) / slabs;
    let window = held * (e.triangles * WINDOW_BYTES_PER_TRI + e.vertices * WINDOW_BYTES_PER_VERT);
    // Surface is not spread evenly over the slabs: allow twice the mean.
    2.0 * window + scratch_bytes(plan) + 64e6
}

fn scratch_bytes(plan: &Plan) -> f64 {
    rayon::current_num_threads() as f64 * (plan.grid.brick as f64 + 1.0).powi(3) * 42.0
}

/// The largest resolution whose estimate fits `budget` bytes, given the
/// estimate `e` at resolution `n` (output size scales with n^2).
pub fn resolution_fitting(e: &Estimate, n: usize, budget: f64) -> usize {
    let fixed = 64e6;
    if budget <= fixed || e.bytes <= fixed {
        return n;
    }
    let r = ((budget - fixed) / (e.bytes - fixed)).sqrt();
    ((n as f64 * r).floor() as usize).clamp(1, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fitting_resolution_scales_with_square_root() {
        let e = Estimate {
            triangles: 0.0,
            vertices: 0.0,
            bytes: 64e6 + 4e9,
        };
        assert_eq!(resolution_fitting(&e, 1000, 64e6 + 1e9), 500);
    }
}
