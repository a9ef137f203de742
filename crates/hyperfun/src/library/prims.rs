//! Primitives, distance primitives and other geometric helpers
//! (LIBRARY.md sections 1, 5 and 6), written in the C code's operation order.

use super::{el, point3, r0_and, tiny, Arg, Kind::*, Output, Registry, SENTINEL};
use microfrep_core::Expr;
use std::f64::consts::PI;

/// `p - c` per axis.
fn delta(p: &[Expr], c: &[Expr]) -> [Expr; 3] {
    [&p[0] - el(c, 0), &p[1] - el(c, 1), &p[2] - el(c, 2)]
}

fn guard(bad: Expr, sentinel: f64, v: Expr) -> Expr {
    Expr::select(bad, Expr::constant(sentinel), v)
}

fn sphere(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let [dx, dy, dz] = delta(p, a[1].array());
        a[2].real().square() - dx.square() - dy.square() - dz.square()
    }))
}

fn ellipsoid(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let [dx, dy, dz] = delta(p, a[1].array());
        let (ra, rb, rc) = (a[2].real(), a[3].real(), a[4].real());
        let v = 1.0 - (dx / &ra).square() - (dy / &rb).square() - (dz / &rc).square();
        guard(tiny(&ra).or(tiny(&rb)).or(tiny(&rc)), SENTINEL, v)
    }))
}

/// Index pairs of the two axes across axis `k`.
fn across(k: usize) -> (usize, usize) {
    [(1, 2), (0, 2), (0, 1)][k]
}

fn cylinder<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        a[2].real().square() - d[i].square() - d[j].square()
    }))
}

fn ell_cyl<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        let (ra, rb) = (a[2].real(), a[3].real());
        let v = 1.0 - (&d[i] / &ra).square() - (&d[j] / &rb).square();
        guard(tiny(&ra).or(tiny(&rb)), SENTINEL, v)
    }))
}

fn torus<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        let (r, r0) = (a[2].real(), a[3].real());
        r0.square() - d[0].square() - d[1].square() - d[2].square() - r.square()
            + 2.0 * &r * (d[i].square() + d[j].square()).sqrt()
    }))
}

fn cone<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        let r = a[2].real();
        d[K].square() - (&d[i] / &r).square() - (&d[j] / &r).square()
    }))
}

fn ell_cone<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        d[K].square() - (&d[i] / a[2].real()).square() - (&d[j] / a[3].real()).square()
    }))
}

fn block(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let v = a[1].array();
        let w = [a[2].real(), a[3].real(), a[4].real()];
        let s: Vec<Expr> = (0..3)
            .map(|k| (&p[k] - el(v, k)) * (el(v, k) + &w[k] - &p[k]))
            .collect();
        let val = r0_and(&r0_and(&s[0], &s[1]), &s[2]);
        let bad = w[0].lt(0.0).or(w[1].lt(0.0)).or(w[2].lt(0.0));
        guard(bad, SENTINEL, val)
    }))
}

fn superell(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let [dx, dy, dz] = delta(p, a[1].array());
        let r: Vec<Expr> = (2..7).map(|k| a[k].real()).collect();
        let (u, v, w) = (dx / &r[0], dy / &r[1], dz / &r[2]);
        let (s1, s2) = (&r[3], &r[4]);
        let e2 = 2.0 / s2;
        let val = 1.0 - (u.abs().pow(&e2) + v.abs().pow(&e2)).pow(s2 / s1) - w.abs().pow(2.0 / s1);
        let bad = r.iter().map(tiny).reduce(|x, y| x.or(y)).unwrap();
        guard(bad, SENTINEL, val)
    }))
}

/// Squared distances from the point to the centres `(x0_i, y0_i, z0_i)`,
/// one per element of `x0`.
fn centre_r2(p: &[Expr], a: &[Arg]) -> Vec<Expr> {
    let (x0, y0, z0) = (a[1].array(), a[2].array(), a[3].array());
    (0..x0.len())
        .map(|i| {
            (&p[0] - &x0[i]).square() + (&p[1] - el(y0, i)).square() + (&p[2] - el(z0, i)).square()
        })
        .collect()
}

fn blobby(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (ka, kb) = (a[4].array(), a[5].array());
        let mut sum = Expr::constant(0.0);
        for (i, r2) in centre_r2(p, a).iter().enumerate() {
            sum = sum + el(kb, i) * (-el(ka, i) * r2).exp();
        }
        sum - a[6].real()
    }))
}

