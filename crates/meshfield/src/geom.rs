//! Point-triangle geometry: closest point with its feature, and the exact
//! signed solid angle.

use crate::mesh::{cross, dot, norm, sub};

/// Which part of a triangle a closest point lies on. Edge `k` joins
/// corners `k` and `k + 1 (mod 3)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    /// The interior of the face.
    Face,
    /// An edge (0: corners 0-1, 1: corners 1-2, 2: corners 2-0).
    Edge(u8),
    /// A corner.
    Vertex(u8),
}

fn add_scaled(a: [f64; 3], d: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + d[0] * t, a[1] + d[1] * t, a[2] + d[2] * t]
}

/// Closest point to `p` on the segment from corner `i` to corner `j` of `t`
/// (edge `k`), with its feature.
fn on_segment(p: [f64; 3], t: &[[f64; 3]; 3], k: usize) -> ([f64; 3], Feature) {
    let (i, j) = (k, (k + 1) % 3);
    let (a, b) = (t[i], t[j]);
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let s = if len2 > 0.0 {
        dot(sub(p, a), ab) / len2
    } else {
        0.0
    };
    if s <= 0.0 {
        (a, Feature::Vertex(i as u8))
    } else if s >= 1.0 {
        (b, Feature::Vertex(j as u8))
    } else {
        (add_scaled(a, ab, s), Feature::Edge(k as u8))
    }
}

/// Closest point of a degenerate triangle: the nearest of its three edges.
fn on_edges(p: [f64; 3], t: &[[f64; 3]; 3]) -> ([f64; 3], Feature) {
    let mut best = on_segment(p, t, 0);
    let mut bd = dist2(p, best.0);
    for k in 1..3 {
        let c = on_segment(p, t, k);
        let d = dist2(p, c.0);
        if d < bd {
            best = c;
            bd = d;
        }
    }
    best
}

pub(crate) fn dist2(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

/// Closest point to `p` on the triangle `t` and the feature it lies on, by
/// the Voronoi regions of the corners, edges and face (tested in that order
/// with dot products). `degenerate` triangles (zero area) are treated as
/// their three edges, and so is any triangle whose region tests meet a zero
/// denominator, so the result is always finite for finite input.
pub fn closest_on_triangle(
    p: [f64; 3],
    t: &[[f64; 3]; 3],
    degenerate: bool,
) -> ([f64; 3], Feature) {
    if degenerate {
        return on_edges(p, t);
    }
    let [a, b, c] = *t;
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let den = d1 - d3;
        if den <= 0.0 {
            return on_edges(p, t);
        }
        return (add_scaled(a, ab, d1 / den), Feature::Edge(0));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let den = d2 - d6;
        if den <= 0.0 {
            return on_edges(p, t);
        }
        return (add_scaled(a, ac, d2 / den), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    let e43 = d4 - d3;
    let e56 = d5 - d6;
    if va <= 0.0 && e43 >= 0.0 && e56 >= 0.0 {
        let den = e43 + e56;
        if den <= 0.0 {
            return on_edges(p, t);
        }
        return (add_scaled(b, sub(c, b), e43 / den), Feature::Edge(1));
    }
    let den = va + vb + vc;
    if den <= 0.0 || !den.is_finite() {
        return on_edges(p, t);
    }
    let v = vb / den;
    let w = vc / den;
    (
        [
            a[0] + ab[0] * v + ac[0] * w,
            a[1] + ab[1] * v + ac[1] * w,
            a[2] + ab[2] * v + ac[2] * w,
        ],
        Feature::Face,
    )
}

/// Signed solid angle of triangle `t` seen from `q` (Van Oosterom and
/// Strackee's formula), positive when `q` is on the side the
/// counter-clockwise normal points away from (the inside of an outward
/// oriented surface); in [-2 pi, 2 pi].
pub fn solid_angle(q: [f64; 3], t: &[[f64; 3]; 3]) -> f64 {
    let a = sub(t[0], q);
    let b = sub(t[1], q);
    let c = sub(t[2], q);
    let (la, lb, lc) = (norm(a), norm(b), norm(c));
    let det = dot(a, cross(b, c));
    let den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    2.0 * det.atan2(den)
}

/// Unit normal of a triangle (zero for a degenerate one).
pub fn unit_normal(t: &[[f64; 3]; 3]) -> [f64; 3] {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let l = norm(n);
    if l > 0.0 {
        n.map(|c| c / l)
    } else {
        [0.0; 3]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_of_a_triangle() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let cases = [
            ([0.2, 0.2, 1.0], [0.2, 0.2, 0.0], Feature::Face),
            ([-1.0, -1.0, 0.5], [0.0, 0.0, 0.0], Feature::Vertex(0)),
            ([2.0, -0.5, 0.0], [1.0, 0.0, 0.0], Feature::Vertex(1)),
            ([0.0, 3.0, 0.0], [0.0, 1.0, 0.0], Feature::Vertex(2)),
            ([0.5, -1.0, 0.0], [0.5, 0.0, 0.0], Feature::Edge(0)),
            ([1.0, 1.0, 0.0], [0.5, 0.5, 0.0], Feature::Edge(1)),
            ([-1.0, 0.5, 2.0], [0.0, 0.5, 0.0], Feature::Edge(2)),
        ];
        for (p, c, f) in cases {
            let (q, g) = closest_on_triangle(p, &t, false);
            assert!(dist2(q, c) < 1e-30, "{p:?}: {q:?}");
            assert_eq!(g, f, "{p:?}");
        }
        // A degenerate (collinear) triangle is its segments.
        let d = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let (q, g) = closest_on_triangle([1.5, 1.0, 0.0], &d, true);
        assert!(dist2(q, [1.5, 0.0, 0.0]) < 1e-30 && g == Feature::Edge(1));
        let (q, _) = closest_on_triangle([1.5, 1.0, 0.0], &d, false);
        assert!(q.iter().all(|c| c.is_finite()));
    }

    #[test]
    fn solid_angle_of_an_octant_and_sign() {
        // The triangle (e_x, e_y, e_z) covers one octant (4 pi / 8) from the origin.
        let t = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let w = solid_angle([0.0; 3], &t);
        assert!((w - std::f64::consts::PI / 2.0).abs() < 1e-14, "{w}");
        assert!((solid_angle([1.0; 3], &t) + solid_angle([0.0; 3], &t)).abs() < 2.0);
        assert!(solid_angle([1.0; 3], &t) < 0.0);
    }
}
