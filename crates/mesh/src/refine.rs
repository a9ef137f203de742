//! Moving vertices from their grid edges onto the surface: regula falsi
//! (Illinois variant) along each edge, a block of edges at a time on the
//! f32 batch evaluator (one evaluation per step for the whole block; the
//! f64 point evaluator was 5x slower than the rest of the mesher together).

use microfrep_core::{BatchEval, BLOCK};

/// Regula falsi steps; Illinois converges superlinearly, so a few steps
/// reach f32 precision on smooth surfaces.
const STEPS: usize = 5;
/// Vertices stay this fraction of the edge away from its ends, so vertices
/// on different edges of a tet never coincide (no degenerate triangles).
const T_MIN: f32 = 1e-3;

/// One edge to refine: from its inside end `p0` (sample `g0 >= 0`) to its
/// outside end `p1` (sample `g1 < 0`).
#[derive(Clone, Copy)]
pub struct Edge {
    p0: [f32; 3],
    d: [f32; 3],
    g0: f32,
    g1: f32,
}

impl Edge {
    pub fn new(p0: [f64; 3], p1: [f64; 3], g0: f32, g1: f32) -> Edge {
        Edge {
            p0: p0.map(|v| v as f32),
            d: std::array::from_fn(|k| (p1[k] - p0[k]) as f32),
            g0,
            g1,
        }
    }
}

/// Appends the refined position of every edge to `out`, in order.
pub fn refine_edges(ev: &mut BatchEval, edges: &[Edge], out: &mut Vec<[f32; 3]>) {
    for chunk in edges.chunks(BLOCK) {
        let n = chunk.len();
        let mut lo = [0.0f32; BLOCK];
        let mut hi = [1.0f32; BLOCK];
        let mut glo = [0.0f32; BLOCK];
        let mut ghi = [0.0f32; BLOCK];
        let mut t = [0.5f32; BLOCK];
        // Edges whose samples do not bracket a root (their sign was set by
        // interval proof or the padding) keep the midpoint.
        let mut live = [false; BLOCK];
        for (i, e) in chunk.iter().enumerate() {
            glo[i] = e.g0;
            ghi[i] = e.g1;
            live[i] = e.g0 >= 0.0 && e.g1 < 0.0;
        }
        for _ in 0..STEPS {
            {
                let (x, y, z) = ev.coords_mut();
                for (i, e) in chunk.iter().enumerate() {
                    if live[i] {
                        let s = (lo[i] * ghi[i] - hi[i] * glo[i]) / (ghi[i] - glo[i]);
                        t[i] = if s > lo[i] && s < hi[i] {
                            s
                        } else {
                            0.5 * (lo[i] + hi[i])
                        };
                    }
                    let p = lerp(e, t[i]);
                    (x[i], y[i], z[i]) = (p[0], p[1], p[2]);
                }
            }
            let g = ev.eval_loaded(n);
            for i in 0..n {
                if !live[i] {
                    continue;
                }
                if g[i] >= 0.0 {
                    lo[i] = t[i];
                    glo[i] = g[i];
                    ghi[i] *= 0.5;
                } else if g[i] < 0.0 {
                    hi[i] = t[i];
                    ghi[i] = g[i];
                    glo[i] *= 0.5;
                } else {
                    live[i] = false; // NaN: stop here
                }
            }
        }
        for (i, e) in chunk.iter().enumerate() {
            out.push(lerp(e, t[i].clamp(T_MIN, 1.0 - T_MIN)));
        }
    }
}

fn lerp(e: &Edge, t: f32) -> [f32; 3] {
    std::array::from_fn(|k| e.p0[k] + t * e.d[k])
}
