//! `hfDEllipsoid` (LIBRARY.md section 5): signed distance to an ellipsoid
//! by HyperFun's Newton iteration on the Lagrange parameter, in the C code's
//! operation order.
//!
//! The iteration count depends on the point, so the distance is not a
//! closed-form graph. With constant centre and half-axes (the usual case) it
//! becomes a data-driven field node at the (possibly mapped) point, so the
//! model stays lowered: the shapes crate's `DEllipsoid` (the reference's
//! iteration in its operation order, gradients, a 1-Lipschitz interval).
//! Symbolic centre or axes send the model to the per-point fallback.

use super::{el, Arg, Output, SENTINEL};
use microfrep_core::{Expr, Field};
use microfrep_shapes::DEllipsoid;
use std::sync::Arc;

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
    let field = match DEllipsoid::with_centre(centre, axes) {
        Ok(f) => f,
        // Degenerate axes give the sentinel; non-finite ones are left to
        // the per-point path, which reproduces whatever the C code computes.
        Err(_) if axes.iter().any(|x| x.abs() < 1e-6) => {
            return Output::value(Expr::constant(SENTINEL));
        }
        Err(_) => return Output::needs_constants(),
    };
    let consts: Option<Vec<f64>> = p.iter().map(Expr::as_const).collect();
    if let Some(q) = consts {
        return Output::value(Expr::constant(field.eval([q[0], q[1], q[2]])));
    }
    Output::value(Expr::field_at(
        Arc::new(field),
        [p[0].clone(), p[1].clone(), p[2].clone()],
    ))
}
