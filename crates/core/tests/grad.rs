//! Gradients: `GradEval` and `GradBatchEval` against central finite
//! differences at generic points, the symbolic `Expr::gradient()` against
//! `GradEval`, and the f32 lanes of `GradBatchEval` against both `GradEval`
//! (partials) and `BatchEval` (values, bit for bit).

use microfrep_core::frep::{intersection, union};
use microfrep_core::{
    BatchEval, BinaryOp, Expr, Field, GradBatchEval, GradEval, GridField, PointEval, Tape, UnaryOp,
    BLOCK,
};
use proptest::prelude::*;
use std::sync::Arc;

fn config(cases: u32, seed: u64) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        // A fixed seed keeps runs reproducible.
        rng_seed: proptest::test_runner::RngSeed::Fixed(seed),
        ..ProptestConfig::default()
    }
}

/// Smooth nodes that keep values in [-1, 1] for arguments in [-1, 1].
const N_SMOOTH: usize = 16;

fn smooth_op(k: usize, a: Expr, b: Expr) -> Expr {
    match k {
        0 => 0.5 * (a + b),
        1 => 0.5 * (a - b),
        2 => a * b,
        3 => a.sin(),
        4 => (2.0 * a).cos(),
        5 => a.tanh(),
        6 => a.atan(),
        7 => a.square(),
        8 => 0.3 * a.exp(),
        9 => 0.9 * (2.0 + a).ln(),
        10 => 0.4 * a.sinh() + 0.3 * a.cosh(),
        11 => 0.5 * (0.5 * a).asin() + 0.2 * (0.5 * b).acos(),
        12 => (a.square() + 0.25).sqrt() - 0.5,
        13 => 0.5 * (1.5 + 0.5 * a).pow(b),
        14 => 0.6 * &a / (2.0 + &b) + 0.2 * a.atan2(2.0 + &b) + 0.2 * (0.7 * b).tan(),
        _ => 0.5 * a.powi(3) - 0.5 * (2.0 + b).powi(-2),
    }
}

/// Piecewise ops, differentiable away from their kinks and jumps.
fn piecewise_op(k: usize, a: Expr, b: Expr) -> Expr {
    match k {
        0 => a.min(b),
        1 => a.max(b),
        2 => a.abs(),
        3 => Expr::select(a.gt(&b), a.square(), 0.5 * b),
        4 => 0.5 * (3.0 * a).fract(),
        5 => Expr::unary(UnaryOp::Tri, 3.0 * a),
        6 => Expr::unary(UnaryOp::Saw, 3.0 * a),
        7 => a.modulo(0.7) + a.rem(0.3),
        8 => 0.1 * (3.0 * &a).floor() + 0.5 * a.sign() * b,
        _ => Expr::binary(BinaryOp::Mod, a, 2.0 + b) * 0.3,
    }
}

/// R-function set operations, scaled to keep values in [-1, 1]: constant
/// parameters (0 and not) and one that varies in space (a register).
const N_SETS: usize = 4;

fn set_op(k: usize, a: Expr, b: Expr) -> Expr {
    match k {
        0 => 0.4 * union(&a, &b, 0.0),
        1 => 0.4 * intersection(&a, &b, 0.0),
        2 => 0.4 * union(&a, &b, 0.45),
        _ => 0.4 * intersection(&a, &b, 0.3 * (&a * &b).square() + 0.1),
    }
}

fn build(consts: &[f64], steps: &[(usize, usize, usize)], piecewise: bool) -> Expr {
    build_with(consts, steps, |k, a, b| {
        if piecewise && k >= N_SMOOTH {
            piecewise_op(k - N_SMOOTH, a, b)
        } else {
            smooth_op(k % N_SMOOTH, a, b)
        }
    })
}

/// Smooth ops (`k < N_SMOOTH`) and set operations (the next `N_SETS`).
fn build_sets(consts: &[f64], steps: &[(usize, usize, usize)]) -> Expr {
    build_with(consts, steps, |k, a, b| {
        if k >= N_SMOOTH {
            set_op(k - N_SMOOTH, a, b)
        } else {
            smooth_op(k, a, b)
        }
    })
}

fn build_with(
    consts: &[f64],
    steps: &[(usize, usize, usize)],
    op: impl Fn(usize, Expr, Expr) -> Expr,
) -> Expr {
    let mut nodes: Vec<Expr> = Expr::xyz().to_vec();
    nodes.extend(consts.iter().map(|&c| Expr::constant(c)));
    for &(k, i, j) in steps {
        let len = nodes.len();
        let (a, b) = (
            nodes[len - 1 - i % len].clone(),
            nodes[len - 1 - j % len].clone(),
        );
        nodes.push(op(k, a, b));
    }
    nodes.pop().unwrap()
}

