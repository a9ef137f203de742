//! Argument checks shared by the builders. A builder returns `Err(output)`
//! for a call that cannot be lowered as given: a static error (wrong array
//! length, unknown kind code) or a kind code that is not a constant.

use microfrep_core::Expr;
use microfrep_hyperfun::library::{Arg, Output};

pub type Built = Result<Output, Output>;

/// Runs a builder body, turning its early exits into the call's output.
pub fn out(f: impl FnOnce() -> Built) -> Output {
    f().unwrap_or_else(|e| e)
}

/// A value output.
pub fn value(e: Expr) -> Built {
    Ok(Output::value(e))
}

/// An array argument of exactly three elements (a point or per-axis values).
pub fn three(a: &Arg, what: &str) -> Result<[Expr; 3], Output> {
    match a.array() {
        [x, y, z] => Ok([x.clone(), y.clone(), z.clone()]),
        v => Err(Output::error(format!(
            "{what} must be an array of 3 elements, not {}",
            v.len()
        ))),
    }
}

/// An integer code in `lo..=hi` that must be known when the model is
/// loaded (a point-dependent code sends the model to the per-point path).
pub fn code(a: &Arg, what: &str, lo: i64, hi: i64) -> Result<i64, Output> {
    let Some(v) = a.real().as_const() else {
        return Err(Output::needs_constants());
    };
    if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
        return Err(Output::error(format!(
            "{what} must be an integer from {lo} to {hi}, not {v}"
        )));
    }
    Ok(v as i64)
}
