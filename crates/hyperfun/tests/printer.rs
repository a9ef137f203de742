//! Core expressions written as HyperFun parse back and keep their values.

use microfrep_core::{Expr, PointEval, Tape};
use microfrep_hyperfun::printer::{to_hyperfun, try_to_hyperfun};
use microfrep_hyperfun::{load, parse};

fn value(e: &Expr, p: [f64; 3]) -> f64 {
    PointEval::new(&Tape::new(e)).eval(p)
}

/// Prints `e`, loads it back and compares values at a few points.
fn round_trip(e: &Expr, points: &[[f64; 3]]) {
    let text = to_hyperfun(e, "my_model");
    let m =
        load(&text, "printed.hf", None).unwrap_or_else(|d| panic!("{}\n{text}", d.render(&text)));
    for &p in points {
        // Where HyperFun raises a run-time error (e.g. 1/0) the loaded value
        // is NaN by design; the core expression has no such notion.
        if m.eval_points(&[p])[0].is_err() {
            assert!(value(&m.value, p).is_nan());
            continue;
        }
        let (want, got) = (value(e, p), value(&m.value, p));
        assert!(
            want == got || (want - got).abs() <= 1e-9 * want.abs().max(1.0),
            "{p:?}: {want} vs {got}\n{text}"
        );
    }
}

const POINTS: [[f64; 3]; 4] = [
    [0.3, 0.4, 0.5],
    [1.5, -0.7, 2.2],
    [-2.5, 1.25, -0.75],
    [0.0, 0.0, 0.0],
];

#[test]
fn examples_print_as_valid_hyperfun() {
    let examples = microfrep_structures::examples::all();
    assert!(!examples.is_empty());
    for ex in examples {
        let e = (ex.build)();
        let text = to_hyperfun(&e, ex.name);
        parse(&text, ex.name).unwrap_or_else(|d| panic!("{}: {}", ex.name, d.render(&text)));
        // Values agree at a few points spread over the example's box.
        let (lo, hi) = ex.bounds;
        let at = |t: f64| [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * t);
        round_trip(&e, &[at(0.31), at(0.5), at(0.77)]);
    }
}

#[test]
fn rewritten_operations_keep_their_values() {
    let [x, y, z] = Expr::xyz();
    let shared = (x.clone() * 2.0).sin();
    let cases = [
        shared.clone() + shared.square(),
        x.sign() + y.round() * 10.0 + z.fract(),
        x.modulo(0.7) + y.rem(-0.4) + z.powi(3) + x.powi(-2),
        Expr::select(x.lt(y.clone()), z.clone(), -z.clone())
            + x.eq_(0.3)
            + y.ne_(0.4).and(z.gt(0.0)),
        x.not() + (y.clone() / 4.0) + x.min(y.clone()).max(z.clone()) + y.atan2(x.clone()),
        Expr::unary(microfrep_core::UnaryOp::Tri, x.clone() * 3.0)
            + Expr::unary(microfrep_core::UnaryOp::Saw, y.clone() * 3.0),
        (x.clone() - 1.5e-9) * 1e20
            + y.trunc()
            + z.ceil()
            + x.abs().sqrt()
            + y.exp()
            + x.cos().atan(),
    ];
    for e in &cases {
        round_trip(e, &POINTS);
    }
}

#[test]
fn deep_sums_are_split_into_temporaries() {
    let mut e = Expr::x();
    for k in 0..500 {
        e = e + Expr::y() * f64::from(k);
    }
    round_trip(&e, &POINTS);
}

#[test]
fn bad_object_names_are_refused() {
    assert!(try_to_hyperfun(&Expr::x(), "sin").is_err());
    assert!(try_to_hyperfun(&Expr::x(), "9lives").is_err());
    assert!(try_to_hyperfun(&Expr::x(), "x").is_err());
    assert!(to_hyperfun(&Expr::x(), "sin").starts_with("--"));
}
