//! Variable structures (Fryazinov et al.): metamorphosis between cells
//! (Algorithm 2) and transfinite interpolation between space partitions.
//!
//! Parameterised cells need nothing special: every cell parameter is an
//! [`Expr`] and may depend on the point. A variable period is a field period
//! in [`crate::replicate::Wave`]; for a period driven by the distance to an
//! outer shell use [`crate::infill::graded_by_depth`] on the shell.

use microfrep_core::frep::morph;
use microfrep_core::Expr;

/// `(t - a) / (b - a)` clamped to [0, 1]: 0 at `a`, 1 at `b`.
pub fn ramp(t: &Expr, a: impl Into<Expr>, b: impl Into<Expr>) -> Expr {
    let a = a.into();
    ((t - &a) / (b.into() - &a)).max(0.0).min(1.0)
}

/// Metamorphosis `from (1 - t) + to t` with `t` clamped to [0, 1]; Algorithm 2
/// is `metamorphosis(sphere, tori, ramp(z, -10, 10))`.
pub fn metamorphosis(from: &Expr, to: &Expr, t: &Expr) -> Expr {
    morph(from, to, t.max(0.0).min(1.0))
}

/// Transfinite weights `W_i = prod_{j != i} d_j / sum_k prod_{j != k} d_j` for
/// distances `d_i >= 0` to disjoint partitions (0 inside partition i). They
/// sum to 1 and are 1 inside partition i, 0 inside the others. Where every
/// product vanishes (two partitions overlap) each weight is `1/n`.
pub fn transfinite_weights(d: &[Expr]) -> Vec<Expr> {
    let n = d.len();
    let prods: Vec<Expr> = (0..n)
        .map(|i| {
            (0..n)
                .filter(|&j| j != i)
                .map(|j| d[j].clone())
                .reduce(|a, b| a * b)
                .unwrap_or_else(|| Expr::constant(1.0))
        })
        .collect();
    let Some(sum) = prods.iter().cloned().reduce(|a, b| a + b) else {
        return vec![];
    };
    prods
        .into_iter()
        .map(|p| Expr::select(sum.gt(0.0), p / &sum, Expr::constant(1.0 / n as f64)))
        .collect()
}

/// `u = sum_i u_i W_i`: a value (a period, or a cell shape for metamorphosis
/// between several cells) interpolated between partitions.
pub fn transfinite(values: &[Expr], d: &[Expr]) -> Expr {
    transfinite_weights(d)
        .iter()
        .zip(values)
        .map(|(w, u)| w * u)
        .reduce(|a, b| a + b)
        .unwrap_or_else(|| Expr::constant(0.0))
}

/// Distance-like `d >= 0` to the partition given as a solid `f` (0 inside):
/// `max(-g, 0)` with `g` the depth of [`crate::infill::depth`].
pub fn partition_distance(f: &Expr, mode: crate::infill::Depth) -> Expr {
    crate::infill::depth(f, mode).neg().max(0.0)
}
