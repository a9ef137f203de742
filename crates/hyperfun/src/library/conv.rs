//! Convolution surfaces with the Cauchy kernel `1/(1 + S^2 r^2)^2`
//! (LIBRARY.md section 2): closed-form kernel integrals over points, line
//! segments and triangles, summed, minus the threshold.

use super::{el, point3, Arg, Kind::*, Output, Registry};
use microfrep_core::Expr;

type V3 = [Expr; 3];

fn triple(a: &[Expr], n: usize) -> V3 {
    [el(a, 3 * n), el(a, 3 * n + 1), el(a, 3 * n + 2)]
}
fn sub(a: &V3, b: &V3) -> V3 {
    [&a[0] - &b[0], &a[1] - &b[1], &a[2] - &b[2]]
}
fn dot(a: &V3, b: &V3) -> Expr {
    &a[0] * &b[0] + &a[1] * &b[1] + &a[2] * &b[2]
}
fn scale(a: &V3, k: &Expr) -> V3 {
    [&a[0] * k, &a[1] * k, &a[2] * k]
}
fn p3(p: &[Expr]) -> V3 {
    [p[0].clone(), p[1].clone(), p[2].clone()]
}

fn conv_point(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (v, s) = (a[1].array(), a[2].array());
        let mut sum = Expr::constant(0.0);
        for (n, sn) in s.iter().enumerate() {
            let d = sub(&p3(p), &triple(v, n));
            sum = sum + 1.0 / (1.0 + sn.square() * dot(&d, &d)).square();
        }
        sum - a[3].real()
    }))
}

/// Kernel integral over the segment `b -> e` with width `s`.
fn segment(p: &V3, b: &V3, e: &V3, s: &Expr) -> Expr {
    let axis = sub(e, b);
    let l = dot(&axis, &axis).sqrt();
    let u = scale(&axis, &(1.0 / &l));
    let d = sub(p, b);
    let t = dot(&d, &u);
    let s2 = s.square();
    let d2 = dot(&d, &d);
    let pp2 = 1.0 + &s2 * (&d2 - t.square());
    let q2 = 1.0 + &s2 * (&d2 + l.square() - 2.0 * &l * &t);
    let pp = pp2.sqrt();
    let lt = &l - &t;
    &t / (2.0 * &pp2 * (&pp2 + &s2 * t.square()))
        + &lt / (2.0 * &pp2 * &q2)
        + ((s * &t / &pp).atan() + (s * &lt / &pp).atan()) / (2.0 * s * pp.powi(3))
}

fn conv_line(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (b, e, s) = (a[1].array(), a[2].array(), a[3].array());
        let p = p3(p);
        let mut sum = Expr::constant(0.0);
        for (n, sn) in s.iter().enumerate() {
            sum = sum + segment(&p, &triple(b, n), &triple(e, n), sn);
        }
        sum - a[4].real()
    }))
}

fn conv_curve(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (v, s) = (a[1].array(), a[2].array());
        let p = p3(p);
        let mut sum = Expr::constant(0.0);
        for (n, sn) in s.iter().enumerate() {
            sum = sum + segment(&p, &triple(v, n), &triple(v, n + 1), sn);
        }
        sum - a[3].real()
    }))
}

fn conv_line_r(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (b, e, r) = (a[1].array(), a[2].array(), a[3].real());
        let s = Expr::select(r.lt(1.0), 1.0 / &r, Expr::constant(1.0));
        let s2 = s.square();
        let p = p3(p);
        let (mut sum, mut thr) = (Expr::constant(0.0), Expr::constant(0.0));
        for n in 0..e.len() / 3 {
            let (bn, en) = (triple(b, n), triple(e, n));
            let ax = sub(&en, &bn);
            let l = dot(&ax, &ax).sqrt();
            let pt = (1.0 + &s2 * r.square()).sqrt();
            let qt2 = 1.0 + &s2 * (r.square() + l.square());
            thr = &l / (2.0 * pt.square() * qt2) + (&s * &l / &pt).atan() / (2.0 * &s * pt.powi(3));
            let added = &sum + segment(&p, &bn, &en, &s);
            let next = Expr::select(sum.lt(1.0), added, sum.clone());
            sum = Expr::select(next.gt(1.0), Expr::constant(1.0), next);
        }
        sum - thr
    }))
}

