use super::batch::{BatchEval, BLOCK};
use crate::tape::Tape;
use rayon::prelude::*;

/// Evaluates the first output at many points on all rayon threads.
pub fn eval_points_par(tape: &Tape, x: &[f32], y: &[f32], z: &[f32]) -> Vec<f32> {
    let n = x.len();
    assert!(y.len() == n && z.len() == n, "slice lengths differ");
    let mut out = vec![0.0f32; n];
    // Chunks of several blocks keep per-task overhead small.
    const CHUNK: usize = BLOCK * 16;
    out.par_chunks_mut(CHUNK).enumerate().for_each_init(
        || BatchEval::new(tape),
        |ev, (ci, o)| {
            let s = ci * CHUNK;
            let e = s + o.len();
            ev.eval(&x[s..e], &y[s..e], &z[s..e], o);
        },
    );
    out
}

/// Samples a regular grid of `dims` nodes from `min` with spacing `step`
/// (x fastest, then y, then z) on all rayon threads.
pub fn eval_grid_par(tape: &Tape, dims: [usize; 3], min: [f64; 3], step: [f64; 3]) -> Vec<f32> {
    let [nx, ny, nz] = dims;
    let mut out = vec![0.0f32; nx * ny * nz];
    if out.is_empty() {
        return out;
    }
    out.par_chunks_mut(nx * ny).enumerate().for_each_init(
        || (BatchEval::new(tape), Vec::new(), Vec::new(), Vec::new()),
        |(ev, xs, ys, zs), (k, slab)| {
            let z = (min[2] + step[2] * k as f64) as f32;
            xs.clear();
            ys.clear();
            zs.clear();
            for j in 0..ny {
                let y = (min[1] + step[1] * j as f64) as f32;
                for i in 0..nx {
                    xs.push((min[0] + step[0] * i as f64) as f32);
                    ys.push(y);
                    zs.push(z);
                }
            }
            ev.eval(xs, ys, zs, slab);
        },
    );
    let _ = nz;
    out
}
