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
//!
//! **Weights.** The arcs may be rational: each arc's middle (corner)
//! control point carries a weight `w` (the end points, the side
//! midpoints, weight 1; this is the usual NURBS form of a closed conic
//! chain, the knots doubled at the midpoints). `w = 1` is the polynomial
//! B-spline above, `w < 1` pulls the arcs towards their chords (an
//! ellipse, `w = sqrt(2)/2` on a square the inscribed circle), `w > 1`
//! towards the corners (a hyperbola). The segment between an arc and its
//! chord has [`segment_ratio`]`(w)` times its control triangle's area, so
//! the curve encloses `alpha(w) = (1 + segment_ratio(w)) / 2` of any
//! four-point control polygon ([`alpha`]; 5/6 at `w = 1`).

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

/// Ratio of the area between a rational quadratic arc (middle weight `w`)
/// and its chord to the area of its control triangle: 2/3 at `w = 1` (the
/// parabola), `pi/2 - 1` at `w = sqrt(2)/2` (a quarter circle).
///
/// Closed form: with `w = cos(theta)` (`w < 1`) it is
/// `w (theta / sin(theta) - w) / sin(theta)^2`, with `w = cosh(phi)`
/// (`w > 1`) `w (w - phi / sinh(phi)) / sinh(phi)^2`; within 0.05 of 1,
/// where those cancel, the area integral by 32-point Gauss-Legendre
/// quadrature (the integrand's poles are far from the arc there).
pub fn segment_ratio(w: f64) -> f64 {
    if w == 1.0 {
        return 2.0 / 3.0;
    }
    if (w - 1.0).abs() < 0.05 {
        // The unit arc (0,0) -> (1,1) -> (2,0): triangle area 1; the area
        // between it and the chord is the integral of y dx.
        let q = Quad::rational([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]], w);
        return gauss(|t| {
            let p = q.at(t);
            let d = q.tangent(t);
            p[1] * d[0]
        });
    }
    if w < 1.0 {
        let th = w.acos();
        let s = th.sin();
        w * (th / s - w) / (s * s)
    } else {
        let ph = w.acosh();
        let s = ph.sinh();
        w * (w - ph / s) / (s * s)
    }
}

/// The area the closed chain of rational arcs with middle weight `w`
/// encloses, over the area of its four-point control polygon (5/6 at
/// `w = 1`, [`ALPHA`]).
pub fn alpha(w: f64) -> f64 {
    if w == 1.0 {
        ALPHA
    } else {
        0.5 * (1.0 + segment_ratio(w))
    }
}

/// 32-point Gauss-Legendre quadrature of `f` over [0, 1].
fn gauss(f: impl Fn(f64) -> f64) -> f64 {
    use std::sync::OnceLock;
    static NODES: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    let nodes = NODES.get_or_init(|| {
        // Roots of the Legendre polynomial P_32 by Newton from Chebyshev
        // guesses, with their weights.
        let n = 32;
        (0..n)
            .map(|i| {
                let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
                let mut dp = 0.0;
                for _ in 0..100 {
                    let (mut p0, mut p1) = (1.0, x);
                    for k in 2..=n {
                        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                        p0 = p1;
                        p1 = p2;
                    }
                    dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                    let dx = p1 / dp;
                    x -= dx;
                    if dx.abs() < 1e-16 {
                        break;
                    }
                }
                let wt = 2.0 / ((1.0 - x * x) * dp * dp);
                (0.5 * (1.0 + x), 0.5 * wt)
            })
            .collect()
    });
    nodes.iter().map(|&(x, wt)| wt * f(x)).sum()
}

/// A quadratic Bezier arc, rational when its middle control point's
/// weight `w` is not 1 (the end points have weight 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    /// Start, control and end points.
    pub p: [P2; 3],
    /// Weight of the control point `p[1]` (1: the polynomial arc).
    pub w: f64,
}

impl Quad {
    /// The polynomial arc with control points `p`.
    pub fn new(p: [P2; 3]) -> Quad {
        Quad { p, w: 1.0 }
    }

    /// The rational arc with control points `p` and middle weight `w > 0`.
    pub fn rational(p: [P2; 3], w: f64) -> Quad {
        Quad { p, w }
    }

    /// The straight segment `a..b` as a (degenerate) quadratic.
    pub fn line(a: P2, b: P2) -> Quad {
        Quad::new([a, mid(a, b), b])
    }

    /// The weight function `(1-t)^2 + 2 w t (1-t) + t^2` (positive on
    /// [0, 1] for `w > 0`).
    fn denom(&self, t: f64) -> f64 {
        let s = 1.0 - t;
        s * s + 2.0 * self.w * s * t + t * t
    }

    /// Point at `t`.
    pub fn at(&self, t: f64) -> P2 {
        let [a, b, c] = self.p;
        let s = 1.0 - t;
        if self.w == 1.0 {
            return std::array::from_fn(|k| s * s * a[k] + 2.0 * s * t * b[k] + t * t * c[k]);
        }
        let w = self.w;
        let d = self.denom(t);
        std::array::from_fn(|k| (s * s * a[k] + 2.0 * w * s * t * b[k] + t * t * c[k]) / d)
    }

