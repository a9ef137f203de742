//! [`Shape`]: the one compiled model every consumer takes.
//!
//! A shape bundles what meshing, slicing, rendering, voxels, analysis and
//! density solving need of a model, built once:
//! - the value expression and its compiled [`Tape`] (with set operations as
//!   nodes, so interval bounds are tight for every consumer);
//! - an optional run-time error channel: a second output that is 0 where the
//!   model is defined and a code elsewhere, decoded by an [`ErrorSource`]
//!   (a HyperFun model's error sites, say); the value is NaN where the code
//!   is not 0, which every consumer treats as outside;
//! - named attribute channels (material fractions, densities), evaluated
//!   alongside the value;
//! - the model's proven bounds, found on first use by interval subdivision
//!   ([`bounds`]), or given by whoever built the shape.
//!
//! ```
//! use microfrep_core::{Expr, Shape, frep};
//! let [x, y, z] = Expr::xyz();
//! let ball = 1.0 - (x.square() + y.square() + z.square());
//! let half = frep::intersection(&ball, &z, 0.0);
//! let shape = Shape::new(half);
//! assert!(shape.point().eval([0.0, 0.0, 0.5]) > 0.0);
//! let b = shape.bounds().unwrap();
//! assert!((b.max[2] - 1.0).abs() < 0.02 && b.min[2].abs() < 0.02);
//! ```

pub mod bounds;
mod census;

pub use bounds::{Bounds, BoundsError, BoundsOptions};
pub use census::{ErrorCensus, ErrorSource, RuntimeError};

use crate::eval::{BatchEval, GradBatchEval, GradEval, IntervalEval, PointEval};
use crate::{Expr, Field, Tape};
use std::sync::{Arc, OnceLock};

/// A named attribute channel of a shape.
#[derive(Clone, Debug)]
pub struct Attribute {
    /// Name, e.g. `s1` for HyperFun's `s[1]` or a material name.
    pub name: String,
    /// The channel's value at every point.
    pub expr: Expr,
}

/// The error channel of a shape.
#[derive(Clone, Debug)]
struct ErrorChannel {
    expr: Expr,
    source: Arc<dyn ErrorSource>,
}

/// A compiled model with its error channel, attributes and bounds. Cheap
/// to clone (shared data); immutable. See the [module docs](self).
#[derive(Clone, Debug)]
pub struct Shape {
    value: Expr,
    error: Option<ErrorChannel>,
    attributes: Vec<Attribute>,
    /// The value alone: what meshing, slicing and analysis evaluate.
    tape: Tape,
    /// Value, error code and attributes together, compiled on first use.
    all: Arc<OnceLock<Tape>>,
    bounds: Arc<OnceLock<Result<Bounds, BoundsError>>>,
}

impl Shape {
    /// A shape from a value expression alone.
    pub fn new(value: Expr) -> Shape {
        Shape::assemble(value, None, Vec::new())
    }

    /// A shape whose value is a data field evaluated at `(x, y, z)`.
    pub fn from_field(field: Arc<dyn Field>) -> Shape {
        Shape::new(Expr::field(field))
    }

    fn assemble(value: Expr, error: Option<ErrorChannel>, attributes: Vec<Attribute>) -> Shape {
        Shape {
            tape: Tape::new(&value),
            all: Arc::new(OnceLock::new()),
            value,
            error,
            attributes,
            bounds: Arc::new(OnceLock::new()),
        }
    }

    /// This shape with an error channel: `code` is 0 where the model is
    /// defined, else a code that `source` decodes. The value should already
    /// be NaN where the code is not 0 (HyperFun lowering does this).
    pub fn with_errors(self, code: Expr, source: Arc<dyn ErrorSource>) -> Shape {
        let error = (code.as_const() != Some(0.0)).then_some(ErrorChannel { expr: code, source });
        // The value is unchanged: its tape and bounds carry over.
        Shape {
            error,
            all: Arc::new(OnceLock::new()),
            ..self
        }
    }

    /// This shape with one more attribute channel.
    pub fn with_attribute(self, name: &str, expr: Expr) -> Shape {
        let mut attributes = self.attributes;
        attributes.push(Attribute {
            name: name.to_string(),
            expr,
        });
        Shape {
            attributes,
            all: Arc::new(OnceLock::new()),
            ..self
        }
    }

    /// This shape with bounds known by other means (a built-in example's
    /// box, a mesh's bounding box); [`Shape::bounds`] then returns them.
    pub fn with_bounds(self, b: Bounds) -> Shape {
        let cell = OnceLock::new();
        let _ = cell.set(Ok(b));
        Shape {
            bounds: Arc::new(cell),
            ..self
        }
    }

