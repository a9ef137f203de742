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

/// Kernel integral over the segment `b -> e` with width `s` (the core's).
fn segment(p: &V3, b: &V3, e: &V3, s: &Expr) -> Expr {
    microfrep_shapes::line_term(p, b, e, s)
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

/// Kernel integral over one triangle (the core's, which relabels the
/// vertices so that the first edge is the longest, as the reference does).
fn triangle(p: &V3, v: [V3; 3], s: &Expr) -> Expr {
    microfrep_shapes::triangle_term(p, [&v[0], &v[1], &v[2]], s)
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
    let nv = v.len() / 3;
    for (k, t) in tri.iter().enumerate() {
        match t.as_const() {
            Some(i) if i.trunc() >= 1.0 && i.trunc() <= nv as f64 => idx.push(i.trunc()),
            Some(i) => {
                return Output::error(format!(
                    "element {} of argument 3 (the triangles) is {i}, not a vertex index \
                     from 1 to {nv}",
                    k + 1
                ))
            }
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
