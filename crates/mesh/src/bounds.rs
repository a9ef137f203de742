//! Bounds of a model from interval analysis: boxes where the model is
//! provably negative are discarded by octree subdivision of a large box.
//!
//! Interval arithmetic alone is loose on R-functions (`f1 + f2 -
//! sqrt(f1^2 + f2^2)` depends on `f1` twice), so a lattice cut by a block would get a
//! box twice the block's size. The set operations are therefore read off the
//! expression first: the solid of an intersection (R-function or `min`) lies
//! in the intersection of its arguments' boxes, the solid of a union in the
//! hull of theirs; only the remaining leaves are bounded by subdivision, and
//! the faces of the combined box are then pushed in on the whole model.

use crate::MeshError;
use microfrep_core::csg::{set_op, SetOp};
use microfrep_core::{Expr, ExprNode, Interval, IntervalEval, Tape};

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

/// A box that holds a model's solid, as tight as the analysis above makes
/// it; an error when the model may be unbounded or is empty.
pub fn model_bounds_of(expr: &Expr) -> Result<Box3, MeshError> {
    let tape = Tape::new(expr);
    let mut ev = IntervalEval::new(&tape);
    match solid_box(expr)? {
        SetBox::Empty => Err(empty()),
        SetBox::Box(b) if finite(&b) => Ok(shrink_faces(&mut ev, b, 1, 64)),
        // The structure did not bound it: the whole model as one leaf.
        SetBox::Box(_) => match leaf_box(expr, &tape)? {
            SetBox::Box(b) if finite(&b) => Ok(shrink_faces(&mut ev, b, ROUNDS, SLAB_BUDGET)),
            SetBox::Empty => Err(empty()),
            SetBox::Box(_) => Err(unbounded()),
        },
    }
}

/// As [`model_bounds_of`] from the tape alone (no set structure to read):
/// subdivision of the whole model only.
pub fn model_bounds(tape: &Tape) -> Result<Box3, MeshError> {
    let first = shrink(tape, [[-SEARCH; 3], [SEARCH; 3]], [true; 3])?.ok_or_else(empty)?;
    if touches(&first) {
        return Err(unbounded());
    }
    let b = second_pass(tape, first, [true; 3])?;
    Ok(shrink_faces(
        &mut IntervalEval::new(tape),
        b,
        ROUNDS,
        SLAB_BUDGET,
    ))
}

fn empty() -> MeshError {
    MeshError::Input("the model is empty in the search box; give --bounds".into())
}

fn unbounded() -> MeshError {
    MeshError::Input(
        "interval analysis cannot bound the model (it may be unbounded); give --bounds".into(),
    )
}

fn finite(b: &Box3) -> bool {
    b.iter().flatten().all(|v| v.is_finite())
}

fn touches(b: &Box3) -> bool {
    (0..3).any(|a| b[0][a] <= -SEARCH || b[1][a] >= SEARCH)
}

/// Subdivides again from the first hull, slightly enlarged.
fn second_pass(tape: &Tape, first: Box3, split: [bool; 3]) -> Result<Box3, MeshError> {
    let pad: [f64; 3] = std::array::from_fn(|a| 1e-3 * (first[1][a] - first[0][a]) + 1e-9);
    let b = [
        std::array::from_fn(|a| first[0][a] - pad[a]),
        std::array::from_fn(|a| first[1][a] + pad[a]),
    ];
    Ok(shrink(tape, b, split)?.unwrap_or(first))
}

/// Where a solid may be: nowhere, or in a box whose sides may be infinite.
#[derive(Clone, Copy, Debug, PartialEq)]
enum SetBox {
    Empty,
    Box(Box3),
}

const ALL: SetBox = SetBox::Box([[f64::NEG_INFINITY; 3], [f64::INFINITY; 3]]);

fn meet(a: SetBox, b: SetBox) -> SetBox {
    match (a, b) {
        (SetBox::Empty, _) | (_, SetBox::Empty) => SetBox::Empty,
        (SetBox::Box(p), SetBox::Box(q)) => {
            let lo: [f64; 3] = std::array::from_fn(|k| p[0][k].max(q[0][k]));
            let hi: [f64; 3] = std::array::from_fn(|k| p[1][k].min(q[1][k]));
            if (0..3).any(|k| lo[k] > hi[k]) {
                SetBox::Empty
            } else {
                SetBox::Box([lo, hi])
            }
        }
    }
}