    /// Derivative at `t`.
    pub fn tangent(&self, t: f64) -> P2 {
        let [a, b, c] = self.p;
        if self.w == 1.0 {
            return std::array::from_fn(|k| 2.0 * ((1.0 - t) * (b[k] - a[k]) + t * (c[k] - b[k])));
        }
        // (N' D - N D') / D^2 with N, D the homogeneous numerator and
        // weight; the cubic terms cancel, leaving
        // 2 [w s^2 (b - a) + s t (c - a) + w t^2 (c - b)] / D^2.
        let (w, s) = (self.w, 1.0 - t);
        let d = self.denom(t);
        std::array::from_fn(|k| {
            2.0 * (w * s * s * (b[k] - a[k]) + s * t * (c[k] - a[k]) + w * t * t * (c[k] - b[k]))
                / (d * d)
        })
    }

    /// `(1/2) int (x dy - y dx)` along the arc: summed over a closed chain,
    /// the enclosed area. Rational arcs: the chord's term plus the
    /// segment, [`segment_ratio`] times the signed control triangle.
    pub fn area_term(&self) -> f64 {
        let [a, b, c] = self.p;
        if self.w == 1.0 {
            return (2.0 * cross(a, b) + cross(a, c) + 2.0 * cross(b, c)) / 6.0;
        }
        let tri = 0.5 * (cross(a, b) + cross(b, c) - cross(a, c));
        0.5 * cross(a, c) + segment_ratio(self.w) * tri
    }

    /// The part of the arc for `t` in `t0..t1` (blossoming; rational arcs
    /// in homogeneous coordinates, brought back to end weights 1).
    pub fn sub(&self, t0: f64, t1: f64) -> Quad {
        let [a, b, c] = self.p;
        let w0 = (1.0 - t0) * (1.0 - t1);
        let w1 = (1.0 - t0) * t1 + t0 * (1.0 - t1);
        let w2 = t0 * t1;
        if self.w == 1.0 {
            return Quad::new([
                self.at(t0),
                std::array::from_fn(|k| w0 * a[k] + w1 * b[k] + w2 * c[k]),
                self.at(t1),
            ]);
        }
        let w = self.w;
        let hw = w0 + w1 * w + w2;
        let m = std::array::from_fn(|k| (w0 * a[k] + w1 * w * b[k] + w2 * c[k]) / hw);
        let nw = hw / (self.denom(t0) * self.denom(t1)).sqrt();
        Quad::rational([self.at(t0), m, self.at(t1)], nw)
    }

    /// Closest point: parameter and squared distance.
    pub fn closest(&self, q: P2) -> (f64, f64) {
        if self.w != 1.0 {
            return self.closest_rational(q);
        }
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

impl Quad {
    /// Closest point on a rational arc: the roots of the quartic
    /// `(N - q D) . (N' D - N D')` (the sign of `d |B - q|^2 / dt`) on
    /// [0, 1], bracketed on 64 intervals and polished by bisection, and
    /// the two ends.
    fn closest_rational(&self, q: P2) -> (f64, f64) {
        let dist2 = |t: f64| {
            let p = self.at(t);
            (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
        };
        let f = |t: f64| {
            let p = self.at(t);
            let d = self.tangent(t);
            (p[0] - q[0]) * d[0] + (p[1] - q[1]) * d[1]
        };
        let mut best = (0.0, dist2(0.0));
        let e = dist2(1.0);
        if e < best.1 {
            best = (1.0, e);
        }
        const N: usize = 64;
        let mut prev = f(0.0);
        for i in 0..N {
            let (mut lo, mut hi) = (i as f64 / N as f64, (i + 1) as f64 / N as f64);
            let next = f(hi);
            // A minimum: the distance falls, then grows.
            if prev < 0.0 && next >= 0.0 {
                for _ in 0..60 {
                    let m = 0.5 * (lo + hi);
                    if f(m) < 0.0 {
                        lo = m;
                    } else {
                        hi = m;
                    }
                }
                let t = 0.5 * (lo + hi);
                let v = dist2(t);
                if v < best.1 {
                    best = (t, v);
                }
            }
            prev = next;
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
    std::array::from_fn(|k| {
        Quad::new([
            mid(ctrl[k], ctrl[(k + 1) % 4]),
            ctrl[(k + 1) % 4],
            mid(ctrl[(k + 1) % 4], ctrl[(k + 2) % 4]),
        ])
    })
}

/// The closed chain of rational quadratic arcs on a four-point control
/// polygon, each corner weighted `w` (`w = 1`: [`bspline`], exactly).
pub fn rational_bspline(ctrl: &[P2; 4], w: f64) -> [Quad; 4] {
    bspline(ctrl).map(|q| Quad { w, ..q })
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
        // Rational arcs: the numerator of g(B(t)), with g1 weighted.
        let (g0, g1, g2) = (g(a.p[0]), a.w * g(a.p[1]), g(a.p[2]));
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
/// rectangle `lo..hi`, exactly (arcs clipped at the roots of quadratics;
/// rational arcs too, their area terms in closed form).
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
