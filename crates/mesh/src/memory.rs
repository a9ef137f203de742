//! Predicting the peak memory of a meshing job before the dense work, from
//! a coarse sampling of the model: surface cells scale with the square of
//! the resolution.

use crate::{CellMethod, Grid, Plan};
use microfrep_core::{eval_grid_par, Tape};

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

/// Bytes in a GiB, for messages.
pub const GIB: f64 = (1u64 << 30) as f64;

/// Bytes held whatever the job: the tape, thread pools, buffers.
const FIXED: f64 = 64e6;

/// A meshing job's predicted output size and peak memory, from
/// [`estimate`] or [`estimate_grid`]; the counts are estimates from a
/// coarse sampling, not exact.
#[derive(Clone, Copy, Debug)]
pub struct Estimate {
    /// Predicted number of triangles.
    pub triangles: f64,
    /// Predicted number of vertices.
    pub vertices: f64,
    /// Peak bytes of the job meshed into memory, everything included.
    pub bytes: f64,
    /// The part of `bytes` that grows with the cube of the resolution (the
    /// brick classes), the rest growing with its square.
    pub volume_bytes: f64,
}

/// Bytes of the brick classes of `grid` (one a brick).
pub fn classes_bytes(grid: &Grid) -> f64 {
    grid.bricks.iter().map(|&b| b as f64).product::<f64>()
}

/// Estimated output size and peak bytes of `plan`.
pub fn estimate(plan: &Plan) -> Estimate {
    estimate_grid(&plan.tape, &plan.grid, plan.cells)
}

/// Estimated output size and peak bytes of meshing `tape` (clipped to the
/// box, [`Plan::frame`]) on `grid`, before the plan is made: from a
/// sampling of at most 65^3 nodes and never more nodes than the grid has,
/// so a small job is never dearer to predict than to run.
pub fn estimate_grid(tape: &Tape, g: &Grid, method: CellMethod) -> Estimate {
    let n = g.cells.iter().copied().max().unwrap_or(1);
    let m = COARSE.min(n);
    let scale = n as f64 / m as f64;
    let step = g.h * scale;
    let dims = g
        .cells
        .map(|c| ((c as f64 / scale).ceil() as usize).max(1) + 1);
    let v = eval_grid_par(tape, dims, g.origin, [step; 3]);
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
    let (tpc, vpc) = match method {
        CellMethod::Tetrahedra => (TRIS_PER_CELL, VERTS_PER_CELL),
        CellMethod::Cubes => (CUBES_TRIS_PER_CELL, CUBES_VERTS_PER_CELL),
    };
    let triangles = cells * tpc;
    let vertices = cells * vpc;
    let classes = classes_bytes(g);
    Estimate {
        triangles,
        vertices,
        bytes: triangles * BYTES_PER_TRI
            + vertices * BYTES_PER_VERT
            + scratch_bytes(g)
            + classes
            + FIXED,
        volume_bytes: classes,
    }
}

/// Bytes per vertex of colouring a mesh held in memory: the channel's f32
/// value and the 3-byte colour of every vertex, rounded up.
pub const COLOUR_BYTES_PER_VERT: f64 = 8.0;

/// `e` for a mesh coloured in memory ([`crate::job::JobOptions::colour`]):
/// its vertex colours added. (Streamed, the values go to a scratch file and
/// colours are made a block at a time: no more memory.)
pub fn with_colours(e: &Estimate) -> Estimate {
    Estimate {
        bytes: e.bytes + e.vertices * COLOUR_BYTES_PER_VERT,
        ..*e
    }
}

/// Bytes per triangle and per vertex held by the pipeline while it works:
/// the brick's triangles and their global copy (12 + 12); per vertex its
/// position, key, two correction sums and final copy (12 + 12 + 40 + 12;
/// the sums are now kept only for vertices on brick faces, so this is an
/// upper bound).
const WINDOW_BYTES_PER_TRI: f64 = 24.0;
const WINDOW_BYTES_PER_VERT: f64 = 76.0;

/// Estimated peak bytes of `plan` streamed to disk: the pipeline holds
/// four groups of z-slabs of bricks at a time (the one being finished, the
/// one before it until its triangles are out, the next one, and the one
/// being meshed meanwhile), never the whole mesh.
pub fn streaming_bytes(plan: &Plan, e: &Estimate) -> f64 {
    streaming_bytes_grid(&plan.grid, e)
}

/// [`streaming_bytes`] from the grid alone.
pub fn streaming_bytes_grid(grid: &Grid, e: &Estimate) -> f64 {
    let slabs = grid.bricks[2] as f64;
    let held = ((4 * slabs_per_group(grid)) as f64).min(slabs) / slabs;
    let window = held * (e.triangles * WINDOW_BYTES_PER_TRI + e.vertices * WINDOW_BYTES_PER_VERT);
    // Surface is not spread evenly over the slabs: allow twice the mean.
    2.0 * window + scratch_bytes(grid) + e.volume_bytes + FIXED
}

/// Z-slabs of bricks per pipeline step: enough bricks per group to keep
/// every thread busy.
pub(crate) fn slabs_per_group(grid: &Grid) -> usize {
    let per_slab = grid.bricks[0] * grid.bricks[1];
    let want = 4 * rayon::current_num_threads();
    want.div_ceil(per_slab).clamp(1, grid.bricks[2])
}

fn scratch_bytes(grid: &Grid) -> f64 {
    rayon::current_num_threads() as f64 * (grid.brick as f64 + 1.0).powi(3) * 42.0
}

/// The largest resolution whose estimate fits `budget` bytes, given the
/// estimate `e` at resolution `n` (output size scales with n^2, the brick
/// table with n^3).
pub fn resolution_fitting(e: &Estimate, n: usize, budget: f64) -> usize {
    let area = (e.bytes - e.volume_bytes - FIXED).max(0.0);
    let bytes_at = |m: f64| {
        let r = m / n as f64;
        FIXED + area * r * r + e.volume_bytes * r * r * r
    };
    if bytes_at(n as f64) <= budget {
        return n;
    }
    // bytes_at is increasing: bisect on the resolution.
    let (mut lo, mut hi) = (1usize, n);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if bytes_at(mid as f64) <= budget {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
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
            volume_bytes: 0.0,
        };
        assert_eq!(resolution_fitting(&e, 1000, 64e6 + 1e9), 500);
        assert_eq!(resolution_fitting(&e, 1000, 1e12), 1000);
        // A brick table growing with the cube: 8e9 at 1000 is 1e9 at 500.
        let e = Estimate {
            bytes: 64e6 + 8e9,
            volume_bytes: 8e9,
            ..e
        };
        assert_eq!(resolution_fitting(&e, 1000, 64e6 + 1e9), 500);
    }
}
