//! Multi-threaded evaluation gives the single-threaded batch results, and
//! `a * a` compiles as a square (tighter intervals, same values).

use microfrep_core::{
    eval_grid_par, eval_points_par, BatchEval, Expr, Interval, IntervalEval, PointEval, Tape,
};

fn model() -> Expr {
    let [x, y, z] = Expr::xyz();
    (3.0 * &x).sin() * (3.0 * &y).cos() + (2.0 * &z).sin() - 0.1 * (&x * &y)
}

#[test]
fn parallel_points_match_one_batch() {
    let tape = Tape::new(&model());
    let n = 10_000;
    let x: Vec<f32> = (0..n).map(|i| (i as f32 * 0.37).sin() * 2.0).collect();
    let y: Vec<f32> = (0..n).map(|i| (i as f32 * 0.11).cos() * 2.0).collect();
    let z: Vec<f32> = (0..n).map(|i| i as f32 / n as f32 - 0.5).collect();
    let par = eval_points_par(&tape, &x, &y, &z);
    let mut one = vec![0.0f32; n];
    BatchEval::new(&tape).eval(&x, &y, &z, &mut one);
    assert_eq!(par, one);
}

#[test]
fn parallel_grid_is_x_fastest_and_matches_point_values() {
    let tape = Tape::new(&model());
    let (dims, min, step) = ([7, 5, 3], [-1.0, -0.5, 0.25], [0.3, 0.2, 0.5]);
    let v = eval_grid_par(&tape, dims, min, step);
    assert_eq!(v.len(), 105);
    let mut pe = PointEval::new(&tape);
    for k in 0..3 {
        for j in 0..5 {
            for i in 0..7 {
                let p = [0, 1, 2].map(|a| {
                    let idx = [i, j, k][a] as f64;
                    (min[a] + step[a] * idx) as f32 as f64
                });
                let got = v[i + 7 * (j + 5 * k)] as f64;
                assert!((got - pe.eval(p)).abs() < 1e-5, "{p:?}");
            }
        }
    }
    assert!(eval_grid_par(&tape, [0, 4, 4], min, step).is_empty());
}

#[test]
fn product_of_a_node_with_itself_is_a_square() {
    let x = Expr::x();
    let prod = Tape::new(&(&x * &x - 1.0));
    let sq = Tape::new(&(x.square() - 1.0));
    assert_eq!(prod.listing(), sq.listing());
    // Over a box straddling 0 the square's bound starts at 0, not below.
    let i = IntervalEval::new(&prod).eval(
        Interval::new(-2.0, 3.0),
        Interval::point(0.0),
        Interval::point(0.0),
    );
    assert_eq!((i.lo, i.hi), (-1.0, 8.0));
}

#[test]
fn eval_all_bounds_every_output_in_one_pass() {
    let [x, y, _] = Expr::xyz();
    let tape = Tape::with_outputs(&[x.clone() + 1.0, y.square(), x.lt(-5.0)]);
    let b = Interval::new(-1.0, 2.0);
    let all = IntervalEval::new(&tape).eval_all(b, b, b);
    let one: Vec<Interval> = (0..3)
        .map(|k| IntervalEval::new(&tape).eval_output(k, b, b, b))
        .collect();
    assert_eq!(all.len(), 3);
    for (a, o) in all.iter().zip(&one) {
        assert_eq!((a.lo, a.hi), (o.lo, o.hi));
    }
    assert_eq!((all[0].lo, all[0].hi), (0.0, 3.0));
    assert_eq!((all[1].lo, all[1].hi), (0.0, 4.0));
    assert_eq!((all[2].lo, all[2].hi), (0.0, 0.0));
}
