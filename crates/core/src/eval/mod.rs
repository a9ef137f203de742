//! The four evaluators of a tape: point (f64 reference), batch (f32 hot
//! path), interval (sound bounds) and gradient (forward mode), plus helpers
//! that spread batch work over threads.
//!
//! The evaluation modes are also traits ([`Function`] and the evaluator
//! traits below, in the manner of Fidget's `Function`), so that another
//! backend (a JIT, a GPU interpreter) is a type implementing them and
//! inherits the generic test suites of `crates/core/tests/backend/`. The
//! virtual machine of this module is the implementation for [`Tape`]: its
//! evaluators are the structs [`PointEval`], [`BatchEval`],
//! [`IntervalEval`], [`GradEval`] and [`GradBatchEval`], which consumers may
//! also name directly.

pub(crate) mod batch;
mod deriv;
mod grad;
mod interval;
mod parallel;
mod point;

pub use batch::grad::GradBatchEval;
pub use batch::{BatchEval, BLOCK};
pub use deriv::{binary_partials, unary_derivative};
pub use grad::GradEval;
pub use interval::IntervalEval;
pub use parallel::{eval_grid_par, eval_points_par};
pub use point::PointEval;

use crate::{Interval, Tape};

/// A compiled model for one backend: the factory of its evaluators.
pub trait Function: Clone + Send + Sync + 'static {
    /// Point evaluator (f64).
    type Point: PointEvaluator;
    /// Interval evaluator.
    type Interval: IntervalEvaluator;
    /// Batch evaluator (f32).
    type Batch: BatchEvaluator;
    /// Gradient evaluator (f64, one point).
    type Grad: GradEvaluator;
    /// Batched gradient evaluator (f32).
    type GradBatch: GradBatchEvaluator;

    /// Compiles a tape for this backend.
    fn compile(tape: &Tape) -> Self;
    /// The tape it was compiled from.
    fn tape(&self) -> &Tape;
    /// A new point evaluator.
    fn point(&self) -> Self::Point;
    /// A new interval evaluator.
    fn interval(&self) -> Self::Interval;
    /// A new batch evaluator.
    fn batch(&self) -> Self::Batch;
    /// A new gradient evaluator.
    fn grad(&self) -> Self::Grad;
    /// A new batched gradient evaluator.
    fn grad_batch(&self) -> Self::GradBatch;
}

/// Evaluates outputs at single points in f64.
pub trait PointEvaluator: Send {
    /// Sets parameter `index` of the tape.
    fn set_param(&mut self, index: usize, v: f64);
    /// Output `k` at `p`.
    fn eval_output(&mut self, k: usize, p: [f64; 3]) -> f64;
}

/// Bounds outputs over boxes.
pub trait IntervalEvaluator: Send {
    /// Sets parameter `index` of the tape.
    fn set_param(&mut self, index: usize, v: f64);
    /// Bounds of output `k` over the box `b`.
    fn eval_output(&mut self, k: usize, b: [Interval; 3]) -> Interval;
}

/// Evaluates outputs at many points in f32.
pub trait BatchEvaluator: Send {
    /// Sets parameter `index` of the tape.
    fn set_param(&mut self, index: usize, v: f64);
    /// Output `k` at `(x[i], y[i], z[i])` into `out[i]`; all slices have the
    /// same length.
    fn eval_output(&mut self, k: usize, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]);
}

/// Value and gradient of outputs at single points in f64.
pub trait GradEvaluator: Send {
    /// Sets parameter `index` of the tape.
    fn set_param(&mut self, index: usize, v: f64);
    /// Value and gradient of output `k` at `p`.
    fn eval_output(&mut self, k: usize, p: [f64; 3]) -> (f64, [f64; 3]);
}

/// Value and gradient of output 0 at many points, as `[v, dx, dy, dz]` in f32.
pub trait GradBatchEvaluator: Send {
    /// Sets parameter `index` of the tape.
    fn set_param(&mut self, index: usize, v: f64);
    /// `out[i] = [v, dv/dx, dv/dy, dv/dz]` at `(x[i], y[i], z[i])`.
    fn eval(&mut self, x: &[f32], y: &[f32], z: &[f32], out: &mut [[f32; 4]]);
}

impl Function for Tape {
    type Point = PointEval;
    type Interval = IntervalEval;
    type Batch = BatchEval;
    type Grad = GradEval;
    type GradBatch = GradBatchEval;

    fn compile(tape: &Tape) -> Self {
        tape.clone()
    }
    fn tape(&self) -> &Tape {
        self
    }
    fn point(&self) -> PointEval {
        PointEval::new(self)
    }
    fn interval(&self) -> IntervalEval {
        IntervalEval::new(self)
    }
    fn batch(&self) -> BatchEval {
        BatchEval::new(self)
    }
    fn grad(&self) -> GradEval {
        GradEval::new(self)
    }
    fn grad_batch(&self) -> GradBatchEval {
        GradBatchEval::new(self)
    }
}

impl PointEvaluator for PointEval {
    fn set_param(&mut self, index: usize, v: f64) {
        PointEval::set_param(self, index, v)
    }
    fn eval_output(&mut self, k: usize, p: [f64; 3]) -> f64 {
        PointEval::eval_output(self, k, p)
    }
}

impl IntervalEvaluator for IntervalEval {
    fn set_param(&mut self, index: usize, v: f64) {
        IntervalEval::set_param(self, index, v)
    }
    fn eval_output(&mut self, k: usize, b: [Interval; 3]) -> Interval {
        IntervalEval::eval_output(self, k, b[0], b[1], b[2])
    }
}

impl BatchEvaluator for BatchEval {
    fn set_param(&mut self, index: usize, v: f64) {
        BatchEval::set_param(self, index, v)
    }
    fn eval_output(&mut self, k: usize, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        BatchEval::eval_output(self, k, x, y, z, out)
    }
}

impl GradEvaluator for GradEval {
    fn set_param(&mut self, index: usize, v: f64) {
        GradEval::set_param(self, index, v)
    }
    fn eval_output(&mut self, k: usize, p: [f64; 3]) -> (f64, [f64; 3]) {
        GradEval::eval_output(self, k, p)
    }
}

impl GradBatchEvaluator for GradBatchEval {
    fn set_param(&mut self, index: usize, v: f64) {
        GradBatchEval::set_param(self, index, v)
    }
    fn eval(&mut self, x: &[f32], y: &[f32], z: &[f32], out: &mut [[f32; 4]]) {
        GradBatchEval::eval(self, x, y, z, out)
    }
}
