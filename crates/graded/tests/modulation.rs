//! Bias, gain, noise modulation, Park's union_a / intersect_a and depth:
//! defining values, limits, closed forms, sign rules and sound intervals.

use microfrep_core::{frep, Expr, Interval, IntervalEval, PointEval, Tape};
use microfrep_graded::depth::{depth, first_order_depth, Reference};
use microfrep_graded::dmf::{
    bias, bias_value, gain, gain_value, noise_modulated, sketch, turbulence,
};
use microfrep_graded::smooth::{intersect_a, intersect_a_value, union_a, union_a_value};

fn at(e: &Expr, p: [f64; 3]) -> f64 {
    PointEval::new(&Tape::new(e)).eval(p)
}

fn t_of(t: f64) -> [f64; 3] {
    [t, 0.0, 0.0]
}

#[test]
fn bias_hits_its_defining_values() {
    let t = Expr::x();
    for b in [0.1, 0.25, 0.5, 0.7, 0.9] {
        let e = bias(&t, b);
        assert_eq!(at(&e, t_of(0.0)), 0.0);
        assert!((at(&e, t_of(0.5)) - b).abs() < 1e-15, "b = {b}");
        assert_eq!(at(&e, t_of(1.0)), 1.0);
        assert!((bias_value(0.5, b) - b).abs() < 1e-15);
        // The core's bias is the same formula on [0, 1].
        let core = frep::bias(&t, b);
        for k in 0..=20 {
            let v = k as f64 / 20.0;
            assert!((at(&core, t_of(v)) - at(&e, t_of(v))).abs() < 1e-15);
        }
        // Clamped outside [0, 1]: never NaN.
        assert_eq!(at(&e, t_of(-0.5)), 0.0);
        assert_eq!(at(&e, t_of(1.5)), 1.0);
    }
    // b > 0.5 pushes the density up, b < 0.5 down.
    assert!(bias_value(0.3, 0.8) > 0.3 && bias_value(0.3, 0.2) < 0.3);
}

#[test]
fn gain_hits_its_defining_values() {
    let t = Expr::x();
    for g in [0.1, 0.3, 0.5, 0.8, 0.95] {
        let e = gain(&t, g);
        let want = [
            (0.0, 0.0),
            (0.25, 0.5 - g / 2.0),
            (0.5, 0.5),
            (0.75, 0.5 + g / 2.0),
            (1.0, 1.0),
        ];
        for (x, v) in want {
            assert!((at(&e, t_of(x)) - v).abs() < 1e-14, "g {g} t {x}");
            assert!((gain_value(x, g) - v).abs() < 1e-14);
        }
        let core = frep::gain(&t, g);
        let mut last = -1.0;
        for k in 0..=40 {
            let v = k as f64 / 40.0;
            let y = at(&e, t_of(v));
            assert!((at(&core, t_of(v)) - y).abs() < 1e-14);
            assert!(y >= last, "gain not monotone at {v}");
            last = y;
        }
        assert_eq!(at(&e, t_of(-1.0)), 0.0);
        assert_eq!(at(&e, t_of(2.0)), 1.0);
    }
    // g > 0.5 steepens the middle (below the identity on the lower half),
    // g < 0.5 flattens it.
    assert!(gain_value(0.4, 0.8) < 0.4 && gain_value(0.4, 0.2) > 0.4);
}

#[test]
fn sketch_is_gain_of_bias_and_intervals_contain_values() {
    let t = Expr::x();
    let e = sketch(&t, 0.3, 0.7);
    for k in 0..=50 {
        let v = -0.2 + 1.4 * k as f64 / 50.0;
        let want = gain_value(bias_value(v, 0.3), 0.7);
        assert!((at(&e, t_of(v)) - want).abs() < 1e-14);
    }
    let tape = Tape::new(&e);
    let mut iv = IntervalEval::new(&tape);
    let mut pe = PointEval::new(&tape);
    for k in 0..40 {
        let lo = -0.3 + 0.035 * k as f64;
        let hi = lo + 0.1;
        let b = iv.eval(
            Interval::new(lo, hi),
            Interval::point(0.0),
            Interval::point(0.0),
        );
        for s in 0..=10 {
            let v = pe.eval([lo + (hi - lo) * s as f64 / 10.0, 0.0, 0.0]);
            assert!(b.contains(v), "{v} outside {b:?}");
        }
    }
}

