//! Dropping error sites that no input can reach.
//!
//! Many checks guard operations that can never fail, e.g. the square root
//! of a sum of squares. Each site's condition is bounded by interval
//! evaluation over all of space with every parameter unbounded; a site whose
//! condition is provably 0 everywhere is removed. The error output then
//! often folds to the constant 0, so it costs nothing next to the value.

use microfrep_core::{Expr, Interval, IntervalEval, Tape};

/// The first-wins error code of `sites` (in evaluation order), without the
/// sites that can never fire.
pub fn error_code(sites: &[(Expr, Expr)]) -> Expr {
    let live = reachable(sites);
    let mut err = Expr::constant(0.0);
    for ((hit, code), keep) in sites.iter().zip(live) {
        if keep {
            let new = Expr::select(hit.clone(), code.clone(), Expr::constant(0.0));
            err = Expr::select(err.clone(), err, new);
        }
    }
    err
}

/// Per site: whether its condition may be true somewhere.
fn reachable(sites: &[(Expr, Expr)]) -> Vec<bool> {
    let conds: Vec<Expr> = sites.iter().map(|(h, _)| h.clone()).collect();
    if conds.is_empty() {
        return Vec::new();
    }
    // Constant conditions (the per-point fallback's) need no bound.
    if conds.iter().all(|h| h.as_const().is_some()) {
        return conds.iter().map(|h| h.as_const() != Some(0.0)).collect();
    }
    let tape = Tape::with_outputs(&conds);
    let mut ie = IntervalEval::new(&tape);
    for k in 0..tape.params().len() {
        ie.set_param_interval(k, Interval::ENTIRE);
    }
    let all = Interval::ENTIRE;
    ie.eval_all(all, all, all)
        .into_iter()
        .map(|i| i.may_be_nan() || i.lo != 0.0 || i.hi != 0.0)
        .collect()
}
