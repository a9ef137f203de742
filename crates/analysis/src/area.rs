//! Area of the zero set inside a tetrahedron: a triangle (1-3 sign split)
//! or a quadrilateral (2-2 split), with its vertices on the tetrahedron's
//! edges, either where the linear interpolant of the vertex values is zero
//! or at any other points on those edges (the field's refined roots). The
//! polygon and the part of the tetrahedron on its inside are then a
//! polytope whose volume and area are taken exactly; a quadrilateral that
//! is not planar is taken as the mean of its two triangulations.

use microfrep_core::geom::{cross, norm, sub};

/// The zero-set polygon of a tetrahedron: `n` (0, 3 or 4) vertices, each on
/// the edge `(i, j)` at parameter `t` from `i`, in cyclic order.
#[derive(Clone, Copy, Debug)]
pub struct IsoPolygon {
    /// Number of polygon vertices: 0 when the tetrahedron is not cut, 3 for a
    /// triangle (1-3 sign split), 4 for a quadrilateral (2-2 split).
    pub n: usize,
    /// Vertices of the tetrahedron with `f >= 0`.
    pub inside: usize,
    /// The polygon's vertices as `(i, j, t)`: on the edge from tetrahedron
    /// vertex `i` to vertex `j`, at parameter `t` in `[0, 1]` measured from `i`.
    /// Only the first `n` entries are meaningful.
    pub verts: [(usize, usize, f64); 4],
}

impl IsoPolygon {
    /// Fraction of the tetrahedron's volume on the inside of the polygon.
    /// With one vertex apart (1-3 split) its corner tetrahedron is cut at
    /// the polygon's vertices; with two on each side (2-2) the inside part
    /// is a wedge, three tetrahedra, whose volume depends on the diagonal
    /// of the quadrilateral unless it is planar: the mean of both.
    pub fn inside_fraction(&self) -> f64 {
        let t = |k: usize| self.verts[k].2;
        match (self.n, self.inside) {
            (0, 0) => 0.0,
            (0, _) => 1.0,
            (3, 1) => t(0) * t(1) * t(2),
            (3, _) => 1.0 - t(0) * t(1) * t(2),
            _ => {
                // Vertices ac, bc, bd, ad (a, b inside).
                let (t1, t3, t4, t2) = (t(0), t(1), t(2), t(3));
                // Diagonal ac-bd, then ad-bc.
                let v1 = t1 * t2 + t1 * t4 * (1.0 - t2) + t3 * t4 * (1.0 - t1);
                let v2 = t1 * t2 + t2 * t3 * (1.0 - t1) + t3 * t4 * (1.0 - t2);
                0.5 * (v1 + v2)
            }
        }
    }

    /// Linear interpolation of per-vertex values `g` at the polygon's
    /// vertices, averaged (the value at its vertex centroid).
    pub fn mean_of(&self, g: [f64; 4]) -> f64 {
        let s: f64 = self.verts[..self.n]
            .iter()
            .map(|&(i, j, t)| g[i] + t * (g[j] - g[i]))
            .sum();
        s / self.n.max(1) as f64
    }

    /// Area of the polygon for tetrahedron vertices `p`.
    pub fn area(&self, p: &[[f64; 3]; 4]) -> f64 {
        let v: [[f64; 3]; 4] = std::array::from_fn(|k| {
            let (i, j, t) = self.verts[k];
            std::array::from_fn(|a| p[i][a] + t * (p[j][a] - p[i][a]))
        });
        match self.n {
            3 => tri(v[0], v[1], v[2]),
            // The mean of the two triangulations (equal when planar).
            4 => {
                0.5 * (tri(v[0], v[1], v[2])
                    + tri(v[0], v[2], v[3])
                    + tri(v[0], v[1], v[3])
                    + tri(v[1], v[2], v[3]))
            }
            _ => 0.0,
        }
    }
}

/// The zero set of the linear interpolant of `f` (inside is `f >= 0`).
pub fn iso_polygon(f: [f64; 4]) -> IsoPolygon {
    iso_polygon_cut(f, |i, j| f[i] / (f[i] - f[j]))
}

