//! `GridField`: trilinear interpolation, its bounds and gradient, input
//! errors, and its use as an ordinary graph node in every evaluator.

use microfrep_core::field::GridError;
use microfrep_core::{
    BatchEval, Expr, Field, GradEval, GridField, Interval, IntervalEval, PointEval, Tape,
};
use proptest::prelude::*;
use std::sync::Arc;

const MIN: [f64; 3] = [-1.0, 0.0, 2.0];
const MAX: [f64; 3] = [1.0, 3.0, 2.5];
const DIMS: [usize; 3] = [5, 7, 4];

/// A trilinear function (linear in each coordinate separately): the grid
/// reproduces it exactly, up to rounding.
fn trilinear(p: [f64; 3]) -> f64 {
    let [x, y, z] = p;
    0.5 + 2.0 * x - y + 3.0 * z + 0.7 * x * y - 1.1 * y * z + 0.4 * x * y * z
}

/// A non-polynomial field, so interpolation errors show.
fn wavy(p: [f64; 3]) -> f64 {
    (3.0 * p[0]).sin() * (2.0 * p[1]).cos() + p[2] * p[2]
}

fn in_box() -> impl Strategy<Value = [f64; 3]> {
    [MIN[0]..MAX[0], MIN[1]..MAX[1], MIN[2]..MAX[2]]
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 1000,
        failure_persistence: None,
        // A fixed seed keeps runs reproducible.
        rng_seed: proptest::test_runner::RngSeed::Fixed(7),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    /// Trilinear (hence linear) functions are reproduced, value and gradient.
    #[test]
    fn reproduces_trilinear_functions(p in in_box()) {
        let g = GridField::sample("t", DIMS, MIN, MAX, trilinear).unwrap();
        let (v, d) = g.grad(p);
        prop_assert!((v - trilinear(p)).abs() < 1e-12, "{} vs {}", v, trilinear(p));
        let [x, y, z] = p;
        let want = [
            2.0 + 0.7 * y + 0.4 * y * z,
            -1.0 + 0.7 * x - 1.1 * z + 0.4 * x * z,
            3.0 - 1.1 * y + 0.4 * x * y,
        ];
        for a in 0..3 {
            prop_assert!((d[a] - want[a]).abs() < 1e-11, "axis {}: {} vs {}", a, d[a], want[a]);
        }
    }

    /// The bound over any box (also reaching outside the grid) contains the
    /// values at points of the box.
    #[test]
    fn interval_contains_values(
        c in [-1.5f64..1.5, -0.5f64..3.5, 1.8f64..2.7],
        w in [0.0f64..1.0, 0.0f64..1.0, 0.0f64..0.3],
        ts in prop::collection::vec([0.0f64..=1.0, 0.0f64..=1.0, 0.0f64..=1.0], 16),
    ) {
        let g = GridField::sample("w", DIMS, MIN, MAX, wavy).unwrap();
        let b: [Interval; 3] = std::array::from_fn(|a| Interval::new(c[a] - w[a], c[a] + w[a]));
        let bound = g.interval(b);
        prop_assert!(bound.lo <= bound.hi);
        for t in ts {
            let p: [f64; 3] = std::array::from_fn(|a| (b[a].lo + (b[a].hi - b[a].lo) * t[a]).min(b[a].hi));
            let v = g.eval(p);
            prop_assert!(bound.contains(v), "{} at {:?} not in {:?}", v, p, bound);
        }
    }

    /// Inside a cell the gradient is the derivative of the interpolant.
    #[test]
    fn gradient_matches_finite_differences(p in in_box()) {
        let g = GridField::sample("w", DIMS, MIN, MAX, wavy).unwrap();
        let (_, d) = g.grad(p);
        let h = 1e-7;
        for a in 0..3 {
            let step = (MAX[a] - MIN[a]) / (DIMS[a] - 1) as f64;
            let t = (p[a] - MIN[a]) / step;
            if (t - t.round()).abs() * step < 2.0 * h {
                continue; // on a cell face the derivative jumps
            }
            let (mut q, mut r) = (p, p);
            q[a] += h;
            r[a] -= h;
            let fd = (g.eval(q) - g.eval(r)) / (2.0 * h);
            prop_assert!((d[a] - fd).abs() < 1e-6 * (1.0 + fd.abs()), "axis {}: {} vs {}", a, d[a], fd);
        }
    }

    /// As a graph node, under a transform and inside an operation, the field
    /// gives consistent results in all four evaluators.
    #[test]
    fn field_node_in_all_evaluators(p in [-0.9f64..0.9, 0.1f64..2.9, 2.05f64..2.45]) {
        let g: Arc<dyn Field> = Arc::new(GridField::sample("w", DIMS, MIN, MAX, wavy).unwrap());
        let [x, y, z] = Expr::xyz();
        // Evaluated at (y/3 - 0.5, 3x... ) mapped into the grid box, times a function.
        let q = [0.5 * &x, &y * 0.9 + 0.1, z.clone()];
        let e = Expr::field_at(g.clone(), q) * (1.0 + x.square()) - &y;
        let tape = Tape::new(&e);
        let want = g.eval([0.5 * p[0], p[1] * 0.9 + 0.1, p[2]]) * (1.0 + p[0] * p[0]) - p[1];
        let v = PointEval::new(&tape).eval(p);
        prop_assert!((v - want).abs() < 1e-12);
        let (gv, grad) = GradEval::new(&tape).eval(p);
        prop_assert!((gv - want).abs() < 1e-12);
        let h = 1e-7;
        let mut pe = PointEval::new(&tape);
        for a in 0..3 {
            let (mut s, mut r) = (p, p);
            s[a] += h;
            r[a] -= h;
            let fd = (pe.eval(s) - pe.eval(r)) / (2.0 * h);
            // Cell faces of the mapped coordinate can fall inside the stencil.
            let fd2 = { s[a] -= h / 2.0; r[a] += h / 2.0; (pe.eval(s) - pe.eval(r)) / h };
            if (fd - fd2).abs() < 1e-5 * (1.0 + fd.abs()) {
                prop_assert!((grad[a] - fd).abs() < 1e-5 * (1.0 + fd.abs()), "axis {}: {} vs {}", a, grad[a], fd);
            }
        }
        let mut out = [0.0f32];
        BatchEval::new(&tape).eval(&[p[0] as f32], &[p[1] as f32], &[p[2] as f32], &mut out);
        prop_assert!((out[0] as f64 - want).abs() < 1e-4 * (1.0 + want.abs()));
        let b = p.map(|c| Interval::new(c - 0.01, c + 0.01));
        let bound = IntervalEval::new(&tape).eval(b[0], b[1], b[2]);
        prop_assert!(bound.contains(v) && !bound.may_be_nan(), "{} not in {:?}", v, bound);
    }
}