#[test]
fn noise_modulation_stays_in_range() {
    let p = Expr::xyz();
    let tb = turbulence(&p, 3.0, 4, 7);
    let m = noise_modulated(&Expr::x(), &p, 0.3, 5.0, 11);
    let (tt, tm) = (Tape::new(&tb), Tape::new(&m));
    let (mut et, mut em) = (PointEval::new(&tt), PointEval::new(&tm));
    let mut varied = false;
    for i in 0..500 {
        let q = [
            (i as f64 * 0.37).fract(),
            (i as f64 * 0.61).fract(),
            (i as f64 * 0.13).fract(),
        ];
        let v = et.eval(q);
        assert!((0.0..=4.0).contains(&v), "turbulence {v}");
        let w = em.eval(q);
        assert!((0.0..=1.0).contains(&w), "modulated {w}");
        varied |= (w - q[0].clamp(0.0, 1.0)).abs() > 0.01;
    }
    assert!(varied, "noise changed nothing");
}

/// Deterministic values in [-3, 3] with both signs.
fn sets() -> Vec<Vec<f64>> {
    let mut s = 0x1234_5678u64;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 6.0 - 3.0
    };
    (0..200)
        .map(|k| (0..2 + k % 4).map(|_| next()).collect())
        .collect()
}

#[test]
fn union_a_and_intersect_a_tend_to_max_and_min() {
    for fs in sets() {
        let n = fs.len() as f64;
        let max = fs.iter().copied().fold(f64::MIN, f64::max);
        let min = fs.iter().copied().fold(f64::MAX, f64::min);
        let mut last = (f64::INFINITY, f64::INFINITY);
        for a in [1.0, 2.0, 4.0, 16.0, 64.0, 256.0, 1024.0] {
            let u = union_a_value(&fs, a);
            let i = intersect_a_value(&fs, a);
            let bound = (n.powf(1.0 / a) - 1.0) * max.abs() + 1e-12;
            assert!(u >= max - 1e-12 && u - max <= bound, "{fs:?} a {a}: {u}");
            let bound = (n.powf(1.0 / a) - 1.0) * min.abs() + 1e-12;
            assert!(i <= min + 1e-12 && min - i <= bound, "{fs:?} a {a}: {i}");
            let err = ((u - max).abs(), (i - min).abs());
            assert!(err.0 <= last.0 + 1e-12 && err.1 <= last.1 + 1e-12);
            last = err;
            // The sign rule of max and min holds exactly.
            assert_eq!(u >= 0.0, max >= 0.0);
            assert_eq!(i >= 0.0, min >= 0.0);
        }
        assert!(last.0 <= 0.002 * max.abs() + 1e-12 && last.1 <= 0.002 * min.abs() + 1e-12);
    }
}

#[test]
fn union_a_is_parks_power_sum_for_positive_arguments() {
    let fs = [0.3, 1.7, 0.9];
    for a in [1.0, 3.0, 5.0] {
        let park_i = fs
            .iter()
            .map(|f: &f64| f.powf(a))
            .sum::<f64>()
            .powf(1.0 / a);
        let park_u = fs
            .iter()
            .map(|f: &f64| f.powf(-a))
            .sum::<f64>()
            .powf(-1.0 / a);
        assert!((union_a_value(&fs, a) - park_i).abs() < 1e-14);
        assert!((intersect_a_value(&fs, a) - park_u).abs() < 1e-14);
        // Park's femur union of quadratic forms q (surface at 1) is
        // 1 / union_a(1/q).
        let inv: Vec<f64> = fs.iter().map(|q| 1.0 / q).collect();
        assert!((park_u - 1.0 / union_a_value(&inv, a)).abs() < 1e-14);
    }
    // No overflow: the core's unscaled power sum is infinite here.
    let big = [1e6, 2e6];
    let u = union_a_value(&big, 400.0);
    assert!(u.is_finite() && (u - 2e6).abs() < 2e6 * 0.002, "{u}");
    assert!(2e6f64.powf(400.0).is_infinite());
}

