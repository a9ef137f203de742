//! Convolution surfaces with the Cauchy kernel `1/(1 + S^2 r^2)^2`
//! (Sherstyuk), closed forms as coded in HyperFun by K. Yoshikawa. The
//! primitive count is the length of the kernel-width list `s`, except for
//! hfConvLineR, which counts segment ends.

use crate::{dot, need, norm2, sub, PrimError};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// `sum_n 1/(1 + S_n^2 |p - q_n|^2)^2 - T` (hfConvPoint).
pub fn conv_point(
    p: &P3,
    points: &[P3],
    s: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    need("hfConvPoint", "vect", points, s.len())?;
    let mut sum = Expr::constant(0.0);
    for (q, sn) in points.iter().zip(s) {
        sum = sum + 1.0 / (1.0 + sn.square() * norm2(&sub(p, q))).square();
    }
    Ok(sum - t.into())
}

/// Errors when segment `index` has constant ends that coincide (HyperFun
/// aborts the program there); other zero-length segments evaluate to NaN.
fn check_segment(prim: &'static str, index: usize, b: &P3, e: &P3) -> Result<(), PrimError> {
    let same = (0..3).all(|i| match (b[i].as_const(), e[i].as_const()) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    });
    if same {
        return Err(PrimError::ZeroSegment { prim, index });
    }
    Ok(())
}

/// The kernel integral of one segment from `b` to `e` at `p`.
pub fn line_term(p: &P3, b: &P3, e: &P3, s: &Expr) -> Expr {
    let be = sub(e, b);
    let l = norm2(&be).sqrt();
    let dir = [&be[0] / &l, &be[1] / &l, &be[2] / &l];
    let d = sub(p, b);
    let d2 = norm2(&d);
    let xx = dot(&d, &dir);
    let s2 = s.square();
    let pp2 = 1.0 + &s2 * (&d2 - xx.square());
    let pp = pp2.sqrt();
    let q2 = 1.0 + &s2 * (&d2 + l.square() - 2.0 * &l * &xx);
    let lx = &l - &xx;
    &xx / (2.0 * &pp2 * (&pp2 + &s2 * xx.square()))
        + &lx / (2.0 * &pp2 * q2)
        + ((s * &xx / &pp).atan() + (s * &lx / &pp).atan()) / (2.0 * s * pp2 * &pp)
}

/// Segments from `begin[n]` to `end[n]` (hfConvLine).
pub fn conv_line(
    p: &P3,
    begin: &[P3],
    end: &[P3],
    s: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    let n = s.len();
    need("hfConvLine", "begin", begin, n)?;
    need("hfConvLine", "end", end, n)?;
    let mut sum = Expr::constant(0.0);
    for i in 0..n {
        check_segment("hfConvLine", i, &begin[i], &end[i])?;
        sum = sum + line_term(p, &begin[i], &end[i], &s[i]);
    }
    Ok(sum - t.into())
}

/// Polyline: segment `n` runs from `vertices[n]` to `vertices[n + 1]`
/// (hfConvCurve).
pub fn conv_curve(
    p: &P3,
    vertices: &[P3],
    s: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    let n = s.len();
    if n > 0 {
        need("hfConvCurve", "vect", vertices, n + 1)?;
    }
    let mut sum = Expr::constant(0.0);
    for i in 0..n {
        check_segment("hfConvCurve", i, &vertices[i], &vertices[i + 1])?;
        sum = sum + line_term(p, &vertices[i], &vertices[i + 1], &s[i]);
    }
    Ok(sum - t.into())
}

/// "Radius" segments (hfConvLineR): `S = 1/R` if `R < 1`, else 1; the
/// running sum takes each segment's term only while it is below 1 and is
/// clamped at 1; the threshold subtracted is that of the last segment alone,
/// `l/(2 PT^2 QT2) + atan(S l/PT)/(2 S PT^3)` with `PT^2 = 1 + S^2 R^2`,
/// `QT2 = 1 + S^2 (R^2 + l^2)`. The count is the length of `end`.
pub fn conv_line_r(
    p: &P3,
    begin: &[P3],
    end: &[P3],
    r: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    let n = end.len();
    need("hfConvLineR", "end", end, 1)?;
    need("hfConvLineR", "begin", begin, n)?;
    let r = r.into();
    let s = Expr::select(r.lt(1.0), 1.0 / &r, Expr::constant(1.0));
    let s2 = s.square();
    let pt2 = 1.0 + &s2 * r.square();
    let pt = pt2.sqrt();
    let mut sum = Expr::constant(0.0);
    let mut threshold = Expr::constant(0.0);
    for i in 0..n {
        check_segment("hfConvLineR", i, &begin[i], &end[i])?;
        let l = norm2(&sub(&end[i], &begin[i])).sqrt();
        let qt2 = 1.0 + &s2 * (r.square() + l.square());
        threshold = &l / (2.0 * &pt2 * qt2) + (&s * &l / &pt).atan() / (2.0 * &s * &pt2 * &pt);
        let added = &sum + line_term(p, &begin[i], &end[i], &s);
        let clamped = Expr::select(added.gt(1.0), Expr::constant(1.0), added);
        sum = Expr::select(sum.lt(1.0), clamped, sum);
    }
    Ok(sum - threshold)
}

