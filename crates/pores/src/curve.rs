//! 2D pores (Kou and Tan, Sec. 4.1): the derived polygon of a cell, the
//! closed quadratic B-spline it controls, the area that curve encloses
//! (exactly, also clipped by the cell) and the signed distance to it.
//!
//! The paper's "order 3" NURBS is the quadratic: with four control points
//! `P0..P3` (all weights 1, uniform periodic knots) the closed curve is four
//! quadratic Bezier arcs, arc `k` from `(P_k + P_k+1) / 2` to
//! `(P_k+1 + P_k+2) / 2` with control point `P_k+1`, tangent to the control
//! polygon at the midpoints of its sides. It encloses
//! `area(P) - (1/12) sum_k area(P_k-1, P_k, P_k+1)`, and for any
//! quadrilateral the four corner triangles sum to twice its area, so the
//! curve encloses exactly 5/6 of its control polygon: the paper's
//! experimental `alpha = 0.83` of Eq. 6 is [`ALPHA`] = 5/6.

/// Ratio of the area enclosed by the closed quadratic B-spline to the area
/// of its four-point control polygon (exact).
pub const ALPHA: f64 = 5.0 / 6.0;

/// A 2D point.
pub type P2 = [f64; 2];

fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn lerp(a: P2, b: P2, t: f64) -> P2 {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

fn mid(a: P2, b: P2) -> P2 {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
}

/// Eq. 4: area of the derived polygon of a square of side `l` whose
/// derived points lie at distances `l1..l4` along its four sides (each
/// measured from the side's first corner, counter-clockwise).
pub fn eq4_area(l: f64, l1: f64, l2: f64, l3: f64, l4: f64) -> f64 {
    l * l - 0.5 * (l * (l1 + l2 + l3 + l4) - (l1 * l2 + l2 * l3 + l3 * l4 + l4 * l1))
}

/// Eq. 7: `beta = 2 (l^2 - P area_cell / alpha)` for porosity `p` of a cell
/// of area `area_cell` whose parent square has side `l`.
pub fn eq7_beta(l: f64, p: f64, area_cell: f64, alpha: f64) -> f64 {
    2.0 * (l * l - p * area_cell / alpha)
}

/// Eq. 8: the fourth distance `l4` that gives porosity `p`, from the other
/// three (NaN when `l1 + l3 = l`, where `l4` has no effect on the area).
pub fn eq8_l4(l: f64, l1: f64, l2: f64, l3: f64, p: f64, area_cell: f64, alpha: f64) -> f64 {
    let beta = eq7_beta(l, p, area_cell, alpha);
    let den = l - l1 - l3;
    if den == 0.0 {
        return f64::NAN;
    }
    (beta + l1 * l2 + l2 * l3 - l * (l1 + l2 + l3)) / den
}

/// Eq. 4 for a rectangle, in fractions `r_i = l_i / side_i`: the derived
/// polygon's area over the rectangle's.
pub fn polygon_fraction(r: [f64; 4]) -> f64 {
    1.0 - 0.5
        * ((1.0 - r[0]) * r[1] + (1.0 - r[1]) * r[2] + (1.0 - r[2]) * r[3] + (1.0 - r[3]) * r[0])
}

/// Eq. 8 in fractions: `r4` giving polygon fraction `q` (NaN when
/// `r1 + r3 = 1`).
pub fn solve_r4(r1: f64, r2: f64, r3: f64, q: f64) -> f64 {
    let den = 1.0 - r1 - r3;
    if den == 0.0 {
        return f64::NAN;
    }
    (2.0 * (1.0 - q) - (1.0 - r1) * r2 - (1.0 - r2) * r3 - r1) / den
}

/// The derived polygon of the rectangle `lo..hi`: the points at fractions
/// `r` along its sides, counter-clockwise from the corner `lo`.
pub fn derived_polygon(lo: P2, hi: P2, r: [f64; 4]) -> [P2; 4] {
    let c = [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    std::array::from_fn(|k| lerp(c[k], c[(k + 1) % 4], r[k]))
}

/// Shoelace area of a polygon (counter-clockwise positive).
pub fn shoelace(p: &[P2]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| cross(p[i], p[(i + 1) % n])).sum::<f64>()
}

/// A quadratic Bezier arc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    /// Start, control and end points.
    pub p: [P2; 3],
}

