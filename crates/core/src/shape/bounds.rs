//! Proven bounds of a model: a box that holds its solid (`f >= 0`), found by
//! interval subdivision.
//!
//! Space is searched from a large cube (side 2e6 units about the origin):
//! an octree is refined level by level, keeping only the boxes where the
//! model's interval may reach `>= 0`, until a level would hold too many
//! boxes; the hull of what is left is searched again from itself; then each
//! face of that box is pushed inwards by bisection on the thickness of the
//! slab next to it that subdivision proves empty (a slab where a probe
//! point is solid is settled without it). Set operations are nodes
//! of the tape with exact interval rules ([`crate::Interval::set`]), so a
//! lattice cut by a part is bounded by the part.
//!
//! The work is counted in interval operations (boxes times tape length) and
//! capped by [`BoundsOptions::budget`], so a huge model cannot stall a
//! command: when the budget runs out the box found so far (sound, maybe
//! loose) is returned, and a search that could not get away from the search
//! cube is an error that asks for explicit bounds. The count, not the
//! clock, decides, so the same model always gets the same box.

use crate::{Interval, IntervalEval, PointEval, Tape};
use std::sync::Arc;

/// Half side of the cube searched first.
const SEARCH: f64 = 1e6;
/// Most boxes kept per octree level.
const MAX_BOXES: usize = 1 << 12;
/// Most octree levels.
const MAX_DEPTH: usize = 40;
/// Bisection steps per face and rounds over the six faces.
const FACE_STEPS: usize = 9;
const ROUNDS: usize = 2;
/// Interval evaluations allowed for proving one slab empty.
const SLAB_EVALS: usize = 16384;
/// Undecided boxes of a slab also probed at a point (see
/// [`proven_empty`]).
const SLAB_PROBES: usize = 64;

/// An axis-aligned box, `min` to `max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

impl Bounds {
    /// The box from its corners.
    pub fn new(min: [f64; 3], max: [f64; 3]) -> Bounds {
        Bounds { min, max }
    }
    /// `[min, max]`, the form most consumers take.
    pub fn corners(&self) -> [[f64; 3]; 2] {
        [self.min, self.max]
    }
    /// Side lengths.
    pub fn size(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.max[a] - self.min[a])
    }
    /// Whether every coordinate is finite and `min <= max` on every axis.
    pub fn is_valid(&self) -> bool {
        (0..3).all(|a| {
            self.min[a].is_finite() && self.max[a].is_finite() && self.min[a] <= self.max[a]
        })
    }
}

impl From<[[f64; 3]; 2]> for Bounds {
    fn from(b: [[f64; 3]; 2]) -> Bounds {
        Bounds::new(b[0], b[1])
    }
}

/// Why no box was found.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BoundsError {
    /// Intervals prove the model empty in the whole search cube.
    #[error("the model is empty in the search region (|x|, |y|, |z| < 1e6); give --bounds")]
    Empty,
    /// The solid may reach the search cube: the model may be unbounded (a
    /// bare lattice), or its intervals are too loose to tell.
    #[error(
        "interval analysis cannot bound the model (it may be unbounded, like a bare lattice); \
         give --bounds"
    )]
    Unbounded,
    /// The work budget ran out before the search got away from the
    /// search cube.
    #[error(
        "interval analysis could not bound the model within its work budget \
         ({budget} interval operations); give --bounds"
    )]
    Budget {
        /// The budget that was spent.
        budget: u64,
    },
}

/// How much work the search may do, and whom to tell.
#[derive(Clone)]
pub struct BoundsOptions {
    /// Most interval operations (boxes evaluated times tape length).
    pub budget: u64,
    /// Called with the fraction of the budget spent, now and then.
    pub progress: Option<Arc<dyn Fn(f64) + Send + Sync>>,
}

impl Default for BoundsOptions {
    /// A budget of 1.2e8 interval operations: about a second on one core.
    fn default() -> Self {
        BoundsOptions {
            budget: 120_000_000,
            progress: None,
        }
    }
}

