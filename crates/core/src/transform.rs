//! Space mappings. Each function takes the point `p` (usually `Expr::xyz()`)
//! and returns the inverse-mapped point, so `f.remap(&translate(&p, t))` is
//! the shape `f` moved by `t`. Working on points rather than shapes is what
//! HyperFun's in-place `hfShift3D(x, ...)` style needs, and lets any
//! parameter be a field of the (original) point.

use crate::expr::Expr;

/// A point as three coordinate expressions (usually `Expr::xyz()` or an
/// already mapped point).
pub type P3 = [Expr; 3];

fn e(v: impl Into<Expr>) -> Expr {
    v.into()
}

/// Moves a shape by `t`.
pub fn translate(p: &P3, t: [Expr; 3]) -> P3 {
    [&p[0] - &t[0], &p[1] - &t[1], &p[2] - &t[2]]
}

/// Scales a shape by `s` about the origin (no check for zero factors).
pub fn scale(p: &P3, s: [Expr; 3]) -> P3 {
    [&p[0] / &s[0], &p[1] / &s[1], &p[2] / &s[2]]
}

/// Turns a shape by `angle` (radians, right-handed) about the x axis.
pub fn rotate_x(p: &P3, angle: impl Into<Expr>) -> P3 {
    let a = angle.into();
    let (c, s) = (a.cos(), a.sin());
    [
        p[0].clone(),
        &p[1] * &c + &p[2] * &s,
        -(&p[1] * &s) + &p[2] * &c,
    ]
}

/// Turns a shape about the y axis.
pub fn rotate_y(p: &P3, angle: impl Into<Expr>) -> P3 {
    let a = angle.into();
    let (c, s) = (a.cos(), a.sin());
    [
        -(&p[2] * &s) + &p[0] * &c,
        p[1].clone(),
        &p[2] * &c + &p[0] * &s,
    ]
}

/// Turns a shape about the z axis.
pub fn rotate_z(p: &P3, angle: impl Into<Expr>) -> P3 {
    let a = angle.into();
    let (c, s) = (a.cos(), a.sin());
    [
        &p[0] * &c + &p[1] * &s,
        -(&p[0] * &s) + &p[1] * &c,
        p[2].clone(),
    ]
}

/// Turns a shape by `angle` about the unit `axis` through the origin
/// (Rodrigues; the inverse rotation is applied to the point).
pub fn rotate(p: &P3, axis: [f64; 3], angle: f64) -> P3 {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let k = [axis[0] / n, axis[1] / n, axis[2] / n];
    let (c, s) = (angle.cos(), -angle.sin());
    let t = 1.0 - c;
    let m = [
        [
            t * k[0] * k[0] + c,
            t * k[0] * k[1] - s * k[2],
            t * k[0] * k[2] + s * k[1],
        ],
        [
            t * k[0] * k[1] + s * k[2],
            t * k[1] * k[1] + c,
            t * k[1] * k[2] - s * k[0],
        ],
        [
            t * k[0] * k[2] - s * k[1],
            t * k[1] * k[2] + s * k[0],
            t * k[2] * k[2] + c,
        ],
    ];
    linear(p, m, [0.0; 3])
}

/// The point map `q = m p + t` (give the inverse of the shape's transform).
pub fn linear(p: &P3, m: [[f64; 3]; 3], t: [f64; 3]) -> P3 {
    std::array::from_fn(|i| {
        let mut acc = e(t[i]);
        for (j, pj) in p.iter().enumerate() {
            if m[i][j] != 0.0 {
                acc = acc + pj * m[i][j];
            }
        }
        acc
    })
}

/// Applies the affine transform `x -> m x + t` to a shape: the point is
/// mapped by the inverse. Fails if `m` is singular.
pub fn affine(p: &P3, m: [[f64; 3]; 3], t: [f64; 3]) -> Option<P3> {
    let inv = invert3(m)?;
    let ti: [f64; 3] = std::array::from_fn(|i| -(0..3).map(|j| inv[i][j] * t[j]).sum::<f64>());
    Some(linear(p, inv, ti))
}

fn invert3(m: [[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if det.abs() < 1e-300 || !det.is_finite() {
        return None;
    }
    let c = |a: usize, b: usize, cc: usize, d: usize| m[a][b] * m[cc][d] - m[a][d] * m[cc][b];
    Some([
        [
            c(1, 1, 2, 2) / det,
            -c(0, 1, 2, 2) / det,
            c(0, 1, 1, 2) / det,
        ],
        [
            -c(1, 0, 2, 2) / det,
            c(0, 0, 2, 2) / det,
            -c(0, 0, 1, 2) / det,
        ],
        [
            c(1, 0, 2, 1) / det,
            -c(0, 0, 2, 1) / det,
            c(0, 0, 1, 1) / det,
        ],
    ])
}

/// Twist about z: the rotation angle goes linearly from `th1` at `z1` to
/// `th2` at `z2` (not clamped), as HyperFun's `hfTwistZ`.
pub fn twist_z(p: &P3, z1: f64, z2: f64, th1: f64, th2: f64) -> P3 {
    let t = (&p[2] - z1) / (z2 - z1);
    let th = (1.0 - &t) * th1 + t * th2;
    rotate_z(p, th)
}

/// Taper along z: x and y are scaled by `s1` at `z1` to `s2` at `z2`, held
/// constant beyond (HyperFun's `hfTaperZ`, factors near zero treated as 1).
pub fn taper_z(p: &P3, z1: f64, z2: f64, s1: f64, s2: f64) -> P3 {
    let t = (&p[2] - z1) / (z2 - z1);
    let k = Expr::select(
        p[2].lt(z1),
        e(s1),
        Expr::select(p[2].gt(z2), e(s2), (1.0 - &t) * s1 + t * s2),
    );
    let k = Expr::select(k.abs().lt(1e-6), e(1.0), k);
    [&p[0] / &k, &p[1] / &k, p[2].clone()]
}

/// Stretch about the point `q` by factors `s` (HyperFun's `hfStretch3D`).
pub fn stretch(p: &P3, q: [f64; 3], s: [Expr; 3]) -> P3 {
    std::array::from_fn(|i| q[i] + (&p[i] - q[i]) / &s[i])
}
