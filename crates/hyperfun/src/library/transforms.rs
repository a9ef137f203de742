//! Space transformations (LIBRARY.md section 3). Each overwrites its first
//! argument with the inverse-mapped point and returns 1; with a point array
//! of the wrong length the C code would read out of bounds, here the array
//! is left unchanged and the call returns the sentinel.

use super::{el, tiny, Arg, Kind::*, Output, Registry, SENTINEL};
use microfrep_core::Expr;

/// Runs `f` on the point (length 3) and writes its result into argument 0.
fn map(a: &[Arg], f: impl FnOnce([Expr; 3]) -> [Expr; 3]) -> Output {
    let p = a[0].array();
    if p.len() != 3 {
        return Output::value(Expr::constant(SENTINEL));
    }
    let q = f([p[0].clone(), p[1].clone(), p[2].clone()]);
    Output::writes(Expr::constant(1.0), vec![(0, q.to_vec())])
}

fn shift(a: &[Arg]) -> Output {
    map(a, |[x, y, z]| {
        [x - a[1].real(), y - a[2].real(), z - a[3].real()]
    })
}

fn scale(a: &[Arg]) -> Output {
    map(a, |[x, y, z]| {
        [x / a[1].real(), y / a[2].real(), z / a[3].real()]
    })
}

/// Turns `(u, v)` by `th`: `(u cos + v sin, -u sin + v cos)`.
fn turn(u: &Expr, v: &Expr, th: &Expr) -> (Expr, Expr) {
    let (c, s) = (th.cos(), th.sin());
    (u * &c + v * &s, -(u * &s) + v * &c)
}

/// Rotation about axis `K` with the plane pair in the C code's order.
fn rotate_by<const K: usize>(p: [Expr; 3], th: &Expr) -> [Expr; 3] {
    let [x, y, z] = p;
    match K {
        0 => {
            let (y2, z2) = turn(&y, &z, th);
            [x, y2, z2]
        }
        1 => {
            let (z2, x2) = turn(&z, &x, th);
            [x2, y, z2]
        }
        _ => {
            let (x2, y2) = turn(&x, &y, th);
            [x2, y2, z]
        }
    }
}

fn rotate<const K: usize>(a: &[Arg]) -> Output {
    map(a, |p| rotate_by::<K>(p, &a[1].real()))
}

fn twist<const K: usize>(a: &[Arg]) -> Output {
    map(a, |p| {
        let (c1, c2, th1, th2) = (a[1].real(), a[2].real(), a[3].real(), a[4].real());
        let t = (&p[K] - &c1) / (c2 - &c1);
        let th = (1.0 - &t) * th1 + t * th2;
        rotate_by::<K>(p, &th)
    })
}

fn taper<const K: usize>(a: &[Arg]) -> Output {
    map(a, |mut p| {
        let (c1, c2, s1, s2) = (a[1].real(), a[2].real(), a[3].real(), a[4].real());
        let t = (&p[K] - &c1) / (&c2 - &c1);
        let lerp = (1.0 - &t) * &s1 + &t * &s2;
        let k = Expr::select(p[K].lt(&c1), s1, Expr::select(p[K].gt(&c2), s2, lerp));
        let k = Expr::select(tiny(&k), Expr::constant(1.0), k);
        for (i, c) in p.iter_mut().enumerate() {
            if i != K {
                *c = &*c / &k;
            }
        }
        p
    })
}

fn stretch(a: &[Arg]) -> Output {
    map(a, |p| {
        let q = a[1].array();
        let s = [a[2].real(), a[3].real(), a[4].real()];
        let mut i = 0;
        p.map(|pk| {
            let v = el(q, i) + (pk - el(q, i)) / &s[i];
            i += 1;
            v
        })
    })
}

/// Shared loop of the two space maps: `weight(u)` from the scaled offsets.
fn space_map(a: &[Arg], weight: fn(&[Expr; 3]) -> (Expr, Expr)) -> Output {
    map(a, |mut p| {
        let (src, dst, b) = (a[1].array(), a[2].array(), a[3].array());
        for i in 0..src.len() / 3 {
            let d: Vec<Expr> = (0..3)
                .map(|k| el(dst, 3 * i + k) - &src[3 * i + k])
                .collect();
            let u = [0, 1, 2]
                .map(|k| (&p[k] - el(dst, 3 * i + k)) / (el(b, 3 * i + k) * (1.0 + d[k].abs())));
            let (apply, w) = weight(&u);
            for k in 0..3 {
                p[k] = Expr::select(apply.clone(), &p[k] - &w * &d[k], p[k].clone());
            }
        }
        p
    })
}

fn map_exp(a: &[Arg]) -> Output {
    space_map(a, |u| {
        let w = (-(u[0].square() + u[1].square() + u[2].square())).exp();
        (Expr::constant(1.0), w)
    })
}

fn map_cubic(a: &[Arg]) -> Output {
    space_map(a, |u| {
        let r = (u[0].square() + u[1].square() + u[2].square()).sqrt();
        let w = (1.0 - &r).powi(3) / (1.0 + &r);
        (r.le(1.0), w)
    })
}

pub(super) fn register(r: &mut Registry) {
    const TWIST: &[super::Kind] = &[A, R, R, R, R];
    r.register("hfshift3d", &[A, R, R, R], shift);
    r.register("hfscale3d", &[A, R, R, R], scale);
    r.register("hfrotate3dx", &[A, R], rotate::<0>);
    r.register("hfrotate3dy", &[A, R], rotate::<1>);
    r.register("hfrotate3dz", &[A, R], rotate::<2>);
    r.register("hftwistx", TWIST, twist::<0>);
    r.register("hftwisty", TWIST, twist::<1>);
    r.register("hftwistz", TWIST, twist::<2>);
    r.register("hftaperx", TWIST, taper::<0>);
    r.register("hftapery", TWIST, taper::<1>);
    r.register("hftaperz", TWIST, taper::<2>);
    r.register("hfstretch3d", &[A, A, R, R, R], stretch);
    r.register("hfspacemapexp", &[A, A, A, A], map_exp);
    r.register("hfspacemapcubic", &[A, A, A, A], map_cubic);
}
