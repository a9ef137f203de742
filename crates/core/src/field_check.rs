//! A reusable check of any [`Field`] in all four evaluation modes.
//!
//! A data-driven field (mesh distance, scans, pores, Bezier data, ...) is
//! only useful as a graph node if its four modes agree: the f32 batch with
//! the f64 reference, the interval bounds with the values inside their box,
//! the gradient with finite differences of the value, and the node inside a
//! compiled model with the field called directly. [`check_field`] tests all
//! of that on seeded random points and boxes in a region and reports the
//! first violation with the point or box that shows it, so a new field gets
//! these checks with one call in its tests:
//!
//! ```
//! use microfrep_core::field_check::{check_field, FieldCheck};
//! use microfrep_core::GridField;
//! # use std::sync::Arc;
//! let g = GridField::sample("g", [9, 9, 9], [-1.0; 3], [1.0; 3], |p| p[0] * p[1] - p[2]).unwrap();
//! let g: Arc<dyn microfrep_core::Field> = Arc::new(g);
//! let report = check_field(&g, &FieldCheck::new([[-1.0; 3], [1.0; 3]])).unwrap();
//! assert!(report.points > 0 && report.boxes > 0);
//! ```

use crate::{
    BatchEval, Expr, Field, GradBatchEval, GradEval, Interval, IntervalEval, PointEval, Tape,
};
use std::sync::Arc;

/// What to check and how strictly.
#[derive(Clone, Debug)]
pub struct FieldCheck {
    /// Region the points and boxes are drawn from (min, max).
    pub region: [[f64; 3]; 2],
    /// Random points for the point, batch and gradient checks.
    pub points: usize,
    /// Random boxes for the interval checks.
    pub boxes: usize,
    /// Points sampled inside each box.
    pub points_per_box: usize,
    /// Largest box side, as a fraction of the region's side.
    pub max_box: f64,
    /// Seed of the point and box generator.
    pub seed: u64,
    /// Batch against point: `|batch - point| <= abs + rel |point|`.
    pub batch_abs: f64,
    /// Relative part of the batch tolerance.
    pub batch_rel: f64,
    /// Gradient against central differences, relative to `1 + |grad|`.
    pub grad_tol: f64,
    /// Step of the central differences, as a fraction of the region's
    /// diagonal.
    pub fd_step: f64,
    /// Whether [`Field::grad_interval`] is expected to bound the gradient
    /// (the default implementation, unbounded, passes trivially).
    pub check_grad_interval: bool,
}

impl FieldCheck {
    /// Defaults for a region: 2000 points, 300 boxes of up to a quarter of
    /// the region, f32-level batch agreement (1e-5 absolute and relative),
    /// gradients within 1e-3.
    pub fn new(region: [[f64; 3]; 2]) -> FieldCheck {
        FieldCheck {
            region,
            points: 2000,
            boxes: 300,
            points_per_box: 12,
            max_box: 0.25,
            seed: 0x5eed,
            batch_abs: 1e-5,
            batch_rel: 1e-5,
            grad_tol: 1e-3,
            fd_step: 1e-6,
            check_grad_interval: true,
        }
    }
}

/// What a passing check covered.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FieldReport {
    /// Points checked (point, batch, gradient, graph node).
    pub points: usize,
    /// Points where the finite-difference check was skipped because the
    /// field is not smooth there (the two step sizes disagree).
    pub not_smooth: usize,
    /// Boxes checked.
    pub boxes: usize,
    /// Largest batch-against-point difference seen.
    pub max_batch_error: f64,
}

/// Small deterministic generator (splitmix64), so checks are reproducible
/// without a dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

