//! Noise: Gardner's series against its formula and HyperFun's values; the
//! seeded gradient noise for determinism, range, lattice zeros, period,
//! gradient against central differences, interval soundness and batch mode.

// Expected values are the reference interpreter's, 17 significant digits.
#![allow(clippy::excessive_precision)]

use microfrep_core::noise::{gradient_noise, noise_g, GradientNoise, NOISE_BOUND, NOISE_SLOPE};
use microfrep_core::{BatchEval, Expr, Field, GradEval, Interval, IntervalEval, PointEval, Tape};

type P = [f64; 3];

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn point(&mut self, h: f64) -> P {
        [self.range(-h, h), self.range(-h, h), self.range(-h, h)]
    }
}

fn gardner(q: P, amp: f64, w: f64, ph: f64) -> f64 {
    let a2 = amp / 1.17;
    let s = q.map(|v| (w * v).sin());
    let sx = amp * s[0] + a2 * (w * q[0] / 1.35 + ph * s[2]).sin();
    let sy = amp * s[1] + a2 * (w * q[1] / 1.35 + ph * s[0]).sin();
    let sz = amp * s[2] + a2 * (w * q[2] / 1.35 + ph * s[1]).sin();
    sx * sy * sz
}

#[test]
fn gardner_noise_matches_formula_and_hyperfun() {
    let e = noise_g(&Expr::xyz(), 2.5, 0.7, 1.4);
    let tape = Tape::new(&e);
    let mut pe = PointEval::new(&tape);
    let probes = [
        ([0.3, 0.4, 0.5], 6.5758250111186065),
        ([1.5, -0.7, 2.2], 5.8980731150730747),
        ([-2.5, 1.25, -0.75], -0.21783551934330195),
        ([1.8, 2.1, 0.0], 33.570205302850404),
    ];
    for (q, w) in probes {
        assert!(
            (pe.eval(q) - w).abs() < 1e-12 * (1.0 + w.abs()),
            "{q:?}: {} vs {w}",
            pe.eval(q)
        );
    }
    let mut rng = Rng(1);
    let mut ge = GradEval::new(&tape);
    let mut ie = IntervalEval::new(&tape);
    for _ in 0..100 {
        let q = rng.point(10.0);
        let w = gardner(q, 2.5, 0.7, 1.4);
        assert!((pe.eval(q) - w).abs() < 1e-12 * (1.0 + w.abs()));
        let (_, g) = ge.eval(q);
        for a in 0..3 {
            let (mut lo, mut hi) = (q, q);
            lo[a] -= 1e-5;
            hi[a] += 1e-5;
            let fd = (gardner(hi, 2.5, 0.7, 1.4) - gardner(lo, 2.5, 0.7, 1.4)) / 2e-5;
            assert!((fd - g[a]).abs() < 1e-4 * (1.0 + fd.abs()));
        }
        let r = rng.range(0.0, 1.0);
        let iv = ie.eval(
            Interval::new(q[0] - r, q[0] + r),
            Interval::new(q[1], q[1] + r),
            Interval::new(q[2] - r, q[2]),
        );
        for _ in 0..10 {
            let s = [
                q[0] + r * rng.range(-1.0, 1.0),
                q[1] + r * rng.next(),
                q[2] - r * rng.next(),
            ];
            assert!(iv.contains(gardner(s, 2.5, 0.7, 1.4)));
        }
    }
}

#[test]
fn gradient_noise_is_deterministic_and_seeded() {
    let (a, b, c) = (
        GradientNoise::new(42),
        GradientNoise::new(42),
        GradientNoise::new(43),
    );
    let mut rng = Rng(2);
    let mut differ = 0;
    for _ in 0..1000 {
        let q = rng.point(50.0);
        assert_eq!(a.eval(q).to_bits(), b.eval(q).to_bits());
        if (a.eval(q) - c.eval(q)).abs() > 1e-3 {
            differ += 1;
        }
    }
    assert!(differ > 900, "seeds 42 and 43 agree too often ({differ})");
    // Values pinned for seed 42, so a change of the construction shows.
    let pinned = [a.eval([0.5, 0.25, 0.125]), a.eval([-3.7, 12.1, 100.9])];
    assert_eq!(pinned.map(|v| (v * 1e12).round() / 1e12), PINNED_42);
}

const PINNED_42: [f64; 2] = [-0.414147749543, -0.139244742437];