impl Quad {
    /// The straight segment `a..b` as a (degenerate) quadratic.
    pub fn line(a: P2, b: P2) -> Quad {
        Quad {
            p: [a, mid(a, b), b],
        }
    }

    /// Point at `t`.
    pub fn at(&self, t: f64) -> P2 {
        let [a, b, c] = self.p;
        let s = 1.0 - t;
        std::array::from_fn(|k| s * s * a[k] + 2.0 * s * t * b[k] + t * t * c[k])
    }

    /// Derivative at `t`.
    pub fn tangent(&self, t: f64) -> P2 {
        let [a, b, c] = self.p;
        std::array::from_fn(|k| 2.0 * ((1.0 - t) * (b[k] - a[k]) + t * (c[k] - b[k])))
    }

    /// `(1/2) int (x dy - y dx)` along the arc: summed over a closed chain,
    /// the enclosed area.
    pub fn area_term(&self) -> f64 {
        let [a, b, c] = self.p;
        (2.0 * cross(a, b) + cross(a, c) + 2.0 * cross(b, c)) / 6.0
    }

    /// The part of the arc for `t` in `t0..t1` (blossoming).
    pub fn sub(&self, t0: f64, t1: f64) -> Quad {
        let [a, b, c] = self.p;
        let w0 = (1.0 - t0) * (1.0 - t1);
        let w1 = (1.0 - t0) * t1 + t0 * (1.0 - t1);
        let w2 = t0 * t1;
        Quad {
            p: [
                self.at(t0),
                std::array::from_fn(|k| w0 * a[k] + w1 * b[k] + w2 * c[k]),
                self.at(t1),
            ],
        }
    }