#[test]
fn union_a_expressions_match_the_reference_in_every_mode() {
    let p = Expr::xyz();
    let fs = [
        &p[0] - 0.2,
        0.5 - &p[1],
        (&p[2] * &p[0]) - 0.1,
        Expr::constant(-0.3),
    ];
    for a in [2.0, 7.5] {
        let (u, i) = (union_a(&fs, a), intersect_a(&fs, a));
        let tape = Tape::with_outputs(&[u, i]);
        let mut pe = PointEval::new(&tape);
        let mut iv = IntervalEval::new(&tape);
        for k in 0..300 {
            let q = [
                -1.0 + 2.0 * (k as f64 * 0.381_966).fract(),
                -1.0 + 2.0 * (k as f64 * 0.618_034).fract(),
                -1.0 + 2.0 * (k as f64 * 0.236_068).fract(),
            ];
            let vals: Vec<f64> = vec![q[0] - 0.2, 0.5 - q[1], q[2] * q[0] - 0.1, -0.3];
            let got = pe.eval_all(q);
            assert!((got[0] - union_a_value(&vals, a)).abs() < 1e-12, "{q:?}");
            assert!(
                (got[1] - intersect_a_value(&vals, a)).abs() < 1e-12,
                "{q:?}"
            );
            let b = q.map(|c| Interval::new(c - 0.05, c + 0.05));
            let bounds = iv.eval_all(b[0], b[1], b[2]);
            for s in 0..8 {
                let r: [f64; 3] =
                    std::array::from_fn(|d| if s >> d & 1 == 1 { b[d].hi } else { b[d].lo });
                let v = pe.eval_all(r);
                assert!(bounds[0].contains(v[0]) && bounds[1].contains(v[1]));
            }
        }
    }
    assert_eq!(union_a(&[], 3.0).as_const(), Some(f64::NEG_INFINITY));
    assert_eq!(intersect_a(&[], 3.0).as_const(), Some(f64::INFINITY));
}

#[test]
fn depth_of_a_distance_is_exact_and_of_a_function_follows_the_closed_forms() {
    let p = Expr::xyz();
    let r = (p[0].square() + p[1].square() + p[2].square()).sqrt();
    let dist = Reference::Distance(1.0 - &r);
    let r2 = p[0].square() + p[1].square() + p[2].square();
    let func = Reference::Function(1.0 - &r2);
    // A true distance with no singular point: the half-space z <= 1.
    let ndist = depth(&(1.0 - &p[2]));
    for d in [0.05, 0.1, 0.3, 0.6, 1.0] {
        let rr = 1.0 - d;
        let q = [0.0, 0.0, rr];
        let d = 1.0 - rr;
        assert_eq!(at(&dist.depth(), q), d);
        // A distance normalised: d / sqrt(1 + d^2).
        let nd = at(&ndist, q);
        assert!((nd - d / (1.0 + d * d).sqrt()).abs() < 1e-14, "{nd} {d}");
        // The ball's function: (1 - r^2)/(1 + r^2).
        let nb = at(&func.depth(), q);
        assert!((nb - (1.0 - rr * rr) / (1.0 + rr * rr)).abs() < 1e-14);
    }
    // The accuracy figures stated in the docs.
    let rel = |e: &Expr, d: f64| at(e, [0.0, 0.0, 1.0 - d]) / d - 1.0;
    assert!((rel(&ndist, 0.1) + 0.005).abs() < 0.0005);
    assert!((rel(&ndist, 0.3) + 0.042).abs() < 0.001);
    assert!((rel(&ndist, 1.0) + 0.29).abs() < 0.005);
    assert!((rel(&func.depth(), 0.1) - 0.050).abs() < 0.001);
    assert!((rel(&func.depth(), 0.3) - 0.141).abs() < 0.002);
    // F / |grad F| = N / sqrt(1 - N^2); exact for an affine function.
    let plane = 2.0 * (0.5 - &p[2]);
    assert!((at(&first_order_depth(&plane), [0.3, 0.1, 0.2]) - 0.3).abs() < 1e-15);
    let f = 1.0 - &r2;
    let q = [0.1, 0.2, 0.6];
    let n = at(&depth(&f), q);
    assert!((at(&first_order_depth(&f), q) - n / (1.0 - n * n).sqrt()).abs() < 1e-12);
}