/// The points as three coordinate slices.
fn split(pts: &[[f32; 3]]) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    (
        pts.iter().map(|p| p[0]).collect(),
        pts.iter().map(|p| p[1]).collect(),
        pts.iter().map(|p| p[2]).collect(),
    )
}

/// `GradBatchEval`'s output at the points.
fn grad_batch(tape: &Tape, pts: &[[f32; 3]]) -> Vec<[f32; 4]> {
    let (x, y, z) = split(pts);
    let mut out = vec![[0.0f32; 4]; pts.len()];
    GradBatchEval::new(tape).eval(&x, &y, &z, &mut out);
    out
}

/// `BatchEval`'s values at the points.
fn batch_values(tape: &Tape, pts: &[[f32; 3]]) -> Vec<f32> {
    let (x, y, z) = split(pts);
    let mut out = vec![0.0f32; pts.len()];
    BatchEval::new(tape).eval(&x, &y, &z, &mut out);
    out
}

/// Whether an f32 partial agrees with the f64 one `want` at the same input
/// (see `grad_batch_matches_grad_eval` for the bound).
fn grad_close(got: f64, want: f64) -> bool {
    let tol = (2e-5 + 1e-6 * want.abs().sqrt()) * (1.0 + want.abs());
    (got - want).abs() <= tol || (got.is_nan() && want.is_nan())
}

/// Whether the f32 lanes agree with the f64 reference: the value bit for
/// bit with `BatchEval`'s, the partials within `grad_close`.
fn check_against_reference(tape: &Tape, pts: &[[f32; 3]]) -> Result<(), TestCaseError> {
    let out = grad_batch(tape, pts);
    let vals = batch_values(tape, pts);
    let mut ge = GradEval::new(tape);
    for (i, q) in pts.iter().enumerate() {
        prop_assert!(
            out[i][0].to_bits() == vals[i].to_bits() || (out[i][0].is_nan() && vals[i].is_nan()),
            "value at {:?}: grad batch {} batch {}",
            q,
            out[i][0],
            vals[i]
        );
        let (_, g) = ge.eval(q.map(f64::from));
        for a in 0..3 {
            let got = out[i][a + 1] as f64;
            prop_assert!(
                grad_close(got, g[a]),
                "axis {} at {:?}: grad batch {} point {}",
                a,
                q,
                got,
                g[a]
            );
        }
    }
    Ok(())
}

/// Central difference along each axis with step h.
fn central(pe: &mut PointEval, p: [f64; 3], h: f64) -> [f64; 3] {
    std::array::from_fn(|a| {
        let (mut q, mut r) = (p, p);
        q[a] += h;
        r[a] -= h;
        (pe.eval(q) - pe.eval(r)) / (2.0 * h)
    })
}

fn point() -> impl Strategy<Value = [f64; 3]> {
    [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0]
}

