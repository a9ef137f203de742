//! Sums of radial terms over a list of centres: hfBlobby, hfMetaball, hfSoft.
//! The term count is the number of centres, as HyperFun takes it from `x0`.

use crate::{need, norm2, sub, PrimError};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// `sum_i b_i exp(-a_i r_i^2) - T` with `r_i = |p - centre_i|` (hfBlobby).
pub fn blobby(
    p: &P3,
    centres: &[P3],
    a: &[Expr],
    b: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    let n = centres.len();
    need("hfBlobby", "a", a, n)?;
    need("hfBlobby", "b", b, n)?;
    let mut sum = Expr::constant(0.0);
    for i in 0..n {
        let r2 = norm2(&sub(p, &centres[i]));
        sum = sum + &b[i] * (-(&a[i] * r2)).exp();
    }
    Ok(sum - t.into())
}

/// `sum_i m_i - T` (hfMetaball): `m = b (1 - 3 r^2/d^2)` for `r <= d/3`,
/// `1.5 b (1 - r/d)^2` for `d/3 < r < d`, 0 beyond; terms with `d_i <= 0`
/// contribute nothing.
pub fn metaball(
    p: &P3,
    centres: &[P3],
    b: &[Expr],
    d: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    let n = centres.len();
    need("hfMetaball", "b", b, n)?;
    need("hfMetaball", "d", d, n)?;
    let zero = Expr::constant(0.0);
    let mut sum = zero.clone();
    for i in 0..n {
        let (bi, di) = (&b[i], &d[i]);
        let r2 = norm2(&sub(p, &centres[i]));
        let r = r2.sqrt();
        let near = bi * (1.0 - 3.0 * &r2 / di.square());
        let far = 1.5 * bi * (1.0 - &r / di).square();
        let m = Expr::select(
            r.le(di / 3.0),
            near,
            Expr::select(r.lt(di), far, zero.clone()),
        );
        sum = sum + Expr::select(di.gt(0.0), m, zero.clone());
    }
    Ok(sum - t.into())
}

/// `sum_i (1 - 22 r^2/(9 d^2) + 17 r^4/(9 d^4) - 4 r^6/(9 d^6)) - T` over the
/// terms with `r <= d_i` (hfSoft, Wyvill's soft objects).
pub fn soft(p: &P3, centres: &[P3], d: &[Expr], t: impl Into<Expr>) -> Result<Expr, PrimError> {
    let n = centres.len();
    need("hfSoft", "d", d, n)?;
    let mut sum = Expr::constant(0.0);
    for i in 0..n {
        let r2 = norm2(&sub(p, &centres[i]));
        let d2 = d[i].square();
        let term = 1.0 - 22.0 * &r2 / (9.0 * &d2) + 17.0 * r2.square() / (9.0 * d2.square())
            - 4.0 * r2.powi(3) / (9.0 * d2.powi(3));
        sum = sum + Expr::select(r2.sqrt().le(&d[i]), term, Expr::constant(0.0));
    }
    Ok(sum - t.into())
}
