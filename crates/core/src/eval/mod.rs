//! The four evaluators of a tape: point (f64 reference), batch (f32 hot
//! path), interval (sound bounds) and gradient (forward mode), plus helpers
//! that spread batch work over threads.

mod batch;
mod deriv;
mod grad;
mod interval;
mod parallel;
mod point;

pub use batch::{BatchEval, BLOCK};
pub use deriv::{binary_partials, unary_derivative};
pub use grad::{GradBatchEval, GradEval};
pub use interval::IntervalEval;
pub use parallel::{eval_grid_par, eval_points_par};
pub use point::PointEval;
