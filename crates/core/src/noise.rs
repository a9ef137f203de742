//! Noise: Gardner's sine series (hfNoiseG) as an expression, and a seeded 3D
//! gradient noise (Perlin-style) as a data-driven field.

use crate::expr::Expr;
use crate::field::Field;
use crate::interval::Interval;
use crate::transform::P3;
use std::sync::Arc;

/// Gardner's solid noise (hfNoiseG): with `A' = amp/1.17`, `s_i = sin(freq p_i)`,
/// `S_x = amp s_x + A' sin(freq p_x/1.35 + phase s_z)` (and cyclically
/// `y <- x`, `z <- y`), the value is `S_x S_y S_z`. A displacement to add to
/// a shape, not a solid.
pub fn noise_g(
    p: &P3,
    amp: impl Into<Expr>,
    freq: impl Into<Expr>,
    phase: impl Into<Expr>,
) -> Expr {
    let (amp, freq, phase) = (amp.into(), freq.into(), phase.into());
    let amp2 = &amp / 1.17;
    let s: [Expr; 3] = std::array::from_fn(|i| (&freq * &p[i]).sin());
    // Each axis is perturbed by the sine of the axis before it (x by z).
    let term =
        |i: usize, j: usize| &amp * &s[i] + &amp2 * (&freq * &p[i] / 1.35 + &phase * &s[j]).sin();
    term(0, 2) * term(1, 0) * term(2, 1)
}

/// Proven bound on [`GradientNoise`] values: each corner term is a dot of an
/// edge gradient (two components +-1) with an offset in the unit cube, so
/// at most 2, and the value is a convex combination of corner terms.
pub const NOISE_BOUND: f64 = 2.0;

/// Bound on each partial derivative: `1` from the corner gradients plus the
/// fade slope (at most 15/8) times the difference of two values of
/// magnitude at most 2.
pub const NOISE_SLOPE: f64 = 1.0 + 1.875 * 4.0;

/// The twelve edge directions of a cube (improved Perlin noise).
const GRADS: [[f64; 3]; 12] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
];

/// Seeded gradient noise on the unit integer lattice, quintic fade.
///
/// Values lie in `[-NOISE_BOUND, NOISE_BOUND]` = [-2, 2] (in practice about
/// [-1, 1]); 0 at every lattice point; period 256 on each axis. Same seed,
/// same values, on every run and platform (only IEEE `+ - *` and `floor`).
/// Scale the point to change the frequency.
#[derive(Clone)]
pub struct GradientNoise {
    seed: u64,
    /// Permutation of 0..256, stored twice so hashed indices never wrap.
    perm: [u8; 512],
}

impl std::fmt::Debug for GradientNoise {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GradientNoise(seed {})", self.seed)
    }
}

/// splitmix64 step: a small, well-mixed hash for the permutation shuffle.
fn splitmix64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn fade_slope(t: f64) -> f64 {
    30.0 * t * t * (t - 1.0) * (t - 1.0)
}

impl GradientNoise {
    /// Noise with the lattice permutation shuffled from `seed`.
    pub fn new(seed: u64) -> GradientNoise {
        let mut table: [u8; 256] = std::array::from_fn(|i| i as u8);
        let mut state = seed;
        // Fisher-Yates; the modulo bias of a 64-bit draw over <= 256 is negligible.
        for i in (1..256).rev() {
            let j = (splitmix64(&mut state) % (i as u64 + 1)) as usize;
            table.swap(i, j);
        }
        let perm = std::array::from_fn(|i| table[i & 255]);
        GradientNoise { seed, perm }
    }

    fn corner_grad(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        let h = self.perm[self.perm[self.perm[i] as usize + j] as usize + k];
        GRADS[h as usize % 12]
    }

