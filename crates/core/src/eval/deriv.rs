//! Derivative rules shared by the gradient evaluators.
//!
//! Piecewise-constant ops (floor, sign, comparisons, ...) have derivative 0
//! where they are differentiable; at a jump the one-sided value is returned.

use crate::ops::{BinaryOp, UnaryOp};

/// d op(a) / da, given `a` and `v = op(a)`.
#[inline]
pub fn unary_derivative(op: UnaryOp, a: f64, v: f64) -> f64 {
    use UnaryOp::*;
    match op {
        Neg => -1.0,
        Abs => crate::ops::sign(a),
        Sqrt => 0.5 / v,
        Square => 2.0 * a,
        Exp => v,
        Ln => 1.0 / a,
        Sin => a.cos(),
        Cos => -a.sin(),
        Tan => 1.0 + v * v,
        Asin => 1.0 / (1.0 - a * a).sqrt(),
        Acos => -1.0 / (1.0 - a * a).sqrt(),
        Atan => 1.0 / (1.0 + a * a),
        Sinh => a.cosh(),
        Cosh => a.sinh(),
        Tanh => 1.0 - v * v,
        Sign | Floor | Ceil | Trunc | Round | Not => 0.0,
        Fract | Saw => 1.0,
        Tri => {
            let s = 0.5 * a + 0.25;
            if s - s.floor() < 0.5 {
                1.0
            } else {
                -1.0
            }
        }
    }
}

/// (d op / da, d op / db) at `(a, b)` with `v = op(a, b)`.
#[inline]
pub fn binary_partials(op: BinaryOp, a: f64, b: f64, v: f64) -> (f64, f64) {
    use BinaryOp::*;
    match op {
        Add => (1.0, 1.0),
        Sub => (1.0, -1.0),
        Mul => (b, a),
        Div => (1.0 / b, -a / (b * b)),
        Pow => {
            let da = if b == 0.0 { 0.0 } else { b * a.powf(b - 1.0) };
            let db = if a > 0.0 { v * a.ln() } else { 0.0 };
            (da, db)
        }
        Atan2 => {
            let r2 = a * a + b * b;
            (b / r2, -a / r2)
        }
        Min => {
            if a <= b {
                (1.0, 0.0)
            } else {
                (0.0, 1.0)
            }
        }
        Max => {
            if a >= b {
                (1.0, 0.0)
            } else {
                (0.0, 1.0)
            }
        }
        Mod => (1.0, -(a / b).floor()),
        Rem => (1.0, -(a / b).trunc()),
        Lt | Le | Gt | Ge | Eq | Ne | And | Or => (0.0, 0.0),
    }
}

/// d a^n / da.
#[inline]
pub fn powi_derivative(a: f64, n: i32) -> f64 {
    if n == 0 {
        0.0
    } else {
        n as f64 * a.powi(n - 1)
    }
}
