mod common;
use common::*;
use microfrep_core::frep::subtraction;
use microfrep_core::Expr;
use microfrep_shapes::{half_space, sphere, v3};
use microfrep_structures::examples::{toriball_cell, unit_sphere};
use microfrep_structures::infill::{graded_by_depth, Depth};
use microfrep_structures::replicate::*;
use microfrep_structures::variable::*;

#[test]
fn transfinite_weights_sum_to_one_and_reproduce_partitions() {
    let p = Expr::xyz();
    // Three disjoint partitions: x < -1, x > 1, and a ball around (0, 3, 0).
    let parts = [
        half_space(&p, [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
        half_space(&p, [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        sphere(&p, &v3([0.0, 3.0, 0.0]), 0.5),
    ];
    let d: Vec<Expr> = parts
        .iter()
        .map(|f| partition_distance(f, Depth::Normalized))
        .collect();
    let w = transfinite_weights(&d);
    let values = [
        Expr::constant(0.2),
        Expr::constant(0.5),
        0.3 + Expr::y() * 0.01,
    ];
    let u = transfinite(&values, &d);
    for q in spread(-3.0, 3.0, 200) {
        let ws: Vec<f64> = w.iter().map(|e| at(e, q)).collect();
        assert!((ws.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{q:?}");
        assert!(ws.iter().all(|&x| (0.0..=1.0).contains(&x)));
        let inside: Vec<usize> = (0..3).filter(|&i| at(&parts[i], q) >= 0.0).collect();
        if let [i] = inside[..] {
            assert!((ws[i] - 1.0).abs() < 1e-12);
            assert!((at(&u, q) - at(&values[i], q)).abs() < 1e-12);
        }
    }
    // Half way between the two half-spaces (and far from the ball) the period is mixed.
    let mid = at(&u, [0.0, -3.0, 0.0]);
    assert!(mid > 0.2 && mid < 0.5);
}

#[test]
fn transfinite_period_and_cell_shape() {
    let p = Expr::xyz();
    let left = half_space(&p, [-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
    let right = half_space(&p, [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]);
    let d = [
        partition_distance(&left, Depth::Function),
        partition_distance(&right, Depth::Function),
    ];
    // Period 0.2 on the left, 0.4 on the right.
    let period = transfinite(&[Expr::constant(0.2), Expr::constant(0.4)], &d);
    // Cell shape: tori on the left, a sphere on the right, by metamorphosis.
    let w = transfinite_weights(&d);
    let waves = std::array::from_fn(|_| Wave::Triangle(period.clone()));
    let s = replicate_with(&waves, [-1.0; 3], [1.0; 3], |q| {
        metamorphosis(&toriball_cell(q), &sphere(q, &v3([0.0; 3]), 0.6), &w[1])
    });
    // Deep on each side it is that side's structure exactly.
    let tori = volumetric(&toriball_cell(&p), Kind::Triangle, 0.2, [-1.0; 3], [1.0; 3]);
    let ball = volumetric(
        &sphere(&p, &v3([0.0; 3]), 0.6),
        Kind::Triangle,
        0.4,
        [-1.0; 3],
        [1.0; 3],
    );
    for q in spread(-0.5, 0.5, 30) {
        let l = [q[0] - 2.0, q[1], q[2]];
        let r = [q[0] + 2.0, q[1], q[2]];
        assert!((at(&s, l) - at(&tori, l)).abs() < 1e-9);
        assert!((at(&s, r) - at(&ball, r)).abs() < 1e-9);
    }
    // In between, both the period and the shape are mixed.
    let m = [0.0, 0.05, 0.0];
    assert!((at(&s, m) - at(&tori, m)).abs() > 1e-3 && (at(&s, m) - at(&ball, m)).abs() > 1e-3);
}

#[test]
fn metamorphosis_algorithm_2() {
    let p = Expr::xyz();
    let (tori, ball) = (toriball_cell(&p), sphere(&p, &v3([0.0; 3]), 0.8));
    let m = metamorphosis(&ball, &tori, &ramp(&Expr::z(), -10.0, 10.0));
    for q in spread(-1.0, 1.0, 30) {
        let t = (q[2] + 10.0) / 20.0;
        let want = at(&tori, q) * t + at(&ball, q) * (1.0 - t);
        assert!((at(&m, q) - want).abs() < 1e-9);
    }
    // Clamped beyond the ramp.
    let far = [0.3, 0.1, 15.0];
    assert!((at(&m, far) - at(&tori, far)).abs() < 1e-12);
}

#[test]
fn period_driven_by_distance_to_outer_shell() {
    // Period 0.1 at the unit sphere's surface, 0.3 from depth 0.5 inwards.
    let period = graded_by_depth(&unit_sphere(), Depth::Normalized, 0.5, 0.1, 0.3);
    let s = volumetric(
        &toriball_cell(&Expr::xyz()),
        Kind::Sawtooth,
        period.clone(),
        [-1.0; 3],
        [1.0; 3],
    );
    let fixed = volumetric(
        &toriball_cell(&Expr::xyz()),
        Kind::Sawtooth,
        0.3,
        [-1.0; 3],
        [1.0; 3],
    );
    for q in spread(-0.2, 0.2, 20) {
        assert!((at(&s, q) - at(&fixed, q)).abs() < 1e-9);
    }
    assert!((at(&period, [0.0, 1.0, 0.0]) - 0.1).abs() < 1e-12);
}

#[test]
fn multiscale_nesting() {
    // Fine tori-ball structure with a hole cut in each coarse cell, used as
    // the unit cell of a coarser replication.
    let p = Expr::xyz();
    let fine = volumetric(
        &toriball_cell(&p),
        Kind::Triangle,
        0.25,
        [-1.0; 3],
        [1.0; 3],
    );
    let cell = subtraction(&fine, &sphere(&p, &v3([0.0; 3]), 0.5), 0.0);
    let coarse = volumetric(&cell, Kind::Triangle, 3.0, [-1.0; 3], [1.0; 3]);
    for q in spread(-1.4, 1.4, 40) {
        // Within the central coarse cell (width 3 maps [-1.5, 1.5] onto [-1, 1]).
        let inner = q.map(|c| c / 1.5);
        assert!((at(&coarse, q) - at(&cell, inner)).abs() < 1e-9);
    }
    // The coarse cell's hole is empty, the fine structure present outside it.
    assert!(at(&coarse, [0.0, 0.0, 0.0]) < 0.0);
    assert!(at(&coarse, [0.0, 0.0, 3.0]) < 0.0);
}
