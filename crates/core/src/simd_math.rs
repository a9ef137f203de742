//! Branch-free f32 versions of the libm functions on the batch hot path:
//! [`sin`], [`cos`], [`exp`], [`ln`] and [`pow`].
//!
//! libm's `sinf`/`cosf` are opaque calls that stop the compiler from
//! vectorising a loop; these are plain arithmetic (Cody-Waite range reduction
//! and a Taylor polynomial) so a loop over a block becomes SIMD code. Absolute
//! error is below 2e-7 for |x| < 1e4 and grows with |x| beyond (f32 itself has
//! no better resolution there). [`exp`], [`ln`] and [`pow`] are within 1 ulp
//! over their whole range, with libm's special cases (see their docs). The
//! f64 point evaluator stays libm and the reference.

// pi split into three parts with trailing zero bits, so k * PI_A is exact.
const PI_A: f32 = 3.140625;
const PI_B: f32 = 9.675_026e-4;
const PI_C: f32 = 1.509_958e-7;
const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// sin(r) for r in [-pi/2, pi/2], degree-11 Taylor polynomial (error < 6e-8).
#[inline(always)]
fn sin_poly(r: f32) -> f32 {
    let r2 = r * r;
    let p = -2.505_210_8e-8_f32;
    let p = p * r2 + 2.755_731_9e-6;
    let p = p * r2 - 1.984_127e-4;
    let p = p * r2 + 8.333_333e-3;
    let p = p * r2 - 1.666_666_7e-1;
    r + r * r2 * p
}

/// (-1)^k for an integral float k, without a branch.
#[inline(always)]
fn parity_sign(k: f32) -> f32 {
    let half = k * 0.5;
    let odd = half - half.floor(); // 0 or 0.5
    1.0 - 4.0 * odd
}

/// sin(x), branch-free f32 (see the module docs for the error).
#[inline(always)]
pub fn sin(x: f32) -> f32 {
    let k = (x * INV_PI).round_ties_even();
    let r = ((x - k * PI_A) - k * PI_B) - k * PI_C;
    parity_sign(k) * sin_poly(r)
}

/// cos(x), branch-free f32 (see the module docs for the error).
#[inline(always)]
pub fn cos(x: f32) -> f32 {
    // cos(x) = -(-1)^k sin(x - (k + 1/2) pi) with k = round(x/pi - 1/2).
    let k = (x * INV_PI - 0.5).round_ties_even();
    let kh = k + 0.5;
    let r = ((x - kh * PI_A) - kh * PI_B) - kh * PI_C;
    -parity_sign(k) * sin_poly(r)
}

/// Floor that the compiler turns into one rounding instruction per vector.
#[inline(always)]
pub fn floor(x: f32) -> f32 {
    x.floor()
}

// ---------------------------------------------------------------------------
// exp, ln and pow.
//
// libm's `expf`, `logf` and `powf` are opaque calls too. These evaluate in
// f64 with plain polynomials and bit manipulation (no tables, no branches),
// so a loop over f32 lanes vectorises (4 f64 lanes per AVX2 register). The
// f64 kernels have a relative error near 1e-12, far below f32's resolution,
// so the one rounding to f32 at the end decides the result: the maximum
// error is 1 ulp (measured over tens of millions of inputs against f64 libm
// rounded to f32: at most 0.5 ulp plus the kernels' 1e-12, that is, the
// correctly rounded result except in near-halfway cases). Results that are
// f32 subnormals are rounded from their f64 value, so they keep the same
// bound; subnormal inputs are exact in f64 and need no special path.

/// `1.5 * 2^52`: adding it rounds an f64 of magnitude below 2^51 to an
/// integer (ties to even) that sits in the low bits of the sum's encoding.
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

/// Bits of the f32 nearest sqrt(1/2), where the mantissa range of [`log2_kernel`] starts.
const SQRT_HALF_BITS: i32 = 0x3f35_04f3;

/// log2(x) in f64 for a finite, positive f32 `x` (normal or subnormal).
///
/// `x = 2^e m` with `m` in [sqrt(1/2), sqrt(2)), and
/// `ln m = 2 atanh(t)`, `t = (m - 1)/(m + 1)`, `|t| < 0.1716`: the series
/// `2t (1 + t^2/3 + t^4/5 + ...)` to `t^16` leaves a relative error below
/// 2e-13.
#[inline(always)]
fn log2_kernel(x: f32) -> f64 {
    // Subnormals: scale by 2^24 (exact) into the normal range first.
    let sub = x < f32::MIN_POSITIVE;
    let xs = if sub { x * 16_777_216.0 } else { x };
    let bits = xs.to_bits() as i32;
    let e = bits.wrapping_sub(SQRT_HALF_BITS) >> 23;
    let m = f32::from_bits(bits.wrapping_sub(e << 23) as u32) as f64;
    let e = e as f64 - if sub { 24.0 } else { 0.0 };
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let p = 1.0 / 13.0;
    let p = fma(p, t2, 1.0 / 11.0);
    let p = fma(p, t2, 1.0 / 9.0);
    let p = fma(p, t2, 1.0 / 7.0);
    let p = fma(p, t2, 1.0 / 5.0);
    let p = fma(p, t2, 1.0 / 3.0);
    let ln_m = fma(2.0 * t, t2 * p, 2.0 * t);
    fma(ln_m, std::f64::consts::LOG2_E, e)
}

