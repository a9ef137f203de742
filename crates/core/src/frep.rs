//! FRep operations on defining functions (inside is `f >= 0`).
//!
//! R-functions, blends, offsets, metamorphosis, smooth n-ary operations and
//! replicating waves (Pasko et al. 2009, Eqs. 2-3, 7; Fryazinov et al.
//! Eqs. 2-3, 10-14; Park et al. section 2.2). Every numeric parameter is an
//! [`Expr`], so it may vary in space.

use crate::expr::{blend_displacement, Expr};
use crate::ops::SetOp;

/// R-function union `(f1 + f2 + sqrt(f1^2 + f2^2 - 2 a f1 f2)) / (1 + a)`
/// as a set node of the graph; `alpha = 1` is exactly `max`, `alpha = 0` is
/// HyperFun's `|`.
///
/// For alpha in [0, 1] the result is `>= 0` exactly when either argument is
/// (tested for |f1|/|f2| up to 1e14; near 1/eps the smaller argument is lost
/// to rounding in `f1 + f2`). The same holds for the intersection and
/// subtraction.
pub fn union(f1: &Expr, f2: &Expr, alpha: impl Into<Expr>) -> Expr {
    Expr::set(SetOp::Union, f1, f2, alpha)
}

/// R-function intersection; `alpha = 1` is exactly `min`.
pub fn intersection(f1: &Expr, f2: &Expr, alpha: impl Into<Expr>) -> Expr {
    Expr::set(SetOp::Intersection, f1, f2, alpha)
}

/// `f1 \ f2 = f1 & (-f2)`.
pub fn subtraction(f1: &Expr, f2: &Expr, alpha: impl Into<Expr>) -> Expr {
    intersection(f1, &f2.neg(), alpha)
}

/// Set complement `-f`.
pub fn complement(f: &Expr) -> Expr {
    f.neg()
}

/// Union of many shapes, folded left to right.
pub fn union_all(fs: &[Expr], alpha: impl Into<Expr>) -> Expr {
    let alpha = alpha.into();
    let mut it = fs.iter();
    let first = it.next().expect("union of no shapes").clone();
    it.fold(first, |acc, f| union(&acc, f, alpha.clone()))
}

/// Intersection of many shapes, folded left to right.
pub fn intersection_all(fs: &[Expr], alpha: impl Into<Expr>) -> Expr {
    let alpha = alpha.into();
    let mut it = fs.iter();
    let first = it.next().expect("intersection of no shapes").clone();
    it.fold(first, |acc, f| intersection(&acc, f, alpha.clone()))
}

/// Blend parameters of Eq. 7: `a0` amount (> 0 adds material), `a1`, `a2`
/// extent along each argument.
#[derive(Clone, Debug)]
pub struct Blend {
    /// Amount added at the seam (> 0 adds material, < 0 removes it).
    pub a0: Expr,
    /// Extent of the blend along the first argument.
    pub a1: Expr,
    /// Extent of the blend along the second argument.
    pub a2: Expr,
}

impl Blend {
    /// Blend parameters from the amount and the two extents.
    pub fn new(a0: impl Into<Expr>, a1: impl Into<Expr>, a2: impl Into<Expr>) -> Blend {
        Blend {
            a0: a0.into(),
            a1: a1.into(),
            a2: a2.into(),
        }
    }
    /// The displacement `a0 / (1 + (f1/a1)^2 + (f2/a2)^2)`.
    pub fn displacement(&self, f1: &Expr, f2: &Expr) -> Expr {
        blend_displacement(f1, f2, &self.a0, &self.a1, &self.a2)
    }

    fn node(&self, op: SetOp, f1: &Expr, f2: &Expr, alpha: Expr) -> Expr {
        Expr::blend(
            op,
            [
                f1.clone(),
                f2.clone(),
                alpha,
                self.a0.clone(),
                self.a1.clone(),
                self.a2.clone(),
            ],
        )
    }
}

/// Blended union (Eq. 7 with `|a`), a blend node of the graph.
pub fn blend_union(f1: &Expr, f2: &Expr, b: &Blend, alpha: impl Into<Expr>) -> Expr {
    b.node(SetOp::Union, f1, f2, alpha.into())
}

