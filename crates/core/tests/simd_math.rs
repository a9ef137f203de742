//! The vectorisable f32 `exp`, `ln` and `pow` of `simd_math` against f64
//! libm: at most 1 ulp over millions of random inputs spread over the whole
//! f32 range (subnormals included), and libm's special cases exactly (same
//! class, same sign of zeros and infinities) on every pair of edge values.
//! The batch evaluator's exp, ln and pow steps are these functions.

use microfrep_core::simd_math;
use microfrep_core::{BatchEval, Expr, Tape, UnaryOp};

/// splitmix64: a fixed-seed generator, so the inputs are the same every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A positive finite f32 with uniformly random bits (so every binade,
    /// subnormals included, is as likely).
    fn positive_bits(&mut self) -> f32 {
        loop {
            let v = f32::from_bits((self.next() as u32) & 0x7fff_ffff);
            if v.is_finite() && v > 0.0 {
                return v;
            }
        }
    }
}

/// The spacing of f32 values at `v` (the subnormal spacing below 2^-126).
fn ulp_at(v: f64) -> f64 {
    let a = v.abs();
    if a < f32::MIN_POSITIVE as f64 {
        return 2f64.powi(-149);
    }
    let e = ((a.to_bits() >> 52) as i32) - 1023;
    2f64.powi(e.min(127) - 23)
}

/// Error of `got` against the exact value `want` (f64 libm), in f32 ulps.
/// Beyond the f32 range, only inf (or the largest f32) is accepted.
fn ulps(got: f32, want: f64) -> f64 {
    if want.abs() > f32::MAX as f64 {
        let ok = got.is_infinite() || got.abs() == f32::MAX;
        return if ok && got.signum() as f64 == want.signum() {
            0.0
        } else {
            f64::INFINITY
        };
    }
    if got.is_nan() || got.is_infinite() {
        return f64::INFINITY;
    }
    (got as f64 - want).abs() / ulp_at(want)
}

/// Worst error so far and its input.
#[derive(Default)]
struct Worst {
    ulps: f64,
    at: (f32, f32),
    n: usize,
}

impl Worst {
    fn add(&mut self, e: f64, at: (f32, f32)) {
        self.n += 1;
        if !(e <= self.ulps) {
            self.ulps = e;
            self.at = at;
        }
    }
    fn check(&self, what: &str) {
        println!(
            "{what}: worst {:.4} ulp at {:?} over {} inputs",
            self.ulps, self.at, self.n
        );
        assert!(
            self.ulps <= 1.0,
            "{what}: {} ulp at {:?}",
            self.ulps,
            self.at
        );
    }
}

const N: usize = 2_000_000;

#[test]
fn exp_is_within_one_ulp() {
    let mut rng = Rng(1);
    let mut w = Worst::default();
    for _ in 0..N {
        // The whole range where exp is finite and above the subnormal floor...
        let x = rng.uniform(-104.0, 89.0) as f32;
        w.add(ulps(simd_math::exp(x), (x as f64).exp()), (x, 0.0));
        // ...and small arguments, where exp(x) - 1 is tiny.
        let x = (rng.uniform(-1.0, 1.0) * 2f64.powi(-((rng.next() % 30) as i32))) as f32;
        w.add(ulps(simd_math::exp(x), (x as f64).exp()), (x, 0.0));
    }
    // Every f32 near the overflow and underflow thresholds.
    for b in 0..200_000u32 {
        for x in [
            f32::from_bits(0x42b1_0000 + b),
            -f32::from_bits(0x42ce_0000 + b),
        ] {
            w.add(ulps(simd_math::exp(x), (x as f64).exp()), (x, 0.0));
        }
    }
    w.check("exp");
}

#[test]
fn ln_is_within_one_ulp() {
    let mut rng = Rng(2);
    let mut w = Worst::default();
    for _ in 0..N {
        let x = rng.positive_bits();
        w.add(ulps(simd_math::ln(x), (x as f64).ln()), (x, 0.0));
        // Near 1, where ln x is small and cancellation would show.
        let x = (1.0 + rng.uniform(-0.3, 0.3) * 2f64.powi(-((rng.next() % 24) as i32))) as f32;
        w.add(ulps(simd_math::ln(x), (x as f64).ln()), (x, 0.0));
    }
    // Every f32 in [0.5, 2), both sides of the mantissa reduction's split.
    for b in 0x3f00_0000u32..0x4000_0000 {
        let x = f32::from_bits(b);
        w.add(ulps(simd_math::ln(x), (x as f64).ln()), (x, 0.0));
    }
    w.check("ln");
}

