//! `hfConvArc`: convolution arcs (LIBRARY.md section 2), including the C
//! code's side effects: it adds `EPS` to each rotation angle and writes it
//! back, and overwrites openings above 180 degrees with 180.

use super::{el, point3, Arg, Kind::*, Output, Registry, EPS};
use microfrep_core::Expr;

/// The reference's value of pi for degree conversion. Deliberately the
/// truncated value the C code uses (not `std::f64::consts::PI`): results must
/// match the reference interpreter.
#[allow(clippy::approx_constant)]
const PI: f64 = 3.141592;

/// The arc kernel integral of the core (`microfrep_shapes::arc_term`)
/// with the argument order used here.
fn arc(x: &Expr, y: &Expr, z: &Expr, r: &Expr, th: &Expr, s: &Expr) -> Expr {
    microfrep_shapes::arc_term(&[x.clone(), y.clone(), z.clone()], r, s, th)
}

fn conv_arc(a: &[Arg]) -> Output {
    let (centre, radius, theta, axis, angle, s) = (
        a[1].array(),
        a[2].array(),
        a[3].array(),
        a[4].array(),
        a[5].array(),
        a[6].array(),
    );
    let mut new_angle = angle.to_vec();
    let mut new_theta = theta.to_vec();
    let value = point3(a, |p| {
        let mut sum = Expr::constant(0.0);
        for (n, sn) in s.iter().enumerate() {
            let u: Vec<Expr> = (0..3).map(|k| el(axis, 3 * n + k) + EPS).collect();
            let len = (u[0].square() + u[1].square() + u[2].square()).sqrt();
            let u: Vec<Expr> = u.iter().map(|c| c / &len).collect();
            let ang = el(angle, n) + EPS;
            if let Some(slot) = new_angle.get_mut(n) {
                *slot = ang.clone();
            }
            let phi = -(&ang * PI / 180.0);
            let (c, sn_) = (phi.cos(), phi.sin());
            let d: Vec<Expr> = (0..3).map(|k| &p[k] - el(centre, 3 * n + k)).collect();
            // Rodrigues: M d = c d + s (u x d) + (1 - c)(u . d) u.
            let cross = [
                &u[1] * &d[2] - &u[2] * &d[1],
                &u[2] * &d[0] - &u[0] * &d[2],
                &u[0] * &d[1] - &u[1] * &d[0],
            ];
            let ud = &u[0] * &d[0] + &u[1] * &d[1] + &u[2] * &d[2];
            let q: Vec<Expr> = (0..3)
                .map(|k| &c * &d[k] + &sn_ * &cross[k] + (1.0 - &c) * &ud * &u[k])
                .collect();
            let r = el(radius, n);
            let th = el(theta, n);
            let th = Expr::select(th.gt(360.0), Expr::constant(360.0), th);
            let big = th.gt(180.0);
            // Above 180 degrees: the remainder, seen from the point turned
            // by -180 degrees about z, then a 180-degree arc.
            let (cz, sz) = ((-PI).cos(), (-PI).sin());
            let (xr, yr) = (&q[0] * cz - &q[1] * sz, &q[0] * sz + &q[1] * cz);
            let rest = arc(&xr, &yr, &q[2], &r, &((&th - 180.0) * PI / 180.0), sn);
            let main_th = Expr::select(big.clone(), Expr::constant(180.0), th);
            if let Some(slot) = new_theta.get_mut(n) {
                *slot = main_th.clone();
            }
            let main = arc(&q[0], &q[1], &q[2], &r, &(main_th * PI / 180.0), sn);
            sum = sum + Expr::select(big, rest, Expr::constant(0.0)) + main;
        }
        sum - a[7].real()
    });
    Output::writes(value, vec![(3, new_theta), (5, new_angle)])
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfconvarc", &[A, A, A, A, A, A, A, R], conv_arc);
}
