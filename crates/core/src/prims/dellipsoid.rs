//! hfDEllipsoid: signed Euclidean distance to an ellipsoid by HyperFun's
//! Newton iteration, as a data-driven node (an iteration has no closed form
//! in the graph).

use super::{sub, HF_EPS};
use crate::expr::Expr;
use crate::field::Field;
use crate::interval::Interval;
use crate::transform::P3;
use std::sync::Arc;

/// Ellipsoid distance field centred at the origin; [`d_ellipsoid`] maps the
/// point to the centre. Half-axes are fixed numbers, as the iteration runs
/// outside the graph.
#[derive(Debug, Clone)]
pub struct DEllipsoid {
    axes: [f64; 3],
}

/// Bad half-axes for [`DEllipsoid`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("hfDEllipsoid: half-axis {index} is {value}, needs finite magnitude >= 1e-6")]
pub struct DEllipsoidError {
    pub index: usize,
    pub value: f64,
}

impl DEllipsoid {
    /// Half-axes `(a, b, cc)`; HyperFun returns its sentinel below `EPS`, here
    /// such axes (and non-finite ones) are an error.
    pub fn new(axes: [f64; 3]) -> Result<DEllipsoid, DEllipsoidError> {
        for (index, &value) in axes.iter().enumerate() {
            if !value.is_finite() || value.abs() < HF_EPS {
                return Err(DEllipsoidError { index, value });
            }
        }
        Ok(DEllipsoid { axes })
    }

    /// The Lagrange parameter `t` of the nearest point `a^2 d/(t + a^2)` and
    /// whether `d` started inside, by HyperFun's iteration: Newton on
    /// `s(t) = P^2 Q^2 W^2 - a^2 dx^2 Q^2 W^2 - ...`, at most 128 steps, stop
    /// when `|s| < 1e-6`.
    fn solve(&self, d: [f64; 3]) -> (f64, bool) {
        let [a, b, c] = self.axes;
        let sq = [a * a, b * b, c * c];
        let w = [
            sq[0] * d[0] * d[0],
            sq[1] * d[1] * d[1],
            sq[2] * d[2] * d[2],
        ];
        let ratio = (d[0] / a).powi(2) + (d[1] / b).powi(2) + (d[2] / c).powi(2);
        let inside = ratio < 1.0;
        let mut t = if inside {
            0.0
        } else {
            a.max(b).max(c) * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        };
        for _ in 0..128 {
            let (p, q, r) = (t + sq[0], t + sq[1], t + sq[2]);
            let (p2, q2, r2) = (p * p, q * q, r * r);
            let s = p2 * q2 * r2 - w[0] * q2 * r2 - w[1] * p2 * r2 - w[2] * p2 * q2;
            if s.abs() < 1e-6 {
                break;
            }
            let (pq, pr, qr) = (p * q, p * r, q * r);
            let ds = 2.0
                * (pq * r * (qr + pr + pq)
                    - w[0] * qr * (q + r)
                    - w[1] * pr * (p + r)
                    - w[2] * pq * (p + q));
            t -= s / ds;
        }
        (t, inside)
    }

    fn value_at(&self, d: [f64; 3], t: f64, inside: bool) -> f64 {
        let dist = (0..3)
            .map(|i| {
                let a2 = self.axes[i] * self.axes[i];
                // nearest - d = a^2 d/(t + a^2) - d
                let diff = a2 * d[i] / (t + a2) - d[i];
                diff * diff
            })
            .sum::<f64>()
            .sqrt();
        if inside {
            dist
        } else {
            -dist
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
    /// (`n ~ nearest / a^2 = d/(t + a^2)`), 0 where that normal vanishes.
    fn grad(&self, d: [f64; 3]) -> (f64, [f64; 3]) {
        let (t, inside) = self.solve(d);
        let v = self.value_at(d, t, inside);
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
/// positive inside (hfDEllipsoid), as a field node at `p - c`.
pub fn d_ellipsoid(p: &P3, c: &P3, axes: [f64; 3]) -> Result<Expr, DEllipsoidError> {
    let field = DEllipsoid::new(axes)?;
    Ok(Expr::field_at(Arc::new(field), sub(p, c)))
}
