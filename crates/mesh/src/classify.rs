//! Brick classification by interval arithmetic: bricks where the model is
//! provably negative (empty) or non-negative (full) need no sampling.

use crate::grid::Grid;
use microfrep_core::{Interval, IntervalEval, Tape};
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrickClass {
    Empty,
    Full,
    /// May hold surface (or the bounds were unknown: NaN).
    Surface,
}

/// Class of every brick, in brick index order, from interval bounds of the
/// tape's first output (tight through set operations, which are nodes).
pub fn classify(tape: &Tape, grid: &Grid) -> Vec<BrickClass> {
    (0..grid.brick_count())
        .into_par_iter()
        .map_init(
            || IntervalEval::new(tape),
            |ev, k| {
                let (lo, n) = grid.brick_nodes(grid.brick_coords(k));
                let a = grid.node_pos(lo);
                let b = grid.node_pos(std::array::from_fn(|i| lo[i] + n[i] - 1));
                let iv = |i: usize| Interval::new(a[i], b[i]);
                let r = ev.eval(iv(0), iv(1), iv(2));
                if r.is_nan() {
                    BrickClass::Surface
                } else if r.hi < 0.0 {
                    BrickClass::Empty
                } else if r.lo >= 0.0 && !r.may_be_nan() {
                    BrickClass::Full
                } else {
                    BrickClass::Surface
                }
            },
        )
        .collect()
}

/// The sign that interval analysis proves for node `i`, if any brick that
/// contains it (closed box) was found empty or full. Sampled signs of shared
/// nodes are overridden with it, so a node has the same sign in every brick.
pub fn proven_sign(grid: &Grid, classes: &[BrickClass], i: [usize; 3]) -> Option<bool> {
    let cand = |a: usize| -> [Option<usize>; 2] {
        let b = i[a] / grid.brick;
        let own = (b < grid.bricks[a]).then_some(b);
        let below = (i[a].is_multiple_of(grid.brick) && b > 0).then(|| b - 1);
        [own, below]
    };
    let (cx, cy, cz) = (cand(0), cand(1), cand(2));
    for bz in cz.iter().flatten() {
        for by in cy.iter().flatten() {
            for bx in cx.iter().flatten() {
                match classes[grid.brick_index([*bx, *by, *bz])] {
                    BrickClass::Empty => return Some(false),
                    BrickClass::Full => return Some(true),
                    BrickClass::Surface => {}
                }
            }
        }
    }
    None
}

/// Interval evaluations spent at most per brick on [`unproven_cells`]:
/// where the bounds are loose (deep R-function trees) proving every cell
/// would cost one evaluation per cell and more, dwarfing the meshing.
const THIN_BUDGET: usize = 2048;

/// Cell-sized boxes of a brick whose samples all have one sign that
/// interval analysis cannot prove to have that sign throughout: places
/// where a feature thinner than a cell may have been missed. Found by
/// subdividing the brick and dropping boxes proven uniform; when the
/// evaluation budget runs out, the cells of the boxes left count as
/// unproven.
pub fn unproven_cells(
    ev: &mut IntervalEval,
    grid: &Grid,
    lo: [usize; 3],
    n: [usize; 3],
    inside: bool,
) -> usize {
    let mut stack = vec![(lo, n.map(|c| c - 1))];
    let mut found = 0;
    let mut budget = THIN_BUDGET;
    while let Some((c0, size)) = stack.pop() {
        if budget == 0 {
            found += size.iter().product::<usize>();
            continue;
        }
        budget -= 1;
        let a = grid.node_pos(c0);
        let b = grid.node_pos(std::array::from_fn(|k| c0[k] + size[k]));
        let iv = |k: usize| Interval::new(a[k], b[k]);
        let r = ev.eval(iv(0), iv(1), iv(2));
        let proven = if inside {
            r.lo >= 0.0 && !r.may_be_nan()
        } else {
            r.hi < 0.0
        };
        if proven {
            continue;
        }
        if size.iter().all(|&s| s <= 1) {
            found += 1;
            continue;
        }
        // Halve every axis longer than one cell.
        let halves = size.map(|s| {
            if s > 1 {
                vec![s / 2, s - s / 2]
            } else {
                vec![s]
            }
        });
        let mut z0 = c0[2];
        for &sz in &halves[2] {
            let mut y0 = c0[1];
            for &sy in &halves[1] {
                let mut x0 = c0[0];
                for &sx in &halves[0] {
                    stack.push(([x0, y0, z0], [sx, sy, sz]));
                    x0 += sx;
                }
                y0 += sy;
            }
            z0 += sz;
        }
    }
    found
}
