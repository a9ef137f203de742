//! Graph and tape compilation: determinism, sharing of identical
//! subexpressions, constant folding, and that the compiled tape computes what
//! the expression tree says.

use microfrep_core::{BinaryOp, Expr, ExprNode, Graph, PointEval, Tape, UnaryOp};
use proptest::prelude::*;

const N_OPS: usize = UnaryOp::ALL.len() + BinaryOp::ALL.len() + 2;

/// Builds a DAG from steps (as in the interval tests); every call makes
/// fresh nodes, so two calls share no pointers.
fn build(consts: &[f64], steps: &[(usize, [usize; 3], i32)]) -> Expr {
    let mut nodes: Vec<Expr> = Expr::xyz().to_vec();
    nodes.extend(consts.iter().map(|&c| Expr::constant(c)));
    for &(op, pick, n) in steps {
        let len = nodes.len();
        let arg = |k: usize| nodes[len - 1 - pick[k] % len.min(6)].clone();
        let e = if op < UnaryOp::ALL.len() {
            Expr::unary(UnaryOp::ALL[op], arg(0))
        } else if op < UnaryOp::ALL.len() + BinaryOp::ALL.len() {
            Expr::binary(BinaryOp::ALL[op - UnaryOp::ALL.len()], arg(0), arg(1))
        } else if op == N_OPS - 2 {
            arg(0).powi(n)
        } else {
            Expr::select(arg(0), arg(1), arg(2))
        };
        nodes.push(e);
    }
    nodes.pop().unwrap()
}

/// Independent reference: direct recursive evaluation of the tree.
fn eval_tree(e: &Expr, p: [f64; 3]) -> f64 {
    match e.node() {
        ExprNode::Var(a) => p[*a as usize],
        ExprNode::Const(c) => *c,
        ExprNode::Param { default, .. } => *default,
        ExprNode::Unary(op, a) => op.apply(eval_tree(a, p)),
        ExprNode::Binary(op, a, b) => op.apply(eval_tree(a, p), eval_tree(b, p)),
        ExprNode::PowI(a, n) => eval_tree(a, p).powi(*n),
        ExprNode::Select(c, a, b) => {
            if eval_tree(c, p) != 0.0 {
                eval_tree(a, p)
            } else {
                eval_tree(b, p)
            }
        }
        ExprNode::Set { op, a, b, alpha } => {
            op.apply(eval_tree(a, p), eval_tree(b, p), eval_tree(alpha, p))
        }
        ExprNode::Blend { .. } => eval_tree(&e.expand(), p),
        ExprNode::Field { .. } => unreachable!("no fields in these graphs"),
    }
}

fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()) || a == b
}

fn steps() -> impl Strategy<Value = Vec<(usize, [usize; 3], i32)>> {
    prop::collection::vec((0..N_OPS, any::<[usize; 3]>(), -4i32..=5), 1..14)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 1500,
        failure_persistence: None,
        // A fixed seed keeps runs reproducible.
        rng_seed: proptest::test_runner::RngSeed::Fixed(6),
        ..ProptestConfig::default()
    })]

    /// The same model built twice compiles to the same tape.
    #[test]
    fn identical_graphs_identical_tapes(consts in prop::collection::vec(-3.0f64..3.0, 1..3), s in steps()) {
        let a = Tape::new(&build(&consts, &s));
        let b = Tape::new(&build(&consts, &s));
        prop_assert_eq!(a.listing(), b.listing());
    }

    /// Register allocation and simplification preserve the value: the tape
    /// equals direct evaluation of the tree, bit for bit.
    #[test]
    fn tape_equals_tree(consts in prop::collection::vec(-3.0f64..3.0, 1..3), s in steps(), p in [-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0]) {
        let e = build(&consts, &s);
        let tape = Tape::new(&e);
        let (t, r) = (PointEval::new(&tape).eval(p), eval_tree(&e, p));
        prop_assert!(same(t, r), "tape {} tree {} for {:?}\n{}", t, r, e, tape.listing());
    }

    /// Substituting constants for x, y, z folds the whole model to one
    /// constant, equal to what evaluation gives.
    #[test]
    fn constants_fold_to_evaluated_value(consts in prop::collection::vec(-3.0f64..3.0, 1..3), s in steps(), p in [-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0]) {
        let e = build(&consts, &s);
        let folded = e.remap(&p.map(Expr::constant));
        let c = folded.as_const();
        prop_assert!(c.is_some(), "not folded: {:?}", folded);
        let v = PointEval::new(&Tape::new(&e)).eval(p);
        prop_assert!(same(c.unwrap(), v), "folded {:?} evaluated {}", c, v);
        let mut g = Graph::new();
        g.add(&folded);
        prop_assert_eq!(g.len(), 1);
    }
}

