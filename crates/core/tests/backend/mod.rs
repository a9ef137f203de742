//! Test suites written once for any evaluation backend: a type implementing
//! `microfrep_core::Function` gets them all with one line,
//! `backend_suites!(name, Type);` (see `tests/backends.rs`, which runs them
//! on the VM and on a toy second backend).
//!
//! The suites: interval soundness on random graphs over every op and set
//! operation; batch against point on random smooth graphs; gradients
//! against finite differences; every op against its f64 reference.

#![allow(dead_code)]

use microfrep_core::{
    BatchEvaluator, BinaryOp, Expr, Function, GradBatchEvaluator, GradEvaluator, Interval,
    IntervalEvaluator, PointEvaluator, SetOp, Tape, UnaryOp,
};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

/// Ops a generated node may use: every unary and binary op, PowI, Select,
/// the two set operations (fixed alpha in [-1, 1]) and a set operation
/// with a varying alpha.
pub const N_OPS: usize = UnaryOp::ALL.len() + BinaryOp::ALL.len() + 5;

/// One generated node: op code, operand picks, an integer exponent.
pub type Step = (usize, [usize; 3], i32);

/// Builds a DAG from x, y, z, the constants and one node per step.
pub fn build(consts: &[f64], steps: &[Step]) -> Expr {
    let mut nodes: Vec<Expr> = Expr::xyz().to_vec();
    nodes.extend(consts.iter().map(|&c| Expr::constant(c)));
    let (nu, nb) = (UnaryOp::ALL.len(), BinaryOp::ALL.len());
    for &(op, pick, n) in steps {
        let len = nodes.len();
        let arg = |k: usize| nodes[len - 1 - pick[k] % len.min(6)].clone();
        let alpha = [0.0, 0.5, -0.5, 1.0, 0.25][pick[2] % 5];
        let e = if op < nu {
            Expr::unary(UnaryOp::ALL[op], arg(0))
        } else if op < nu + nb {
            Expr::binary(BinaryOp::ALL[op - nu], arg(0), arg(1))
        } else {
            match op - nu - nb {
                0 => arg(0).powi(n),
                1 => Expr::select(arg(0), arg(1), arg(2)),
                2 => Expr::set(SetOp::Union, &arg(0), &arg(1), alpha),
                3 => Expr::set(SetOp::Intersection, &arg(0), &arg(1), alpha),
                _ => Expr::set(SetOp::Intersection, &arg(0), &arg(1), 0.5 * arg(2).sin()),
            }
        };
        nodes.push(e);
    }
    nodes.pop().unwrap()
}

/// Steps over every op.
pub fn step() -> impl Strategy<Value = Step> {
    (0..N_OPS, any::<[usize; 3]>(), -5i32..=6)
}

/// Constants: small integers, ordinary reals and a few large values.
pub fn constant() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-3i32..=3).prop_map(f64::from),
        -4.0f64..4.0,
        prop::sample::select(vec![0.5, -0.5, 1e-3, 100.0, -1e6]),
    ]
}

/// A box axis: centre and half-width.
pub fn axis() -> impl Strategy<Value = (f64, f64)> {
    (
        prop_oneof![4 => -5.0f64..5.0, 1 => -1000.0f64..1000.0],
        prop::sample::select(vec![0.0, 1e-9, 1e-3, 0.1, 1.0, 4.0, 50.0]),
    )
}

/// The box's corners, centre and `ts` fractions along each axis.
pub fn points(b: [(f64, f64); 3], ts: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut ps: Vec<[f64; 3]> = (0..8)
        .map(|c| {
            std::array::from_fn(|a| b[a].0 + b[a].1 * if c >> a & 1 == 1 { 1.0 } else { -1.0 })
        })
        .collect();
    ps.push(std::array::from_fn(|a| b[a].0));
    ps.extend(
        ts.iter()
            .map(|t| std::array::from_fn(|a| b[a].0 + b[a].1 * (2.0 * t[a] - 1.0))),
    );
    ps
}

/// The interval over the box holds every non-NaN point value in it and
/// flags NaN wherever a point value is NaN.
pub fn interval_case<F: Function>(
    consts: &[f64],
    steps: &[Step],
    b: [(f64, f64); 3],
    ts: &[[f64; 3]],
) -> Result<(), TestCaseError> {
    let e = build(consts, steps);
    let f = F::compile(&Tape::new(&e));
    let iv: [Interval; 3] =
        std::array::from_fn(|a| Interval::new(b[a].0 - b[a].1, b[a].0 + b[a].1));
    let r = f.interval().eval_output(0, iv);
    let mut pe = f.point();
    for p in points(b, ts) {
        let v = pe.eval_output(0, p);
        if v.is_nan() {
            prop_assert!(r.may_be_nan(), "NaN at {:?} but {:?} for {:?}", p, r, e);
        } else {
            prop_assert!(r.contains(v), "{} at {:?} not in {:?} for {:?}", v, p, r, e);
        }
    }
    Ok(())
}