#[test]
fn bad_input_gives_errors() {
    let v = |n: usize| vec![0.0; n];
    assert_eq!(
        GridField::new("g", [1, 2, 2], MIN, MAX, v(4)).unwrap_err(),
        GridError::TooSmall([1, 2, 2])
    );
    assert_eq!(
        GridField::new("g", [2, 2, 2], MIN, MAX, v(7)).unwrap_err(),
        GridError::WrongLength {
            dims: [2, 2, 2],
            got: 7,
            want: 8
        }
    );
    assert_eq!(
        GridField::new("g", [2, 2, 2], [0.0, 1.0, 0.0], [1.0, 1.0, 1.0], v(8)).unwrap_err(),
        GridError::BadBox(1)
    );
    assert_eq!(
        GridField::new("g", [2, 2, 2], [0.0; 3], [1.0, 1.0, f64::INFINITY], v(8)).unwrap_err(),
        GridError::BadBox(2)
    );
    let mut bad = v(8);
    bad[5] = f64::NAN;
    assert_eq!(
        GridField::new("g", [2, 2, 2], [0.0; 3], [1.0; 3], bad).unwrap_err(),
        GridError::NotFinite { index: 5 }
    );
    // Sizes whose product overflows or exceeds the limit are errors, not
    // panics or allocation failures.
    let huge = [usize::MAX, 3, 3];
    assert_eq!(
        GridField::new("g", huge, [0.0; 3], [1.0; 3], v(8)).unwrap_err(),
        GridError::TooLarge(huge)
    );
    let big = [1 << 12, 1 << 12, 1 << 12];
    assert_eq!(
        GridField::sample("g", big, [0.0; 3], [1.0; 3], |_| 0.0).unwrap_err(),
        GridError::TooLarge(big)
    );
}

/// Outside the box, coordinates clamp to the nearest boundary sample.
#[test]
fn clamps_outside_the_box() {
    let g = GridField::sample("t", DIMS, MIN, MAX, trilinear).unwrap();
    let corner = g.eval(MAX);
    assert_eq!(g.eval([5.0, 9.0, 3.0]), corner);
    assert_eq!(g.grad([5.0, 9.0, 3.0]).1, [0.0; 3]);
    assert!(g.eval([f64::NAN, 0.0, 2.0]).is_nan());
}

/// The shared four-mode harness passes on the grid field and fails on a
/// field whose interval lies.
#[test]
fn four_mode_harness_accepts_grid_and_rejects_a_liar() {
    use microfrep_core::field_check::{check_field, FieldCheck};
    let g: Arc<dyn Field> = Arc::new(GridField::sample("w", DIMS, MIN, MAX, wavy).unwrap());
    let mut cfg = FieldCheck::new([MIN, MAX]);
    // Trilinear interpolation has kinks at cell faces; the gradient check
    // skips them itself, the rest must hold everywhere.
    cfg.grad_tol = 1e-3;
    let r = check_field(&g, &cfg).unwrap();
    assert_eq!(r.points, cfg.points);
    assert_eq!(r.boxes, cfg.boxes);

    #[derive(Debug)]
    struct Liar;
    impl Field for Liar {
        fn name(&self) -> &str {
            "liar"
        }
        fn eval(&self, p: [f64; 3]) -> f64 {
            p[0]
        }
        fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
            (p[0], [1.0, 0.0, 0.0])
        }
        fn interval(&self, b: [Interval; 3]) -> Interval {
            // Too narrow by half.
            Interval::new(b[0].lo, b[0].mid())
        }
    }
    let liar: Arc<dyn Field> = Arc::new(Liar);
    let e = check_field(&liar, &FieldCheck::new([MIN, MAX])).unwrap_err();
    assert!(e.contains("outside the interval"), "{e}");
}
