//! Park et al.'s smooth n-ary union and intersection with exponent `a`
//! (§2.2), in microfrep's sign convention (inside `f >= 0`).
//!
//! Park writes, for functions negative inside (his convention),
//! `union_a = (f_1^-a + ... + f_n^-a)^(-1/a)` (tending to `min`) and
//! `intersect_a = (f_1^a + ... + f_n^a)^(1/a)` (tending to `max`), `a > 0`,
//! and applies them to positive potentials whose surface is a positive level
//! (the femur implant: quadratic forms `q_i`, surface `union_a(q) = 1`).
//! Flipping the sign convention swaps `min` and `max`, so here
//!
//! - [`union_a`] is the power sum `(sum f_i^a)^(1/a)`, tending to `max`, and
//! - [`intersect_a`] is `(sum f_i^-a)^(-1/a)`, tending to `min`,
//!
//! exactly, for positive arguments (densities, potentials). Park's femur
//! union of `q_i` equals `1 / union_a(1/q_i)` (same surface at level 1).
//!
//! For signed defining functions the two formulas are applied to the
//! magnitudes on each side of zero: with `M = max f_i`,
//!
//! - if `M >= 0`: `union_a = (sum max(f_i, 0)^a)^(1/a)`;
//! - if `M < 0`: `union_a = -(sum |f_i|^-a)^(-1/a)`;
//!
//! and `intersect_a(f) = -union_a(-f)`. This keeps the sign rule of `max`
//! and `min` exactly (`union_a >= 0` iff some `f_i >= 0`, `intersect_a >= 0`
//! iff all are), is continuous, and reduces to Park's formulas for positive
//! arguments. Bounds: `M <= union_a <= n^(1/a) M` where `M > 0` and
//! `M <= union_a <= n^(-1/a) M` where `M < 0`, so
//! `|union_a - max| <= (n^(1/a) - 1) |max|`, which vanishes as `a`
//! grows (the same for `intersect_a` and `min`). The blend rounds the union
//! outwards and the intersection inwards by at most that factor.
//!
//! The sums are computed on ratios `f_i / M` in `[0, 1]` (or `>= 1` below
//! zero, raised to `-a`), so no term overflows whatever `a` and the
//! magnitudes. The core's `frep::smooth_union_n` / `smooth_intersection_n`
//! are the same power sums for positive arguments only: they are NaN for a
//! negative argument with a fractional `a` and overflow to infinity when
//! `f^a` exceeds the f64 range (e.g. `f = 10`, `a = 400`).

use microfrep_core::Expr;

/// Smooth union (tends to `max` as `a` grows). An empty list is the empty
/// set (`-inf`); one function is returned unchanged. `a > 0` may be a field.
pub fn union_a(fs: &[Expr], a: impl Into<Expr>) -> Expr {
    let a = a.into();
    match fs {
        [] => Expr::constant(f64::NEG_INFINITY),
        [f] => f.clone(),
        _ => {
            let m = fs[1..].iter().fold(fs[0].clone(), |m, f| m.max(f));
            // The ratios are 0/0 where M = 0; there the result is 0 whatever
            // the ratios, so divide by 1 instead.
            let safe = Expr::select(m.eq_(0.0), Expr::constant(1.0), m.clone());
            let pos = sum(fs.iter().map(|f| (f.max(0.0) / &safe).pow(a.clone())));
            let neg = sum(fs.iter().map(|f| (f / &safe).pow(a.neg())));
            let s = Expr::select(m.ge(0.0), pos.pow(1.0 / &a), neg.pow(-1.0 / &a));
            m * s
        }
    }
}

/// Smooth intersection (tends to `min` as `a` grows): `-union_a(-f)`. An
/// empty list is all space (`+inf`).
pub fn intersect_a(fs: &[Expr], a: impl Into<Expr>) -> Expr {
    match fs {
        [] => Expr::constant(f64::INFINITY),
        [f] => f.clone(),
        _ => {
            let neg: Vec<Expr> = fs.iter().map(|f| f.neg()).collect();
            union_a(&neg, a).neg()
        }
    }
}

fn sum(it: impl Iterator<Item = Expr>) -> Expr {
    it.reduce(|s, t| s + t).unwrap_or(Expr::constant(0.0))
}

/// Reference value of [`union_a`] (f64), for tests.
pub fn union_a_value(fs: &[f64], a: f64) -> f64 {
    let Some(m) = fs.iter().copied().reduce(f64::max) else {
        return f64::NEG_INFINITY;
    };
    if fs.len() == 1 || m == 0.0 {
        return m;
    }
    if m > 0.0 {
        m * fs
            .iter()
            .map(|f| (f.max(0.0) / m).powf(a))
            .sum::<f64>()
            .powf(1.0 / a)
    } else {
        m * fs
            .iter()
            .map(|f| (f / m).powf(-a))
            .sum::<f64>()
            .powf(-1.0 / a)
    }
}

/// Reference value of [`intersect_a`] (f64).
pub fn intersect_a_value(fs: &[f64], a: f64) -> f64 {
    let neg: Vec<f64> = fs.iter().map(|f| -f).collect();
    -union_a_value(&neg, a)
}
