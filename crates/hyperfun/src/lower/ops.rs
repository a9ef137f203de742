//! HyperFun's numeric semantics on symbolic values: operators, built-ins and
//! conditions, each returning the value plus the conditions under which the
//! reference interpreter raises a run-time error.

use crate::library::EPS;
use microfrep_core::{Expr, SetOp};

/// A run-time error condition: truth value (1 = error) and message.
pub type Fault = (Expr, &'static str);

/// Run-time error of a division by (nearly) zero.
pub const DIV_ZERO: &str = "Division by zero";
/// Run-time error of a negative base raised to a non-integer power.
pub const NEG_POWER: &str = "Negative value for power";
/// Run-time error of a base within EPS of zero raised to a power not above
/// EPS.
pub const ZERO_POWER: &str = "Zero value in negative or zero power";
/// Run-time error of the square root of a negative value.
pub const NEG_SQRT: &str = "Negative value for square root";
/// Run-time error of the logarithm of a value that is not positive.
pub const NEG_LOG: &str = "Negative for log function";
/// Run-time error of `asin` or `acos` outside `[-1, 1]`.
pub const TRIG_RANGE: &str = "Argument must be in range -1.0 .. +1.0";
/// Run-time error of `tan` where `|cos| < EPS` (near a pole).
pub const TAN: &str = "Cannot compute tan for this argument";
/// Run-time error of an array index outside the array.
pub const INDEX_RANGE: &str = "Array index out of range";
/// Run-time error of reading a scalar that was never assigned.
pub const NOT_INIT: &str = "Not initialized variable";
/// Run-time error of reading an array element that was never assigned, or
/// an array that does not exist.
pub const UNASSIGNED: &str = "Unassigned identificator used in expression";
/// Run-time error of passing an array to a function while some of its
/// elements were never assigned.
pub const ARRAY_UNASSIGNED: &str = "Some items of array are unassigned";
/// Run-time error of a `while` loop that runs past the iteration limit
/// (microfrep's own; the reference would hang).
pub const LOOP_LIMIT: &str = "Loop did not terminate within the iteration limit";

fn c(v: f64) -> Expr {
    Expr::constant(v)
}

/// Truth of a HyperFun value: `|v| >= EPS`.
pub fn truth(v: &Expr) -> Expr {
    v.abs().ge(EPS)
}

/// Rounding rule of SPEC 6.1: half up, `c - 1` if `c - d > 0.5` else `c`.
pub fn hf_round(d: &Expr) -> Expr {
    let ce = d.ceil();
    Expr::select((&ce - d).gt(0.5), &ce - 1.0, ce)
}

/// Same rule on a number (for sizes and constant indices).
pub fn hf_round_f(d: f64) -> f64 {
    let ce = d.ceil();
    if ce - d > 0.5 {
        ce - 1.0
    } else {
        ce
    }
}

/// HyperFun's `|`: the R-function union at ALPHA = 0, a set node of the
/// core graph. (The spec's `abs` under the root is left out: a sum of
/// squares is never negative and NaN stays NaN, so values, gradients and
/// intervals are the same without it.)
pub fn union(a: &Expr, b: &Expr) -> Expr {
    Expr::set(SetOp::Union, a, b, 0.0)
}

/// HyperFun's `&`: the R-function intersection at ALPHA = 0.
pub fn intersection(a: &Expr, b: &Expr) -> Expr {
    Expr::set(SetOp::Intersection, a, b, 0.0)
}

/// HyperFun's `\`: the intersection of `a` with the complement `-b`.
pub fn subtraction(a: &Expr, b: &Expr) -> Expr {
    intersection(a, &-b)
}

/// `a / b`, with the division-by-zero fault where `|b| < EPS`.
pub fn div(a: &Expr, b: &Expr) -> (Expr, Vec<Fault>) {
    (a / b, vec![(b.abs().lt(EPS), DIV_ZERO)])
}

/// `a` multiplied by itself `n` times starting from 1, as the C loop does.
fn repeated(a: &Expr, n: u32) -> Expr {
    if n > 64 {
        return a.powi(n as i32);
    }
    (0..n).fold(c(1.0), |acc, _| acc * a)
}

/// Power with the three-step rule of SPEC 6.2.
pub fn pow(a: &Expr, b: &Expr) -> (Expr, Vec<Fault>) {
    let small = a.abs().lt(EPS);
    let zero_fault = (small.and(b.le(EPS)), ZERO_POWER);
    if let Some(bv) = b.as_const() {
        let value = if bv - bv.floor() < EPS {
            let n = hf_round_f(bv.abs());
            let r = repeated(a, n.min(u32::MAX as f64) as u32);
            if bv < 0.0 {
                1.0 / r
            } else {
                r
            }
        } else {
            let neg = (small.not().and(a.lt(0.0)), NEG_POWER);
            let v = (b * a.ln()).exp();
            return (Expr::select(small, c(0.0), v), vec![zero_fault, neg]);
        };
        return (Expr::select(small, c(0.0), value), vec![zero_fault]);
    }
    let is_int = (b - b.floor()).lt(EPS);
    let n = hf_round(&b.abs());
    let int_v = a.pow(Expr::select(b.lt(0.0), -&n, n));
    let real_v = (b * a.ln()).exp();
    let v = Expr::select(is_int.clone(), int_v, real_v);
    let neg = (small.not().and(is_int.not()).and(a.lt(0.0)), NEG_POWER);
    (Expr::select(small, c(0.0), v), vec![zero_fault, neg])
}

/// A built-in function call by (lower-case) name; `None` if not a built-in.
pub fn builtin(name: &str, a: &[Expr]) -> Option<(Expr, Vec<Fault>)> {
    let one = |v: Expr| Some((v, vec![]));
    let x = a.first()?;
    match (name, a.len()) {
        ("sqrt", 1) => Some((x.sqrt(), vec![(x.lt(0.0), NEG_SQRT)])),
        ("exp", 1) => one(x.exp()),
        ("log", 1) => Some((x.ln(), vec![(x.gt(0.0).not(), NEG_LOG)])),
        ("logd", 1) => Some((
            x.ln() / std::f64::consts::LN_10,
            vec![(x.gt(0.0).not(), NEG_LOG)],
        )),
        ("sin", 1) => one(x.sin()),
        ("cos", 1) => one(x.cos()),
        ("tan", 1) => Some((x.tan(), vec![(x.cos().abs().lt(EPS), TAN)])),
        ("asin", 1) => Some((x.asin(), vec![(x.abs().gt(1.0), TRIG_RANGE)])),
        ("acos", 1) => Some((x.acos(), vec![(x.abs().gt(1.0), TRIG_RANGE)])),
        ("atan", 1) => one(x.atan()),
        ("sinh", 1) => one(x.sinh()),
        ("cosh", 1) => one(x.cosh()),
        ("tanh", 1) => one(x.tanh()),
        ("abs", 1) => one(x.abs()),
        // The reference overwrites its -1 with 1: always 1 (`check` warns).
        ("sign", 1) => one(c(1.0)),
        ("ceil", 1) => one(x.ceil()),
        ("floor", 1) => one(x.floor()),
        ("int", 1) => one(x.trunc()),
        ("frac", 1) => one(x - x.trunc()),
        ("mod", 2) => one(hf_round(x).rem(hf_round(&a[1]))),
        // The reference's `x > y ? x : y` is `max` wherever no argument is
        // NaN (NaN values come only from run-time errors, which the error
        // output reports); as min/max nodes they keep tight interval
        // bounds and per-region simplification.
        ("max", 2) => one(x.max(&a[1])),
        ("min", 2) => one(x.min(&a[1])),
        ("atan2", 2) => one(x.atan2(&a[1])),
        _ => None,
    }
}

/// Names and arities of the built-ins, for the parser.
pub const BUILTINS: &[(&str, usize)] = &[
    ("sqrt", 1),
    ("exp", 1),
    ("log", 1),
    ("logd", 1),
    ("sin", 1),
    ("cos", 1),
    ("tan", 1),
    ("asin", 1),
    ("acos", 1),
    ("atan", 1),
    ("sinh", 1),
    ("cosh", 1),
    ("tanh", 1),
    ("abs", 1),
    ("sign", 1),
    ("ceil", 1),
    ("floor", 1),
    ("int", 1),
    ("frac", 1),
    ("mod", 2),
    ("max", 2),
    ("min", 2),
    ("atan2", 2),
];