#[test]
fn pow_is_within_one_ulp() {
    let mut rng = Rng(3);
    let mut w = Worst::default();
    let mut one = |x: f32, y: f32| {
        let want = (x as f64).powf(y as f64);
        w.add(ulps(simd_math::pow(x, y), want), (x, y));
    };
    for _ in 0..N {
        // Any positive base, an exponent that keeps the result near the f32
        // range (subnormal results included).
        let x = rng.positive_bits();
        let l = (x as f64).log2();
        let target = rng.uniform(-152.0, 130.0);
        let y = if l.abs() > 1e-3 {
            (target / l) as f32
        } else {
            rng.uniform(-50.0, 50.0) as f32
        };
        one(x, y);
        // Bases near 1 with large exponents: the product y log2 x needs far
        // more than f32 precision here.
        let x = (1.0 + rng.uniform(-0.01, 0.01)) as f32;
        let y = rng.uniform(-8000.0, 8000.0) as f32;
        one(x, y);
        // Typical graded-material use: [0, 1] to a moderate power.
        let x = rng.uniform(0.0, 1.0) as f32;
        let y = rng.uniform(0.0, 8.0) as f32;
        one(x, y);
        // Negative bases with integer exponents: the sign of odd powers.
        let x = -(rng.uniform(0.0, 40.0) as f32);
        let y = (rng.next() % 61) as f32 - 30.0;
        one(x, y);
    }
    w.check("pow");
}

/// Edge values: zeros, ones, infinities, NaN, subnormals, the extremes, and
/// integer and non-integer exponents of both parities and signs.
fn edges() -> Vec<f32> {
    let mut v = vec![
        0.0,
        1.0,
        2.0,
        3.0,
        0.5,
        1.5,
        0.25,
        4.0,
        10.0,
        1e-20,
        1e20,
        1e-40,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        f32::from_bits(0x007f_ffff),
        f32::MAX,
        f32::EPSILON,
        1.0 + f32::EPSILON,
        1.0 - f32::EPSILON / 2.0,
        16_777_216.0,
        16_777_217.0,
        8_388_609.0,
        2.5e9,
        127.0,
        128.0,
        -149.0,
        -150.0,
        f32::INFINITY,
    ];
    v.extend(v.clone().iter().map(|x| -x));
    v.push(f32::NAN);
    v
}

/// Same class and sign as the f64 reference, and within 1 ulp when finite
/// and nonzero.
fn agrees(got: f32, want: f64) -> bool {
    if want.is_nan() {
        return got.is_nan();
    }
    if want == 0.0 || want.is_infinite() {
        return got.to_bits() == (want as f32).to_bits();
    }
    if want.abs() < 2f64.powi(-150) {
        // Below half the smallest subnormal: 0 of the right sign, or the
        // smallest subnormal at exactly half.
        return got == 0.0 && got.is_sign_negative() == want.is_sign_negative();
    }
    ulps(got, want) <= 1.0 && (got == 0.0 || got.is_sign_negative() == want.is_sign_negative())
}