/// 2^z in f64 for `|z| <= 300` (the callers clamp; beyond that any f32
/// result is 0 or infinite anyway).
///
/// `z = k + r`, `k` the nearest integer, `|r| <= 1/2`; `2^r = e^(r ln 2)` by
/// its Taylor polynomial to degree 11 (relative error below 2e-15), times
/// `2^k` built in the exponent field.
#[inline(always)]
fn exp2_kernel(z: f64) -> f64 {
    let shifted = z + ROUND_MAGIC;
    let k = shifted - ROUND_MAGIC;
    let r = (z - k) * std::f64::consts::LN_2;
    let ki = shifted.to_bits().wrapping_sub(ROUND_MAGIC.to_bits());
    let scale = f64::from_bits(ki.wrapping_add(1023) << 52);
    let p = 1.0 / 5_040.0;
    let p = fma(p, r, 1.0 / 720.0);
    let p = fma(p, r, 1.0 / 120.0);
    let p = fma(p, r, 1.0 / 24.0);
    let p = fma(p, r, 1.0 / 6.0);
    let p = fma(p, r, 0.5);
    let p = fma(p, r, 1.0);
    let p = fma(p, r, 1.0);
    p * scale
}

/// `a * b + c`: one fused instruction where the target has FMA (the
/// default x86-64-v3 build), else a multiply and an add (a libm `fma` call
/// would stop vectorisation). Either way within the error bounds above; the
/// last bits of f64 intermediates, and so rarely the f32 result, may differ
/// between the two builds.
#[inline(always)]
fn fma(a: f64, b: f64, c: f64) -> f64 {
    #[cfg(target_feature = "fma")]
    {
        a.mul_add(b, c)
    }
    #[cfg(not(target_feature = "fma"))]
    {
        a * b + c
    }
}

/// `z` limited to [-300, 300]; NaN becomes 0 (its lane is overwritten by the caller).
#[inline(always)]
fn clamp_exponent(z: f64) -> f64 {
    let z = if z < -300.0 { -300.0 } else { z };
    let z = if z > 300.0 { 300.0 } else { z };
    if z.is_nan() {
        0.0
    } else {
        z
    }
}

/// e^x, branch-free f32, at most 1 ulp from the exact value (see above).
/// `exp(NaN)` is NaN, `exp(-inf) = 0`, `exp(inf) = inf`; results below
/// 2^-126 are rounded subnormals.
#[inline(always)]
pub fn exp(x: f32) -> f32 {
    let z = clamp_exponent(x as f64 * std::f64::consts::LOG2_E);
    let r = exp2_kernel(z) as f32;
    if x.is_nan() {
        x
    } else {
        r
    }
}

/// ln x, branch-free f32, at most 1 ulp from the exact value (see above).
/// `ln(1) = 0` exactly, `ln(+-0) = -inf`, `ln(inf) = inf`, NaN for
/// negative x and NaN.
#[inline(always)]
pub fn ln(x: f32) -> f32 {
    let ok = x > 0.0 && x < f32::INFINITY;
    let l = (log2_kernel(if ok { x } else { 1.0 }) * std::f64::consts::LN_2) as f32;
    let l = if x == 0.0 { f32::NEG_INFINITY } else { l };
    let l = if x == f32::INFINITY { x } else { l };
    if x < 0.0 || x.is_nan() {
        f32::NAN
    } else {
        l
    }
}

/// x^y, branch-free f32, at most 1 ulp from the exact value (see above),
/// with the special cases of C99 / IEEE 754 `pow` (as libm's `powf`):
/// `pow(x, +-0) = 1` and `pow(1, y) = 1` for any x and y, NaN included;
/// `pow(-1, +-inf) = 1`; otherwise NaN in, NaN out; a finite negative base
/// with a finite non-integer exponent gives NaN; a negative base (also -0
/// and -inf) with an odd integer exponent gives the negative of
/// `pow(|x|, y)`, with any other integer exponent the positive value;
/// `pow(+-0, y) = 0` for `y > 0` and `inf` for `y < 0`; `pow(inf, y)` is
/// `inf` for `y > 0` and 0 for `y < 0`; `pow(x, +-inf)` is 0 or inf by
/// whether `|x| < 1`. Overflow gives inf, underflow a rounded subnormal or 0.
#[inline(always)]
pub fn pow(x: f32, y: f32) -> f32 {
    let ax = x.abs();
    let finite = ax > 0.0 && ax < f32::INFINITY;
    let l = log2_kernel(if finite { ax } else { 1.0 });
    let r = exp2_kernel(clamp_exponent(y as f64 * l)) as f32;
    // Zero and infinite bases (the kernel saw 1 there).
    let (small, big) = if y < 0.0 {
        (f32::INFINITY, 0.0)
    } else {
        (0.0, f32::INFINITY)
    };
    let r = if ax == f32::INFINITY { big } else { r };
    let r = if ax == 0.0 { small } else { r };
    // Signs of negative bases: infinite y counts as an even integer.
    let y_int = y.trunc() == y;
    let half = y * 0.5;
    let y_odd = y_int && half.trunc() != half;
    let r = if x.is_sign_negative() && y_odd { -r } else { r };
    let r = if x < 0.0 && x > f32::NEG_INFINITY && !y_int {
        f32::NAN
    } else {
        r
    };
    let r = if x.is_nan() || y.is_nan() {
        f32::NAN
    } else {
        r
    };
    let one = x == 1.0 || y == 0.0 || (x == -1.0 && y.is_infinite());
    if one {
        1.0
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sin_cos_match_libm() {
        let mut worst = 0.0f64;
        for i in -200000..200000 {
            let x = i as f32 * 0.0123;
            let s = super::sin(x) as f64 - (x as f64).sin();
            let c = super::cos(x) as f64 - (x as f64).cos();
            worst = worst.max(s.abs()).max(c.abs());
        }
        assert!(worst < 5e-7, "worst abs error {worst}");
    }
}