/// Subexpressions written twice (as separate trees, commuted arguments
/// included) are stored once.
#[test]
fn duplicated_subexpressions_stored_once() {
    let make = || {
        let [x, y, z] = Expr::xyz();
        (x * &y).sin() + (z - 1.0)
    };
    let [x, y, _] = Expr::xyz();
    let e = make() * make() + (y * x).sin();
    let mut g = Graph::new();
    g.add(&e);
    let mut single = Graph::new();
    single.add(&make());
    // The whole model adds only the outer product and sum to one copy.
    assert_eq!(g.len(), single.len() + 2, "{:?}", g.nodes());
    assert_eq!(single.len(), 8); // x y mul sin z 1 sub add
}

/// Constant subtrees fold and identities vanish, so they cost no instructions.
#[test]
fn constants_fold_in_tape() {
    let x = Expr::x();
    let e = (Expr::constant(2.0) + 3.0) * &x + Expr::constant(4.0).sqrt() * 0.0 + (x.clone() * 1.0);
    let tape = Tape::new(&e);
    // 5 * x + 0 + x: the `+ 0` stays (it turns -0 into +0), `* 1` goes.
    let listing = tape.listing();
    assert!(listing.contains("const 5e0"), "{listing}");
    assert!(!listing.contains("sqrt"), "{listing}");
    assert!(!listing.contains("const 1e0"), "{listing}");
    assert_eq!(PointEval::new(&tape).eval([2.0, 0.0, 0.0]), 12.0);
    // -(-x) is x: no instruction at all.
    assert!(Tape::new(&(-(-x.clone()))).is_empty());
}

/// Real powers with whole constant exponents become integer powers: the
/// same values in f64 (to rounding) for every kind of base, other powers
/// untouched, nodes without such powers shared, and through field nodes
/// and their partials (a field's gradient expression) too.
#[test]
fn integer_powers_keep_values() {
    use microfrep_core::GridField;
    use std::sync::Arc;
    let [x, y, z] = Expr::xyz();
    let plain = (&x * 2.0).sin() + &y;
    let mut parts = vec![plain.clone()];
    for n in -6..=6 {
        parts.push((&x - 0.5).pow(n as f64) * 0.01);
    }
    let field = GridField::new(
        "g",
        [3, 3, 3],
        [-1.0; 3],
        [1.0; 3],
        (0..27).map(|i| (i % 5) as f64 * 0.3).collect(),
    )
    .unwrap();
    let mapped = Expr::field_at(Arc::new(field), [x.pow(3.0), y.clone(), z.pow(2.0)]);
    let [gx, _, gz] = mapped.gradient();
    parts.extend([mapped, gx, gz]);
    let kept = [x.pow(2.5), x.pow(17.0), x.pow(&y)];
    let e = parts
        .iter()
        .chain(&kept)
        .fold(Expr::constant(0.0), |s, p| s + p);
    let r = e.with_integer_powers();
    // Only the three powers that are not whole (or too large) remain.
    let count = |t: &Tape| t.listing().matches(" pow ").count();
    assert_eq!(
        count(&Tape::new(&e)),
        13 + 2 + 2 + 3,
        "{}",
        Tape::new(&e).listing()
    );
    assert_eq!(count(&Tape::new(&r)), 3, "{}", Tape::new(&r).listing());
    for p in &kept {
        assert!(std::ptr::eq(p.with_integer_powers().node(), p.node()));
    }
    assert!(std::ptr::eq(
        plain.with_integer_powers().node(),
        plain.node()
    ));
    let (mut a, mut b) = (
        PointEval::new(&Tape::new(&e)),
        PointEval::new(&Tape::new(&r)),
    );
    let bases = [
        -2.0,
        -1.0,
        -0.25,
        0.0,
        0.5,
        0.75,
        1.5,
        3.0,
        f64::INFINITY,
        f64::NAN,
    ];
    for &bx in &bases {
        for &by in &[0.3, 2.0] {
            for &bz in &[-0.6, 0.0, 0.4] {
                let (u, v) = (a.eval([bx, by, bz]), b.eval([bx, by, bz]));
                assert!(
                    u == v || (u - v).abs() <= 1e-12 * u.abs() || (u.is_nan() && v.is_nan()),
                    "at ({bx}, {by}, {bz}): {u} vs {v}"
                );
            }
        }
    }
    // Each power on its own, at the special bases.
    for n in -6..=6 {
        let one = Tape::new(&x.pow(n as f64).with_integer_powers());
        let mut pe = PointEval::new(&one);
        for &bx in &[
            -2.0,
            -0.0,
            0.0,
            0.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ] {
            let (got, want) = (pe.eval([bx, 0.0, 0.0]), bx.powf(n as f64));
            assert!(
                got == want
                    || (got - want).abs() <= 1e-15 * want.abs()
                    || (got.is_nan() && want.is_nan()),
                "{bx}^{n}: {got} vs {want}"
            );
        }
    }
}