/// Kernel integral over one triangle (vertices relabelled so that a1-a2 is
/// the longest edge, by cyclic shift).
fn triangle(p: &V3, v: [V3; 3], s: &Expr) -> Expr {
    let len2 = |a: &V3, b: &V3| {
        let d = sub(a, b);
        dot(&d, &d)
    };
    let (e01, e12, e20) = (len2(&v[0], &v[1]), len2(&v[1], &v[2]), len2(&v[2], &v[0]));
    // Three cyclic labellings; pick the one whose first edge is longest.
    let pick = |k: usize| {
        [
            v[k % 3].clone(),
            v[(k + 1) % 3].clone(),
            v[(k + 2) % 3].clone(),
        ]
    };
    let first = e01.ge(&e12).and(e01.ge(&e20));
    let second = e12.ge(&e20);
    let sel = |x: &V3, y: &V3, z: &V3| -> V3 {
        [0, 1, 2].map(|i| {
            Expr::select(
                first.clone(),
                x[i].clone(),
                Expr::select(second.clone(), y[i].clone(), z[i].clone()),
            )
        })
    };
    let (l0, l1, l2) = (pick(0), pick(1), pick(2));
    let a1 = sel(&l0[0], &l1[0], &l2[0]);
    let a2 = sel(&l0[1], &l1[1], &l2[1]);
    let a3 = sel(&l0[2], &l1[2], &l2[2]);
    let edge = sub(&a2, &a1);
    let el2 = dot(&edge, &edge);
    let tb = dot(&sub(&a3, &a1), &edge) / &el2;
    let b: V3 = [0, 1, 2].map(|i| &a1[i] + &tb * &edge[i]);
    let norm = |w: &V3| dot(w, w).sqrt();
    let (ub, vb) = (sub(&a2, &b), sub(&a3, &b));
    let (e2, h) = (norm(&ub), norm(&vb));
    let u = scale(&ub, &(1.0 / &e2));
    let vv = scale(&vb, &(1.0 / &h));
    let e1 = norm(&sub(&a1, &b));
    let d = sub(p, &b);
    let (uc, vc) = (dot(&d, &u), dot(&d, &vv));
    let g = &vc - &h;
    let m = &e2 * &g + &uc * &h;
    let k = &uc * &h - &e1 * &g;
    let c2 = 1.0 / s.square() + dot(&d, &d) - uc.square();
    let q = &c2 - vc.square();
    let w = &c2 - 2.0 * &vc * &h + h.square();
    let hq = h.square() * (&q + uc.square());
    let a2s = e1.square() * &w + &hq - 2.0 * &e1 * &h * &uc * &g;
    let b2s = e2.square() * &w + &hq + 2.0 * &e2 * &h * &uc * &g;
    let n1 = &e1 + &uc;
    let n2 = &e2 - &uc;
    let n3 = &e1 * &n1 + &vc * &h;
    let n4 = -(&e1 * &uc) - &g * &h;
    let n5 = -(&e2 * &n2) - &vc * &h;
    let n6 = -(&e2 * &uc) + &g * &h;
    let (ra, rb, rc) = (a2s.sqrt(), b2s.sqrt(), c2.sqrt());
    let part =
        |coef: Expr, x: Expr, y: Expr, r: &Expr| coef * ((x / r).atan() + (y / r).atan()) / r;
    (part(k, n3, n4, &ra) + part(m, n5, n6, &rb) + part(vc.clone(), n1, n2, &rc)) / (2.0 * q * s)
}

fn conv_triangle(a: &[Arg]) -> Output {
    Output::value(point3(a, |p| {
        let (v, s) = (a[1].array(), a[2].array());
        let p = p3(p);
        let mut sum = Expr::constant(0.0);
        for (n, sn) in s.iter().enumerate() {
            let tri = [0, 1, 2].map(|k| triple(v, 3 * n + k));
            sum = sum + triangle(&p, tri, sn);
        }
        sum - a[3].real()
    }))
}

fn conv_mesh(a: &[Arg]) -> Output {
    let (v, tri, s) = (a[1].array(), a[2].array(), a[3].array());
    let mut idx = Vec::new();
    for t in tri {
        match t.as_const() {
            Some(i) => idx.push(i.trunc()),
            // Vertex indices must be known to pick the vertices.
            None => return Output::needs_constants(),
        }
    }
    Output::value(point3(a, |p| {
        let p = p3(p);
        let vert = |i: f64| {
            if i >= 1.0 && i <= (v.len() / 3) as f64 {
                triple(v, i as usize - 1)
            } else {
                [0, 1, 2].map(|_| Expr::constant(f64::NAN))
            }
        };
        let mut sum = Expr::constant(0.0);
        for (n, sn) in s.iter().enumerate() {
            let t = [0, 1, 2].map(|k| vert(idx.get(3 * n + k).copied().unwrap_or(0.0)));
            sum = sum + triangle(&p, t, sn);
        }
        sum - a[4].real()
    }))
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfconvpoint", &[A, A, A, R], conv_point);
    r.register("hfconvline", &[A, A, A, A, R], conv_line);
    r.register("hfconvcurve", &[A, A, A, R], conv_curve);
    r.register("hfconvliner", &[A, A, A, R], conv_line_r);
    r.register("hfconvtriangle", &[A, A, A, R], conv_triangle);
    r.register("hfconvmesh", &[A, A, A, A, R], conv_mesh);
}
