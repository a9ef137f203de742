//! FRep operations against their definitions: R-function identities and sign
//! rules, blends, offsets, metamorphosis, smooth n-ary operations, bias/gain
//! and the replicating waves.

use microfrep_core::{frep, Expr, PointEval, Tape};
use proptest::prelude::*;

fn eval(e: &Expr, p: [f64; 3]) -> f64 {
    PointEval::new(&Tape::new(e)).eval(p)
}

/// Values of f1 = x and f2 = y: zeros, and both signs over eight decades
/// (the sign rules are exact while |f1|/|f2| stays well inside 1/eps).
fn arg() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        (-4.0f64..4.0, any::<bool>()).prop_map(|(e, s)| if s {
            10f64.powf(e)
        } else {
            -(10f64.powf(e))
        }),
    ]
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 2000,
        failure_persistence: None,
        // A fixed seed keeps runs reproducible.
        rng_seed: proptest::test_runner::RngSeed::Fixed(3),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    /// For any alpha in [0, 1]: the union is inside exactly where either
    /// argument is, the intersection where both are, the subtraction where
    /// the first is and the second is not.
    #[test]
    fn r_function_signs(f1 in arg(), f2 in arg(), alpha in prop_oneof![Just(0.0), Just(1.0), 0.0f64..1.0]) {
        let [x, y, _] = Expr::xyz();
        // Alpha as a parameter, so the general formula runs even at alpha = 1.
        let a = Expr::param("alpha", alpha);
        let p = [f1, f2, 0.0];
        let u = eval(&frep::union(&x, &y, a.clone()), p);
        let i = eval(&frep::intersection(&x, &y, a.clone()), p);
        let s = eval(&frep::subtraction(&x, &y, a), p);
        prop_assert_eq!(u >= 0.0, f1 >= 0.0 || f2 >= 0.0, "union {} at alpha {}", u, alpha);
        prop_assert_eq!(i >= 0.0, f1 >= 0.0 && f2 >= 0.0, "intersection {} at alpha {}", i, alpha);
        prop_assert_eq!(s >= 0.0, f1 >= 0.0 && -f2 >= 0.0, "subtraction {} at alpha {}", s, alpha);
    }

    /// Alpha = 1 gives max/min exactly (the constant shortcut); the general
    /// formula agrees with them to sqrt(eps) relative, as `sqrt(f1^2 + f2^2 -
    /// 2 f1 f2)` cancels when f1 is close to f2.
    #[test]
    fn alpha_one_is_max_min(f1 in -1e3f64..1e3, f2 in -1e3f64..1e3) {
        let [x, y, _] = Expr::xyz();
        let p = [f1, f2, 0.0];
        prop_assert_eq!(eval(&frep::union(&x, &y, 1.0), p), f1.max(f2));
        prop_assert_eq!(eval(&frep::intersection(&x, &y, 1.0), p), f1.min(f2));
        prop_assert_eq!(eval(&frep::subtraction(&x, &y, 1.0), p), f1.min(-f2));
        let one = Expr::param("alpha", 1.0);
        let tol = 1e-7 * (f1.abs() + f2.abs());
        prop_assert!((eval(&frep::union(&x, &y, one.clone()), p) - f1.max(f2)).abs() <= tol);
        prop_assert!((eval(&frep::intersection(&x, &y, one), p) - f1.min(f2)).abs() <= tol);
    }

    /// Alpha = 0 is HyperFun's `f1 + f2 +- sqrt(f1^2 + f2^2)`.
    #[test]
    fn alpha_zero_closed_form(f1 in -1e3f64..1e3, f2 in -1e3f64..1e3) {
        let [x, y, _] = Expr::xyz();
        let p = [f1, f2, 0.0];
        let r = (f1 * f1 + f2 * f2).sqrt();
        prop_assert_eq!(eval(&frep::union(&x, &y, 0.0), p), f1 + f2 + r);
        prop_assert_eq!(eval(&frep::intersection(&x, &y, 0.0), p), f1 + f2 - r);
    }

    /// Eq. 7: the blend adds `a0 / (1 + (f1/a1)^2 + (f2/a2)^2)` to the R-function.
    #[test]
    fn blends_match_eq7(f1 in -3.0f64..3.0, f2 in -3.0f64..3.0, a0 in -1.0f64..1.0, a1 in 0.1f64..2.0, a2 in 0.1f64..2.0) {
        let [x, y, _] = Expr::xyz();
        let b = frep::Blend::new(a0, a1, a2);
        let p = [f1, f2, 0.0];
        let disp = |g1: f64, g2: f64| a0 / (1.0 + (g1 / a1).powi(2) + (g2 / a2).powi(2));
        let r = (f1 * f1 + f2 * f2).sqrt();
        let rn = (f1 * f1 + f2 * f2).sqrt();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (1.0 + b.abs());
        prop_assert!(close(eval(&frep::blend_union(&x, &y, &b, 0.0), p), f1 + f2 + r + disp(f1, f2)));
        prop_assert!(close(eval(&frep::blend_intersection(&x, &y, &b, 0.0), p), f1 + f2 - r + disp(f1, f2)));
        prop_assert!(close(eval(&frep::blend_subtraction(&x, &y, &b, 0.0), p), f1 - f2 - rn + disp(f1, -f2)));
    }

    /// Metamorphosis interpolates linearly and hits both ends exactly.
    #[test]
    fn morph_interpolates(f1 in -10.0f64..10.0, f2 in -10.0f64..10.0, t in 0.0f64..1.0) {
        let [x, y, z] = Expr::xyz();
        let m = frep::morph(&x, &y, z);
        prop_assert_eq!(eval(&m, [f1, f2, 0.0]), f1);
        prop_assert_eq!(eval(&m, [f1, f2, 1.0]), f2);
        let v = eval(&m, [f1, f2, t]);
        prop_assert!((v - (f1 + (f2 - f1) * t)).abs() <= 1e-13 * (1.0 + f1.abs() + f2.abs()));
    }

    /// Smooth n-ary operations lie between the max (min) and n^(1/a) times it,
    /// so they tend to max (min) as the exponent grows.
    #[test]
    fn smooth_n_ary_bounds(fs in prop::collection::vec(0.01f64..10.0, 3), a in prop::sample::select(vec![1.0, 2.0, 8.0, 64.0])) {
        let [x, y, z] = Expr::xyz();
        let args = [x, y, z];
        let p = [fs[0], fs[1], fs[2]];
        let max = fs.iter().cloned().fold(0.0, f64::max);
        let min = fs.iter().cloned().fold(f64::INFINITY, f64::min);
        let k = 3f64.powf(1.0 / a);
        let u = eval(&frep::smooth_union_n(&args, a), p);
        let i = eval(&frep::smooth_intersection_n(&args, a), p);
        let eps = 1e-12;
        prop_assert!(u >= max * (1.0 - eps) && u <= k * max * (1.0 + eps), "union {} max {} a {}", u, max, a);
        prop_assert!(i <= min * (1.0 + eps) && i >= min / k * (1.0 - eps), "intersection {} min {} a {}", i, min, a);
    }

    /// Bias and gain: bias(0.5) = b, gain(0.25) = 0.5 - g/2, gain(0.75) = 0.5 + g/2.
    #[test]
    fn bias_gain_closed_values(b in 0.05f64..0.95, g in 0.05f64..0.95) {
        let t = Expr::x();
        let bias = frep::bias(&t, b);
        let gain = frep::gain(&t, g);
        prop_assert!((eval(&bias, [0.5, 0.0, 0.0]) - b).abs() < 1e-14);
        prop_assert_eq!(eval(&bias, [0.0, 0.0, 0.0]), 0.0);
        prop_assert_eq!(eval(&bias, [1.0, 0.0, 0.0]), 1.0);
        prop_assert!((eval(&gain, [0.25, 0.0, 0.0]) - (0.5 - g / 2.0)).abs() < 1e-14);
        prop_assert!((eval(&gain, [0.75, 0.0, 0.0]) - (0.5 + g / 2.0)).abs() < 1e-14);
        prop_assert!((eval(&gain, [0.5, 0.0, 0.0]) - 0.5).abs() < 1e-14);
    }

    /// Waves stay in [0, 1]; the sawtooth has period a, the triangle 2a and
    /// equals `1/2 + asin(sin(pi t/a))/pi`.
    #[test]
    fn waves_range_period_and_reference(t in -50.0f64..50.0, a in prop::sample::select(vec![0.2, 0.5, 1.0, 3.0])) {
        let x = Expr::x();
        let saw = Tape::new(&frep::sawtooth(&x, a));
        let tri = Tape::new(&frep::triangle(&x, a));
        let (mut s, mut w) = (PointEval::new(&saw), PointEval::new(&tri));
        let sv = s.eval([t, 0.0, 0.0]);
        let tv = w.eval([t, 0.0, 0.0]);
        prop_assert!((0.0..=1.0).contains(&sv) && (0.0..=1.0).contains(&tv));
        // Away from the sawtooth's jumps (at (k + 1/2) a) it repeats with period a.
        let phase = (t / a + 0.5).rem_euclid(1.0);
        if phase > 1e-9 && phase < 1.0 - 1e-9 {
            prop_assert!((s.eval([t + a, 0.0, 0.0]) - sv).abs() < 1e-12);
            prop_assert!((s.eval([t - 3.0 * a, 0.0, 0.0]) - sv).abs() < 1e-12);
        }
        prop_assert!((w.eval([t + 2.0 * a, 0.0, 0.0]) - tv).abs() < 1e-12);
        prop_assert!((w.eval([t - 4.0 * a, 0.0, 0.0]) - tv).abs() < 1e-12);
        // The asin(sin) reference loses accuracy near its peaks (asin' -> inf):
        // there it is itself only good to about sqrt(eps).
        let sin = (std::f64::consts::PI * t / a).sin();
        let reference = 0.5 + sin.asin() / std::f64::consts::PI;
        let tol = if sin.abs() < 0.999 { 1e-12 } else { 1e-7 };
        prop_assert!((tv - reference).abs() < tol, "tri {} reference {}", tv, reference);
    }
}