#[test]
fn edge_cases_match_libm() {
    let e = edges();
    let mut bad = Vec::new();
    for &x in &e {
        let want = (x as f64).exp();
        if !agrees(simd_math::exp(x), want) {
            bad.push(format!(
                "exp({x:e}) = {:e}, libm {want:e}",
                simd_math::exp(x)
            ));
        }
        let want = (x as f64).ln();
        if !agrees(simd_math::ln(x), want) {
            bad.push(format!("ln({x:e}) = {:e}, libm {want:e}", simd_math::ln(x)));
        }
        for &y in &e {
            let got = simd_math::pow(x, y);
            // f64 pow has the same special cases as powf, and is exact
            // enough to judge f32 results.
            let want = (x as f64).powf(y as f64);
            let libm32 = x.powf(y);
            let class_ok = got.is_nan() == libm32.is_nan()
                && (libm32.is_nan() || got.is_sign_negative() == libm32.is_sign_negative())
                && (got == 0.0) == (libm32 == 0.0)
                && got.is_infinite() == libm32.is_infinite();
            if !agrees(got, want) || !class_ok {
                bad.push(format!(
                    "pow({x:e}, {y:e}) = {got:e}, libm f64 {want:e}, powf {libm32:e}"
                ));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "{} mismatches:\n{}",
        bad.len(),
        bad.join("\n")
    );
    // The exact identities called out in the docs.
    for &x in &e {
        assert_eq!(simd_math::pow(x, 0.0), 1.0);
        assert_eq!(simd_math::pow(x, -0.0), 1.0);
        assert_eq!(simd_math::pow(1.0, x), 1.0);
    }
    assert_eq!(simd_math::ln(1.0).to_bits(), 0);
    assert_eq!(simd_math::exp(0.0), 1.0);
    assert!(simd_math::pow(-2.0, 0.5).is_nan());
    assert_eq!(simd_math::pow(-2.0, 3.0), -8.0);
    assert_eq!(simd_math::pow(-2.0, -2.0), 0.25);
    assert_eq!(simd_math::pow(-0.0, 3.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(simd_math::pow(-0.0, -3.0), f32::NEG_INFINITY);
    assert_eq!(simd_math::pow(0.0, 0.5).to_bits(), 0);
    assert_eq!(simd_math::pow(-1.0, f32::INFINITY), 1.0);
}

/// Integer powers give the exact value whenever it is an f32 (small
/// integers to small powers), as libm does.
#[test]
fn exact_integer_powers_are_exact() {
    for b in -12i32..=12 {
        for n in 0..=8 {
            let want = (b as f64).powi(n);
            if want.abs() < (1u64 << 24) as f64 {
                assert_eq!(simd_math::pow(b as f32, n as f32), want as f32, "{b}^{n}");
            }
        }
    }
    for k in -149..=127 {
        assert_eq!(simd_math::exp(0.0), 1.0);
        assert_eq!(simd_math::pow(2.0, k as f32) as f64, 2f64.powi(k), "2^{k}");
    }
}

/// The batch evaluator's exp, ln and pow steps (whole blocks, a constant
/// exponent as an immediate, and a per-lane exponent) give exactly these
/// functions' values, so the vectorised loops compute what was tested.
#[test]
fn batch_steps_use_these_functions() {
    let [x, y, _] = Expr::xyz();
    let n = 3 * microfrep_core::BLOCK + 17;
    let mut rng = Rng(4);
    let xs: Vec<f32> = (0..n).map(|_| rng.uniform(-3.0, 3.0) as f32).collect();
    let ys: Vec<f32> = (0..n).map(|_| rng.uniform(-4.0, 4.0) as f32).collect();
    let zs = vec![0.0f32; n];
    let cases: Vec<(Expr, Box<dyn Fn(f32, f32) -> f32>)> = vec![
        (
            Expr::unary(UnaryOp::Exp, x.clone()),
            Box::new(|a, _| simd_math::exp(a)),
        ),
        (
            Expr::unary(UnaryOp::Ln, x.clone()),
            Box::new(|a, _| simd_math::ln(a)),
        ),
        (x.pow(&y), Box::new(simd_math::pow)),
        (
            x.abs().pow(&Expr::constant(0.37)),
            Box::new(|a: f32, _| simd_math::pow(a.abs(), 0.37)),
        ),
        (
            Expr::constant(1.7).pow(&y),
            Box::new(|_, b| simd_math::pow(1.7, b)),
        ),
    ];
    for (i, (e, f)) in cases.iter().enumerate() {
        let mut ev = BatchEval::new(&Tape::new(e));
        let mut out = vec![0.0f32; n];
        ev.eval(&xs, &ys, &zs, &mut out);
        for k in 0..n {
            let want = f(xs[k], ys[k]);
            assert!(
                out[k].to_bits() == want.to_bits() || (out[k].is_nan() && want.is_nan()),
                "case {i} at ({}, {}): {} vs {}",
                xs[k],
                ys[k],
                out[k],
                want
            );
        }
    }
}