proptest! {
    #![proptest_config(config(1500, 5))]

    /// Smooth graphs: forward-mode gradients equal central differences to
    /// 1e-6 (relative to 1 + |gradient|); the step 1e-4 leaves a truncation
    /// error of order 1e-8 times the third derivative.
    #[test]
    fn grad_matches_finite_differences(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH, 0usize..6, 0usize..6), 1..12),
        p in point(),
    ) {
        let e = build(&consts, &steps, false);
        let tape = Tape::new(&e);
        let (v, g) = GradEval::new(&tape).eval(p);
        let mut pe = PointEval::new(&tape);
        prop_assert_eq!(v, pe.eval(p));
        let fd = central(&mut pe, p, 1e-4);
        let fd2 = central(&mut pe, p, 5e-5);
        for a in 0..3 {
            // Richardson extrapolation removes the h^2 term.
            let rich = (4.0 * fd2[a] - fd[a]) / 3.0;
            prop_assert!((g[a] - rich).abs() <= 1e-6 * (1.0 + g[a].abs()),
                "axis {}: grad {} fd {} for {:?}", a, g[a], rich, e);
        }
    }

    /// With kinks and jumps: at points where the stencil does not straddle
    /// one (the two step sizes agree), the gradient matches.
    #[test]
    fn piecewise_grad_matches_away_from_kinks(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH + 10, 0usize..6, 0usize..6), 1..8),
        p in point(),
    ) {
        let e = build(&consts, &steps, true);
        let tape = Tape::new(&e);
        let (_, g) = GradEval::new(&tape).eval(p);
        let mut pe = PointEval::new(&tape);
        let fd = central(&mut pe, p, 1e-6);
        let fd2 = central(&mut pe, p, 5e-7);
        for a in 0..3 {
            if (fd[a] - fd2[a]).abs() > 1e-4 * (1.0 + fd[a].abs()) {
                continue; // a kink or jump within 1e-6 of p
            }
            prop_assert!((g[a] - fd[a]).abs() <= 1e-4 * (1.0 + g[a].abs()),
                "axis {}: grad {} fd {} for {:?}", a, g[a], fd[a], e);
        }
    }

    /// The symbolic gradient evaluates to what forward mode computes.
    #[test]
    fn symbolic_gradient_matches_grad_eval(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH + 10, 0usize..6, 0usize..6), 1..10),
        p in point(),
    ) {
        let e = build(&consts, &steps, true);
        let (v, g) = GradEval::new(&Tape::new(&e)).eval(p);
        let sym = Tape::with_outputs(&e.gradient());
        let s = PointEval::new(&sym).eval_all(p);
        for a in 0..3 {
            prop_assert!((g[a] - s[a]).abs() <= 1e-12 * (1.0 + g[a].abs()),
                "axis {}: forward {} symbolic {} (value {}) for {:?}", a, g[a], s[a], v, e);
        }
    }

    /// The f32 forward mode against the f64 one at the same f32 inputs, on
    /// smooth graphs and R-functions of up to 10 ops with values in [-1, 1].
    /// Each f32 derivative factor is within a few ulp of its f64 value at
    /// the f32 operand, and the operand within the value batch's 2e-6 of the
    /// f64 one. Where factors are of order one that leaves a few 1e-6
    /// relative to 1 + |partial| (largest seen: 8.5e-6); the bound's 2e-5
    /// covers it. Large partials come from nearing a pole (`1 / (2 + b)`
    /// for b near -2): for a factor like `c / (a - p)^2` the operand's error
    /// `d` changes it by the relative `2 d / |a - p|`, which grows as the
    /// square root of the factor, hence the bound's `1e-6 sqrt(|partial|)`
    /// (largest seen: 7e-5 relative at a partial of 1e5, where the bound is
    /// 3.4e-4). The values are `BatchEval`'s bit for bit.
    #[test]
    fn grad_batch_matches_grad_eval(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH + N_SETS, 0usize..6, 0usize..6), 1..10),
        pts in prop::collection::vec([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], 1..300),
    ) {
        let e = build_sets(&consts, &steps);
        check_against_reference(&Tape::new(&e), &pts)?;
    }

    /// With kinks and jumps too: values are still `BatchEval`'s bit for
    /// bit, and at points where the f64 partials do not change between the
    /// point and a step of 1e-4 around it on each axis (no kink or jump is
    /// near, so f32 rounding of the input cannot switch a branch), the f32
    /// partials agree with them.
    #[test]
    fn piecewise_grad_batch_matches_grad_eval(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH + 10, 0usize..6, 0usize..6), 1..8),
        pts in prop::collection::vec([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], 1..300),
    ) {
        let e = build(&consts, &steps, true);
        let tape = Tape::new(&e);
        let out = grad_batch(&tape, &pts);
        let vals = batch_values(&tape, &pts);
        let mut ge = GradEval::new(&tape);
        for (i, q) in pts.iter().enumerate() {
            prop_assert!(
                out[i][0].to_bits() == vals[i].to_bits() || (out[i][0].is_nan() && vals[i].is_nan()),
                "value at {:?}: grad batch {} batch {}", q, out[i][0], vals[i]
            );
            let p = q.map(f64::from);
            let (_, g) = ge.eval(p);
            let steady = (0..3).all(|a| {
                [1e-4, -1e-4].iter().all(|h| {
                    let mut r = p;
                    r[a] += h;
                    let (_, gr) = ge.eval(r);
                    (0..3).all(|b| (gr[b] - g[b]).abs() <= 1e-2 * (1.0 + g[b].abs()))
                })
            });
            if !steady {
                continue;
            }
            for a in 0..3 {
                let got = out[i][a + 1] as f64;
                prop_assert!(grad_close(got, g[a]),
                    "axis {} at {:?}: grad batch {} point {} for {:?}", a, q, got, g[a], e);
            }
        }
    }

    /// A point's result does not depend on how the points are cut into
    /// calls and blocks: evaluating them all at once, one at a time, and in
    /// uneven pieces gives the same bits.
    #[test]
    fn grad_batch_is_independent_of_blocks(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH + N_SETS, 0usize..6, 0usize..6), 1..10),
        pts in prop::collection::vec([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], BLOCK..2 * BLOCK + 50),
        cut in 1usize..BLOCK,
    ) {
        let tape = Tape::new(&build_sets(&consts, &steps));
        let bits = |o: &[[f32; 4]]| o.iter().map(|g| g.map(f32::to_bits)).collect::<Vec<_>>();
        let whole = bits(&grad_batch(&tape, &pts));
        let mut ev = GradBatchEval::new(&tape);
        let (x, y, z) = split(&pts);
        let mut pieces = vec![[0.0f32; 4]; pts.len()];
        let mut start = 0;
        for (k, len) in [cut, 1, BLOCK, 3].into_iter().cycle().enumerate() {
            if start == pts.len() || k > 4 * pts.len() {
                break;
            }
            let end = (start + len).min(pts.len());
            ev.eval(&x[start..end], &y[start..end], &z[start..end], &mut pieces[start..end]);
            start = end;
        }
        prop_assert_eq!(bits(&pieces), whole.clone());
        for (i, q) in pts.iter().enumerate().step_by(17) {
            let mut one = [[0.0f32; 4]];
            ev.eval(&[q[0]], &[q[1]], &[q[2]], &mut one);
            prop_assert_eq!(bits(&one)[0], whole[i]);
        }
    }
}