/// Sawtooth replication of a fully connected cell (its values agree on
/// opposite faces) is continuous across cell faces; a cell without that
/// property jumps, which shows the check can fail.
#[test]
fn sawtooth_replication_of_connected_cell_is_continuous() {
    use std::f64::consts::TAU;
    let a = 0.4;
    let [x, y, z] = Expr::xyz();
    let q = [
        frep::sawtooth(&x, a),
        frep::sawtooth(&y, a),
        frep::sawtooth(&z, a),
    ];
    // Periodic cell on [0, 1]^3: a Schwarz-P like level function.
    let [u, v, w] = Expr::xyz();
    let cell = (TAU * &u).cos() + (TAU * &v).cos() + (TAU * &w).cos();
    let open_cell = &u + &v; // values differ on opposite faces
    let rep = Tape::new(&cell.remap(&q));
    let rep_open = Tape::new(&open_cell.remap(&q));
    let (mut pe, mut po) = (PointEval::new(&rep), PointEval::new(&rep_open));
    let h = 1e-9;
    let mut worst = 0.0f64;
    let mut worst_open = 0.0f64;
    for k in -5..5 {
        let face = (k as f64 + 0.5) * a;
        for s in 0..7 {
            let o = 0.13 * s as f64 - 0.4;
            for p in [[face, o, 0.3 * o], [o, face, -o], [0.7 * o, o, face]] {
                let near = |d: f64| p.map(|c| if c == face { c + d } else { c });
                worst = worst.max((pe.eval(near(-h)) - pe.eval(near(h))).abs());
                worst_open = worst_open.max((po.eval(near(-h)) - po.eval(near(h))).abs());
            }
        }
    }
    // Lipschitz constant of the replicated cell is 3 * 2 pi / a < 50.
    assert!(worst < 50.0 * 2.0 * h + 1e-12, "jump {worst}");
    assert!(worst_open > 0.5, "open cell should jump, {worst_open}");
}

