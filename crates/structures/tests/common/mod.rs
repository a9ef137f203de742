//! Shared helpers for the integration tests.
#![allow(dead_code)]

use microfrep_core::{BatchEval, Expr, IntervalEval, PointEval, Tape};

/// f64 reference value at `p`.
pub fn at(e: &Expr, p: [f64; 3]) -> f64 {
    let t = Tape::new(e);
    PointEval::new(&t).eval(p)
}

/// f32 batch values at the points.
pub fn batch(e: &Expr, pts: &[[f64; 3]]) -> Vec<f32> {
    let t = Tape::new(e);
    let mut ev = BatchEval::new(&t);
    let c = |i: usize| pts.iter().map(|p| p[i] as f32).collect::<Vec<_>>();
    let mut out = vec![0.0; pts.len()];
    ev.eval(&c(0), &c(1), &c(2), &mut out);
    out
}

/// Interval bounds on a box.
pub fn interval(e: &Expr, lo: [f64; 3], hi: [f64; 3]) -> (f64, f64) {
    use microfrep_core::Interval;
    let t = Tape::new(e);
    let iv = IntervalEval::new(&t).eval(
        Interval::new(lo[0], hi[0]),
        Interval::new(lo[1], hi[1]),
        Interval::new(lo[2], hi[2]),
    );
    (iv.lo, iv.hi)
}

/// A deterministic spread of points in `[lo, hi]^3`.
pub fn spread(lo: f64, hi: f64, count: usize) -> Vec<[f64; 3]> {
    let a = [0.819_172_513, 0.671_043_607, 0.549_700_478];
    (1..=count)
        .map(|i| std::array::from_fn(|k| lo + (hi - lo) * (0.5 + a[k] * i as f64).fract()))
        .collect()
}