impl std::fmt::Debug for BoundsOptions {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoundsOptions")
            .field("budget", &self.budget)
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

type Box3 = [[f64; 3]; 2];

/// Interval (and point) evaluation of output 0 with the work counted.
struct Search<'o> {
    ev: IntervalEval,
    point: PointEval,
    cost: u64,
    spent: u64,
    opts: &'o BoundsOptions,
    next_report: u64,
}

impl Search<'_> {
    fn exhausted(&self) -> bool {
        self.spent >= self.opts.budget
    }

    /// Whether the box may hold solid. NaN is outside, so a bound that
    /// may also be NaN still excludes solid where its finite part is < 0;
    /// only the "nothing known" bound keeps the box.
    fn may_hold(&mut self, b: &Box3) -> bool {
        self.spent += self.cost;
        if let Some(p) = &self.opts.progress {
            if self.spent >= self.next_report {
                p((self.spent as f64 / self.opts.budget as f64).min(1.0));
                self.next_report = self.spent + self.opts.budget / 100 + 1;
            }
        }
        let iv = |k: usize| Interval::new(b[0][k], b[1][k]);
        let r = self.ev.eval(iv(0), iv(1), iv(2));
        r.is_nan() || r.hi >= 0.0
    }

    /// Whether the model is solid at `p` (counted as one evaluation).
    fn solid_at(&mut self, p: [f64; 3]) -> bool {
        self.spent += self.cost;
        self.point.eval(p) >= 0.0
    }
}

/// The box of output 0 of `tape` (see the module docs).
pub(crate) fn find(tape: &Tape, opts: &BoundsOptions) -> Result<Bounds, BoundsError> {
    let mut s = Search {
        ev: IntervalEval::new(tape),
        point: PointEval::new(tape),
        cost: tape.len().max(1) as u64,
        spent: 0,
        opts,
        next_report: 0,
    };
    let search = [[-SEARCH; 3], [SEARCH; 3]];
    let first = match octree(&mut s, search) {
        None => return Err(BoundsError::Empty),
        Some(b) => b,
    };
    if touches(&first) {
        return Err(if s.exhausted() {
            BoundsError::Budget {
                budget: opts.budget,
            }
        } else {
            BoundsError::Unbounded
        });
    }
    // Again from the first hull, slightly enlarged: the levels now start
    // at the part's own scale.
    let pad: [f64; 3] = std::array::from_fn(|a| 1e-3 * (first[1][a] - first[0][a]) + 1e-9);
    let again = [
        std::array::from_fn(|a| first[0][a] - pad[a]),
        std::array::from_fn(|a| first[1][a] + pad[a]),
    ];
    let b = match octree_boxes(&mut s, again) {
        Some(live) => meet(hull(&live), first),
        None => first,
    };
    let b = shrink_faces(&mut s, b);
    if let Some(p) = &opts.progress {
        p(1.0);
    }
    Ok(Bounds::new(b[0], b[1]))
}

fn touches(b: &Box3) -> bool {
    (0..3).any(|a| b[0][a] <= -SEARCH || b[1][a] >= SEARCH)
}

fn meet(a: Box3, b: Box3) -> Box3 {
    [
        std::array::from_fn(|k| a[0][k].max(b[0][k])),
        std::array::from_fn(|k| a[1][k].min(b[1][k])),
    ]
}

/// The eight children of a box.
fn children(b: &Box3) -> impl Iterator<Item = Box3> + '_ {
    (0..8).map(move |c| {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for a in 0..3 {
            let mid = 0.5 * (b[0][a] + b[1][a]);
            if c >> a & 1 == 0 {
                (lo[a], hi[a]) = (b[0][a], mid);
            } else {
                (lo[a], hi[a]) = (mid, b[1][a]);
            }
        }
        [lo, hi]
    })
}

/// Hull of the boxes that may hold solid after refining `b` level by level
/// until a level would exceed [`MAX_BOXES`] or the budget is spent; `None`
/// when every box is proven empty.
fn octree(s: &mut Search, b: Box3) -> Option<Box3> {
    octree_boxes(s, b).map(|l| hull(&l))
}

