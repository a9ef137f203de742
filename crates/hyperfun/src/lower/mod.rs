//! Lowering a parsed HyperFun program to the core graph.
//!
//! A model becomes expressions: the value, an error code (0 = fine, `k` =
//! entry `k - 1` of the error table) and its attributes `s[1..=n]`.
//! Compiled together with `Tape::with_outputs` (or as a [`Shape`] with
//! attribute channels `s1..sn`), they run at the core's speed in every
//! evaluation mode.
//!
//! The program is executed symbolically: statements run in order on
//! expressions. An `if` whose condition depends on the point runs both
//! branches, each under its condition, and merges every variable and array
//! element either branch wrote with `select` (HyperFun truth `|v| >= EPS`);
//! an error site inside a branch counts only where the branch is taken.
//! Loops whose condition stays constant (a fixed trip count) are unrolled.
//! What cannot become one graph takes the per-point fallback (the same
//! executor with constant inputs, each output wrapped as a `Field`, no
//! interval bounds): a `while` whose condition depends on the point (its
//! trip count, and so the size of the graph, would vary from point to
//! point), a library call whose constant argument depends on the point,
//! and branch merging past [`MERGE_BUDGET`] select nodes. [`Model::per_point`]
//! says why.

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
pub use exec::{PerPoint, MERGE_BUDGET};
use fallback::{Channel, Output};
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
    /// The error sites behind the codes of `error`.
    pub errors: ErrorTable,
    /// The attributes `s[1..=n]` of the evaluated object as they stand
    /// when its evaluation ends (material fractions, colours): one per
    /// entry of the `s[n]` its header declares, none when it declares no
    /// `s`. An entry the program never assigns is 0 (the reference starts
    /// `s` at 0 and then keeps each point's values for the next point; here
    /// every point starts from 0, so results do not depend on the order of
    /// evaluation). Calls `obj(x, a, s)` write the callee's final `s` back,
    /// as in the reference. NaN wherever the model raises a run-time error,
    /// like the value.
    pub attributes: Vec<Expr>,
    /// `a[k]` parameters as `(name, value)`: names `a1`, `a2`, ... are the
    /// `Expr::param` names of the lowered graph.
    pub params: Vec<(String, f64)>,
    /// False when the model runs through the per-point fallback (parameters
    /// are then fixed at load time and intervals are unbounded).
    pub lowered: bool,
    /// Why the model runs per point, when `lowered` is false.
    pub per_point: Option<PerPoint>,
    /// Run-time errors that the statement at their position raises every
    /// time it runs, for any point (a constant array index out of range,
    /// a variable read before any assignment): certain bugs, which
    /// [`crate::check::check`] reports as errors.
    pub certain_errors: Vec<LowerError>,
    /// The per-point interpreter of this object (what the fallback runs,
    /// and [`Model::interpreted`] for a lowered model).
    interp: Arc<fallback::Interp>,
}

/// A static error found while lowering (message, position).
#[derive(Clone, Debug, PartialEq)]
pub struct LowerError {
    /// The reason, as the user should read it.
    pub message: String,
    /// Where in the file.
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
    let n_attr = if obj.s_declared { obj.s_size } else { 0 };
    let interp = Arc::new(fallback::Interp::new(
        program.clone(),
        object,
        registry.clone(),
        table.clone(),
        pvals.clone(),
        n_attr,
    ));
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
        attributes: Vec::new(),
        params: names.into_iter().zip(pvals.iter().copied()).collect(),
        lowered: true,
        per_point: None,
        certain_errors: Vec::new(),
        interp,
    };
    let run = ex.run(obj, inputs);
    let base = Model {
        certain_errors: std::mem::take(&mut ex.certain)
            .into_iter()
            .map(|(message, pos)| LowerError { message, pos })
            .collect(),
        ..base
    };
    match run {
        Ok(out) => {
            let error = prune::error_code(&ex.sites);
            let mut s = out.s;
            // A library call may have written more or fewer elements into
            // `s` than the header declares.
            s.resize(n_attr, Expr::constant(0.0));
            Ok(Model {
                value: guard(out.value, &error),
                attributes: s.into_iter().map(|a| guard(a, &error)).collect(),
                error,
                ..base
            })
        }
        Err(Stop::Static(message, pos)) => Err(LowerError { message, pos }),
        Err(Stop::NeedsPoint(why)) => {
            let interp = base.interp.clone();
            Ok(base.on(interp, why))
        }
    }
}

