//! The f32 batch evaluator against the f64 point reference.
//!
//! Stated tolerance (also in the `BatchEval` doc), at the same f32 input:
//! - per op: `|batch - point| <= 1e-6 |point| + 5e-7`, away from the jumps of
//!   discontinuous ops and where the f64 value fits in f32; NaN in one exactly
//!   when NaN in the other;
//! - graphs of up to 16 well-conditioned ops (Lipschitz constant near 1,
//!   values in [-1, 1]): `|batch - point| <= 2e-6`.

use microfrep_core::{BatchEval, BinaryOp, Expr, PointEval, Tape, UnaryOp, BLOCK};
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

/// Batch values and f64 reference values at the given f32 points.
fn both(e: &Expr, pts: &[[f32; 3]]) -> (Vec<f32>, Vec<f64>) {
    let tape = Tape::new(e);
    let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
        pts.iter().map(|p| p[0]).collect(),
        pts.iter().map(|p| p[1]).collect(),
        pts.iter().map(|p| p[2]).collect(),
    );
    let mut out = vec![0.0f32; pts.len()];
    BatchEval::new(&tape).eval(&x, &y, &z, &mut out);
    let mut pe = PointEval::new(&tape);
    let reference = pts.iter().map(|p| pe.eval(p.map(f64::from))).collect();
    (out, reference)
}

/// Deterministic pseudo-random points in [lo, hi]^3 (a simple LCG is enough).
fn sample(n: usize, lo: f32, hi: f32, seed: u64) -> Vec<[f32; 3]> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((s >> 40) as f32 / (1u64 << 24) as f32)
    };
    (0..n).map(|_| [next(), next(), next()]).collect()
}

/// Whether an op has a jump at `(a, b)` within f32 rounding of the argument.
fn near_jump(op: Option<UnaryOp>, bop: Option<BinaryOp>, a: f64, b: f64) -> bool {
    let near_int = |v: f64| (v - v.round()).abs() < 1e-5 * (1.0 + v.abs());
    match (op, bop) {
        (Some(UnaryOp::Saw), _) => near_int(a + 0.5),
        (_, Some(BinaryOp::Mod)) => near_int(a / b),
        _ => false,
    }
}

fn check(e: &Expr, pts: &[[f32; 3]], op: Option<UnaryOp>, bop: Option<BinaryOp>) {
    let (b, p) = both(e, pts);
    for (i, (&bv, &pv)) in b.iter().zip(&p).enumerate() {
        let q = pts[i];
        if near_jump(op, bop, q[0] as f64, q[1] as f64) || pv.abs() > 1e30 {
            continue;
        }
        assert_eq!(
            bv.is_nan(),
            pv.is_nan(),
            "{e:?} at {q:?}: batch {bv} point {pv}"
        );
        if !pv.is_nan() {
            let err = (bv as f64 - pv).abs();
            assert!(
                err <= 1e-6 * pv.abs() + 5e-7,
                "{e:?} at {q:?}: batch {bv} point {pv} err {err:e}"
            );
        }
    }
}

/// Every unary and binary op, PowI and Select, on a sampled domain that
/// covers both signs, zero, several periods and (for the inverse
/// trigonometric ops) the edge of their domain.
#[test]
fn each_op_agrees_with_reference() {
    let [x, y, z] = Expr::xyz();
    let mut pts = sample(4 * BLOCK + 17, -10.0, 10.0, 1);
    pts.extend(sample(BLOCK, -1.1, 1.1, 2));
    // Exact integers, halves and zeros: the edges of floor, round, sign, not, ...
    pts.extend((-20..=20).map(|k| [k as f32 * 0.5, (k % 3) as f32, 0.0]));
    for op in UnaryOp::ALL {
        check(&Expr::unary(op, x.clone()), &pts, Some(op), None);
    }
    for op in BinaryOp::ALL {
        check(
            &Expr::binary(op, x.clone(), y.clone()),
            &pts,
            None,
            Some(op),
        );
    }
    for n in [-3, -1, 3, 4, 7] {
        check(&x.powi(n), &pts, None, None);
    }
    check(
        &Expr::select(x.gt(&y), y.clone(), z.clone()),
        &pts,
        None,
        None,
    );
    // Powers of positive bases with real exponents, and sin/cos over many periods.
    let far = sample(2 * BLOCK, -1000.0, 1000.0, 3);
    check(&x.sin(), &far, None, None);
    check(&x.cos(), &far, None, None);
    check(&x.abs().pow(&y * 0.3), &pts, None, None);
}

/// Well-conditioned graph nodes: each keeps values in [-1, 1] given
/// arguments in [-1, 1], with a Lipschitz constant near 1.
const N_SAFE: usize = 22;

fn safe_op(k: usize, a: Expr, b: Expr) -> Expr {
    match k {
        0 => 0.5 * (a + b),
        1 => 0.5 * (a - b),
        2 => a * b,
        3 => a.min(b),
        4 => a.max(b),
        5 => a.sin(),
        6 => a.cos(),
        7 => a.tanh(),
        8 => a.atan(),
        9 => -a,
        10 => a.abs(),
        11 => a.square(),
        12 => 0.3 * a.exp(),
        13 => 0.9 * (2.0 + a).ln(),
        14 => 0.5 * a.sinh(),
        15 => 0.5 * a.cosh(),
        16 => (0.5 * a).asin(),
        17 => 0.3 * (0.5 * a).acos(),
        18 => (a.square() + 0.25).sqrt() - 0.5,
        19 => 0.5 * (1.5 + 0.5 * a).pow(b),
        20 => a / (2.0 + b),
        _ => a.powi(3),
    }
}

proptest! {
    #![proptest_config(config(300, 4))]

    #[test]
    fn random_graphs_agree(
        consts in prop::collection::vec(-1.0f64..1.0, 1..3),
        steps in prop::collection::vec((0..N_SAFE, 0usize..6, 0usize..6), 1..16),
        seed in any::<u64>(),
    ) {
        let mut nodes: Vec<Expr> = Expr::xyz().to_vec();
        nodes.extend(consts.iter().map(|&c| Expr::constant(c)));
        for &(k, i, j) in &steps {
            let len = nodes.len();
            let (a, b) = (nodes[len - 1 - i % len].clone(), nodes[len - 1 - j % len].clone());
            nodes.push(safe_op(k, a, b));
        }
        let e = nodes.pop().unwrap();
        let pts = sample(BLOCK + 40, -1.0, 1.0, seed);
        let (b, p) = both(&e, &pts);
        for i in 0..pts.len() {
            let err = (b[i] as f64 - p[i]).abs();
            prop_assert!(err <= 2e-6, "{:?} at {:?}: batch {} point {} err {:e}", e, pts[i], b[i], p[i], err);
        }
    }
}