fn hull(live: &[Box3]) -> Box3 {
    let mut hull = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for bx in live {
        for a in 0..3 {
            hull[0][a] = hull[0][a].min(bx[0][a]);
            hull[1][a] = hull[1][a].max(bx[1][a]);
        }
    }
    hull
}

/// The boxes that may hold solid after refining `b` level by level (see
/// [`octree`]).
fn octree_boxes(s: &mut Search, b: Box3) -> Option<Vec<Box3>> {
    if !s.may_hold(&b) {
        return None;
    }
    let mut live = vec![b];
    for _ in 0..MAX_DEPTH {
        if s.exhausted() {
            break;
        }
        let mut next = Vec::with_capacity(live.len() * 8);
        for bx in &live {
            for c in children(bx) {
                if s.may_hold(&c) {
                    next.push(c);
                }
            }
        }
        if next.is_empty() {
            // The children cover their parents: nothing holds solid.
            return None;
        }
        if next.len() > MAX_BOXES {
            break;
        }
        live = next;
    }
    Some(live)
}

/// Moves each face of `b` inwards by bisection on the thickness of the
/// slab next to it that subdivision proves empty.
fn shrink_faces(s: &mut Search, mut b: Box3) -> Box3 {
    for _ in 0..ROUNDS {
        for a in 0..3 {
            for side in 0..2 {
                let ext = b[1][a] - b[0][a];
                if ext <= 0.0 {
                    continue;
                }
                let (mut lo, mut hi) = (0.0, 1.0);
                for _ in 0..FACE_STEPS {
                    if s.exhausted() {
                        break;
                    }
                    let mid = 0.5 * (lo + hi);
                    let mut slab = b;
                    if side == 0 {
                        slab[1][a] = b[0][a] + mid * ext;
                    } else {
                        slab[0][a] = b[1][a] - mid * ext;
                    }
                    // The slab's face towards the rest of the box.
                    let inner = (a, slab[1 - side][a]);
                    if proven_empty(s, slab, inner) {
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

/// Whether the model is negative on all of slab `b`, by halving the longest
/// side of undecided boxes until the intervals tell or [`SLAB_EVALS`] boxes
/// have been evaluated. `inner` is the slab's face towards the rest of the
/// box (axis, coordinate): where solid in the slab most likely is, joined
/// to the rest of the part. The first [`SLAB_PROBES`] undecided boxes are
/// taken breadth first, so they spread over the slab, and each is probed
/// at a point (the middle of its side on `inner`, or its centre): one that
/// is solid settles it at once. Without the probes the search would spend
/// its whole allowance to find that out (on a dense structure, at every
/// bisection step of every face: 1 s for a gyroid sheet in a cube, 30 ms
/// with them). Then depth first, to keep the list short; the boxes
/// evaluated are the same either way when the slab is proven empty.
fn proven_empty(s: &mut Search, b: Box3, inner: (usize, f64)) -> bool {
    let mut boxes = std::collections::VecDeque::from([b]);
    let mut left = SLAB_EVALS;
    let mut probes = SLAB_PROBES;
    loop {
        let next = if probes > 0 {
            boxes.pop_front()
        } else {
            boxes.pop_back()
        };
        let Some(b) = next else { break };
        if !s.may_hold(&b) {
            continue;
        }
        if left == 0 || s.exhausted() {
            return false;
        }
        if probes > 0 {
            probes -= 1;
            let (axis, at) = inner;
            let mut p: [f64; 3] = std::array::from_fn(|k| 0.5 * (b[0][k] + b[1][k]));
            if b[0][axis] == at || b[1][axis] == at {
                p[axis] = at;
            }
            if s.solid_at(p) {
                return false;
            }
        }
        left -= 1;
        let a = (0..3)
            .max_by(|&i, &j| (b[1][i] - b[0][i]).total_cmp(&(b[1][j] - b[0][j])))
            .unwrap_or(0);
        let mid = 0.5 * (b[0][a] + b[1][a]);
        let (mut l, mut h) = (b, b);
        l[1][a] = mid;
        h[0][a] = mid;
        boxes.push_back(h);
        boxes.push_back(l);
    }
    true
}