    /// Value and analytic gradient.
    pub fn value_grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|v| !v.is_finite()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let cell = p.map(|v| v.floor());
        let f: [f64; 3] = std::array::from_fn(|a| p[a] - cell[a]);
        // Lattice index modulo 256 (the saturating cast cannot panic).
        let idx = cell.map(|c| (c as i64).rem_euclid(256) as usize);
        let w = f.map(fade);
        let dw = f.map(fade_slope);
        // Corner terms c[dx][dy][dz] = g . (f - corner).
        let mut c = [[[0.0; 2]; 2]; 2];
        let mut g = [[[[0.0; 3]; 2]; 2]; 2];
        for (dx, cx) in c.iter_mut().enumerate() {
            for (dy, cy) in cx.iter_mut().enumerate() {
                for (dz, cz) in cy.iter_mut().enumerate() {
                    let gr = self.corner_grad(
                        (idx[0] + dx) & 255,
                        (idx[1] + dy) & 255,
                        (idx[2] + dz) & 255,
                    );
                    let off = [f[0] - dx as f64, f[1] - dy as f64, f[2] - dz as f64];
                    *cz = gr[0] * off[0] + gr[1] * off[1] + gr[2] * off[2];
                    g[dx][dy][dz] = gr;
                }
            }
        }
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        // Trilinear interpolation of any per-corner quantity with weights w.
        let tri = |q: &dyn Fn(usize, usize, usize) -> f64| {
            let y0 = lerp(
                lerp(q(0, 0, 0), q(1, 0, 0), w[0]),
                lerp(q(0, 1, 0), q(1, 1, 0), w[0]),
                w[1],
            );
            let y1 = lerp(
                lerp(q(0, 0, 1), q(1, 0, 1), w[0]),
                lerp(q(0, 1, 1), q(1, 1, 1), w[0]),
                w[1],
            );
            lerp(y0, y1, w[2])
        };
        let value = tri(&|i, j, k| c[i][j][k]);
        // d/dx = interpolated corner gradients + fade slope times the
        // difference of the interpolations on the two faces across x.
        let bil = |q: &dyn Fn(usize, usize) -> f64, s: f64, t: f64| {
            lerp(lerp(q(0, 0), q(1, 0), s), lerp(q(0, 1), q(1, 1), s), t)
        };
        let across = [
            bil(&|j, k| c[1][j][k] - c[0][j][k], w[1], w[2]),
            bil(&|i, k| c[i][1][k] - c[i][0][k], w[0], w[2]),
            bil(&|i, j| c[i][j][1] - c[i][j][0], w[0], w[1]),
        ];
        let grad = std::array::from_fn(|a| tri(&|i, j, k| g[i][j][k][a]) + dw[a] * across[a]);
        (value, grad)
    }
}

impl Field for GradientNoise {
    fn name(&self) -> &str {
        "gradient_noise"
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.value_grad(p).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.value_grad(p)
    }

    /// Value at the box centre plus the slope bound times the half widths
    /// (mean value theorem), clamped to the proven range.
    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let full = Interval::new(-NOISE_BOUND, NOISE_BOUND);
        if b.iter().any(|i| !i.lo.is_finite() || !i.hi.is_finite()) {
            return full;
        }
        let v = self.eval(b.map(|i| i.mid()));
        let reach = NOISE_SLOPE * b.iter().map(|i| 0.5 * i.width()).sum::<f64>();
        // A hair for the rounding of the mid point and of the value.
        let r = reach * (1.0 + 1e-12) + 1e-12;
        Interval::new((v - r).max(-NOISE_BOUND), (v + r).min(NOISE_BOUND))
    }

    fn grad_interval(&self, _b: [Interval; 3]) -> [Interval; 3] {
        [Interval::new(-NOISE_SLOPE, NOISE_SLOPE); 3]
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            out[i] = self.value_grad([x[i] as f64, y[i] as f64, z[i] as f64]).0 as f32;
        }
    }
}

/// Gradient noise with `seed` at the (possibly mapped) point `p`.
pub fn gradient_noise(p: &P3, seed: u64) -> Expr {
    Expr::field_at(Arc::new(GradientNoise::new(seed)), p.clone())
}