/// Blended intersection (Eq. 7).
pub fn blend_intersection(f1: &Expr, f2: &Expr, b: &Blend, alpha: impl Into<Expr>) -> Expr {
    b.node(SetOp::Intersection, f1, f2, alpha.into())
}

/// Blended subtraction: blended intersection with `-f2`.
pub fn blend_subtraction(f1: &Expr, f2: &Expr, b: &Blend, alpha: impl Into<Expr>) -> Expr {
    b.node(SetOp::Intersection, f1, &f2.neg(), alpha.into())
}

/// Constant offset `f + d` (Eq. 13): `d > 0` grows the solid.
pub fn offset(f: &Expr, d: impl Into<Expr>) -> Expr {
    f + d.into()
}

/// Normalised offset `f / sqrt(f^2 + |grad f|^2) + d` (Eq. 14): the
/// normalisation makes `f` behave like a distance near its zero set, so the
/// offset is nearly uniform in thickness. The gradient is built symbolically,
/// so the result supports every evaluation mode.
pub fn normalized_offset(f: &Expr, d: impl Into<Expr>) -> Expr {
    normalize(f) + d.into()
}

/// `f / sqrt(f^2 + |grad f|^2)`: a distance-like version of `f` with the same zero set.
pub fn normalize(f: &Expr) -> Expr {
    let g = f.gradient();
    f / (f.square() + g[0].square() + g[1].square() + g[2].square()).sqrt()
}

/// Metamorphosis: linear interpolation `f1 (1 - t) + f2 t`; `t` may be a field.
pub fn morph(f1: &Expr, f2: &Expr, t: impl Into<Expr>) -> Expr {
    let t = t.into();
    f1 * (1.0 - &t) + f2 * t
}

/// Smooth union of n positive functions (Park et al. Eq. in 2.2, translated
/// to inside-positive densities): `(sum f_i^a)^(1/a)`, tending to `max` as
/// `a -> inf`. Defined for `f_i > 0` (densities, potentials).
pub fn smooth_union_n(fs: &[Expr], a: impl Into<Expr>) -> Expr {
    let a = a.into();
    let sum = fs
        .iter()
        .map(|f| f.pow(a.clone()))
        .reduce(|s, t| s + t)
        .expect("smooth union of no shapes");
    sum.pow(1.0 / a)
}

/// Smooth intersection of n positive functions: `(sum f_i^-a)^(-1/a)`,
/// tending to `min` as `a -> inf`.
pub fn smooth_intersection_n(fs: &[Expr], a: impl Into<Expr>) -> Expr {
    let a = a.into();
    let sum = fs
        .iter()
        .map(|f| f.pow(a.neg()))
        .reduce(|s, t| s + t)
        .expect("smooth intersection of no shapes");
    sum.pow(-1.0 / a)
}

/// Sawtooth replicating function (Fryazinov Eq. 2) with period `a`, which
/// may be a field (Eq. 10): `1/2 + (t/a - floor(t/a + 1/2))`, values in [0, 1).
pub fn sawtooth(t: &Expr, period: impl Into<Expr>) -> Expr {
    Expr::unary(crate::UnaryOp::Saw, t / period.into())
}

/// Triangle-wave replicating function (Fryazinov Eq. 3, Eq. 11 with a field
/// period): equal to `1/2 + asin(sin(pi t/a))/pi`, computed exactly with
/// `fract`. Values in [0, 1]; its period is `2a` and every second cell of
/// width `a` is mirrored.
pub fn triangle(t: &Expr, period: impl Into<Expr>) -> Expr {
    Expr::unary(crate::UnaryOp::Tri, t / period.into())
}

/// Bias `t^(ln b / ln 0.5)` (Park et al.): bias(0) = 0, bias(0.5) = b, bias(1) = 1.
pub fn bias(t: &Expr, b: impl Into<Expr>) -> Expr {
    t.pow(b.into().ln() / 0.5f64.ln())
}

/// Gain (Park et al.): `bias_{1-g}(2t)/2` below 1/2, `1 - bias_{1-g}(2 - 2t)/2` above.
pub fn gain(t: &Expr, g: impl Into<Expr>) -> Expr {
    let b = 1.0 - g.into();
    let lo = bias(&(2.0 * t), b.clone()) * 0.5;
    let hi = 1.0 - bias(&(2.0 - 2.0 * t), b) * 0.5;
    Expr::select(t.lt(0.5), lo, hi)
}