/// Checks `field` in all four modes over `cfg.region`; `Err` describes the
/// first violation.
pub fn check_field(field: &Arc<dyn Field>, cfg: &FieldCheck) -> Result<FieldReport, String> {
    let [lo, hi] = cfg.region;
    if (0..3).any(|a| !(lo[a].is_finite() && hi[a].is_finite() && lo[a] < hi[a])) {
        return Err(format!("region {:?} is empty or not finite", cfg.region));
    }
    let mut rng = Rng(cfg.seed);
    let mut report = FieldReport::default();
    let diag = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt();

    // Points on the f32 grid, so the batch and the reference see the same input.
    let pts: Vec<[f64; 3]> = (0..cfg.points)
        .map(|_| std::array::from_fn(|a| (lo[a] + (hi[a] - lo[a]) * rng.unit()) as f32 as f64))
        .collect();
    let xs: Vec<f32> = pts.iter().map(|p| p[0] as f32).collect();
    let ys: Vec<f32> = pts.iter().map(|p| p[1] as f32).collect();
    let zs: Vec<f32> = pts.iter().map(|p| p[2] as f32).collect();
    let mut batch = vec![0.0f32; pts.len()];
    field.eval_batch(&xs, &ys, &zs, &mut batch);

    // The field as a node of a compiled model, in every evaluator.
    let node = Expr::field(field.clone());
    let field: &dyn Field = &**field;
    let tape = Tape::new(&node);
    let mut point_ev = PointEval::new(&tape);
    let mut grad_ev = GradEval::new(&tape);
    let mut node_batch = vec![0.0f32; pts.len()];
    BatchEval::new(&tape).eval(&xs, &ys, &zs, &mut node_batch);
    let mut node_grads = vec![[0.0f32; 4]; pts.len()];
    GradBatchEval::new(&tape).eval(&xs, &ys, &zs, &mut node_grads);

    for (i, &p) in pts.iter().enumerate() {
        let v = field.eval(p);
        if !same(field.eval(p), v) {
            return Err(format!("eval is not deterministic at {p:?}"));
        }
        let (gv, g) = field.grad(p);
        if !(same(gv, v) || (gv - v).abs() <= 1e-9 * (1.0 + v.abs())) {
            return Err(format!("grad's value {gv} differs from eval {v} at {p:?}"));
        }
        let b = batch[i] as f64;
        let err = (b - v).abs();
        if !(same(b, v) || err <= cfg.batch_abs + cfg.batch_rel * v.abs()) {
            return Err(format!("batch {b} differs from point {v} at {p:?}"));
        }
        if err.is_finite() {
            report.max_batch_error = report.max_batch_error.max(err);
        }
        // The node in a compiled model is the field itself.
        let pv = point_ev.eval(p);
        if !same(pv, v) {
            return Err(format!("as a graph node: point {pv} vs field {v} at {p:?}"));
        }
        if !same(node_batch[i] as f64, batch[i] as f64) {
            return Err(format!(
                "as a graph node: batch {} vs field batch {} at {p:?}",
                node_batch[i], batch[i]
            ));
        }
        let (nv, ng) = grad_ev.eval(p);
        if !same(nv, v) || (0..3).any(|a| !same(ng[a], g[a])) {
            return Err(format!(
                "as a graph node: gradient ({nv}, {ng:?}) vs field ({v}, {g:?}) at {p:?}"
            ));
        }
        let bg = node_grads[i];
        let close32 =
            |a: f32, b: f64| same(a as f64, b) || (a as f64 - b).abs() <= 1e-5 * (1.0 + b.abs());
        if !close32(bg[0], v) || (0..3).any(|a| !close32(bg[a + 1], g[a])) {
            return Err(format!(
                "as a graph node: batched gradient {bg:?} vs field ({v}, {g:?}) at {p:?}"
            ));
        }
        if v.is_finite() {
            check_gradient(field, p, g, cfg.fd_step * diag, cfg.grad_tol, &mut report)?;
        }
        report.points += 1;
    }

    let mut iv_ev = IntervalEval::new(&tape);
    for _ in 0..cfg.boxes {
        let b: [Interval; 3] = std::array::from_fn(|a| {
            let w = (hi[a] - lo[a]) * cfg.max_box * rng.unit();
            let c = lo[a] + (hi[a] - lo[a] - w) * rng.unit();
            Interval::new(c, c + w)
        });
        let bound = field.interval(b);
        if bound.lo > bound.hi {
            return Err(format!("interval {bound:?} over {b:?} is inverted"));
        }
        let node_bound = iv_ev.eval(b[0], b[1], b[2]);
        if !(node_bound.lo <= bound.lo && bound.hi <= node_bound.hi) {
            return Err(format!(
                "as a graph node: interval {node_bound:?} does not hold the field's {bound:?} over {b:?}"
            ));
        }
        let gb = field.grad_interval(b);
        // Corners and random points of the box.
        for k in 0..8 + cfg.points_per_box {
            let p: [f64; 3] = std::array::from_fn(|a| {
                if k < 8 {
                    if k >> a & 1 == 0 {
                        b[a].lo
                    } else {
                        b[a].hi
                    }
                } else {
                    (b[a].lo + b[a].width() * rng.unit()).min(b[a].hi)
                }
            });
            let (v, g) = field.grad(p);
            if v.is_nan() {
                if !bound.may_be_nan() {
                    return Err(format!(
                        "NaN at {p:?} but the interval {bound:?} says no NaN"
                    ));
                }
            } else if !bound.contains(v) {
                return Err(format!(
                    "value {v} at {p:?} outside the interval {bound:?} of {b:?}"
                ));
            }
            if cfg.check_grad_interval {
                for a in 0..3 {
                    if g[a].is_finite() && !gb[a].contains(g[a]) {
                        return Err(format!(
                            "partial {a} = {} at {p:?} outside the gradient bound {:?} of {b:?}",
                            g[a], gb[a]
                        ));
                    }
                }
            }
        }
        report.boxes += 1;
    }
    Ok(report)
}

/// Central differences at two step sizes; where they agree the field is
/// smooth there and the analytic gradient must match them.
fn check_gradient(
    field: &dyn Field,
    p: [f64; 3],
    g: [f64; 3],
    h: f64,
    tol: f64,
    report: &mut FieldReport,
) -> Result<(), String> {
    let fd = |h: f64| -> [f64; 3] {
        std::array::from_fn(|a| {
            let (mut q, mut r) = (p, p);
            q[a] += h;
            r[a] -= h;
            (field.eval(q) - field.eval(r)) / (2.0 * h)
        })
    };
    let (d1, d2) = (fd(h), fd(0.5 * h));
    let scale = 1.0 + g.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let smooth = (0..3).all(|a| d1[a].is_finite() && (d1[a] - d2[a]).abs() <= 0.1 * tol * scale);
    if !smooth {
        report.not_smooth += 1;
        return Ok(());
    }
    for a in 0..3 {
        if !((g[a] - d2[a]).abs() <= tol * scale) {
            return Err(format!(
                "partial {a} = {} at {p:?}, finite differences give {}",
                g[a], d2[a]
            ));
        }
    }
    Ok(())
}
