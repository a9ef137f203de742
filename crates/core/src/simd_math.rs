//! Branch-free f32 versions of the libm functions on the batch hot path.
//!
//! libm's `sinf`/`cosf` are opaque calls that stop the compiler from
//! vectorising a loop; these are plain arithmetic (Cody-Waite range reduction
//! and a Taylor polynomial) so a loop over a block becomes SIMD code. Absolute
//! error is below 2e-7 for |x| < 1e4 and grows with |x| beyond (f32 itself has
//! no better resolution there); the f64 point evaluator stays the reference.

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
