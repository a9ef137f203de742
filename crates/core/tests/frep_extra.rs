//! FRep operations not covered by the property tests in `frep.rs`:
//! complement and constant offset, n-ary folds, and replicating waves whose
//! period is itself a field (Fryazinov Eqs. 10, 11).

use microfrep_core::{frep, Expr, Interval, IntervalEval, PointEval, Tape};

fn eval(e: &Expr, p: [f64; 3]) -> f64 {
    PointEval::new(&Tape::new(e)).eval(p)
}

#[test]
fn complement_negates_and_offset_shifts() {
    let [x, y, _] = Expr::xyz();
    let f = 1.0 - x.square() - y.square();
    for p in [[0.0, 0.0, 0.0], [0.5, 0.5, 2.0], [2.0, -1.0, 0.0]] {
        let v = eval(&f, p);
        assert_eq!(eval(&frep::complement(&f), p), -v);
        assert_eq!(eval(&frep::offset(&f, 0.25), p), v + 0.25);
    }
    // The offset disc of radius 1 grows to radius sqrt(1.25).
    let g = frep::offset(&f, 0.25);
    assert!(eval(&g, [1.25f64.sqrt() - 1e-9, 0.0, 0.0]) > 0.0);
    assert!(eval(&g, [1.25f64.sqrt() + 1e-9, 0.0, 0.0]) < 0.0);
}

#[test]
fn n_ary_folds_match_pairwise_operations() {
    let [x, y, z] = Expr::xyz();
    let fs = [x.clone(), y.clone() - 0.5, 1.0 - z.clone()];
    for alpha in [0.0, 0.5, 1.0] {
        let u = frep::union_all(&fs, alpha);
        let i = frep::intersection_all(&fs, alpha);
        let u2 = frep::union(&frep::union(&fs[0], &fs[1], alpha), &fs[2], alpha);
        let i2 = frep::intersection(&frep::intersection(&fs[0], &fs[1], alpha), &fs[2], alpha);
        for p in [
            [0.3, 0.1, 2.0],
            [-0.2, 0.4, 1.5],
            [0.1, 0.9, 0.5],
            [-1.0, -1.0, 3.0],
        ] {
            assert_eq!(eval(&u, p), eval(&u2, p));
            assert_eq!(eval(&i, p), eval(&i2, p));
            // Sign: union inside iff some argument is, intersection iff all.
            let vals = [p[0], p[1] - 0.5, 1.0 - p[2]];
            assert_eq!(eval(&u, p) >= 0.0, vals.iter().any(|&v| v >= 0.0));
            assert_eq!(eval(&i, p) >= 0.0, vals.iter().all(|&v| v >= 0.0));
        }
    }
}

#[test]
fn waves_with_a_field_period_follow_the_local_period() {
    let [x, y, _] = Expr::xyz();
    // The cell width grows with y: 0.2 at y = 0, 0.6 at y = 2.
    let period = 0.2 + 0.2 * &y;
    let saw = Tape::new(&frep::sawtooth(&x, period.clone()));
    let tri = Tape::new(&frep::triangle(&x, period));
    let (mut s, mut t) = (PointEval::new(&saw), PointEval::new(&tri));
    for yv in [0.0, 0.5, 2.0] {
        let a = 0.2 + 0.2 * yv;
        for k in 0..40 {
            let xv = -3.0 + 0.1537 * k as f64;
            let sv = s.eval([xv, yv, 0.0]);
            let tv = t.eval([xv, yv, 0.0]);
            assert!((0.0..=1.0).contains(&sv) && (0.0..=1.0).contains(&tv));
            // Along a line of constant y the local period is a (2a for the
            // triangle); checked away from the sawtooth's jumps.
            let phase = (xv / a + 0.5).rem_euclid(1.0);
            if phase > 1e-6 && phase < 1.0 - 1e-6 {
                assert!((s.eval([xv + a, yv, 0.0]) - sv).abs() < 1e-9);
            }
            assert!((t.eval([xv + 2.0 * a, yv, 0.0]) - tv).abs() < 1e-9);
        }
    }
    // Intervals over boxes in which the period varies still bound the values.
    let mut ie = IntervalEval::new(&tri);
    for (bx, by) in [((-1.0, -0.7), (0.0, 0.3)), ((2.0, 2.05), (1.0, 1.5))] {
        let b = ie.eval(
            Interval::new(bx.0, bx.1),
            Interval::new(by.0, by.1),
            Interval::point(0.0),
        );
        for i in 0..=10 {
            for j in 0..=10 {
                let p = [
                    bx.0 + (bx.1 - bx.0) * i as f64 / 10.0,
                    by.0 + (by.1 - by.0) * j as f64 / 10.0,
                    0.0,
                ];
                let v = t.eval(p);
                assert!(b.lo <= v && v <= b.hi, "{v} outside {b:?} at {p:?}");
            }
        }
    }
}