/// Divisions by constants become products with the inverse: none is left
/// (except by constants without a normal f32 inverse), powers of two give
/// the same bits, others agree within an ulp or two in f32 and f64 (also
/// at zero, infinite and NaN numerators), and parts without divisions are
/// shared.
#[test]
fn constant_divisors_are_inverted() {
    use microfrep_core::BatchEval;
    let [x, y, z] = Expr::xyz();
    let plain = x.square() + &y;
    let e = (&x / 3.0 + &y / 0.25) / 7.5 - (&z / 0.1).sin() / &y + &plain / 1e-39 + &x / 1e39;
    let r = e.with_constant_divisors_inverted();
    let divs = |t: &Tape| t.listing().matches(" div ").count();
    let (te, tr) = (Tape::new(&e), Tape::new(&r));
    assert_eq!(divs(&te), 7, "{}", te.listing());
    // The division by y and those by 1e-39 and 1e39 (inverses not normal
    // in f32) stay.
    assert_eq!(divs(&tr), 3, "{}", tr.listing());
    assert!(std::ptr::eq(
        plain.with_constant_divisors_inverted().node(),
        plain.node()
    ));
    let quarter = (&x / 0.25).with_constant_divisors_inverted();
    let (mut a, mut b) = (PointEval::new(&te), PointEval::new(&tr));
    let (mut ba, mut bb) = (BatchEval::new(&te), BatchEval::new(&tr));
    let mut bq = (
        BatchEval::new(&Tape::new(&(&x / 0.25))),
        BatchEval::new(&Tape::new(&quarter)),
    );
    for &px in &[-2.0, -0.0, 0.0, 0.3, 1.7, 1e30, f64::INFINITY, f64::NAN] {
        for &py in &[0.5, -3.0] {
            for &pz in &[0.05, -0.4] {
                let (u, v) = (a.eval([px, py, pz]), b.eval([px, py, pz]));
                let close = |u: f64, v: f64, tol: f64| {
                    u == v || (u - v).abs() <= tol * u.abs() || (u.is_nan() && v.is_nan())
                };
                assert!(close(u, v, 1e-15), "f64 at ({px}, {py}, {pz}): {u} vs {v}");
                let (p, q, w) = ([px as f32], [py as f32], [pz as f32]);
                let (mut fu, mut fv) = ([0f32], [0f32]);
                ba.eval(&p, &q, &w, &mut fu);
                bb.eval(&p, &q, &w, &mut fv);
                assert!(
                    close(fu[0] as f64, fv[0] as f64, 5e-7),
                    "f32 at ({px}, {py}, {pz}): {} vs {}",
                    fu[0],
                    fv[0]
                );
                bq.0.eval(&p, &q, &w, &mut fu);
                bq.1.eval(&p, &q, &w, &mut fv);
                assert!(fu[0].to_bits() == fv[0].to_bits() || fu[0].is_nan() && fv[0].is_nan());
            }
        }
    }
}

