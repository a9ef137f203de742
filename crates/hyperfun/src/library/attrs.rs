//! Scalar attribute helpers `hfA_*` (LIBRARY.md section 7) and `hfA_Union`.
//! The array-writing helpers are in `attr_arrays`, the patterns and noise in
//! `attr_patterns`.

use super::{el, Arg, Kind::*, Output, Registry, EPS};
use microfrep_core::Expr;

fn wave(a: &[Arg]) -> Output {
    let (t, c1, c2, freq) = (a[0].real(), a[1].real(), a[2].real(), a[3].real());
    let k = (1.0 + (freq * t).sin()) / 2.0;
    let (lo, hi) = (c1.min(&c2), c1.max(&c2));
    Output::value(k * (hi - &lo) + lo)
}

fn clamp(a: &[Arg]) -> Output {
    let (f, lo, hi) = (a[0].real(), a[1].real(), a[2].real());
    let v = Expr::select(f.gt(&hi), hi, f.clone());
    Output::value(Expr::select(f.lt(&lo), lo, v))
}

fn pulse(a: &[Arg]) -> Output {
    let (f, hi, lo) = (a[0].real(), a[1].real(), a[2].real());
    Output::value(f.ge(lo).and(f.le(hi)))
}

fn step(a: &[Arg]) -> Output {
    Output::value(a[0].real().ge(a[1].real()))
}

fn smooth_step(a: &[Arg]) -> Output {
    let (f, lo, hi) = (a[3].real(), a[4].real(), a[5].real());
    let u = (&f - &lo) / (&hi - &lo);
    let mid = u.square() * (3.0 - 2.0 * &u);
    let v = Expr::select(f.gt(&hi), Expr::constant(1.0), mid);
    Output::value(Expr::select(f.lt(&lo), Expr::constant(0.0), v))
}

fn modulo(a: &[Arg]) -> Output {
    let (p, q) = (a[0].real(), a[1].real());
    let r = &p - &q * (&p / &q).trunc();
    Output::value(Expr::select(r.lt(0.0), &r + &q, r))
}

fn floor(a: &[Arg]) -> Output {
    Output::value(a[0].real().trunc())
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfa_wave", &[R, R, R, R], wave);
    r.register("hfa_clamp", &[R, R, R], clamp);
    r.register("hfa_pulse", &[R, R, R], pulse);
    r.register("hfa_step", &[R, R], step);
    r.register("hfa_smoothstep", &[R, R, R, R, R, R], smooth_step);
    r.register("hfa_modulo", &[R, R], modulo);
    r.register("hfa_floor", &[R], floor);
    r.register("hfa_union", &[R, R, A, A, A, R], union);
}

/// R0 union of two values that also blends their attribute arrays into
/// `out` (argument 2) where the union is (nearly) inside.
fn union(a: &[Arg]) -> Output {
    let (f1, f2, op) = (a[0].real(), a[1].real(), a[5].real());
    let v = super::r0_or(&f1, &f2);
    let (out, c1, c2) = (a[2].array(), a[3].array(), a[4].array());
    let only1 = f1.ge(0.0).and(f2.lt(0.0));
    let only2 = f2.ge(0.0).and(f1.lt(0.0));
    let inside = v.gt(-EPS);
    let new: Vec<Expr> = (0..out.len())
        .map(|i| {
            let (x, y) = (el(c1, i), el(c2, i));
            let by_op = [
                x.clone(),
                y.clone(),
                &x + &y,
                Expr::select(x.lt(&y), x.clone(), y.clone()),
                Expr::select(x.gt(&y), x.clone(), y.clone()),
            ]
            .into_iter()
            .enumerate()
            .rev()
            .fold(out[i].clone(), |acc, (k, e)| {
                Expr::select(op.eq_(k as f64), e, acc)
            });
            let pick = Expr::select(only1.clone(), x, Expr::select(only2.clone(), y, by_op));
            Expr::select(inside.clone(), pick, out[i].clone())
        })
        .collect();
    Output::writes(v, vec![(2, new)])
}
