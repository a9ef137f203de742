//! Lowering a parsed HyperFun program to the core graph.
//!
//! A model becomes two expressions: the value and an error code (0 = fine,
//! `k` = entry `k - 1` of the error table). Compiled together with
//! `Tape::with_outputs`, both run at the core's speed in every evaluation
//! mode. Models whose control flow depends on the point evaluate through the
//! per-point fallback (same executor, constant inputs) wrapped as a `Field`.

mod census;
mod check;
mod errors;
mod exec;
mod fallback;
pub mod ops;
mod prune;
mod usage;

pub use census::ErrorCensus;
pub use errors::{ErrorTable, RuntimeError};
pub use usage::calls_of;

use crate::ast::{Pos, Program};
use crate::library::Registry;
pub(crate) use exec::grow;
use exec::{Exec, Inputs, Stop};
use microfrep_core::{Expr, PointEval, Shape, Tape};
use std::sync::Arc;

/// Default object name of the reference polygonizer.
pub const DEFAULT_OBJECT: &str = "my_model";

/// A model ready to evaluate.
#[derive(Clone, Debug)]
pub struct Model {
    /// Name of the evaluated object.
    pub object: String,
    /// Names of all objects in the file, in order.
    pub objects: Vec<String>,
    /// The value F (inside where F >= 0); NaN where the model raises a
    /// run-time error (see `error`), which every consumer treats as outside.
    pub value: Expr,
    /// Error code: 0, or a code resolved by `errors`.
    pub error: Expr,
    pub errors: ErrorTable,
    /// `a[k]` parameters as `(name, value)`: names `a1`, `a2`, ... are the
    /// `Expr::param` names of the lowered graph.
    pub params: Vec<(String, f64)>,
    /// False when the model runs through the per-point fallback (parameters
    /// are then fixed at load time and intervals are unbounded).
    pub lowered: bool,
    /// The per-point interpreter, when `lowered` is false.
    interp: Option<Arc<fallback::Interp>>,
}

/// A static error found while lowering (message, position).
#[derive(Clone, Debug, PartialEq)]
pub struct LowerError {
    pub message: String,
    pub pos: Pos,
}

impl std::fmt::Display for LowerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}: {}", self.pos.line, self.pos.col, self.message)
    }
}

impl std::error::Error for LowerError {}

/// Picks the object to evaluate: `name` (default `my_model`) if present,
/// else the first object, as the reference host does.
pub fn select_object(program: &Program, name: Option<&str>) -> Option<usize> {
    let want = name.unwrap_or(DEFAULT_OBJECT).to_ascii_lowercase();
    let found = program.objects.iter().position(|o| o.name == want);
    match (found, name) {
        (Some(i), _) => Some(i),
        (None, Some(_)) => None,
        (None, None) => (!program.objects.is_empty()).then_some(0),
    }
}

/// Picks the object (`name`, default `my_model`, else the first) and lowers
/// it with parameters given as `(k, value)` pairs for `a[k]` (1-based; a
/// later pair for the same `k` wins, unset ones are 0). Every index is
/// checked against the object's declared `a[N]` and every value must be
/// finite, before anything is sized from them.
pub fn load_program(
    program: Arc<Program>,
    name: Option<&str>,
    params: &[(usize, f64)],
) -> Result<Model, LowerError> {
    load_program_with(program, name, params, &Registry::standard())
}

/// As [`load_program`] with a given library (e.g. the standard one plus
/// bound data fields, [`Registry::register_field`]).
pub fn load_program_with(
    program: Arc<Program>,
    name: Option<&str>,
    params: &[(usize, f64)],
    registry: &Registry,
) -> Result<Model, LowerError> {
    let Some(i) = select_object(&program, name) else {
        return Err(LowerError {
            message: match name {
                Some(n) => format!("no object named '{n}'"),
                None => "the file defines no object".into(),
            },
            pos: Pos::default(),
        });
    };
    let dense = dense_params(&program.objects[i], params)?;
    lower(program, i, registry, &dense)
}

/// `a[1..=N]` of `obj` from `(k, value)` pairs, checked.
fn dense_params(obj: &crate::ast::Object, params: &[(usize, f64)]) -> Result<Vec<f64>, LowerError> {
    let error = |message: String| LowerError {
        message,
        pos: Pos::default(),
    };
    let mut dense = vec![0.0; obj.a_size];
    for &(k, v) in params {
        if k == 0 {
            return Err(error(
                "parameter index must be 1 or more (a[1] is the first)".into(),
            ));
        }
        if k > obj.a_size {
            return Err(error(format!(
                "parameter a[{k}] out of range: object '{}' has a[{}]",
                obj.name, obj.a_size
            )));
        }
        if !v.is_finite() {
            return Err(error(format!(
                "parameter a[{k}] must be a finite number, not {v}"
            )));
        }
        dense[k - 1] = v;
    }
    Ok(dense)
}