fn join(a: SetBox, b: SetBox) -> SetBox {
    match (a, b) {
        (SetBox::Empty, x) | (x, SetBox::Empty) => x,
        (SetBox::Box(p), SetBox::Box(q)) => SetBox::Box([
            std::array::from_fn(|k| p[0][k].min(q[0][k])),
            std::array::from_fn(|k| p[1][k].max(q[1][k])),
        ]),
    }
}

/// The coordinates `e` depends on.
fn axes_used(e: &Expr) -> [bool; 3] {
    let mut seen = std::collections::HashSet::new();
    let mut used = [false; 3];
    let mut stack = vec![e];
    while let Some(e) = stack.pop() {
        if !seen.insert(e.node() as *const ExprNode) {
            continue;
        }
        if let ExprNode::Var(a) = e.node() {
            used[*a as usize] = true;
        }
        stack.extend(e.children());
    }
    used
}

fn solid_box(e: &Expr) -> Result<SetBox, MeshError> {
    Ok(match set_op(e) {
        Some(SetOp::And(a, b)) => {
            let a = solid_box(a)?;
            if a == SetBox::Empty {
                return Ok(a);
            }
            meet(a, solid_box(b)?)
        }
        Some(SetOp::Or(a, b)) => join(solid_box(a)?, solid_box(b)?),
        Some(SetOp::Same(a)) => solid_box(a)?,
        Some(SetOp::Not(_)) | None => leaf_box(e, &Tape::new(e))?,
    })
}

/// Where the solid of `e` (compiled as `tape`) may be: the hull of the
/// octree leaves that may hold solid, after subdividing until the leaf count
/// limit (twice, the second time inside the first result). Axes `e` does not
/// depend on are unbounded; so are all the ones it does when the hull
/// reaches the search box (the solid may go on beyond it).
fn leaf_box(e: &Expr, tape: &Tape) -> Result<SetBox, MeshError> {
    let used = axes_used(e);
    if used == [false; 3] {
        // A constant: everywhere or nowhere.
        let r = IntervalEval::new(tape).eval(
            Interval::point(0.0),
            Interval::point(0.0),
            Interval::point(0.0),
        );
        return Ok(if !r.is_nan() && r.hi < 0.0 {
            SetBox::Empty
        } else {
            ALL
        });
    }
    let Some(first) = shrink(tape, [[-SEARCH; 3], [SEARCH; 3]], used)? else {
        return Ok(SetBox::Empty);
    };
    if (0..3).any(|a| used[a] && (first[0][a] <= -SEARCH || first[1][a] >= SEARCH)) {
        return Ok(ALL);
    }
    let b = second_pass(tape, first, used)?;
    // Faces pushed in on this leaf alone, where its intervals are tight;
    // the axes it does not use are pinned to a point meanwhile.
    let pinned = [0, 1].map(|s| std::array::from_fn(|k| if used[k] { b[s][k] } else { 0.0 }));
    let b = shrink_faces(&mut IntervalEval::new(tape), pinned, 2, 256);
    Ok(SetBox::Box([
        std::array::from_fn(|k| if used[k] { b[0][k] } else { f64::NEG_INFINITY }),
        std::array::from_fn(|k| if used[k] { b[1][k] } else { f64::INFINITY }),
    ]))
}

/// Moves each face of `b` inwards by bisection on the thickness of the slab
/// next to it that interval subdivision proves empty.
fn shrink_faces(ev: &mut IntervalEval, mut b: Box3, rounds: usize, budget: usize) -> Box3 {
    for _ in 0..rounds {
        for a in 0..3 {
            if b[0][a] == b[1][a] {
                continue;
            }
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
                    let mut left = budget;
                    if proven_empty(ev, slab, &mut left) {
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

/// Hull of the boxes that may hold solid after subdividing `b` (along the
/// axes in `split` only) until the box count limit.
fn shrink(tape: &Tape, b: Box3, split: [bool; 3]) -> Result<Option<Box3>, MeshError> {
    let mut ev = IntervalEval::new(tape);
    let mut live = vec![b];
    for _ in 0..MAX_DEPTH {
        let mut next = Vec::with_capacity(live.len() * 8);
        for bx in &live {
            for c in 0..8 {
                if (0..3).any(|a| !split[a] && c >> a & 1 == 1) {
                    continue;
                }
                let child: Box3 = {
                    let mut lo = [0.0; 3];
                    let mut hi = [0.0; 3];
                    for a in 0..3 {
                        let mid = 0.5 * (bx[0][a] + bx[1][a]);
                        if !split[a] {
                            (lo[a], hi[a]) = (bx[0][a], bx[1][a]);
                        } else if c >> a & 1 == 0 {
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