/// Smooth ops only, so f32 and f64 stay close: the batch path against the
/// point path on random graphs.
pub fn smooth(consts: &[f64], steps: &[(usize, [usize; 3])]) -> Expr {
    let mut nodes: Vec<Expr> = Expr::xyz().to_vec();
    nodes.extend(consts.iter().map(|&c| Expr::constant(c)));
    for &(op, pick) in steps {
        let len = nodes.len();
        let arg = |k: usize| nodes[len - 1 - pick[k] % len.min(5)].clone();
        let e = match op % 9 {
            0 => arg(0) + arg(1),
            1 => arg(0) - arg(1),
            2 => 0.5 * arg(0) * arg(1),
            3 => arg(0).sin(),
            4 => arg(0).cos(),
            5 => (arg(0).square() + 1.0).sqrt(),
            6 => Expr::set(SetOp::Union, &arg(0), &arg(1), 0.0),
            7 => Expr::set(SetOp::Intersection, &arg(0), &arg(1), 0.5),
            _ => (0.5 * arg(0)).tanh(),
        };
        nodes.push(e);
    }
    nodes.pop().unwrap()
}

/// Batch (f32) against point (f64) at the same f32 points.
pub fn batch_case<F: Function>(
    consts: &[f64],
    steps: &[(usize, [usize; 3])],
    pts: &[[f32; 3]],
) -> Result<(), TestCaseError> {
    let e = smooth(consts, steps);
    let f = F::compile(&Tape::new(&e));
    let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
        pts.iter().map(|p| p[0]).collect(),
        pts.iter().map(|p| p[1]).collect(),
        pts.iter().map(|p| p[2]).collect(),
    );
    let mut out = vec![0.0f32; pts.len()];
    f.batch().eval_output(0, &x, &y, &z, &mut out);
    let mut pe = f.point();
    for (i, p) in pts.iter().enumerate() {
        let want = pe.eval_output(0, p.map(f64::from));
        let got = out[i] as f64;
        let tol = 1e-4 * (1.0 + want.abs());
        prop_assert!(
            (got - want).abs() <= tol,
            "{} vs {} at {:?} for {:?}",
            got,
            want,
            p,
            e
        );
    }
    Ok(())
}

/// Gradients (point and batched) against central differences of the
/// point values, on smooth graphs.
pub fn gradient_case<F: Function>(
    consts: &[f64],
    steps: &[(usize, [usize; 3])],
    pts: &[[f64; 3]],
) -> Result<(), TestCaseError> {
    let e = smooth(consts, steps);
    let f = F::compile(&Tape::new(&e));
    let (mut ge, mut pe, mut gb) = (f.grad(), f.point(), f.grad_batch());
    for &p in pts {
        let (v, g) = ge.eval_output(0, p);
        prop_assert!((v - pe.eval_output(0, p)).abs() <= 1e-12 * (1.0 + v.abs()));
        let h = 1e-6;
        let mut fd = [0.0; 3];
        let mut smooth_here = true;
        for a in 0..3 {
            let (mut q, mut r) = (p, p);
            q[a] += h;
            r[a] -= h;
            fd[a] = (pe.eval_output(0, q) - pe.eval_output(0, r)) / (2.0 * h);
            let (mut q2, mut r2) = (p, p);
            q2[a] += 2.0 * h;
            r2[a] -= 2.0 * h;
            let fd2 = (pe.eval_output(0, q2) - pe.eval_output(0, r2)) / (4.0 * h);
            // Kinks (|x| inside set operations at a = b = 0) are skipped.
            smooth_here &= (fd[a] - fd2).abs() <= 1e-5 * (1.0 + fd[a].abs());
        }
        if !smooth_here {
            continue;
        }
        for a in 0..3 {
            prop_assert!(
                (g[a] - fd[a]).abs() <= 1e-4 * (1.0 + fd[a].abs()),
                "d/d{} = {} vs {} at {:?} for {:?}",
                a,
                g[a],
                fd[a],
                p,
                e
            );
        }
        let q = p.map(|c| c as f32);
        let mut out = [[0.0f32; 4]];
        gb.eval(&[q[0]], &[q[1]], &[q[2]], &mut out);
        let (v32, g32) = ge.eval_output(0, q.map(f64::from));
        prop_assert!((out[0][0] as f64 - v32).abs() <= 1e-4 * (1.0 + v32.abs()));
        for a in 0..3 {
            prop_assert!((out[0][a + 1] as f64 - g32[a]).abs() <= 1e-3 * (1.0 + g32[a].abs()));
        }
    }
    Ok(())
}