/// One triangle's kernel integral. The vertices are relabelled (cyclic
/// shift) so that `a1 a2` is the longest edge, with HyperFun's tie rules.
pub fn triangle_term(p: &P3, tri: [&P3; 3], s: &Expr) -> Expr {
    let len = |a: &P3, b: &P3| norm2(&sub(b, a)).sqrt();
    let (l0, l1, l2) = (
        len(tri[0], tri[1]),
        len(tri[1], tri[2]),
        len(tri[2], tri[0]),
    );
    let shift1 = l1.ge(&l2).and(l1.gt(&l0));
    let shift2 = shift1.not().and(l2.ge(&l1).and(l2.gt(&l0)));
    // shift1: (a1, a2, a3) <- (a2, a3, a1); shift2: <- (a3, a1, a2).
    let pick = |k: usize| -> P3 {
        std::array::from_fn(|i| {
            Expr::select(
                shift1.clone(),
                tri[(k + 1) % 3][i].clone(),
                Expr::select(
                    shift2.clone(),
                    tri[(k + 2) % 3][i].clone(),
                    tri[k][i].clone(),
                ),
            )
        })
    };
    let (a1, a2, a3) = (pick(0), pick(1), pick(2));
    let a21 = sub(&a2, &a1);
    let a13 = sub(&a1, &a3);
    let tt = -dot(&a21, &a13) / norm2(&a21);
    let b: P3 = std::array::from_fn(|i| &a1[i] + &tt * &a21[i]);
    let d = sub(p, &b);
    let unit = |v: P3| -> (P3, Expr) {
        let l = norm2(&v).sqrt();
        (std::array::from_fn(|i| &v[i] / &l), l)
    };
    let (u, e2) = unit(sub(&a2, &b));
    let (v, h) = unit(sub(&a3, &b));
    let e1 = norm2(&sub(&a1, &b)).sqrt();
    let d2 = norm2(&d);
    let uc = dot(&d, &u);
    let vc = dot(&d, &v);
    let g = &vc - &h;
    let m = &e2 * &g + &uc * &h;
    let k = &uc * &h - &e1 * &g;
    let c2 = 1.0 / s.square() + &d2 - uc.square();
    let q = &c2 - vc.square();
    let w = &c2 - 2.0 * &vc * &h + h.square();
    let base = h.square() * (&q + uc.square());
    let a2sq = e1.square() * &w + &base - 2.0 * &e1 * &h * &uc * &g;
    let b2sq = e2.square() * &w + &base + 2.0 * &e2 * &h * &uc * &g;
    let (aa, bb, cc) = (a2sq.sqrt(), b2sq.sqrt(), c2.sqrt());
    let n1 = &e1 + &uc;
    let n2 = &e2 - &uc;
    let n3 = &e1 * &n1 + &vc * &h;
    let n4 = -(&e1 * &uc) - &g * &h;
    let n5 = -(&e2 * &n2) - &vc * &h;
    let n6 = -(&e2 * &uc) + &g * &h;
    let arc =
        |coef: &Expr, x: &Expr, y: &Expr, r: &Expr| coef * ((x / r).atan() + (y / r).atan()) / r;
    (arc(&k, &n3, &n4, &aa) + arc(&m, &n5, &n6, &bb) + arc(&vc, &n1, &n2, &cc)) / (2.0 * q * s)
}

/// Triangles: triangle `n` is `vertices[3n..3n+3]` (hfConvTriangle).
pub fn conv_triangle(
    p: &P3,
    vertices: &[P3],
    s: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    need("hfConvTriangle", "vect", vertices, 3 * s.len())?;
    let mut sum = Expr::constant(0.0);
    for (n, sn) in s.iter().enumerate() {
        let tri = [&vertices[3 * n], &vertices[3 * n + 1], &vertices[3 * n + 2]];
        sum = sum + triangle_term(p, tri, sn);
    }
    Ok(sum - t.into())
}

/// Indexed triangle mesh: triangle `n` has the 0-based vertex indices
/// `tris[n]` (hfConvMesh, whose array holds 1-based indices).
pub fn conv_mesh(
    p: &P3,
    vertices: &[P3],
    tris: &[[usize; 3]],
    s: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    need("hfConvMesh", "tri", tris, s.len())?;
    let mut sum = Expr::constant(0.0);
    for (n, sn) in s.iter().enumerate() {
        let get = |k: usize| {
            let index = tris[n][k];
            vertices.get(index).ok_or(PrimError::BadIndex {
                prim: "hfConvMesh",
                tri: n,
                index,
                count: vertices.len(),
            })
        };
        let tri = [get(0)?, get(1)?, get(2)?];
        sum = sum + triangle_term(p, tri, sn);
    }
    Ok(sum - t.into())
}
