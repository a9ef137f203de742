//! hfDEllipsoid: signed Euclidean distance to an ellipsoid by HyperFun's
//! Newton iteration, as a data-driven node (an iteration has no closed form
//! in the graph). This is the one implementation: the HyperFun library uses
//! it too, and it runs the reference's operations in the reference's order,
//! so values match the reference interpreter bit for bit.

use crate::{sub, HF_EPS};
use microfrep_core::transform::P3;
use microfrep_core::Expr;
use microfrep_core::Field;
use microfrep_core::Interval;
use std::sync::Arc;

/// Ellipsoid distance field with a fixed centre and half-axes (the
/// iteration runs outside the graph), positive inside.
#[derive(Debug, Clone)]
pub struct DEllipsoid {
    centre: [f64; 3],
    axes: [f64; 3],
}

/// Bad half-axes for [`DEllipsoid`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("hfDEllipsoid: half-axis {index} is {value}, needs finite magnitude >= 1e-6")]
pub struct DEllipsoidError {
    /// Which half-axis (0, 1, 2).
    pub index: usize,
    /// Its value.
    pub value: f64,
}

impl DEllipsoid {
    /// Centred at the origin with half-axes `(a, b, cc)`; HyperFun returns
    /// its sentinel below `EPS`, here such axes (and non-finite ones) are
    /// an error.
    pub fn new(axes: [f64; 3]) -> Result<DEllipsoid, DEllipsoidError> {
        DEllipsoid::with_centre([0.0; 3], axes)
    }

    /// Centred at `centre`.
    pub fn with_centre(centre: [f64; 3], axes: [f64; 3]) -> Result<DEllipsoid, DEllipsoidError> {
        for (index, &value) in axes.iter().enumerate() {
            if !value.is_finite() || value.abs() < HF_EPS {
                return Err(DEllipsoidError { index, value });
            }
        }
        Ok(DEllipsoid { centre, axes })
    }

    /// The Lagrange parameter `t` of the nearest point and whether `p`
    /// started inside, by HyperFun's iteration: Newton on `s(t) = P^2 Q^2
    /// W^2 - a^2 dx^2 Q^2 W^2 - ...`, at most 128 steps, stop when
    /// `|s| < 1e-6`; products in the reference's order.
    fn solve(&self, p: [f64; 3]) -> (f64, bool) {
        let [ra, rb, rc] = self.axes;
        let [c1, c2, c3] = self.centre;
        let (dx, dy, dz) = (p[0] - c1, p[1] - c2, p[2] - c3);
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
        (t, inside)
    }

    fn value_at(&self, p: [f64; 3], t: f64, inside: bool) -> f64 {
        let [ra, rb, rc] = self.axes;
        let [c1, c2, c3] = self.centre;
        let (a2, b2, c2s) = (ra * ra, rb * rb, rc * rc);
        let near = [
            (a2 * p[0] + t * c1) / (t + a2),
            (b2 * p[1] + t * c2) / (t + b2),
            (c2s * p[2] + t * c3) / (t + c2s),
        ];
        let d =
            ((near[0] - p[0]).powi(2) + (near[1] - p[1]).powi(2) + (near[2] - p[2]).powi(2)).sqrt();
        if inside {
            d
        } else {
            -d
        }
    }
}

impl Field for DEllipsoid {
    fn name(&self) -> &str {
        "hfDEllipsoid"
    }

    fn eval(&self, d: [f64; 3]) -> f64 {
        let (t, inside) = self.solve(d);
        self.value_at(d, t, inside)
    }

    /// The gradient is minus the unit outward normal at the nearest point
    /// (`n ~ (nearest - c) / a^2 = d/(t + a^2)`), 0 where that normal vanishes.
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let (t, inside) = self.solve(p);
        let v = self.value_at(p, t, inside);
        let d: [f64; 3] = std::array::from_fn(|i| p[i] - self.centre[i]);
        let n: [f64; 3] = std::array::from_fn(|i| d[i] / (t + self.axes[i] * self.axes[i]));
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len.is_finite() && len > 0.0 {
            (v, n.map(|c| -c / len))
        } else {
            (v, [0.0; 3])
        }
    }

    /// A signed Euclidean distance is 1-Lipschitz: the value at the box
    /// centre plus or minus half the box diagonal. This holds where
    /// HyperFun's iteration has found the nearest point. Its stop test
    /// (`|s| < 1e-6`, absolute) ends early when the axes are small (below
    /// about 1), and inside, within about 1e-9 of the plane through the
    /// centre across the shortest axis, it stalls at the pole `t = -a_min^2`
    /// and gives too small a value; such values can leave this bound.
    fn interval(&self, b: [Interval; 3]) -> Interval {
        let centre = b.map(|i| i.mid());
        let v = self.eval(centre);
        if v.is_nan() || b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let half = b
            .iter()
            .map(|i| (0.5 * i.width()).powi(2))
            .sum::<f64>()
            .sqrt();
        // Rounding of the mid point and the sum: widen by a relative hair.
        let r = half * (1.0 + 1e-12) + 1e-12 * (1.0 + v.abs());
        Interval::new(v - r, v + r)
    }

    fn grad_interval(&self, _b: [Interval; 3]) -> [Interval; 3] {
        [Interval::new(-1.0, 1.0); 3]
    }
}

/// Signed distance to the ellipsoid with centre `c` and half-axes `axes`,
/// positive inside (hfDEllipsoid), as a field node: at `p` with the centre
/// in the field when `c` is constant (the reference's arithmetic exactly),
/// else at `p - c`.
pub fn d_ellipsoid(p: &P3, c: &P3, axes: [f64; 3]) -> Result<Expr, DEllipsoidError> {
    let consts: Option<Vec<f64>> = c.iter().map(Expr::as_const).collect();
    if let Some(cv) = consts {
        let field = DEllipsoid::with_centre([cv[0], cv[1], cv[2]], axes)?;
        return Ok(Expr::field_at(Arc::new(field), p.clone()));
    }
    let field = DEllipsoid::new(axes)?;
    Ok(Expr::field_at(Arc::new(field), sub(p, c)))
}
