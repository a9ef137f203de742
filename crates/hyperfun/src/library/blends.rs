//! Blending operations on function values (LIBRARY.md section 4). The SARDEF
//! family (`hfDUni`, `hfDInt`, `hfDSub`) needs the reference's quartic
//! solver and is not registered yet.

use super::{Arg, Kind::*, Output, Registry};
use microfrep_core::{Expr, SetOp};

/// `hfBlendUni`/`hfBlendInt`: the alpha = 0 R-function plus the
/// displacement `a0 / (1 + (f1/a1)^2 + (f2/a2)^2)`, as a blend node.
fn blend(op: SetOp, a: &[Arg]) -> Output {
    let args = [
        a[0].real(),
        a[1].real(),
        Expr::constant(0.0),
        a[2].real(),
        a[3].real(),
        a[4].real(),
    ];
    Output::value(Expr::blend(op, args))
}

fn blend_uni(a: &[Arg]) -> Output {
    blend(SetOp::Union, a)
}

fn blend_int(a: &[Arg]) -> Output {
    blend(SetOp::Intersection, a)
}

/// Roots of `(d - f1 - s)^2 + (d - f2 - s)^2 = r^2`: `d = m ± sqrt(disc)/2`
/// with `m = (f1 + f2)/2 + s`. Returns (centre, half-width, real?).
fn circle_roots(f1: &Expr, f2: &Expr, s: &Expr, r: &Expr) -> (Expr, Expr, Expr) {
    let m = (f1 + f2) / 2.0 + s;
    let disc = 2.0 * r.square() - (f1 - f2).square();
    (m, disc.abs().sqrt() / 2.0, disc.ge(0.0))
}

fn d_blend_uni(a: &[Arg]) -> Output {
    let (f1, f2, r) = (a[0].real(), a[1].real(), a[2].real());
    let (m, h, real) = circle_roots(&f1, &f2, &r, &r);
    let near = Expr::select(real, m - h, Expr::constant(0.0));
    Output::value(Expr::select((&f2 - &f1).abs().le(&r), near, f1.max(&f2)))
}

fn d_blend_int(a: &[Arg]) -> Output {
    let (f1, f2, r) = (a[0].real(), a[1].real(), a[2].real());
    let (m, h, real) = circle_roots(&f1, &f2, &-&r, &r);
    let near = Expr::select(real, m + h, Expr::constant(0.0));
    Output::value(Expr::select((&f2 - &f1).abs().le(&r), near, f1.min(&f2)))
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfblenduni", &[R, R, R, R, R], blend_uni);
    r.register("hfblendint", &[R, R, R, R, R], blend_int);
    r.register("hfdblenduni", &[R, R, R], d_blend_uni);
    r.register("hfdblendint", &[R, R, R], d_blend_int);
}