fn metaball(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (kb, kd) = (a[4].array(), a[5].array());
        let mut sum = Expr::constant(0.0);
        for (i, r2) in centre_r2(p, a).iter().enumerate() {
            let (b, d) = (el(kb, i), el(kd, i));
            let r = r2.sqrt();
            let near = &b * (1.0 - 3.0 * r2 / d.square());
            let mid = 1.5 * &b * (1.0 - &r / &d).square();
            let m = Expr::select(
                r.le(&d / 3.0),
                near,
                Expr::select(r.lt(&d), mid, Expr::constant(0.0)),
            );
            sum = sum + Expr::select(d.gt(0.0), m, Expr::constant(0.0));
        }
        sum - a[6].real()
    }))
}

fn soft(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let kd = a[4].array();
        let mut sum = Expr::constant(0.0);
        for (i, r2) in centre_r2(p, a).iter().enumerate() {
            let d2 = el(kd, i).square();
            let (r4, d4) = (r2.square(), d2.square());
            let term = 1.0 - 22.0 * r2 / (9.0 * &d2) + 17.0 * &r4 / (9.0 * &d4)
                - 4.0 * (&r4 * r2) / (9.0 * (&d4 * &d2));
            sum = sum + Expr::select(r2.sqrt().le(el(kd, i)), term, Expr::constant(0.0));
        }
        sum - a[5].real()
    }))
}

fn noise_g(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (amp, w, phase) = (a[1].real(), a[2].real(), a[3].real());
        let amp2 = &amp / 1.17;
        let s: Vec<Expr> = p.iter().map(|c| (&w * c).sin()).collect();
        let part = |k: usize, other: usize| {
            &amp * &s[k] + &amp2 * (&w * &p[k] / 1.35 + &phase * &s[other]).sin()
        };
        part(0, 2) * part(1, 0) * part(2, 1)
    }))
}

/// Sentinel of `hfDConeX/Y/Z` for a point array whose length is not 3
/// (not the usual one).
pub const SENTINEL_DCONE: f64 = -11111111111.0;
/// Sentinel of `hfDCylinder`.
pub const SENTINEL_DCYLINDER: f64 = -11111111111.1;

/// Like [`point3`] with a function-specific sentinel.
fn point3_or(args: &[Arg], sentinel: f64, f: impl FnOnce(&[Expr]) -> Expr) -> Expr {
    if args[0].array().len() != 3 {
        return Expr::constant(sentinel);
    }
    point3(args, f)
}

fn d_cone<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3_or(a, SENTINEL_DCONE, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        let t = a[2].real().atan();
        -((d[i].square() + d[j].square()).sqrt() * t.cos() - d[K].abs() * t.sin())
    }))
}

fn d_cylinder(a: &[Arg]) -> Output {
    Output::value(point3_or(a, SENTINEL_DCYLINDER, |p| {
        let (c, u) = (a[1].array(), a[2].array());
        let w: Vec<Expr> = (0..3).map(|k| el(c, k) - &p[k]).collect();
        let u: Vec<Expr> = (0..3).map(|k| el(u, k)).collect();
        let cx = &u[1] * &w[2] - &u[2] * &w[1];
        let cy = &u[2] * &w[0] - &u[0] * &w[2];
        let cz = &u[0] * &w[1] - &u[1] * &w[0];
        let len = |x: &Expr, y: &Expr, z: &Expr| (x.square() + y.square() + z.square()).sqrt();
        a[3].real() - len(&cx, &cy, &cz) / len(&u[0], &u[1], &u[2])
    }))
}

fn d_torus<const K: usize>(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let d = delta(p, a[1].array());
        let (i, j) = across(K);
        let rho = (d[i].square() + d[j].square()).sqrt();
        a[3].real() - ((rho - a[2].real()).square() + d[K].square()).sqrt()
    }))
}

/// Most terms a Fourier sawtooth may have (each is a few graph nodes).
pub const MAX_SAWTOOTH_TERMS: f64 = 100_000.0;

/// Fourier sawtooth; the term count must be known when the model is built.
fn sawtooth(a: &[Arg]) -> Output {
    let n = a[1].real().as_const().map(|n| n.trunc());
    let value = match n {
        Some(n) if n.is_nan() => {
            return Output::error("the term count (argument 2) is not a number")
        }
        Some(n) if n <= 1.0 => Expr::constant(0.0),
        Some(n) if n > MAX_SAWTOOTH_TERMS => {
            return Output::error(format!(
            "the term count (argument 2) is {n}; at most {MAX_SAWTOOTH_TERMS} terms are supported"
        ))
        }
        Some(n) => {
            let (t, f) = (a[0].real(), a[3].real());
            let mut sum = Expr::constant(0.0);
            for k in 1..(n as i64) {
                let k = k as f64;
                sum = sum + (2.0 * PI * k * &f * &t).sin() / k;
            }
            2.0 / (a[2].real() * PI) * (0.5 - sum)
        }
        None => return Output::needs_constants(),
    };
    Output::value(value)
}

