//! `hfDEllipsoid` (LIBRARY.md section 5): signed distance to an ellipsoid
//! by HyperFun's Newton iteration on the Lagrange parameter, in the C code's
//! operation order.
//!
//! The iteration count depends on the point, so the distance is not a
//! closed-form graph. With constant centre and half-axes (the usual case) it
//! becomes a data-driven field node at the (possibly mapped) point, so the
//! model stays lowered: values from the C-order iteration, gradients and
//! intervals from the core's `DEllipsoid` (a 1-Lipschitz bound around the
//! box centre). Symbolic centre or axes send the model to the per-point
//! fallback.

use super::{el, Arg, Output, SENTINEL};
use microfrep_core::prims::DEllipsoid;
use microfrep_core::{Expr, Field, Interval};
use std::sync::Arc;

/// The distance field with fixed centre and half-axes, at absolute points.
#[derive(Debug)]
struct HfDEllipsoid {
    centre: [f64; 3],
    axes: [f64; 3],
    core: DEllipsoid,
}

impl HfDEllipsoid {
    fn local(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|k| p[k] - self.centre[k])
    }
}

impl Field for HfDEllipsoid {
    fn name(&self) -> &str {
        "hfDEllipsoid"
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        let [c1, c2, c3] = self.centre;
        let [ra, rb, rc] = self.axes;
        d_ellipsoid_num([p[0], p[1], p[2], c1, c2, c3, ra, rb, rc])
    }
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        (self.eval(p), self.core.grad(self.local(p)).1)
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        let c = self.centre;
        let local: [Interval; 3] = std::array::from_fn(|k| b[k].sub(Interval::point(c[k])));
        self.core.interval(local)
    }
    fn grad_interval(&self, b: [Interval; 3]) -> [Interval; 3] {
        self.core.grad_interval(b)
    }
}

/// `hfDEllipsoid(p, c, a, b, cc)`.
pub(super) fn d_ellipsoid(a: &[Arg]) -> Output {
    let p = a[0].array();
    if p.len() != 3 {
        return Output::value(Expr::constant(SENTINEL));
    }
    // Centre and half-axes: numbers, or the fallback.
    let mut v = [0.0; 6];
    let args = (0..3)
        .map(|k| el(a[1].array(), k))
        .chain((2..5).map(|k| a[k].real()));
    for (slot, e) in v.iter_mut().zip(args) {
        match e.as_const() {
            Some(c) => *slot = c,
            None => return Output::needs_constants(),
        }
    }
    let centre = [v[0], v[1], v[2]];
    let axes = [v[3], v[4], v[5]];
    let consts: Option<Vec<f64>> = p.iter().map(Expr::as_const).collect();
    if let Some(q) = consts {
        let [c1, c2, c3] = centre;
        let [ra, rb, rc] = axes;
        let d = d_ellipsoid_num([q[0], q[1], q[2], c1, c2, c3, ra, rb, rc]);
        return Output::value(Expr::constant(d));
    }
    let core = match DEllipsoid::new(axes) {
        Ok(core) => core,
        // Degenerate axes give the sentinel; non-finite ones are left to
        // the per-point path, which reproduces whatever the C code computes.
        Err(_) if axes.iter().any(|x| x.abs() < 1e-6) => {
            return Output::value(Expr::constant(SENTINEL));
        }
        Err(_) => return Output::needs_constants(),
    };
    let field = HfDEllipsoid { centre, axes, core };
    Output::value(Expr::field_at(
        Arc::new(field),
        [p[0].clone(), p[1].clone(), p[2].clone()],
    ))
}

fn d_ellipsoid_num(v: [f64; 9]) -> f64 {
    let [p1, p2, p3, c1, c2, c3, ra, rb, rc] = v;
    if ra.abs() < 1e-6 || rb.abs() < 1e-6 || rc.abs() < 1e-6 {
        return SENTINEL;
    }
    let (dx, dy, dz) = (p1 - c1, p2 - c2, p3 - c3);
    let (a2, b2, c2s) = (ra * ra, rb * rb, rc * rc);
    let inside = (dx / ra).powi(2) + (dy / rb).powi(2) + (dz / rc).powi(2) < 1.0;
    let mut t = if inside {
        0.0
    } else {
        ra.max(rb).max(rc) * (dx * dx + dy * dy + dz * dz).sqrt()
    };
    for _ in 0..128 {
        let (pp, q, w) = (t + a2, t + b2, t + c2s);
        let s = pp * pp * q * q * w * w
            - a2 * dx * dx * q * q * w * w
            - b2 * dy * dy * pp * pp * w * w
            - c2s * dz * dz * pp * pp * q * q;
        if s.abs() < 1e-6 {
            break;
        }
        let ds = 2.0
            * (pp * q * w * (q * w + pp * w + pp * q)
                - a2 * dx * dx * q * w * (q + w)
                - b2 * dy * dy * pp * w * (pp + w)
                - c2s * dz * dz * pp * q * (pp + q));
        t -= s / ds;
    }
    let near = [
        (a2 * p1 + t * c1) / (t + a2),
        (b2 * p2 + t * c2) / (t + b2),
        (c2s * p3 + t * c3) / (t + c2s),
    ];
    let d = ((near[0] - p1).powi(2) + (near[1] - p2).powi(2) + (near[2] - p3).powi(2)).sqrt();
    if inside {
        d
    } else {
        -d
    }
}