    /// Closest point: parameter and squared distance.
    pub fn closest(&self, q: P2) -> (f64, f64) {
        let [p0, p1, p2] = self.p;
        let a = [p1[0] - p0[0], p1[1] - p0[1]];
        let b = [p0[0] - 2.0 * p1[0] + p2[0], p0[1] - 2.0 * p1[1] + p2[1]];
        let d = [p0[0] - q[0], p0[1] - q[1]];
        let dot = |u: P2, v: P2| u[0] * v[0] + u[1] * v[1];
        // (B(t) - q) . B'(t) / 2 = k3 t^3 + k2 t^2 + k1 t + k0.
        let k3 = dot(b, b);
        let k2 = 3.0 * dot(a, b);
        let k1 = 2.0 * dot(a, a) + dot(d, b);
        let k0 = dot(d, a);
        let dist2 = |t: f64| {
            let p = self.at(t);
            (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
        };
        let mut best = (0.0, dist2(0.0));
        let e = dist2(1.0);
        if e < best.1 {
            best = (1.0, e);
        }
        let mut roots = [f64::NAN; 3];
        let count = solve_cubic(k3, k2, k1, k0, &mut roots);
        for &t0 in &roots[..count] {
            if !(t0 > -1e-3 && t0 < 1.0 + 1e-3) {
                continue;
            }
            // Two Newton steps on the cubic polish the root.
            let mut t = t0.clamp(0.0, 1.0);
            for _ in 0..2 {
                let f = ((k3 * t + k2) * t + k1) * t + k0;
                let df = (3.0 * k3 * t + 2.0 * k2) * t + k1;
                if df.abs() > 1e-300 {
                    t = (t - f / df).clamp(0.0, 1.0);
                }
            }
            let v = dist2(t);
            if v < best.1 {
                best = (t, v);
            }
        }
        best
    }
}

/// Real roots of `a t^3 + b t^2 + c t + d` (any of the leading
/// coefficients may vanish); returns how many were written.
fn solve_cubic(a: f64, b: f64, c: f64, d: f64, out: &mut [f64; 3]) -> usize {
    let scale = a.abs().max(b.abs()).max(c.abs()).max(d.abs());
    if scale == 0.0 {
        return 0;
    }
    if a.abs() <= 1e-12 * scale {
        // Quadratic.
        if b.abs() <= 1e-12 * scale {
            if c == 0.0 {
                return 0;
            }
            out[0] = -d / c;
            return 1;
        }
        let disc = c * c - 4.0 * b * d;
        if disc < 0.0 {
            return 0;
        }
        let s = disc.sqrt();
        let q = -0.5 * (c + c.signum() * s);
        let mut n = 0;
        if q != 0.0 {
            out[n] = d / q;
            n += 1;
        }
        out[n] = q / b;
        return n + 1;
    }
    let (b, c, d) = (b / a, c / a, d / a);
    // t = x - b/3: x^3 + p x + q = 0.
    let p = c - b * b / 3.0;
    let q = 2.0 * b * b * b / 27.0 - b * c / 3.0 + d;
    let shift = -b / 3.0;
    let disc = q * q / 4.0 + p * p * p / 27.0;
    if disc > 0.0 {
        let s = disc.sqrt();
        let u = (-q / 2.0 + s).cbrt();
        let v = (-q / 2.0 - s).cbrt();
        out[0] = u + v + shift;
        1
    } else if p == 0.0 {
        out[0] = shift;
        1
    } else {
        let r = (-p / 3.0).sqrt();
        let phi = (3.0 * q / (2.0 * p) / r).clamp(-1.0, 1.0).acos() / 3.0;
        for (k, o) in out.iter_mut().enumerate() {
            *o = 2.0 * r * (phi - 2.0 * std::f64::consts::PI * k as f64 / 3.0).cos() + shift;
        }
        3
    }
}

/// The closed quadratic B-spline of a four-point control polygon, as its
/// four Bezier arcs.
pub fn bspline(ctrl: &[P2; 4]) -> [Quad; 4] {
    std::array::from_fn(|k| Quad {
        p: [
            mid(ctrl[k], ctrl[(k + 1) % 4]),
            ctrl[(k + 1) % 4],
            mid(ctrl[(k + 1) % 4], ctrl[(k + 2) % 4]),
        ],
    })
}

/// Area enclosed by a closed chain of arcs.
pub fn chain_area(arcs: &[Quad]) -> f64 {
    arcs.iter().map(Quad::area_term).sum()
}

/// The closed convex chain `arcs` clipped to the half-plane
/// `n . x <= c`: the arcs inside, closed by one straight segment.
fn clip_half_plane(arcs: &[Quad], n: P2, c: f64) -> Vec<Quad> {
    let g = |p: P2| n[0] * p[0] + n[1] * p[1] - c;
    let mut kept: Vec<Quad> = Vec::new();
    let mut all_in = true;
    for a in arcs {
        // g(B(t)) = g0 (1-t)^2 + 2 g1 t (1-t) + g2 t^2 = A t^2 + B t + C.
        let (g0, g1, g2) = (g(a.p[0]), g(a.p[1]), g(a.p[2]));
        let qa = g0 - 2.0 * g1 + g2;
        let qb = 2.0 * (g1 - g0);
        let qc = g0;
        let mut ts = vec![0.0];
        let mut roots = [f64::NAN; 3];
        let k = solve_cubic(0.0, qa, qb, qc, &mut roots);
        let mut inner: Vec<f64> = roots[..k]
            .iter()
            .copied()
            .filter(|t| *t > 1e-12 && *t < 1.0 - 1e-12)
            .collect();
        inner.sort_by(|x, y| x.total_cmp(y));
        ts.extend(inner);
        ts.push(1.0);
        for w in ts.windows(2) {
            let tm = 0.5 * (w[0] + w[1]);
            let gm = qc + tm * (qb + tm * qa);
            if gm <= 0.0 {
                kept.push(if w[0] == 0.0 && w[1] == 1.0 {
                    *a
                } else {
                    a.sub(w[0], w[1])
                });
            } else {
                all_in = false;
            }
        }
    }
    if all_in || kept.is_empty() {
        return kept;
    }
    // Close the gaps (one for a convex region) with straight segments.
    let scale = arcs
        .iter()
        .flat_map(|a| a.p)
        .map(|p| p[0].abs().max(p[1].abs()))
        .fold(1e-300, f64::max);
    let mut out = Vec::with_capacity(kept.len() + 1);
    for i in 0..kept.len() {
        let a = kept[i];
        out.push(a);
        let b = kept[(i + 1) % kept.len()];
        let (e, s) = (a.p[2], b.p[0]);
        if (e[0] - s[0]).abs().max((e[1] - s[1]).abs()) > 1e-12 * scale {
            out.push(Quad::line(e, s));
        }
    }
    out
}

/// Area of the region inside the closed convex chain `arcs` and the
/// rectangle `lo..hi`, exactly (arcs clipped at the roots of quadratics).
pub fn clipped_area(arcs: &[Quad], lo: P2, hi: P2) -> f64 {
    let mut v = arcs.to_vec();
    for (n, c) in [
        ([1.0, 0.0], hi[0]),
        ([-1.0, 0.0], -lo[0]),
        ([0.0, 1.0], hi[1]),
        ([0.0, -1.0], -lo[1]),
    ] {
        v = clip_half_plane(&v, n, c);
        if v.is_empty() {
            return 0.0;
        }
    }
    chain_area(&v)
}

/// Signed distance to a closed counter-clockwise chain of arcs, positive
/// inside, with its gradient.
pub fn signed_distance(arcs: &[Quad; 4], q: P2) -> (f64, P2) {
    // Each arc lies in its control triangle: the distance to the triangle
    // bounds the distance to the arc from below. Arcs are solved nearest
    // bound first, and skipped once the bound exceeds the best so far.
    let mut bound = [(0.0f64, 0usize); 4];
    for (k, a) in arcs.iter().enumerate() {
        bound[k] = (triangle_distance2(a.p, q), k);
    }
    bound.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut best = (f64::INFINITY, 0usize, 0.0);
    for &(b2, k) in &bound {
        if b2 >= best.0 {
            break;
        }
        let (t, d2) = arcs[k].closest(q);
        if d2 < best.0 {
            best = (d2, k, t);
        }
    }
    let (d2, k, t) = best;
    let p = arcs[k].at(t);
    let mut tan = arcs[k].tangent(t);
    if tan[0] == 0.0 && tan[1] == 0.0 {
        // A degenerate arc end: the neighbouring arc's tangent (the curve
        // is C1 at the joints).
        let j = if t < 0.5 { (k + 3) % 4 } else { (k + 1) % 4 };
        tan = arcs[j].tangent(if t < 0.5 { 1.0 } else { 0.0 });
    }
    let d = d2.sqrt();
    let v = [q[0] - p[0], q[1] - p[1]];
    let inward = [-tan[1], tan[0]];
    let side = v[0] * inward[0] + v[1] * inward[1];
    if d == 0.0 {
        let l = (inward[0] * inward[0] + inward[1] * inward[1])
            .sqrt()
            .max(1e-300);
        return (0.0, [inward[0] / l, inward[1] / l]);
    }
    let s = if side >= 0.0 { 1.0 } else { -1.0 };
    (s * d, [s * v[0] / d, s * v[1] / d])
}

/// Squared distance from `q` to the triangle `p` (0 inside).
fn triangle_distance2(p: [P2; 3], q: P2) -> f64 {
    let o = |a: P2, b: P2, c: P2| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    let area = o(p[0], p[1], p[2]);
    let s0 = o(p[1], p[2], q);
    let s1 = o(p[2], p[0], q);
    let s2 = o(p[0], p[1], q);
    if area != 0.0
        && ((s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0 && area > 0.0)
            || (s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0 && area < 0.0))
    {
        return 0.0;
    }
    let seg = |a: P2, b: P2| {
        let d = [b[0] - a[0], b[1] - a[1]];
        let l = d[0] * d[0] + d[1] * d[1];
        let t = if l > 0.0 {
            (((q[0] - a[0]) * d[0] + (q[1] - a[1]) * d[1]) / l).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let e = [a[0] + t * d[0] - q[0], a[1] + t * d[1] - q[1]];
        e[0] * e[0] + e[1] * e[1]
    };
    seg(p[0], p[1]).min(seg(p[1], p[2])).min(seg(p[2], p[0]))
}