#[test]
fn gradient_noise_range_lattice_zeros_and_period() {
    let n = GradientNoise::new(7);
    let mut rng = Rng(3);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for _ in 0..100_000 {
        let q = rng.point(300.0);
        let v = n.eval(q);
        assert!(v.abs() <= NOISE_BOUND);
        lo = lo.min(v);
        hi = hi.max(v);
        // Period 256 on each axis.
        let w = n.eval([q[0] + 256.0, q[1] - 512.0, q[2] + 256.0]);
        assert!((v - w).abs() < 1e-9);
    }
    assert!(lo < -0.6 && hi > 0.6, "range [{lo}, {hi}] looks degenerate");
    for i in -5..5 {
        assert_eq!(n.eval([i as f64, (2 * i) as f64, 7.0 - i as f64]), 0.0);
    }
    assert!(n.eval([f64::NAN, 0.5, 0.5]).is_nan());
    assert!(n.eval([f64::INFINITY, 0.5, 0.5]).is_nan());
}

#[test]
fn gradient_noise_gradient_matches_differences_and_slope_bound() {
    let n = GradientNoise::new(11);
    let mut rng = Rng(4);
    for _ in 0..2000 {
        let q = rng.point(20.0);
        let (v, g) = n.grad(q);
        assert_eq!(v, n.eval(q));
        for a in 0..3 {
            assert!(g[a].abs() <= NOISE_SLOPE);
            let (mut lo, mut hi) = (q, q);
            lo[a] -= 1e-6;
            hi[a] += 1e-6;
            let fd = (n.eval(hi) - n.eval(lo)) / 2e-6;
            assert!((fd - g[a]).abs() < 1e-5, "{q:?} d{a}: {fd} vs {}", g[a]);
        }
    }
}

#[test]
fn gradient_noise_intervals_are_sound() {
    let n = GradientNoise::new(5);
    let mut rng = Rng(6);
    for k in 0..400 {
        let c = rng.point(30.0);
        let w = [0.01, 0.1, 0.5, 3.0][k % 4];
        let b: [Interval; 3] = std::array::from_fn(|a| {
            let r = w * rng.next();
            Interval::new(c[a] - r, c[a] + r)
        });
        let iv = n.interval(b);
        assert!(iv.lo >= -NOISE_BOUND && iv.hi <= NOISE_BOUND);
        // The bound shrinks with the box: slope bound times the half widths.
        let reach: f64 = b.iter().map(|i| 0.5 * i.width()).sum();
        assert!(
            iv.width() <= 2.0 * NOISE_SLOPE * reach + 1e-9,
            "{iv:?} over {b:?}"
        );
        for _ in 0..30 {
            let q: P = std::array::from_fn(|a| rng.range(b[a].lo, b[a].hi));
            assert!(iv.contains(n.eval(q)), "{} outside {iv:?}", n.eval(q));
        }
    }
    let unbounded = n.interval([Interval::ENTIRE, Interval::point(0.0), Interval::point(0.0)]);
    assert_eq!(unbounded, Interval::new(-NOISE_BOUND, NOISE_BOUND));
}

#[test]
fn gradient_noise_in_a_graph_all_modes() {
    // Frequency 3 through a mapped point, plus an offset.
    let p = Expr::xyz().map(|c| 3.0 * c);
    let e = gradient_noise(&p, 9) + 0.25;
    let n = GradientNoise::new(9);
    let tape = Tape::new(&e);
    let (mut pe, mut ge, mut ie) = (
        PointEval::new(&tape),
        GradEval::new(&tape),
        IntervalEval::new(&tape),
    );
    let mut rng = Rng(8);
    let pts: Vec<P> = (0..300).map(|_| rng.point(5.0)).collect();
    for q in &pts {
        let (v, g) = ge.eval(*q);
        let (w, gw) = n.grad(q.map(|c| 3.0 * c));
        assert!((pe.eval(*q) - (w + 0.25)).abs() < 1e-15 && (v - (w + 0.25)).abs() < 1e-15);
        for a in 0..3 {
            assert!((g[a] - 3.0 * gw[a]).abs() < 1e-12);
        }
        let iv = ie.eval(
            Interval::new(q[0], q[0] + 0.05),
            Interval::point(q[1]),
            Interval::new(q[2] - 0.05, q[2]),
        );
        assert!(iv.contains(pe.eval(*q)) && iv.contains(pe.eval([q[0] + 0.05, q[1], q[2] - 0.05])));
    }
    let cols: [Vec<f32>; 3] = std::array::from_fn(|a| pts.iter().map(|q| q[a] as f32).collect());
    let mut out = vec![0.0f32; pts.len()];
    BatchEval::new(&tape).eval(&cols[0], &cols[1], &cols[2], &mut out);
    for i in 0..pts.len() {
        let v = pe.eval([cols[0][i] as f64, cols[1][i] as f64, cols[2][i] as f64]);
        assert!((out[i] as f64 - v).abs() < 1e-4, "{} vs {v}", out[i]);
    }
}
