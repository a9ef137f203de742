//! Distance primitives, positive inside (`LIBRARY.md` section 5), except the
//! ellipsoid, which is an iteration (see `dellipsoid.rs`).

use crate::{norm2, others, sub};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// Double cone along `axis` with apex `c` and slope `R` (radius per unit
/// length): `-(rho cos t - |d_axis| sin t)`, `t = atan(R)` (hfDConeX/Y/Z).
pub fn d_cone(p: &P3, c: &P3, axis: usize, r: impl Into<Expr>) -> Expr {
    let dd = sub(p, c);
    let (u, v) = others(axis);
    let t = r.into().atan();
    let rho = (dd[u].square() + dd[v].square()).sqrt();
    -(rho * t.cos() - dd[axis].abs() * t.sin())
}

/// Infinite cylinder of radius `R` around the line through `c` along `u`:
/// `R - |u x (c - p)| / |u|` (hfDCylinder).
pub fn d_cylinder(p: &P3, c: &P3, u: &P3, r: impl Into<Expr>) -> Expr {
    let w = sub(c, p);
    let cross = [
        &u[1] * &w[2] - &u[2] * &w[1],
        &u[2] * &w[0] - &u[0] * &w[2],
        &u[0] * &w[1] - &u[1] * &w[0],
    ];
    r.into() - norm2(&cross).sqrt() / norm2(u).sqrt()
}

/// Torus around `axis` through `c`: `r0 - sqrt((rho - R)^2 + d_axis^2)`
/// (hfDTorusX/Y/Z), the exact signed distance.
pub fn d_torus(p: &P3, c: &P3, axis: usize, big_r: impl Into<Expr>, r0: impl Into<Expr>) -> Expr {
    let dd = sub(p, c);
    let (u, v) = others(axis);
    let rho = (dd[u].square() + dd[v].square()).sqrt();
    r0.into() - ((rho - big_r.into()).square() + dd[axis].square()).sqrt()
}
