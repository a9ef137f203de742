//! The generic backend suites (`tests/backend/mod.rs`) on the virtual
//! machine, and on a toy second backend (the point evaluator wrapped as a
//! batch evaluator) to show that a new backend inherits them with one line.

mod backend;

use microfrep_core::{
    BatchEvaluator, Function, GradBatchEvaluator, GradEval, GradEvaluator, IntervalEval, PointEval,
    PointEvaluator, Tape,
};

/// A second backend: everything by the f64 point path, batches one point
/// at a time.
#[derive(Clone)]
struct PointBackend(Tape);

struct PointBatch(PointEval);

impl BatchEvaluator for PointBatch {
    fn set_param(&mut self, index: usize, v: f64) {
        self.0.set_param(index, v)
    }
    fn eval_output(&mut self, k: usize, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            let p = [x[i] as f64, y[i] as f64, z[i] as f64];
            out[i] = PointEvaluator::eval_output(&mut self.0, k, p) as f32;
        }
    }
}

struct PointGradBatch(GradEval);

impl GradBatchEvaluator for PointGradBatch {
    fn set_param(&mut self, index: usize, v: f64) {
        self.0.set_param(index, v)
    }
    fn eval(&mut self, x: &[f32], y: &[f32], z: &[f32], out: &mut [[f32; 4]]) {
        for i in 0..out.len() {
            let p = [x[i] as f64, y[i] as f64, z[i] as f64];
            let (v, g) = GradEvaluator::eval_output(&mut self.0, 0, p);
            out[i] = [v as f32, g[0] as f32, g[1] as f32, g[2] as f32];
        }
    }
}

impl Function for PointBackend {
    type Point = PointEval;
    type Interval = IntervalEval;
    type Batch = PointBatch;
    type Grad = GradEval;
    type GradBatch = PointGradBatch;

    fn compile(tape: &Tape) -> Self {
        PointBackend(tape.clone())
    }
    fn tape(&self) -> &Tape {
        &self.0
    }
    fn point(&self) -> PointEval {
        PointEval::new(&self.0)
    }
    fn interval(&self) -> IntervalEval {
        IntervalEval::new(&self.0)
    }
    fn batch(&self) -> PointBatch {
        PointBatch(PointEval::new(&self.0))
    }
    fn grad(&self) -> GradEval {
        GradEval::new(&self.0)
    }
    fn grad_batch(&self) -> PointGradBatch {
        PointGradBatch(GradEval::new(&self.0))
    }
}

backend_suites!(vm, microfrep_core::Tape);
backend_suites!(point_as_batch, super::PointBackend);
