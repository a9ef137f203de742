//! Marching tetrahedra on the Kuhn split of the cube, as one table per
//! corner sign pattern.
//!
//! Why the result is a closed, oriented 2-manifold: every cube is split into
//! the same six tetrahedra along its main diagonal (corner 0 to corner 7),
//! so each square face is cut along the diagonal from its lowest to its
//! highest corner, the same diagonal in both cubes that share it: the tets
//! of the whole grid form one simplicial complex. Each grid node gets one
//! sign (inside is f >= 0, decided once per node), so no node is ever zero
//! and the surface is the zero set of the piecewise-linear interpolant of
//! the signs, a regular level set: inside each tet it is one triangle or one
//! quad (two triangles) with its vertices strictly inside the tet's edges,
//! each polygon edge lies in one tet face and that face is shared by exactly
//! two tets, which cut it along the same segment. Hence every mesh edge is in
//! exactly two triangles. Since the outer node layer of the grid is outside,
//! the surface never reaches the grid boundary (closed). Each triangle is
//! oriented so its normal points from the inside corners to the outside
//! ones; that choice is fixed by the signs alone (below), so neighbouring
//! triangles agree and the normals point out of the solid.

use microfrep_core::geom::{cross, dot, sub};
use std::sync::OnceLock;

/// One grid edge of a cell: start corner (bits x, y, z) and direction
/// (nonzero bit set; the edge ends at corner `start | dir`), as `start * 8 + dir`.
pub type CellEdge = u8;

/// The six tets: chains 0 -> a -> a|b -> 7 over the orders of the axes.
fn kuhn_tets() -> [[u8; 4]; 6] {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    perms.map(|[a, b, _]| [0, 1 << a, (1 << a) | (1 << b), 7])
}

fn corner_pos(c: u8) -> [f64; 3] {
    [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64]
}

/// Edge between two corners of one tet (one is a bit subset of the other).
fn edge(u: u8, v: u8) -> CellEdge {
    let (s, e) = if u & v == u { (u, v) } else { (v, u) };
    debug_assert_eq!(s & e, s);
    s * 8 + (s ^ e)
}

fn midpoint(e: CellEdge) -> [f64; 3] {
    let (s, d) = (e >> 3, e & 7);
    let a = corner_pos(s);
    let b = corner_pos(s | d);
    std::array::from_fn(|k| 0.5 * (a[k] + b[k]))
}

/// Triangles of one tet with inside corners `inside` (a subset of `tet`),
/// oriented outwards. With the vertices anywhere strictly inside their edges
/// the orientation relative to an inside corner keeps its sign (the
/// determinant factors into positive edge parameters times a fixed one), so
/// checking it at the edge midpoints decides it for all positions.
fn tet_triangles(tet: [u8; 4], inside: &[u8], out: &mut Vec<[CellEdge; 3]>) {
    let outside: Vec<u8> = tet
        .iter()
        .copied()
        .filter(|c| !inside.contains(c))
        .collect();
    let tris: Vec<[CellEdge; 3]> = match (inside.len(), outside.len()) {
        (1, 3) | (3, 1) => {
            let (v, w) = if inside.len() == 1 {
                (inside[0], &outside[..])
            } else {
                (outside[0], inside)
            };
            vec![[edge(v, w[0]), edge(v, w[1]), edge(v, w[2])]]
        }
        (2, 2) => {
            let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
            let (ac, ad, bd, bc) = (edge(a, c), edge(a, d), edge(b, d), edge(b, c));
            vec![[ac, ad, bd], [ac, bd, bc]]
        }
        _ => vec![],
    };
    let centroid = |s: &[u8]| -> [f64; 3] {
        let mut c = [0.0; 3];
        for &v in s {
            let p = corner_pos(v);
            for k in 0..3 {
                c[k] += p[k] / s.len() as f64;
            }
        }
        c
    };
    let outward = sub(centroid(&outside), centroid(inside));
    for [e0, e1, e2] in tris {
        let (p0, p1, p2) = (midpoint(e0), midpoint(e1), midpoint(e2));
        let n = cross(sub(p1, p0), sub(p2, p0));
        out.push(if dot(n, outward) > 0.0 {
            [e0, e1, e2]
        } else {
            [e0, e2, e1]
        });
    }
}

/// Triangles for each of the 256 corner sign patterns of a cell (bit c set
/// when corner c is inside): `tris[start[m]..start[m + 1]]`.
pub struct CellTable {
    /// Offsets into `tris`, one per sign pattern and one past the end
    /// (`start[256] == tris.len()`).
    pub start: [u16; 257],
    /// Triangles, each as the three cell edges its vertices lie on,
    /// counter-clockwise seen from outside the solid.
    pub tris: Vec<[CellEdge; 3]>,
}

/// The marching-tetrahedra table: every cube cut into the six tetrahedra
/// of the Kuhn split around its main diagonal, each tetrahedron's zero set
/// triangulated and oriented outward. Built on first use and shared.
pub fn cell_table() -> &'static CellTable {
    static TABLE: OnceLock<CellTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut start = [0u16; 257];
        let mut tris = Vec::new();
        for m in 0..256u32 {
            start[m as usize] = tris.len() as u16;
            for tet in kuhn_tets() {
                let inside: Vec<u8> = tet.iter().copied().filter(|&c| m >> c & 1 == 1).collect();
                tet_triangles(tet, &inside, &mut tris);
            }
        }
        start[256] = tris.len() as u16;
        CellTable { start, tris }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_cells_have_no_triangles_and_mixed_ones_do() {
        let t = cell_table();
        for m in 0..256usize {
            let n = (t.start[m + 1] - t.start[m]) as usize;
            assert_eq!(n == 0, m == 0 || m == 255, "mask {m}");
            assert!(n <= 12);
        }
    }

    #[test]
    fn single_inside_corner_zero_gives_one_oriented_fan() {
        // Corner 0 inside: every tet contains corner 0, cut by one triangle
        // each, all facing away from corner 0 (+x+y+z).
        let t = cell_table();
        let tris = &t.tris[t.start[1] as usize..t.start[2] as usize];
        assert_eq!(tris.len(), 6);
        for &[a, b, c] in tris {
            let n = cross(sub(midpoint(b), midpoint(a)), sub(midpoint(c), midpoint(a)));
            assert!(dot(n, [1.0, 1.0, 1.0]) > 0.0);
        }
    }
}