/// Lowers object `object` of `program`. `params` gives `a[1..]` (missing
/// entries are 0).
pub fn lower(
    program: Arc<Program>,
    object: usize,
    registry: &Registry,
    params: &[f64],
) -> Result<Model, LowerError> {
    let obj = &program.objects[object];
    check::check_calls(&program, object, registry)?;
    let pvals: Vec<f64> = (0..obj.a_size)
        .map(|k| params.get(k).copied().unwrap_or(0.0))
        .collect();
    let names: Vec<String> = (1..=obj.a_size).map(|k| format!("a{k}")).collect();
    let table = ErrorTable::default();
    let mut ex = Exec::new(&program, registry, &table);
    let inputs = Inputs {
        x: Expr::xyz().to_vec(),
        a: names
            .iter()
            .zip(&pvals)
            .map(|(n, &v)| Expr::param(n, v))
            .collect(),
    };
    let base = Model {
        object: obj.name.clone(),
        objects: program.objects.iter().map(|o| o.name.clone()).collect(),
        value: Expr::constant(0.0),
        error: Expr::constant(0.0),
        errors: table.clone(),
        params: names.into_iter().zip(pvals.iter().copied()).collect(),
        lowered: true,
        interp: None,
    };
    match ex.run(obj, inputs) {
        Ok(value) => {
            let error = prune::error_code(&ex.sites);
            Ok(Model {
                value: guard(value, &error),
                error,
                ..base
            })
        }
        Err(Stop::Static(message, pos)) => Err(LowerError { message, pos }),
        Err(Stop::NeedsPoint) => {
            let interp = Arc::new(fallback::Interp {
                program: program.clone(),
                object,
                registry: registry.clone(),
                table,
                params: pvals,
                runaway: std::sync::OnceLock::new(),
            });
            let field = |error| {
                Expr::field(Arc::new(fallback::Output {
                    interp: interp.clone(),
                    error,
                }))
            };
            Ok(Model {
                value: field(false),
                error: field(true),
                lowered: false,
                interp: Some(interp),
                ..base
            })
        }
    }
}

/// The value where no run-time error is raised, NaN where one is: every
/// consumer (mesher, slicer, renderer) treats NaN as outside, so a point
/// with an error is never part of the solid. Folds away when `error` is the
/// constant 0.
fn guard(value: Expr, error: &Expr) -> Expr {
    Expr::select(error.clone(), Expr::constant(f64::NAN), value)
}

impl Model {
    /// The model as a core [`Shape`]: the value, with the error code as its
    /// error channel (decoded by this model's error table).
    pub fn shape(&self) -> Shape {
        Shape::new(self.value.clone())
            .with_errors(self.error.clone(), Arc::new(self.errors.clone()))
    }

    /// The loop that ran out of iterations, once any evaluation of a
    /// per-point model met one. From then on every evaluation of the model
    /// reports this error at once (values computed before it are not
    /// revised), so a consumer that evaluates many points should check this
    /// afterwards and fail with the error: the model is broken, and which
    /// points got values first depends on the evaluation order.
    pub fn runaway_loop(&self) -> Option<RuntimeError> {
        let code = *self.interp.as_ref()?.runaway.get()?;
        self.errors.get(code)
    }

    /// Value and error code in one tape (outputs 0 and 1).
    pub fn tape(&self) -> Tape {
        Tape::with_outputs(&[self.value.clone(), self.error.clone()])
    }

    /// Reference (f64) evaluation at points, with the parameters of `params`.
    pub fn eval_points(&self, pts: &[[f64; 3]]) -> Vec<Result<f64, RuntimeError>> {
        let tape = self.tape();
        let mut pe = PointEval::new(&tape);
        for (name, v) in &self.params {
            if let Some(i) = tape.param_index(name) {
                pe.set_param(i, *v);
            }
        }
        pts.iter()
            .map(|&p| {
                let out = pe.eval_all(p);
                self.result(out[0], out[1])
            })
            .collect()
    }

    /// Interprets a (value, code) pair.
    pub fn result(&self, value: f64, code: f64) -> Result<f64, RuntimeError> {
        if code == 0.0 {
            return Ok(value);
        }
        Err(self.errors.get(code).unwrap_or_else(|| RuntimeError {
            message: "evaluation failed".into(),
            line: 0,
            col: 0,
        }))
    }
}