/// The zero-set polygon for the signs of `f`, with its vertex on the edge
/// from vertex `i` (inside) to `j` (outside), or from outside to inside, at
/// parameter `cut(i, j)` from `i`, in `[0, 1]`.
pub fn iso_polygon_cut(f: [f64; 4], cut: impl Fn(usize, usize) -> f64) -> IsoPolygon {
    let pos = f.map(|v| v >= 0.0);
    let n = pos.iter().filter(|&&p| p).count();
    let cut = |i: usize, j: usize| (i, j, cut(i, j));
    let mut verts = [(0, 0, 0.0); 4];
    match n {
        1 | 3 => {
            let lone = (0..4).find(|&i| pos[i] == (n == 1)).unwrap_or(0);
            for (k, j) in (0..4).filter(|&j| j != lone).enumerate() {
                verts[k] = cut(lone, j);
            }
            IsoPolygon {
                n: 3,
                inside: n,
                verts,
            }
        }
        2 => {
            let mut p = (0..4).filter(|&i| pos[i]);
            let mut q = (0..4).filter(|&i| !pos[i]);
            let (a, b) = (p.next().unwrap_or(0), p.next().unwrap_or(1));
            let (c, d) = (q.next().unwrap_or(2), q.next().unwrap_or(3));
            // Around the quadrilateral: ac, bc, bd, ad.
            verts = [cut(a, c), cut(b, c), cut(b, d), cut(a, d)];
            IsoPolygon {
                n: 4,
                inside: 2,
                verts,
            }
        }
        _ => IsoPolygon {
            n: 0,
            inside: n,
            verts,
        },
    }
}

fn tri(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    0.5 * norm(cross(sub(b, a), sub(c, a)))
}

#[cfg(test)]
mod tests {
    use super::*;

    const UNIT: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];

    #[test]
    fn plane_sections_of_the_unit_tetrahedron() {
        // x + y + z = 1/2: the triangle with vertices at 1/2 on the axes.
        let f = UNIT.map(|p| 0.5 - p[0] - p[1] - p[2]);
        let a = iso_polygon(f).area(&UNIT);
        assert!((a - 3f64.sqrt() / 8.0).abs() < 1e-12, "{a}");
        // x = 1/2 on the vertices (0,0,0),(1,0,0): with x < 1/2 the three
        // others... a 1-3 split whose section is the triangle at x = 1/2.
        let f = UNIT.map(|p| p[0] - 0.5);
        let a = iso_polygon(f).area(&UNIT);
        assert!((a - 0.125).abs() < 1e-12, "{a}");
        // x + y = 1/2: 2-2 split; the section is a quadrilateral.
        let f = UNIT.map(|p| 0.5 - p[0] - p[1]);
        let poly = iso_polygon(f);
        assert_eq!(poly.n, 4);
        // Section of the tetrahedron by x + y = s: a rectangle
        // (s sqrt 2) x (1 - s) tilted... area s (1 - s) sqrt 2.
        let a = poly.area(&UNIT);
        assert!((a - 0.25 * 2f64.sqrt()).abs() < 1e-12, "{a}");
    }

    /// Volume of a closed, consistently oriented triangle surface.
    fn enclosed(tris: &[[[f64; 3]; 3]]) -> f64 {
        tris.iter()
            .map(|[a, b, c]| {
                let n = cross(*b, *c);
                a[0] * n[0] + a[1] * n[1] + a[2] * n[2]
            })
            .sum::<f64>()
            / 6.0
    }

    #[test]
    fn cuts_away_from_the_linear_roots_bound_a_polytope() {
        // Vertices 0, 1 inside, 2, 3 outside, cut anywhere on the four
        // edges: the inside part is a wedge whose cut face is not planar.
        // Its volume from its boundary, for either diagonal of that face,
        // averaged, is the fraction (the tetrahedron's volume is 1/6).
        let [a, b, c, d] = UNIT;
        let at = |p: [f64; 3], q: [f64; 3], t: f64| -> [f64; 3] {
            std::array::from_fn(|k| p[k] + t * (q[k] - p[k]))
        };
        for ts in [
            [0.3, 0.8, 0.55, 0.1],
            [0.5, 0.5, 0.5, 0.5],
            [0.9, 0.05, 0.7, 0.35],
        ] {
            let cut = |i: usize, j: usize| match (i, j) {
                (0, 2) => ts[0],
                (1, 2) => ts[1],
                (1, 3) => ts[2],
                _ => ts[3],
            };
            let poly = iso_polygon_cut([1.0, 1.0, -1.0, -1.0], cut);
            let (ac, bc, bd, ad) = (
                at(a, c, ts[0]),
                at(b, c, ts[1]),
                at(b, d, ts[2]),
                at(a, d, ts[3]),
            );
            let sides = [
                [a, ac, bc],
                [a, bc, b],
                [a, b, bd],
                [a, bd, ad],
                [a, ad, ac],
                [b, bc, bd],
            ];
            let with = |cap: [[[f64; 3]; 3]; 2]| {
                let mut all = sides.to_vec();
                all.extend(cap);
                6.0 * enclosed(&all).abs()
            };
            let v1 = with([[ac, ad, bd], [ac, bd, bc]]);
            let v2 = with([[ac, ad, bc], [ad, bd, bc]]);
            let f = poly.inside_fraction();
            assert!(
                (f - 0.5 * (v1 + v2)).abs() < 1e-12,
                "{ts:?}: {f} vs {v1}, {v2}"
            );
        }
    }
}
