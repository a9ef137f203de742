//! Per-point evaluation for models whose control flow depends on the point
//! (a `while` whose trip count varies, ...). It runs the same symbolic
//! executor with constant coordinates, so everything folds to numbers and
//! the semantics are those of the lowered path. Wrapped as a core `Field`,
//! it plugs into every evaluation mode; its intervals are the whole line.

use super::errors::{ErrorTable, RuntimeError};
use super::exec::{Exec, Inputs, Stop, POINT_LOOP_BUDGET};
use crate::ast::Program;
use crate::library::Registry;
use microfrep_core::{Expr, Field, Interval};
use std::sync::{Arc, OnceLock};

/// Everything needed to evaluate one object at a point.
pub struct Interp {
    pub program: Arc<Program>,
    pub object: usize,
    pub registry: Registry,
    pub table: ErrorTable,
    pub params: Vec<f64>,
    /// Error code of the first loop that ran out of iterations at some
    /// point: from then on every point reports it at once instead of
    /// spending the whole budget again (a loop that never ends would cost
    /// that on every sample of a mesh).
    pub runaway: OnceLock<f64>,
}

impl std::fmt::Debug for Interp {
    /// Short: the program can be megabytes (and deep).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = &self.program.objects[self.object].name;
        write!(f, "Interp({name}, params {:?})", self.params)
    }
}

impl Interp {
    /// Value and error code at a point.
    pub fn eval(&self, p: [f64; 3]) -> (f64, f64) {
        if let Some(&code) = self.runaway.get() {
            return (f64::NAN, code);
        }
        let obj = &self.program.objects[self.object];
        let mut ex = Exec::with_budget(
            &self.program,
            &self.registry,
            &self.table,
            POINT_LOOP_BUDGET,
        );
        let inputs = Inputs {
            x: p.iter().map(|&v| Expr::constant(v)).collect(),
            a: self.params.iter().map(|&v| Expr::constant(v)).collect(),
        };
        let out = ex.run(obj, inputs);
        if ex.limit_hit {
            if let Some(code) = ex.err.as_const() {
                let _ = self.runaway.set(code);
            }
        }
        match out {
            Ok(v) => {
                let code = ex.err.as_const().unwrap_or(f64::NAN);
                // As in the lowered graph: no value where an error is raised.
                let v = if code == 0.0 {
                    v.as_const().unwrap_or(f64::NAN)
                } else {
                    f64::NAN
                };
                (v, code)
            }
            // A call whose constant arguments are only known at this point
            // (e.g. a term count computed in a loop) can be invalid here:
            // a run-time error at the call, like any other.
            Err(Stop::Static(message, pos)) => {
                let code = self.table.code(RuntimeError {
                    message,
                    line: pos.line,
                    col: pos.col,
                });
                (f64::NAN, code)
            }
            // With constant inputs every condition is constant.
            Err(Stop::NeedsPoint) => (f64::NAN, f64::NAN),
        }
    }
}

/// Which output of the interpreter a field exposes.
#[derive(Debug)]
pub struct Output {
    pub interp: Arc<Interp>,
    pub error: bool,
}

impl Output {
    fn pick(&self, p: [f64; 3]) -> f64 {
        let (v, e) = self.interp.eval(p);
        if self.error {
            e
        } else {
            v
        }
    }
}

/// Step of the central differences that give the fallback's gradient.
const H: f64 = 1e-6;

impl Field for Output {
    fn name(&self) -> &str {
        if self.error {
            "hyperfun-error"
        } else {
            "hyperfun"
        }
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        self.pick(p)
    }
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let v = self.pick(p);
        let mut g = [0.0; 3];
        for (k, gk) in g.iter_mut().enumerate() {
            let (mut lo, mut hi) = (p, p);
            lo[k] -= H;
            hi[k] += H;
            *gk = (self.pick(hi) - self.pick(lo)) / (2.0 * H);
        }
        (v, g)
    }
    fn interval(&self, _b: [Interval; 3]) -> Interval {
        Interval::ENTIRE
    }
}