/// A power and the power with the exponent one less, as differentiating
/// writes them, share one power: `pow(x, e - 1)` becomes `pow(x, e) / x`,
/// with the same values at signed zeros, infinities, negative bases and
/// NaN, and within a few ulps elsewhere; powers without such a neighbour
/// (or with a whole exponent) stay.
#[test]
fn neighbour_powers_share_one_power() {
    use microfrep_core::BatchEval;
    let [x, y, _] = Expr::xyz();
    let s = x.square() + &y;
    let u = s.pow(0.2);
    let [du, _, _] = u.gradient();
    let lone = (&y + 3.0).pow(1.7) + (&y + 3.0).pow(0.35);
    let e = &u + &du * 0.3 + &lone;
    let r = e.with_neighbour_powers_shared();
    let pows = |t: &Tape| t.listing().matches(" pow ").count();
    let (te, tr) = (Tape::new(&e), Tape::new(&r));
    assert_eq!(pows(&te), 4, "{}", te.listing());
    assert_eq!(pows(&tr), 3, "{}", tr.listing());
    assert!(std::ptr::eq(
        lone.with_neighbour_powers_shared().node(),
        lone.node()
    ));
    // The power on its own: x^(0.2 - 1) next to x^0.2.
    let pair = [x.pow(0.2), x.pow(0.2 - 1.0)];
    let shared: Vec<Expr> = {
        let both = (&pair[0] + &pair[1]).with_neighbour_powers_shared();
        let ExprNode::Binary(_, a, b) = both.node() else {
            panic!("a sum")
        };
        vec![a.clone(), b.clone()]
    };
    let (t1, t2) = (Tape::new(&pair[1]), Tape::new(&shared[1]));
    let (mut p1, mut p2) = (PointEval::new(&t1), PointEval::new(&t2));
    let (mut b1, mut b2) = (BatchEval::new(&t1), BatchEval::new(&t2));
    let bases = [
        -2.0,
        -0.0,
        0.0,
        1e-30,
        0.37,
        1.0,
        2.5,
        1e30,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ];
    for &bx in &bases {
        let (u, v) = (p1.eval([bx, 0.0, 0.0]), p2.eval([bx, 0.0, 0.0]));
        let special = bx == 0.0 || bx.is_infinite() || bx.is_nan() || bx < 0.0;
        if special {
            assert!(
                u == v || (u.is_nan() && v.is_nan()),
                "f64 at {bx}: {u} vs {v}"
            );
        } else {
            assert!((u - v).abs() <= 1e-13 * u.abs(), "f64 at {bx}: {u} vs {v}");
        }
        let (mut fu, mut fv) = ([0f32], [0f32]);
        b1.eval(&[bx as f32], &[0.0], &[0.0], &mut fu);
        b2.eval(&[bx as f32], &[0.0], &[0.0], &mut fv);
        let (fu, fv) = (fu[0], fv[0]);
        if special {
            assert!(
                fu == fv || (fu.is_nan() && fv.is_nan()),
                "f32 at {bx}: {fu} vs {fv}"
            );
        } else {
            // Both round the exponents to f32 (which alone moves tiny and
            // huge bases' powers by more than an ulp): the shared form is
            // as close to the exact power as the original, within 2 ulps.
            let exact = (bx as f32 as f64).powf(0.2 - 1.0);
            let (du, dv) = ((fu as f64 - exact).abs(), (fv as f64 - exact).abs());
            assert!(
                dv <= du + 2.4e-7 * exact,
                "f32 at {bx}: {fu} vs {fv} ({exact})"
            );
        }
    }
    // And the whole expression at a few points.
    let (mut a, mut b) = (PointEval::new(&te), PointEval::new(&tr));
    for p in [[0.3, 0.2, 0.0], [1.5, -0.4, 0.0], [-2.0, 7.0, 0.0]] {
        let (u, v) = (a.eval(p), b.eval(p));
        assert!((u - v).abs() <= 1e-14 * u.abs(), "at {p:?}: {u} vs {v}");
    }
}
