//! microfrep core: FRep models as expression graphs, compiled once into a
//! tape and evaluated in four modes.
//!
//! ```
//! use microfrep_core::{Expr, Tape, PointEval, frep};
//! let [x, y, z] = Expr::xyz();
//! let ball = 1.0 - (x.square() + y.square() + z.square());
//! let cut = -z.clone();
//! let half_ball = frep::intersection(&ball, &cut, 1.0);
//! let tape = Tape::new(&half_ball);
//! assert_eq!(PointEval::new(&tape).eval([0.0, 0.0, -0.5]), 0.5);
//! ```
//!
//! Sign convention everywhere: inside is `f >= 0`.

#![warn(missing_docs)]

pub mod eval;
pub mod expr;
pub mod field;
pub mod field_check;
pub mod frep;
pub mod geom;
pub mod graph;
pub mod interval;
mod merge;
pub mod noise;
pub mod ops;
pub mod shape;
pub mod simd_math;
pub mod simplify;
pub mod spline_field;
mod symbolic;
pub mod tape;
pub mod transform;

pub use eval::{
    eval_grid_par, eval_points_par, BatchEval, BatchEvaluator, Function, GradBatchEval,
    GradBatchEvaluator, GradEval, GradEvaluator, IntervalEval, IntervalEvaluator, PointEval,
    PointEvaluator, BLOCK,
};
pub use expr::{Axis, Expr, ExprNode};
pub use field::{Field, GridField, RayEntry};
pub use graph::{Graph, Node, NodeId};
pub use interval::Interval;
pub use ops::{BinaryOp, SetOp, UnaryOp};
pub use shape::{Bounds, BoundsError, ErrorCensus, ErrorSource, RuntimeError, Shape};
pub use simplify::Simplify;
pub use spline_field::SplineField;
pub use tape::{Op, Tape, ValueId};