/// The value where no run-time error is raised, NaN where one is: every
/// consumer (mesher, slicer, renderer) treats NaN as outside, so a point
/// with an error is never part of the solid. Attributes get the same
/// guard: a point whose evaluation fails has no material either. Folds
/// away when `error` is the constant 0.
fn guard(value: Expr, error: &Expr) -> Expr {
    Expr::select(error.clone(), Expr::constant(f64::NAN), value)
}

impl Model {
    /// The model as a core [`Shape`]: the value, with the error code as its
    /// error channel (decoded by this model's error table) and the
    /// attributes as channels `s1`, `s2`, ... ([`Model::attribute_names`]).
    pub fn shape(&self) -> Shape {
        let mut shape = Shape::new(self.value.clone())
            .with_errors(self.error.clone(), Arc::new(self.errors.clone()));
        for (name, a) in self.attribute_names().iter().zip(&self.attributes) {
            shape = shape.with_attribute(name, a.clone());
        }
        shape
    }

    /// Channel names of the attributes: `s1` for `s[1]`, and so on.
    pub fn attribute_names(&self) -> Vec<String> {
        (1..=self.attributes.len())
            .map(|k| format!("s{k}"))
            .collect()
    }

    /// The same model on the per-point interpreter (what a model that
    /// cannot be lowered runs on): same values, error codes and
    /// attributes, no interval bounds, far slower. For checking the
    /// lowering against the interpreter; parameters are fixed at their
    /// values in [`Model::params`].
    pub fn interpreted(&self) -> Model {
        let old = &self.interp;
        let params: Vec<f64> = self.params.iter().map(|p| p.1).collect();
        let interp = Arc::new(fallback::Interp::new(
            old.program.clone(),
            old.object,
            old.registry.clone(),
            self.errors.clone(),
            params,
            old.attributes,
        ));
        let why = self.per_point.clone().unwrap_or(PerPoint {
            message: "the per-point interpreter was asked for".into(),
            pos: Pos::default(),
        });
        self.on(interp, why)
    }

    /// This model with its outputs taken from `interp`.
    fn on(&self, interp: Arc<fallback::Interp>, why: PerPoint) -> Model {
        let field = |c| Output::expr(&interp, c);
        Model {
            value: field(Channel::Value),
            error: field(Channel::Error),
            attributes: (0..interp.attributes)
                .map(|k| field(Channel::Attribute(k)))
                .collect(),
            lowered: false,
            per_point: Some(why),
            interp: interp.clone(),
            ..self.clone()
        }
    }

    /// The loop that ran out of iterations, once any evaluation of a
    /// per-point model met one. From then on every evaluation of the model
    /// reports this error at once (values computed before it are not
    /// revised), so a consumer that evaluates many points should check this
    /// afterwards and fail with the error: the model is broken, and which
    /// points got values first depends on the evaluation order.
    pub fn runaway_loop(&self) -> Option<RuntimeError> {
        if self.lowered {
            return None;
        }
        let code = *self.interp.runaway.get()?;
        self.errors.get(code)
    }

    /// Value and error code in one tape (outputs 0 and 1).
    pub fn tape(&self) -> Tape {
        Tape::with_outputs(&[self.value.clone(), self.error.clone()])
    }

    /// Reference (f64) evaluation at points, with the parameters of `params`.
    pub fn eval_points(&self, pts: &[[f64; 3]]) -> Vec<Result<f64, RuntimeError>> {
        self.eval_with(&self.tape(), pts, |out| out[0])
    }

    /// As [`Model::eval_points`], with the attributes `s[1..=n]` of each
    /// point after its value.
    pub fn eval_points_with_attributes(
        &self,
        pts: &[[f64; 3]],
    ) -> Vec<Result<(f64, Vec<f64>), RuntimeError>> {
        let mut outs = vec![self.value.clone(), self.error.clone()];
        outs.extend(self.attributes.iter().cloned());
        let tape = Tape::with_outputs(&outs);
        self.eval_with(&tape, pts, |out| (out[0], out[2..].to_vec()))
    }

    /// Evaluates `tape` (outputs value, error code, ...) at `pts` with the
    /// model's parameters; `f` takes what it needs from the outputs.
    fn eval_with<T>(
        &self,
        tape: &Tape,
        pts: &[[f64; 3]],
        f: impl Fn(&[f64]) -> T,
    ) -> Vec<Result<T, RuntimeError>> {
        let mut pe = PointEval::new(tape);
        for (name, v) in &self.params {
            if let Some(i) = tape.param_index(name) {
                pe.set_param(i, *v);
            }
        }
        pts.iter()
            .map(|&p| {
                let out = pe.eval_all(p);
                self.result(out[0], out[1]).map(|_| f(&out))
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