/// A data-driven field inside a graph (mapped coordinates, an operation on
/// its value, its partial derivative as a node): values bit for bit with
/// `BatchEval`, partials within `grad_close` of `GradEval`.
#[test]
fn grad_batch_through_field_nodes() {
    let wavy = |p: [f64; 3]| (3.0 * p[0]).sin() * (2.0 * p[1]).cos() + p[2] * p[2];
    let g: Arc<dyn Field> = Arc::new(
        GridField::sample("w", [9, 11, 7], [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], wavy).unwrap(),
    );
    let [x, y, z] = Expr::xyz();
    let q = [0.5 * &x + 0.1 * &z, y.sin(), 0.8 * &z];
    let node = Expr::field_at(g.clone(), q);
    let mut pts = Vec::new();
    let mut s = 12345u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 40) as f32 / (1u64 << 24) as f32) * 1.8 - 0.9
    };
    for _ in 0..2 * BLOCK + 31 {
        pts.push([next(), next(), next()]);
    }
    let e1 = &node * (1.0 + x.square()) - &y;
    let e2 = union(&node, &(0.5 - z.square()), 0.0);
    // d node / dx holds the field's partials as nodes of their own.
    let e3 = 0.3 * &node.gradient()[0] + &x;
    for e in [e1, e2, e3] {
        check_against_reference(&Tape::new(&e), &pts).unwrap();
    }
}

/// Where a derivative formula has a removable singularity, symbolic and
/// forward mode make the same choice.
#[test]
fn symbolic_and_forward_agree_at_singular_points() {
    let [x, y, _] = Expr::xyz();
    for (e, p) in [
        (x.pow(&y), [0.0, 0.0, 0.0]),
        (x.pow(&y), [0.0, 2.0, 0.0]),
        (x.min(&y), [1.0, 1.0, 0.0]),
    ] {
        let (_, g) = GradEval::new(&Tape::new(&e)).eval(p);
        let s = PointEval::new(&Tape::with_outputs(&e.gradient())).eval_all(p);
        assert_eq!(g.to_vec(), s, "{e:?} at {p:?}");
    }
}

/// Closed forms at chosen points, one per op family.
#[test]
fn closed_form_gradients() {
    let [x, y, z] = Expr::xyz();
    let cases: Vec<(Expr, [f64; 3], [f64; 3])> = vec![
        (
            x.square() + y.square() + z.square(),
            [1.0, 2.0, 3.0],
            [2.0, 4.0, 6.0],
        ),
        (x.atan2(&y), [1.0, 1.0, 0.0], [0.5, -0.5, 0.0]),
        (x.pow(&y), [2.0, 3.0, 0.0], [12.0, 8.0 * 2f64.ln(), 0.0]),
        (
            Expr::unary(UnaryOp::Tri, x.clone()),
            [0.2, 0.0, 0.0],
            [1.0, 0.0, 0.0],
        ),
        (
            Expr::unary(UnaryOp::Tri, x.clone()),
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
        ),
        (x.modulo(&y), [5.5, 2.0, 0.0], [1.0, -2.0, 0.0]),
    ];
    for (e, p, want) in cases {
        let (_, g) = GradEval::new(&Tape::new(&e)).eval(p);
        for a in 0..3 {
            assert!(
                (g[a] - want[a]).abs() < 1e-12,
                "{e:?} at {p:?}: {g:?} != {want:?}"
            );
        }
    }
}
