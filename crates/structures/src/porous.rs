//! Porous media (Pasko et al. Eq. 9): a basic pore replicated through space
//! by the per-axis periodic mapping `x' = p_x sin(q_x x)` and subtracted
//! from the part. Pore size may be graded by depth (see
//! [`crate::infill::graded_by_depth`]) and varied by noise (the core's
//! `noise::noise_g`, Gardner's series, or `noise::gradient_noise`) added to
//! amplitudes, frequencies or the pore.

use microfrep_core::frep::subtraction;
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// Per-axis amplitude `p` and frequency `q` of the mapping; any may be a field.
#[derive(Clone, Debug)]
pub struct PeriodicMap {
    /// Amplitude `p` on each axis.
    pub amp: [Expr; 3],
    /// Frequency `q` on each axis (pores repeat every `pi / q`).
    pub freq: [Expr; 3],
}

impl PeriodicMap {
    /// Same amplitude and frequency on all axes.
    pub fn uniform(amp: impl Into<Expr>, freq: impl Into<Expr>) -> PeriodicMap {
        let (a, q) = (amp.into(), freq.into());
        PeriodicMap {
            amp: [a.clone(), a.clone(), a],
            freq: [q.clone(), q.clone(), q],
        }
    }

    /// The mapped point `(p_x sin(q_x x), p_y sin(q_y y), p_z sin(q_z z))`.
    /// Pores sit where the mapped point is near the origin: at `x = k pi / q_x`.
    pub fn map(&self, p: &P3) -> P3 {
        std::array::from_fn(|i| &self.amp[i] * (&self.freq[i] * &p[i]).sin())
    }
}

/// The replicated pores `F_r = F_p(x', y', z')`. `pore` builds the basic pore
/// (centred at the origin) on the mapped point it is given; its size
/// parameters may use the original coordinates, which is how a pore size
/// graded by depth is written.
pub fn pores(p: &P3, map: &PeriodicMap, pore: impl Fn(&P3) -> Expr) -> Expr {
    pore(&map.map(p))
}

/// The porous part `F \ F_r`.
pub fn porous(part: &Expr, pores: &Expr, alpha: impl Into<Expr>) -> Expr {
    subtraction(part, pores, alpha)
}
