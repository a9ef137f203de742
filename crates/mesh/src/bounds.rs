//! Bounds of a model from interval analysis: boxes where the model is
//! provably negative are discarded by octree subdivision of a large box.

use crate::MeshError;
use microfrep_core::{Interval, IntervalEval, Tape};

/// Half-width of the first box searched.
const SEARCH: f64 = 1e4;
/// Most boxes kept per subdivision level.
const MAX_BOXES: usize = 1 << 15;
const MAX_DEPTH: usize = 24;

type Box3 = [[f64; 3]; 2];

/// Interval evaluations allowed per emptiness proof of one slab.
const SLAB_BUDGET: usize = 4096;
/// Bisection steps per face, and rounds over the six faces.
const FACE_STEPS: usize = 14;
const ROUNDS: usize = 3;

/// Hull of the octree leaves that may hold solid, after subdividing until
/// the leaf count limit (twice, the second time inside the first result),
/// then each face pushed inwards while the slab it sweeps is proven empty.
pub fn model_bounds(tape: &Tape) -> Result<Box3, MeshError> {
    let start = [[-SEARCH; 3], [SEARCH; 3]];
    let first = shrink(tape, start)?.ok_or_else(|| {
        MeshError::Input("the model is empty in the search box; give --bounds".into())
    })?;
    let touches = (0..3).any(|a| first[0][a] <= -SEARCH || first[1][a] >= SEARCH);
    if touches {
        return Err(MeshError::Input(
            "interval analysis cannot bound the model (it may be unbounded); give --bounds".into(),
        ));
    }
    // Second pass from a slightly enlarged first hull.
    let pad: [f64; 3] = std::array::from_fn(|a| 1e-3 * (first[1][a] - first[0][a]) + 1e-9);
    let b = [
        std::array::from_fn(|a| first[0][a] - pad[a]),
        std::array::from_fn(|a| first[1][a] + pad[a]),
    ];
    let hull = shrink(tape, b)?.unwrap_or(first);
    Ok(shrink_faces(&mut IntervalEval::new(tape), hull))
}

/// Moves each face of `b` inwards by bisection on the thickness of the slab
/// next to it that interval subdivision proves empty.
fn shrink_faces(ev: &mut IntervalEval, mut b: Box3) -> Box3 {
    for _ in 0..ROUNDS {
        for a in 0..3 {
            for side in 0..2 {
                let ext = b[1][a] - b[0][a];
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..FACE_STEPS {
                    let mid = 0.5 * (lo + hi);
                    let mut slab = b;
                    if side == 0 {
                        slab[1][a] = b[0][a] + mid * ext;
                    } else {
                        slab[0][a] = b[1][a] - mid * ext;
                    }
                    let mut budget = SLAB_BUDGET;
                    if proven_empty(ev, slab, &mut budget) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                if side == 0 {
                    b[0][a] += lo * ext;
                } else {
                    b[1][a] -= lo * ext;
                }
            }
        }
    }
    b
}

/// Whether the model is negative on all of `b`, by halving the longest
/// side until the intervals tell or the budget runs out.
fn proven_empty(ev: &mut IntervalEval, b: Box3, budget: &mut usize) -> bool {
    let iv = |k: usize| Interval::new(b[0][k], b[1][k]);
    let r = ev.eval(iv(0), iv(1), iv(2));
    if !r.is_nan() && r.hi < 0.0 {
        return true;
    }
    if *budget == 0 {
        return false;
    }
    *budget -= 1;
    let a = (0..3)
        .max_by(|&i, &j| (b[1][i] - b[0][i]).total_cmp(&(b[1][j] - b[0][j])))
        .unwrap_or(0);
    let mid = 0.5 * (b[0][a] + b[1][a]);
    let (mut l, mut h) = (b, b);
    l[1][a] = mid;
    h[0][a] = mid;
    proven_empty(ev, l, budget) && proven_empty(ev, h, budget)
}

fn shrink(tape: &Tape, b: Box3) -> Result<Option<Box3>, MeshError> {
    let mut ev = IntervalEval::new(tape);
    let mut live = vec![b];
    for _ in 0..MAX_DEPTH {
        let mut next = Vec::with_capacity(live.len() * 8);
        for bx in &live {
            for c in 0..8 {
                let child: Box3 = {
                    let mut lo = [0.0; 3];
                    let mut hi = [0.0; 3];
                    for a in 0..3 {
                        let mid = 0.5 * (bx[0][a] + bx[1][a]);
                        if c >> a & 1 == 0 {
                            (lo[a], hi[a]) = (bx[0][a], mid);
                        } else {
                            (lo[a], hi[a]) = (mid, bx[1][a]);
                        }
                    }
                    [lo, hi]
                };
                let iv = |a: usize| Interval::new(child[0][a], child[1][a]);
                let r = ev.eval(iv(0), iv(1), iv(2));
                if r.is_nan() || r.hi >= 0.0 {
                    next.push(child);
                }
            }
        }
        if next.len() > MAX_BOXES {
            break;
        }
        live = next;
        if live.is_empty() {
            return Ok(None);
        }
    }
    let mut hull = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for bx in &live {
        for a in 0..3 {
            hull[0][a] = hull[0][a].min(bx[0][a]);
            hull[1][a] = hull[1][a].max(bx[1][a]);
        }
    }
    Ok(Some(hull))
}