/// Every op on fixed operands: the point path equals its f64 reference
/// bit for bit, the batch path is close, the interval holds the value.
pub fn every_op<F: Function>() {
    let vals = [-2.5, -1.0, -0.25, 0.0, 0.3, 1.0, 2.0, 7.5];
    let [x, y, z] = Expr::xyz();
    let mut cases: Vec<(String, Expr, Box<dyn Fn(f64, f64, f64) -> f64>)> = Vec::new();
    for op in UnaryOp::ALL {
        cases.push((
            op.name().into(),
            Expr::unary(op, x.clone()),
            Box::new(move |a, _, _| op.apply(a)),
        ));
    }
    for op in BinaryOp::ALL {
        cases.push((
            op.name().into(),
            Expr::binary(op, x.clone(), y.clone()),
            Box::new(move |a, b, _| op.apply(a, b)),
        ));
    }
    for op in SetOp::ALL {
        for alpha in [0.0, 0.5] {
            cases.push((
                format!("{}({alpha})", op.name()),
                Expr::set(op, &x, &y, alpha),
                Box::new(move |a, b, _| op.apply(a, b, alpha)),
            ));
        }
        cases.push((
            format!("{}(z)", op.name()),
            Expr::set(op, &x, &y, 0.25 * z.clone()),
            Box::new(move |a, b, c| op.apply(a, b, 0.25 * c)),
        ));
    }
    for (name, e, reference) in cases {
        let f = F::compile(&Tape::new(&e));
        let (mut pe, mut be, mut ie) = (f.point(), f.batch(), f.interval());
        for &a in &vals {
            for &b in &vals {
                let c = 0.5 * (a - b);
                let p = [a, b, c];
                let want = reference(a, b, c);
                let got = pe.eval_output(0, p);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{name}({a}, {b}, {c}): {got} vs {want}"
                );
                let mut out = [0.0f32];
                be.eval_output(0, &[a as f32], &[b as f32], &[c as f32], &mut out);
                let close = out[0] as f64 == want
                    || (out[0] as f64 - want).abs() <= 1e-5 * (1.0 + want.abs())
                    || (out[0].is_nan() && want.is_nan())
                    // Beyond f32's range the batch overflows to infinity.
                    || (want.abs() > 3e38 && out[0].is_infinite())
                    // Discontinuous ops may jump between f32 and f64 (e.g.
                    // at exact comparisons); finite and same-signed suffices.
                    || (out[0].is_finite() && want.is_finite() && matches!(name.as_str(),
                        "floor" | "ceil" | "trunc" | "round" | "fract" | "sign" | "saw" | "tri"
                        | "mod" | "rem" | "lt" | "le" | "gt" | "ge" | "eq" | "ne" | "tan" | "pow"));
                assert!(close, "batch {name}({a}, {b}, {c}): {} vs {want}", out[0]);
                let r = ie.eval_output(
                    0,
                    [Interval::point(a), Interval::point(b), Interval::point(c)],
                );
                assert!(
                    if want.is_nan() {
                        r.may_be_nan()
                    } else {
                        r.contains(want)
                    },
                    "interval {name}({a}, {b}, {c}): {r:?} vs {want}"
                );
            }
        }
    }
}

/// The proptest configuration of the suites (fixed seed: reproducible).
pub fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(11),
        ..ProptestConfig::default()
    }
}

/// Instantiates every suite for a backend type implementing `Function`.
#[macro_export]
macro_rules! backend_suites {
    ($name:ident, $ty:ty) => {
        mod $name {
            use super::backend::*;
            use proptest::prelude::*;

            proptest! {
                #![proptest_config(config(600))]
                #[test]
                fn interval_soundness(
                    consts in prop::collection::vec(constant(), 1..4),
                    steps in prop::collection::vec(step(), 1..14),
                    b in [axis(), axis(), axis()],
                    ts in prop::collection::vec([0.0f64..=1.0, 0.0f64..=1.0, 0.0f64..=1.0], 8),
                ) {
                    interval_case::<$ty>(&consts, &steps, b, &ts)?;
                }

                #[test]
                fn batch_against_point(
                    consts in prop::collection::vec(-2.0f64..2.0, 1..3),
                    steps in prop::collection::vec((0usize..9, any::<[usize; 3]>()), 1..12),
                    pts in prop::collection::vec([-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0], 1..600),
                ) {
                    batch_case::<$ty>(&consts, &steps, &pts)?;
                }

                #[test]
                fn gradients_against_finite_differences(
                    consts in prop::collection::vec(-2.0f64..2.0, 1..3),
                    steps in prop::collection::vec((0usize..9, any::<[usize; 3]>()), 1..10),
                    pts in prop::collection::vec([-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0], 1..12),
                ) {
                    gradient_case::<$ty>(&consts, &steps, &pts)?;
                }
            }

            #[test]
            fn every_op_against_its_reference() {
                every_op::<$ty>();
            }
        }
    };
}
