//! Rod lattices from periodic slabs (Pasko et al. 2009, Eqs. 4-6).

use microfrep_core::frep::{blend_intersection, blend_union, intersection, union, Blend};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// Per-axis slab parameters: frequency `q`, phase `p`, threshold `l` in (-1, 1).
/// Any of them may be a field.
#[derive(Clone, Debug)]
pub struct Slabs {
    pub q: [Expr; 3],
    pub p: [Expr; 3],
    pub l: [Expr; 3],
}

impl Slabs {
    /// Same frequency and threshold on all axes, zero phase.
    pub fn uniform(q: impl Into<Expr>, l: impl Into<Expr>) -> Slabs {
        let (q, l) = (q.into(), l.into());
        let zero = Expr::constant(0.0);
        Slabs {
            q: [q.clone(), q.clone(), q],
            p: [zero.clone(), zero.clone(), zero],
            l: [l.clone(), l.clone(), l],
        }
    }

    /// `s_i = sin(q_i x_i + p_i) - l_i`.
    pub fn slab(&self, p: &P3, i: usize) -> Expr {
        (&self.q[i] * &p[i] + &self.p[i]).sin() - &self.l[i]
    }
}

/// Rod lattice `g = r_x | r_y | r_z` with `r_x = s_y & s_z` etc.; `alpha`
/// selects the R-function (1: min/max, 0: HyperFun's smooth R0).
/// `alpha` may be a field.
pub fn rod_lattice(p: &P3, slabs: &Slabs, alpha: impl Into<Expr>) -> Expr {
    let alpha = alpha.into();
    let s: Vec<Expr> = (0..3).map(|i| slabs.slab(p, i)).collect();
    let rx = intersection(&s[1], &s[2], &alpha);
    let ry = intersection(&s[0], &s[2], &alpha);
    let rz = intersection(&s[0], &s[1], &alpha);
    union(&union(&rx, &ry, &alpha), &rz, alpha)
}

/// Rod lattice with blended junctions (Eq. 7): the rods are joined by the
/// blended union, so `a0 > 0` adds fillets where rods meet.
pub fn blended_rod_lattice(p: &P3, slabs: &Slabs, alpha: impl Into<Expr>, blend: &Blend) -> Expr {
    let alpha = alpha.into();
    let s: Vec<Expr> = (0..3).map(|i| slabs.slab(p, i)).collect();
    let rx = intersection(&s[1], &s[2], &alpha);
    let ry = intersection(&s[0], &s[2], &alpha);
    let rz = intersection(&s[0], &s[1], &alpha);
    blend_union(&blend_union(&rx, &ry, blend, &alpha), &rz, blend, alpha)
}

/// Rod lattice whose rods are blended intersections of slabs (Eq. 7 in
/// Eq. 5, Pasko et al. Fig. 2d): `r_x = s_y &b s_z` etc., joined by the plain
/// union. `a0 > 0` rounds the rods' edges outwards, `a0 < 0` removes material.
pub fn rod_lattice_blended_rods(
    p: &P3,
    slabs: &Slabs,
    alpha: impl Into<Expr>,
    blend: &Blend,
) -> Expr {
    let alpha = alpha.into();
    let s: Vec<Expr> = (0..3).map(|i| slabs.slab(p, i)).collect();
    let rx = blend_intersection(&s[1], &s[2], blend, &alpha);
    let ry = blend_intersection(&s[0], &s[2], blend, &alpha);
    let rz = blend_intersection(&s[0], &s[1], blend, &alpha);
    union(&union(&rx, &ry, &alpha), &rz, alpha)
}

/// Volume fraction of the alpha = 1 lattice with equal parameters on all
/// axes: with `w = (pi - 2 asin l)/(2 pi)` the fraction of each period where
/// one slab is positive, rods fill `3 w^2 - 2 w^3` (inclusion-exclusion).
pub fn rod_lattice_volume_fraction(l: f64) -> f64 {
    let w = (std::f64::consts::PI - 2.0 * l.asin()) / (2.0 * std::f64::consts::PI);
    3.0 * w * w - 2.0 * w * w * w
}
