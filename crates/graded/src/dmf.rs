//! Density modulation functions (Park et al. §2.3, after Perlin's
//! hypertexture): bias, gain, their cascade, and noise and turbulence
//! modulation. Every function maps a parameter `t` (a depth ratio, a radius
//! ratio, a data value) to a density or material fraction in `[0, 1]`.
//!
//! Conventions, exactly:
//!
//! - `bias_b(t) = t^(ln b / ln 0.5)`, so `bias(0) = 0`, `bias(0.5) = b`,
//!   `bias(1) = 1`; `b` in `(0, 1)`, `b = 0.5` is the identity, `b > 0.5`
//!   pushes the density up.
//! - `gain_g(t) = bias_{1-g}(2t) / 2` for `t < 1/2`, `1 - bias_{1-g}(2 - 2t) / 2`
//!   otherwise, so `gain(0) = 0`, `gain(0.25) = 0.5 - g/2`, `gain(0.5) = 0.5`,
//!   `gain(0.75) = 0.5 + g/2`, `gain(1) = 1` (FORMULAS.md §3, Perlin 1989);
//!   `g = 0.5` is the identity, `g > 0.5` steepens the middle of the ramp,
//!   `g < 0.5` flattens it.
//!
//! Here `t` is clamped to `[0, 1]` first, so the functions are total (the
//! power of a negative `t` would be undefined) and every result lies in
//! `[0, 1]`. The core's `frep::bias` and `frep::gain` follow the same
//! formulas without the clamp: they agree with these on `[0, 1]` (tested)
//! and are undefined (NaN) for `t < 0` (bias) or `t > 1` (gain).

use microfrep_core::noise::GradientNoise;
use microfrep_core::Expr;
use std::sync::Arc;

/// `t` clamped to `[0, 1]` (NaN stays NaN).
pub fn clamp01(t: &Expr) -> Expr {
    t.max(0.0).min(1.0)
}

/// Perlin's bias `t^(ln b / ln 0.5)` of `t` clamped to `[0, 1]`; `b` may be
/// a field.
pub fn bias(t: &Expr, b: impl Into<Expr>) -> Expr {
    let t = clamp01(t);
    bias_unclamped(&t, b.into())
}

fn bias_unclamped(t: &Expr, b: Expr) -> Expr {
    match b.as_const() {
        // The identity: skip the power (and its NaN-free but costly ln).
        Some(0.5) => t.clone(),
        _ => t.pow(b.ln() / 0.5f64.ln()),
    }
}

/// Perlin's gain of `t` clamped to `[0, 1]`; `g` may be a field.
pub fn gain(t: &Expr, g: impl Into<Expr>) -> Expr {
    let t = clamp01(t);
    let b = 1.0 - g.into();
    let lo = bias_unclamped(&(2.0 * &t), b.clone()) * 0.5;
    let hi = 1.0 - bias_unclamped(&(2.0 - 2.0 * &t), b) * 0.5;
    Expr::select(t.lt(0.5), lo, hi)
}

/// Park's cascade for sketching a gradient (§3.2, Fig. 2): `gain(bias(t, b), g)`.
pub fn sketch(t: &Expr, b: impl Into<Expr>, g: impl Into<Expr>) -> Expr {
    gain(&bias(t, b), g)
}

/// Reference value of [`bias`] (f64), for tests and tables.
pub fn bias_value(t: f64, b: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    if b == 0.5 {
        t
    } else {
        t.powf(b.ln() / 0.5f64.ln())
    }
}

/// Reference value of [`gain`] (f64).
pub fn gain_value(t: f64, g: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    let b = 1.0 - g;
    if t < 0.5 {
        bias_value(2.0 * t, b) * 0.5
    } else {
        1.0 - bias_value(2.0 - 2.0 * t, b) * 0.5
    }
}

/// Seeded gradient noise (the core's [`GradientNoise`], values in `[-2, 2]`,
/// about `[-1, 1]` in practice) at the point `p` scaled by `frequency`.
pub fn noise(p: &[Expr; 3], frequency: impl Into<Expr>, seed: u64) -> Expr {
    let f = frequency.into();
    let q: [Expr; 3] = std::array::from_fn(|a| &p[a] * &f);
    Expr::field_at(Arc::new(GradientNoise::new(seed)), q)
}

/// Perlin's turbulence `sum_{i < octaves} |noise(2^i f p)| / 2^i`, each
/// octave with its own seed (`seed + i`). Non-negative, below
/// `4 (1 - 2^-octaves)` (the noise bound 2 times the geometric sum).
pub fn turbulence(p: &[Expr; 3], frequency: impl Into<Expr>, octaves: u32, seed: u64) -> Expr {
    let f = frequency.into();
    let mut sum = Expr::constant(0.0);
    for i in 0..octaves {
        let s = (1u64 << i.min(62)) as f64;
        let n = noise(p, &f * s, seed.wrapping_add(i as u64)).abs() / s;
        sum = if i == 0 { n } else { sum + n };
    }
    sum
}

/// A density `t` perturbed by noise and clamped to `[0, 1]`:
/// `clamp(t + amplitude * noise(frequency p))`, Perlin's way of roughening a
/// hypertexture's fuzzy region (Park et al. §2.3, "solid noise").
pub fn noise_modulated(
    t: &Expr,
    p: &[Expr; 3],
    amplitude: impl Into<Expr>,
    frequency: impl Into<Expr>,
    seed: u64,
) -> Expr {
    clamp01(&(t + amplitude.into() * noise(p, frequency, seed)))
}

/// A density `t` perturbed by turbulence, clamped to `[0, 1]`.
pub fn turbulence_modulated(
    t: &Expr,
    p: &[Expr; 3],
    amplitude: impl Into<Expr>,
    frequency: impl Into<Expr>,
    octaves: u32,
    seed: u64,
) -> Expr {
    clamp01(&(t + amplitude.into() * turbulence(p, frequency, octaves, seed)))
}
