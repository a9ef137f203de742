//! Rod lattices from periodic slabs (Pasko et al. 2009, Eqs. 4-6).

use microfrep_core::frep::{blend_intersection, blend_union, intersection, union, Blend};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// Per-axis slab parameters: frequency `q`, phase `p`, threshold `l` in (-1, 1).
/// Any of them may be a field.
#[derive(Clone, Debug)]
pub struct Slabs {
    /// Frequency on each axis (slabs repeat every `2 pi / q`).
    pub q: [Expr; 3],
    /// Phase on each axis, radians.
    pub p: [Expr; 3],
    /// Threshold on each axis, in (-1, 1); larger means thinner slabs.
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

/// Surface area of the alpha = 1 lattice with equal parameters, period 1
/// (q = 2 pi) and phase 0, clipped to the unit cube `[0, 1]^3`. Slab `i` is
/// positive on `[a, a + w]` with `a = asin(l) / (2 pi)`, so the cube splits
/// into 3 x 3 x 3 boxes, a box being solid where at least two of its axes
/// fall in the slab; the area sums the faces between solid and empty boxes
/// (the cube's own faces do not count).
pub fn rod_lattice_area_in_unit_cube(l: f64) -> f64 {
    use std::f64::consts::PI;
    let w = (PI - 2.0 * l.asin()) / (2.0 * PI);
    let a = l.asin() / (2.0 * PI);
    let cuts = [0.0, a, a + w, 1.0];
    let len = |i: usize| cuts[i + 1] - cuts[i];
    let solid = |c: [i32; 3]| -> bool {
        c.iter().all(|&v| (0..3).contains(&v)) && c.iter().filter(|&&v| v == 1).count() >= 2
    };
    let mut area = 0.0;
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                let c = [x, y, z];
                if !solid(c) {
                    continue;
                }
                for ax in 0..3 {
                    for d in [-1, 1] {
                        let mut n = c;
                        n[ax] += d;
                        if !solid(n) {
                            let (u, v) = ((ax + 1) % 3, (ax + 2) % 3);
                            area += len(c[u] as usize) * len(c[v] as usize);
                        }
                    }
                }
            }
        }
    }
    area
}