    /// A new shape whose value is `f(value)`, with the same error channel
    /// and attributes (the bounds are found again: they may have changed).
    pub fn map(&self, f: impl FnOnce(&Expr) -> Expr) -> Shape {
        Shape::assemble(f(&self.value), self.error.clone(), self.attributes.clone())
    }

    /// The value expression.
    pub fn value(&self) -> &Expr {
        &self.value
    }

    /// The compiled value (one output), which the evaluators of this
    /// shape run.
    pub fn tape(&self) -> &Tape {
        &self.tape
    }

    /// All outputs in one tape: output 0 is the value, then the error code
    /// (if [`Shape::error_output`]), then the attributes
    /// ([`Shape::attribute_output`]). Compiled on first use.
    pub fn outputs(&self) -> &Tape {
        self.all.get_or_init(|| {
            let mut outs = vec![self.value.clone()];
            if let Some(e) = &self.error {
                outs.push(e.expr.clone());
            }
            outs.extend(self.attributes.iter().map(|a| a.expr.clone()));
            Tape::with_outputs(&outs)
        })
    }

    /// Output index of the error code in [`Shape::outputs`], if the shape
    /// has an error channel.
    pub fn error_output(&self) -> Option<usize> {
        self.error.as_ref().map(|_| 1)
    }

    /// The decoder of error codes, if the shape has an error channel.
    pub fn error_source(&self) -> Option<&Arc<dyn ErrorSource>> {
        self.error.as_ref().map(|e| &e.source)
    }

    /// The attribute channels, in output order.
    pub fn attributes(&self) -> &[Attribute] {
        &self.attributes
    }

    /// Output index in [`Shape::outputs`] of attribute `k` (0-based) of
    /// [`Shape::attributes`].
    pub fn attribute_output(&self, k: usize) -> usize {
        1 + usize::from(self.error.is_some()) + k
    }

    /// A point (f64) evaluator of the value.
    pub fn point(&self) -> PointEval {
        PointEval::new(&self.tape)
    }
    /// A batch (f32) evaluator of the value.
    pub fn batch(&self) -> BatchEval {
        BatchEval::new(&self.tape)
    }
    /// An interval evaluator of the value.
    pub fn interval(&self) -> IntervalEval {
        IntervalEval::new(&self.tape)
    }
    /// A gradient (f64) evaluator of the value.
    pub fn grad(&self) -> GradEval {
        GradEval::new(&self.tape)
    }
    /// A batched gradient evaluator of the value.
    pub fn grad_batch(&self) -> GradBatchEval {
        GradBatchEval::new(&self.tape)
    }

    /// The model's solid lies in this box: given with
    /// [`Shape::with_bounds`], or found (once, then cached) by interval
    /// subdivision with the default [`BoundsOptions`].
    pub fn bounds(&self) -> Result<Bounds, BoundsError> {
        self.bounds
            .get_or_init(|| bounds::find(&self.tape, &BoundsOptions::default()))
            .clone()
    }

    /// As [`Shape::bounds`] with other options (a different work budget, a
    /// progress report); the result is cached only if none was before.
    pub fn bounds_with(&self, opts: &BoundsOptions) -> Result<Bounds, BoundsError> {
        if let Some(b) = self.bounds.get() {
            return b.clone();
        }
        let b = bounds::find(&self.tape, opts);
        let _ = self.bounds.set(b.clone());
        b
    }

    /// Counts run-time errors at the points `xs x ys x zs` (every
    /// combination), evaluated in f64; boxes where intervals prove the code
    /// 0 are skipped. `None` when the shape has no error channel.
    pub fn error_census(&self, xs: &[f64], ys: &[f64], zs: &[f64]) -> Option<ErrorCensus> {
        let ch = self.error.as_ref()?;
        Some(census::census(&ch.expr, &*ch.source, [xs, ys, zs]))
    }

    /// Decodes an error code of the error output.
    pub fn runtime_error(&self, code: f64) -> Option<RuntimeError> {
        if code == 0.0 {
            return None;
        }
        let ch = self.error.as_ref()?;
        Some(ch.source.decode(code).unwrap_or_else(RuntimeError::unknown))
    }
}

impl From<&Expr> for Shape {
    fn from(e: &Expr) -> Shape {
        Shape::new(e.clone())
    }
}

impl From<Expr> for Shape {
    fn from(e: Expr) -> Shape {
        Shape::new(e)
    }
}