pub(super) fn register(r: &mut Registry) {
    const P3: &[super::Kind] = &[A, A, R];
    const P4: &[super::Kind] = &[A, A, R, R];
    const P5: &[super::Kind] = &[A, A, R, R, R];
    r.register("hfsphere", P3, sphere);
    r.register("hfellipsoid", P5, ellipsoid);
    r.register("hfcylinderx", P3, cylinder::<0>);
    r.register("hfcylindery", P3, cylinder::<1>);
    r.register("hfcylinderz", P3, cylinder::<2>);
    r.register("hfellcylx", P4, ell_cyl::<0>);
    r.register("hfellcyly", P4, ell_cyl::<1>);
    r.register("hfellcylz", P4, ell_cyl::<2>);
    r.register("hftorusx", P4, torus::<0>);
    r.register("hftorusy", P4, torus::<1>);
    r.register("hftorusz", P4, torus::<2>);
    r.register("hfconex", P3, cone::<0>);
    r.register("hfconey", P3, cone::<1>);
    r.register("hfconez", P3, cone::<2>);
    r.register("hfellconex", P4, ell_cone::<0>);
    r.register("hfellconey", P4, ell_cone::<1>);
    r.register("hfellconez", P4, ell_cone::<2>);
    r.register("hfblock", P5, block);
    r.register("hfsuperell", &[A, A, R, R, R, R, R], superell);
    r.register("hfblobby", &[A, A, A, A, A, A, R], blobby);
    r.register("hfmetaball", &[A, A, A, A, A, A, R], metaball);
    r.register("hfsoft", &[A, A, A, A, A, R], soft);
    r.register("hfnoiseg", &[A, R, R, R], noise_g);
    r.register("hfdconex", P3, d_cone::<0>);
    r.register("hfdconey", P3, d_cone::<1>);
    r.register("hfdconez", P3, d_cone::<2>);
    r.register("hfdcylinder", &[A, A, A, R], d_cylinder);
    r.register("hfdtorusx", P4, d_torus::<0>);
    r.register("hfdtorusy", P4, d_torus::<1>);
    r.register("hfdtorusz", P4, d_torus::<2>);
    r.register("hfsawtooth", &[R, R, R, R], sawtooth);
    r.register("hfbeziervolume", &[A, R, R, R, A, A], bezier_volume);
    r.register("hfdellipsoid", P5, super::dellipsoid::d_ellipsoid);
    r.register("hfr", &[A, R], r_callback);
}

/// `hfR(p, index)` calls back into R in the R package; outside R (and in
/// the reference data, whose stub returns 0) it is 0. `check` warns.
fn r_callback(_: &[Arg]) -> Output {
    Output::value(Expr::constant(0.0))
}

/// Bernstein polynomial `C(n, i) (1 - t)^(n - i) t^i`.
fn bernstein(i: usize, n: usize, t: &Expr) -> Expr {
    let binom = (0..i).fold(1.0, |acc, k| acc * (n - k) as f64 / (k + 1) as f64);
    binom * (1.0 - t).powi((n - i) as i32) * t.powi(i as i32)
}

/// Trivariate Bezier volume clipped to its box; the control counts must be
/// known when the model is built.
fn bezier_volume(a: &[Arg]) -> Output {
    let mut counts = [0usize; 3];
    for (k, c) in counts.iter_mut().enumerate() {
        match a[k + 1].real().as_const() {
            Some(v) if (1.0..=20.0).contains(&v.trunc()) => *c = v.trunc() as usize,
            Some(v) => {
                return Output::error(format!(
                    "the control count {} (argument {}) is {v}; it must be from 1 to 20",
                    ["l", "m", "n"][k],
                    k + 2
                ))
            }
            None => return Output::needs_constants(),
        }
    }
    let need = counts.iter().product::<usize>();
    let got = a[5].array().len();
    if got != need {
        return Output::error(format!(
            "argument 6 (the control values) has {got} elements; it must have l*m*n = {need}"
        ));
    }
    Output::value(point3(a, |p| {
        let (bb, w) = (a[4].array(), a[5].array());
        let [l, m, n] = counts;
        let unit = |k: usize| (&p[k] - el(bb, k)) / (el(bb, k + 3) - el(bb, k));
        let (u, v, s) = (unit(0), unit(1), unit(2));
        let mut sum = Expr::constant(0.0);
        for i in 0..l {
            for j in 0..m {
                for k in 0..n {
                    let b =
                        bernstein(i, l - 1, &u) * bernstein(j, m - 1, &s) * bernstein(k, n - 1, &v);
                    sum = sum + b * el(w, i * m * n + j * n + k);
                }
            }
        }
        let slab = |k: usize| (el(bb, k + 3) - &p[k]) * (&p[k] - el(bb, k));
        let clip = r0_and(&r0_and(&slab(0), &slab(1)), &slab(2));
        r0_and(&clip, &sum)
    }))
}
