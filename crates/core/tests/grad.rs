//! Gradients: `GradEval` and `GradBatchEval` against central finite
//! differences at generic points, and the symbolic `Expr::gradient()` against
//! `GradEval`.

use microfrep_core::{BinaryOp, Expr, GradBatchEval, GradEval, PointEval, Tape, UnaryOp};
use proptest::prelude::*;

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

fn build(consts: &[f64], steps: &[(usize, usize, usize)], piecewise: bool) -> Expr {
    let mut nodes: Vec<Expr> = Expr::xyz().to_vec();
    nodes.extend(consts.iter().map(|&c| Expr::constant(c)));
    for &(k, i, j) in steps {
        let len = nodes.len();
        let (a, b) = (
            nodes[len - 1 - i % len].clone(),
            nodes[len - 1 - j % len].clone(),
        );
        nodes.push(if piecewise && k >= N_SMOOTH {
            piecewise_op(k - N_SMOOTH, a, b)
        } else {
            smooth_op(k % N_SMOOTH, a, b)
        });
    }
    nodes.pop().unwrap()
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

    /// The batched gradient equals the point gradient at the same f32 inputs.
    #[test]
    fn grad_batch_matches_grad_eval(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SMOOTH, 0usize..6, 0usize..6), 1..10),
        pts in prop::collection::vec([-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0], 1..300),
    ) {
        let e = build(&consts, &steps, false);
        let tape = Tape::new(&e);
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) =
            (pts.iter().map(|p| p[0]).collect(), pts.iter().map(|p| p[1]).collect(), pts.iter().map(|p| p[2]).collect());
        let mut out = vec![[0.0f32; 4]; pts.len()];
        GradBatchEval::new(&tape).eval(&x, &y, &z, &mut out);
        let mut ge = GradEval::new(&tape);
        for (i, q) in pts.iter().enumerate() {
            let (v, g) = ge.eval(q.map(f64::from));
            let want = [v, g[0], g[1], g[2]];
            for c in 0..4 {
                prop_assert!((out[i][c] as f64 - want[c]).abs() <= 1e-6 * (1.0 + want[c].abs()),
                    "component {}: batch {} point {}", c, out[i][c], want[c]);
            }
        }
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