/// The normalised offset of a sphere `r^2 - |p|^2` moves its zero set out by about d,
/// while the plain offset `f + d` moves it by d / (2r) to first order.
#[test]
fn normalized_offset_moves_sphere_by_d() {
    let [x, y, z] = Expr::xyz();
    let r = 1.0;
    let f = r * r - (x.square() + y.square() + z.square());
    for d in [-0.1, -0.02, 0.02, 0.05, 0.1] {
        let tape = Tape::new(&frep::normalized_offset(&f, d));
        let mut pe = PointEval::new(&tape);
        for dir in [[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [-0.48, 0.6, -0.64]] {
            // Bisection for the zero along the ray (inside at 0.5, outside at 2).
            let at = |t: f64| dir.map(|c: f64| c * t);
            let (mut lo, mut hi) = (0.5, 2.0);
            assert!(pe.eval(at(lo)) > 0.0 && pe.eval(at(hi)) < 0.0);
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if pe.eval(at(m)) >= 0.0 {
                    lo = m
                } else {
                    hi = m
                }
            }
            let moved = lo - r;
            // Exact root of u / sqrt(u^2 + 4 rho^2) = -d with u = r^2 - rho^2.
            assert!((moved - d).abs() < 0.1 * d.abs(), "d {d}: moved {moved}");
        }
    }
}
