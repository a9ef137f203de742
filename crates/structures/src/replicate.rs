//! Unit-cell replication (Fryazinov et al. Eq. 1): a cell defined on a box is
//! repeated through space by mapping each coordinate with a replicating
//! function g(t) in [0, 1].

use microfrep_core::frep::{sawtooth, triangle};
use microfrep_core::transform::P3;
use microfrep_core::{Axis, Expr};

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
    /// The coordinate passes through unchanged: no replication on this axis,
    /// the cell keeps its own extent there.
    Identity,
}

/// The two replicating functions, for the helpers below.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// [`Wave::Sawtooth`].
    Sawtooth,
    /// [`Wave::Triangle`].
    Triangle,
}

impl Kind {
    fn wave(self, period: Expr) -> Wave {
        match self {
            Kind::Sawtooth => Wave::Sawtooth(period),
            Kind::Triangle => Wave::Triangle(period),
        }
    }
}

impl Wave {
    /// The mapped coordinate inside `[min, max]`.
    fn map(&self, t: &Expr, min: &Expr, max: &Expr) -> Expr {
        let g = match self {
            Wave::Sawtooth(a) => sawtooth(t, a.clone()),
            Wave::Triangle(a) => triangle(t, a.clone()),
            Wave::Linear(lo, hi) => (t - *lo) / (hi - lo),
            Wave::Identity => return t.clone(),
        };
        min + g * (max - min)
    }
}

/// The point mapped into the cell box `[min, max]`:
/// `min_i + g_i(p_i) (max_i - min_i)`. Remap a cell with it to replicate.
pub fn replicate(p: &P3, waves: &[Wave; 3], min: [f64; 3], max: [f64; 3]) -> P3 {
    replicate_box(p, waves, &min.map(Expr::constant), &max.map(Expr::constant))
}

/// [`replicate`] with the cell box given as expressions (they may vary in
/// space, which deforms the cells).
pub fn replicate_box(p: &P3, waves: &[Wave; 3], min: &P3, max: &P3) -> P3 {
    std::array::from_fn(|i| waves[i].map(&p[i], &min[i], &max[i]))
}

/// Any cell (itself possibly a cellular structure with further set
/// operations: that is multi-scale nesting) defined on `[min, max]`,
/// replicated through space. Every coordinate in `cell` is remapped; for a
/// parameterised cell whose parameters vary with the original point, use
/// [`replicate_with`].
pub fn replicate_cell(cell: &Expr, waves: &[Wave; 3], min: [f64; 3], max: [f64; 3]) -> Expr {
    cell.remap(&replicate(&Expr::xyz(), waves, min, max))
}

/// A parameterised cell, replicated: `cell` builds the cell on the mapped
/// point it is given, and its parameters may use the original coordinates
/// (`Expr::x()` etc.), e.g. a metamorphosis weight varying across the part.
pub fn replicate_with(
    waves: &[Wave; 3],
    min: [f64; 3],
    max: [f64; 3],
    cell: impl Fn(&P3) -> Expr,
) -> Expr {
    cell(&replicate(&Expr::xyz(), waves, min, max))
}

/// Linear replication: cells of width `period` along `axis` only.
pub fn linear(
    cell: &Expr,
    axis: Axis,
    kind: Kind,
    period: impl Into<Expr>,
    min: [f64; 3],
    max: [f64; 3],
) -> Expr {
    let period = period.into();
    let waves = std::array::from_fn(|i| {
        if i == axis as usize {
            kind.wave(period.clone())
        } else {
            Wave::Identity
        }
    });
    replicate_cell(cell, &waves, min, max)
}

/// Plane replication: cells repeated across the plane normal to `normal_axis`.
pub fn plane(
    cell: &Expr,
    normal_axis: Axis,
    kind: Kind,
    period: impl Into<Expr>,
    min: [f64; 3],
    max: [f64; 3],
) -> Expr {
    let period = period.into();
    let waves = std::array::from_fn(|i| {
        if i == normal_axis as usize {
            Wave::Identity
        } else {
            kind.wave(period.clone())
        }
    });
    replicate_cell(cell, &waves, min, max)
}

/// Volumetric replication: cells repeated along all three axes.
pub fn volumetric(
    cell: &Expr,
    kind: Kind,
    period: impl Into<Expr>,
    min: [f64; 3],
    max: [f64; 3],
) -> Expr {
    let period = period.into();
    let waves = std::array::from_fn(|_| kind.wave(period.clone()));
    replicate_cell(cell, &waves, min, max)
}
