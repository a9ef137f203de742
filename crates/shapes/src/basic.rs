//! Algebraic primitives (`LIBRARY.md` section 1) and half-spaces.

use crate::{norm2, others, sub};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// `R^2 - |p - c|^2` (hfSphere).
pub fn sphere(p: &P3, c: &P3, r: impl Into<Expr>) -> Expr {
    r.into().square() - norm2(&sub(p, c))
}

/// `1 - (dx/a)^2 - (dy/b)^2 - (dz/cc)^2` (hfEllipsoid).
pub fn ellipsoid(p: &P3, c: &P3, axes: &P3) -> Expr {
    let [dx, dy, dz] = sub(p, c);
    1.0 - (dx / &axes[0]).square() - (dy / &axes[1]).square() - (dz / &axes[2]).square()
}

/// Infinite cylinder along `axis` (0 = x, 1 = y, 2 = z): `R^2` minus the
/// squares of the other two offsets (hfCylinderX/Y/Z).
pub fn cylinder(p: &P3, c: &P3, axis: usize, r: impl Into<Expr>) -> Expr {
    let dd = sub(p, c);
    let (u, v) = others(axis);
    r.into().square() - dd[u].square() - dd[v].square()
}

/// Elliptic cylinder along `axis`, half-axes `a`, `b` on the other two axes
/// in increasing order (hfEllCylX/Y/Z).
pub fn ell_cylinder(p: &P3, c: &P3, axis: usize, a: impl Into<Expr>, b: impl Into<Expr>) -> Expr {
    let dd = sub(p, c);
    let (u, v) = others(axis);
    1.0 - (&dd[u] / a.into()).square() - (&dd[v] / b.into()).square()
}

/// Double cone with apex `c` along `axis`: `d_axis^2 - (d_u/R)^2 - (d_v/R)^2`
/// (hfConeX/Y/Z).
pub fn cone(p: &P3, c: &P3, axis: usize, r: impl Into<Expr>) -> Expr {
    let r = r.into();
    ell_cone(p, c, axis, r.clone(), r)
}

/// Elliptic double cone `d_axis^2 - (d_u/a)^2 - (d_v/b)^2` (hfEllConeX/Y/Z).
pub fn ell_cone(p: &P3, c: &P3, axis: usize, a: impl Into<Expr>, b: impl Into<Expr>) -> Expr {
    let dd = sub(p, c);
    let (u, v) = others(axis);
    dd[axis].square() - (&dd[u] / a.into()).square() - (&dd[v] / b.into()).square()
}

/// Torus around `axis` through `c`: `r0^2 - |p-c|^2 - R^2 + 2 R rho`, rho the
/// distance from the axis (hfTorusX/Y/Z).
pub fn torus(p: &P3, c: &P3, axis: usize, big_r: impl Into<Expr>, r0: impl Into<Expr>) -> Expr {
    let dd = sub(p, c);
    let (u, v) = others(axis);
    let big_r = big_r.into();
    let rho = (dd[u].square() + dd[v].square()).sqrt();
    r0.into().square() - norm2(&dd) - big_r.square() + 2.0 * &big_r * rho
}

/// Block with corner `v` and edge lengths `w` (hfBlock): `R0&(R0&(sx, sy), sz)`
/// of the slabs `sx = (x - v1)(v1 + wx - x)`, HyperFun's ALPHA = 0 form.
pub fn block(p: &P3, v: &P3, w: &P3) -> Expr {
    let s: Vec<Expr> = (0..3)
        .map(|i| (&p[i] - &v[i]) * (&v[i] + &w[i] - &p[i]))
        .collect();
    let r0 = |a: &Expr, b: &Expr| Expr::set(microfrep_core::SetOp::Intersection, a, b, 0.0);
    r0(&r0(&s[0], &s[1]), &s[2])
}

/// Superellipsoid `1 - (|u|^(2/s2) + |v|^(2/s2))^(s2/s1) - |w|^(2/s1)` with
/// `u = dx/a` etc. (hfSuperell).
pub fn superellipsoid(p: &P3, c: &P3, axes: &P3, s1: impl Into<Expr>, s2: impl Into<Expr>) -> Expr {
    let [dx, dy, dz] = sub(p, c);
    let (s1, s2) = (s1.into(), s2.into());
    let u = (dx / &axes[0]).abs();
    let v = (dy / &axes[1]).abs();
    let w = (dz / &axes[2]).abs();
    let e2 = 2.0 / &s2;
    1.0 - (u.pow(e2.clone()) + v.pow(e2)).pow(&s2 / &s1) - w.pow(2.0 / s1)
}

/// Half-space bounded by the plane through `q` with outward normal `n`:
/// value `-(n . (p - q))`, so the solid lies opposite `n`.
pub fn half_space(p: &P3, q: [f64; 3], n: [f64; 3]) -> Expr {
    let mut acc = Expr::constant(0.0);
    for i in 0..3 {
        if n[i] != 0.0 {
            acc = acc - (&p[i] - q[i]) * n[i];
        }
    }
    acc
}
