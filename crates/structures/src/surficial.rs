//! Surficial structures (Fryazinov et al. Eqs. 12-14): thin solids around
//! intersection curves and shells from offsets, with constant (the function
//! itself) or normalised (distance-like) offsets.

use crate::infill::{depth, Depth};
use microfrep_core::frep::{intersection, subtraction};
use microfrep_core::Expr;

/// The intersection curve of `f1 = 0` and `f2 = 0` thickened: `(-g1^2) & (-g2^2) + t^2`
/// with `g_i` the (normalised) functions, so with `alpha = 1` it is exactly
/// the set where `|g1| <= t` and `|g2| <= t`.
pub fn intersection_curve(
    f1: &Expr,
    f2: &Expr,
    t: impl Into<Expr>,
    mode: Depth,
    alpha: impl Into<Expr>,
) -> Expr {
    let a = depth(f1, mode).square().neg();
    let b = depth(f2, mode).square().neg();
    intersection(&a, &b, alpha) + t.into().square()
}

/// Shell of thickness `t` inside the solid `f`: `g \ (g - t)`.
pub fn shell(f: &Expr, t: impl Into<Expr>, mode: Depth, alpha: impl Into<Expr>) -> Expr {
    let g = depth(f, mode);
    subtraction(&g, &(&g - t.into()), alpha)
}

/// A shell intersected with a volumetric cellular structure (Fig. 11).
pub fn cellular_shell(
    f: &Expr,
    t: impl Into<Expr>,
    mode: Depth,
    cells: &Expr,
    alpha: impl Into<Expr>,
) -> Expr {
    let alpha = alpha.into();
    intersection(&shell(f, t, mode, &alpha), cells, alpha)
}
