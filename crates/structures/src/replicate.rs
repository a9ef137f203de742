//! Unit-cell replication (Fryazinov et al. Eq. 1): a cell defined on a box is
//! repeated through space by mapping each coordinate with a replicating
//! function g(t) in [0, 1].

use microfrep_core::frep::{sawtooth, triangle};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// How one axis is mapped into the cell box.
#[derive(Clone, Debug)]
pub enum Wave {
    /// Sawtooth with the given period (cells repeat unmirrored; needs full
    /// connectivity for a continuous result).
    Sawtooth(Expr),
    /// Triangle wave: cells of the given width, every second one mirrored
    /// (needs a symmetric cell).
    Triangle(Expr),
    /// Linear map of `[tmin, tmax]` onto the cell: no replication on this axis.
    Linear(f64, f64),
}

impl Wave {
    fn g(&self, t: &Expr) -> Expr {
        match self {
            Wave::Sawtooth(a) => sawtooth(t, a.clone()),
            Wave::Triangle(a) => triangle(t, a.clone()),
            Wave::Linear(lo, hi) => (t - *lo) / (hi - lo),
        }
    }
}

/// The point mapped into the cell box `[min, max]`:
/// `min_i + g_i(p_i) (max_i - min_i)`. Remap a cell with it to replicate.
pub fn replicate(p: &P3, waves: &[Wave; 3], min: [f64; 3], max: [f64; 3]) -> P3 {
    std::array::from_fn(|i| min[i] + waves[i].g(&p[i]) * (max[i] - min[i]))
}
