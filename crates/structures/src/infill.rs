//! Shell with infill (Pasko et al. Eq. 8) for any part, and lattice
//! parameters driven by depth below the part's surface.

use microfrep_core::frep::{blend_union, intersection, normalize, subtraction, union, Blend};
use microfrep_core::Expr;

/// How depth below the surface is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Depth {
    /// The part's own defining function (cheap; its scale is the model's).
    Function,
    /// `f / sqrt(f^2 + |grad f|^2)`: close to the true distance near the
    /// surface, so a depth of 0.1 means about 0.1 length units.
    Normalized,
}

/// Depth below the surface of the part `f` (positive inside).
pub fn depth(f: &Expr, mode: Depth) -> Expr {
    match mode {
        Depth::Function => f.clone(),
        Depth::Normalized => normalize(f),
    }
}

/// A parameter graded by depth: `at_surface` on the surface, `at_depth` from
/// depth `d` inwards, linear in between (clamped). Use it for a lattice's
/// threshold, frequency or phase, or for a pore size.
pub fn graded_by_depth(
    f: &Expr,
    mode: Depth,
    d: impl Into<Expr>,
    at_surface: impl Into<Expr>,
    at_depth: impl Into<Expr>,
) -> Expr {
    let t = (depth(f, mode) / d.into()).max(0.0).min(1.0);
    let (a, b) = (at_surface.into(), at_depth.into());
    &a + (b - &a) * t
}

/// How the shell and the truncated lattice are joined.
#[derive(Clone, Debug)]
pub enum Join {
    /// Plain union (the R-function of the given `alpha`).
    Plain,
    /// Blended union (Eq. 7): rods merge into the shell with fillets.
    Blended(Blend),
}

/// Eq. 8: inner offset `F_o = F - l_o`, shell `F_s = F \ F_o`, truncated
/// lattice `F_g = g & F`, result `F_s | F_g` (plain or blended).
pub fn shell_with_infill(
    f: &Expr,
    l_o: impl Into<Expr>,
    lattice: &Expr,
    alpha: impl Into<Expr>,
    join: &Join,
) -> Expr {
    let alpha = alpha.into();
    let inner = f - l_o.into();
    let shell = subtraction(f, &inner, &alpha);
    let infill = intersection(lattice, f, &alpha);
    match join {
        Join::Plain => union(&shell, &infill, alpha),
        Join::Blended(b) => blend_union(&shell, &infill, b, alpha),
    }
}
