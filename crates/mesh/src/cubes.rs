//! Marching cubes with one fixed rule for ambiguous faces, as one table of
//! triangles per corner sign pattern, built here from first principles
//! rather than typed in.
//!
//! Why the result is a closed, oriented 2-manifold. Every grid node gets one
//! sign (inside is f >= 0, decided once per node), so no node is zero and
//! every vertex lies strictly inside a grid edge with a sign change. On each
//! square face of a cell the crossings are joined by segments that depend
//! on the face's four signs alone: two crossings are joined directly; four
//! (inside corners on a diagonal) are joined so that each inside corner is
//! cut off on its own. Both cells sharing a face therefore cut it along the
//! same segments. Each crossing lies on two faces of the cell, so the
//! segments of one cell form disjoint cycles; each cycle is triangulated as
//! a disk whose inner diagonals never join two crossings of one face (so
//! no diagonal or triangle lies in a face shared with the next cell, and
//! no triangle is degenerate: three points strictly inside edges of a cube
//! are collinear only within one face). Every mesh edge is then either a
//! face segment, in exactly one triangle of each of the two cells sharing
//! the face, or an inner diagonal, in exactly two triangles of one cell;
//! and around a vertex the cells sharing its grid edge chain their fans
//! into one disk. Segments are directed with the inside on a fixed side as
//! seen from outside the face, which orients each cycle, and neighbouring
//! cycles traverse their shared segment in opposite directions: normals
//! point out of the solid. The outer node layer of the grid is outside, so
//! the surface never reaches the grid boundary (closed).

pub use crate::tets::{CellEdge, CellTable};
use microfrep_core::geom::{cross, dot, sub};
use std::sync::OnceLock;

/// Triangles for each of the 256 corner sign patterns of a cell (bit c set
/// when corner c = x + 2 y + 4 z is inside).
pub fn cell_table() -> &'static CellTable {
    &tables().0
}

/// One cycle of face segments of a cell: its crossings in order (the
/// orientation of its triangles) and the range of `cell_table().tris` that
/// triangulates it as a disk.
#[derive(Clone, Debug)]
pub struct Cycle {
    /// The crossings, in the order the cycle's triangles traverse it.
    pub edges: Vec<CellEdge>,
    /// The cycle's triangles in [`cell_table`] (`len - 2` of them).
    pub tris: std::ops::Range<u16>,
}

/// The cycles of face segments for each of the 256 sign patterns:
/// `cycles[start[m]..start[m + 1]]`, in the order their triangles appear in
/// [`cell_table`] (used to replace a cycle's disk by another one with the
/// same boundary, [`crate::sharp`]).
pub struct CycleTable {
    /// Offsets into `cycles`, one per sign pattern and one past the end.
    pub start: [u16; 257],
    /// The cycles of every pattern.
    pub cycles: Vec<Cycle>,
}

/// The table of [`CycleTable`], built with [`cell_table`] on first use.
pub fn cycle_table() -> &'static CycleTable {
    &tables().1
}

fn tables() -> &'static (CellTable, CycleTable) {
    static TABLE: OnceLock<(CellTable, CycleTable)> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut start = [0u16; 257];
        let mut cstart = [0u16; 257];
        let mut tris = Vec::new();
        let mut cycles = Vec::new();
        for m in 0..256usize {
            start[m] = tris.len() as u16;
            cstart[m] = cycles.len() as u16;
            cell_triangles(m as u8, &mut tris, &mut cycles);
        }
        start[256] = tris.len() as u16;
        cstart[256] = cycles.len() as u16;
        (
            CellTable { start, tris },
            CycleTable {
                start: cstart,
                cycles,
            },
        )
    })
}

fn corner_pos(c: u8) -> [f64; 3] {
    [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64]
}

fn midpoint(e: CellEdge) -> [f64; 3] {
    let (a, b) = (corner_pos(e >> 3), corner_pos((e >> 3) | (e & 7)));
    std::array::from_fn(|k| 0.5 * (a[k] + b[k]))
}

fn edge(u: u8, v: u8) -> CellEdge {
    let (s, e) = if u & v == u { (u, v) } else { (v, u) };
    s * 8 + (s ^ e)
}

/// The six faces as (corners in cyclic order, outward normal).
fn faces() -> [([u8; 4], [f64; 3]); 6] {
    std::array::from_fn(|f| {
        let (a, side) = (f / 2, (f % 2) as u8);
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let base = side << a;
        let mut n = [0.0; 3];
        n[a] = if side == 1 { 1.0 } else { -1.0 };
        (
            [base, base | 1 << b, base | 1 << b | 1 << c, base | 1 << c],
            n,
        )
    })
}

/// Whether two cell edges lie on a common face.
fn share_face(e: CellEdge, g: CellEdge) -> bool {
    let (s, d, t, h) = (e >> 3, e & 7, g >> 3, g & 7);
    // Edge e lies on the faces of the axes other than d's, on the side its
    // start corner has; same for g.
    (0..3u8).any(|a| {
        let bit = 1 << a;
        d & bit == 0 && h & bit == 0 && (s & bit) == (t & bit)
    })
}

fn cell_triangles(m: u8, out: &mut Vec<[CellEdge; 3]>, cycles: &mut Vec<Cycle>) {
    let inside = |c: u8| m >> c & 1 == 1;
    // Directed face segments: next[e] is the crossing after e.
    let mut next = [u8::MAX; 64];
    for (corners, normal) in faces() {
        let cut: Vec<CellEdge> = (0..4)
            .map(|i| (corners[i], corners[(i + 1) % 4]))
            .filter(|&(u, v)| inside(u) != inside(v))
            .map(|(u, v)| edge(u, v))
            .collect();
        let pairs: Vec<(CellEdge, CellEdge)> = match cut.len() {
            0 => vec![],
            2 => vec![(cut[0], cut[1])],
            4 => {
                // Inside corners on a diagonal: join the two crossings on
                // the edges around each inside corner.
                let around = |c: u8| -> (CellEdge, CellEdge) {
                    let i = corners.iter().position(|&x| x == c).unwrap();
                    (edge(c, corners[(i + 1) % 4]), edge(c, corners[(i + 3) % 4]))
                };
                corners
                    .iter()
                    .filter(|&&c| inside(c))
                    .map(|&c| around(c))
                    .collect()
            }
            _ => unreachable!("a square has an even number of sign changes"),
        };
        for (p, q) in pairs {
            // Direct p -> q so that the inside end of p's edge lies on the
            // negative side, seen along the outward normal (the sign does
            // not depend on where p and q sit inside their edges).
            let (s, d) = (p >> 3, p & 7);
            let c_in = if inside(s) { s } else { s | d };
            let (mp, mq) = (midpoint(p), midpoint(q));
            let turn = dot(cross(sub(mq, mp), sub(corner_pos(c_in), mp)), normal);
            let (from, to) = if turn < 0.0 { (p, q) } else { (q, p) };
            assert_eq!(
                next[from as usize],
                u8::MAX,
                "mask {m}: two segments leave {from}"
            );
            next[from as usize] = to;
        }
    }
    let mut seen = [false; 64];
    for e0 in 0..64u8 {
        if next[e0 as usize] == u8::MAX || seen[e0 as usize] {
            continue;
        }
        let mut cycle = vec![e0];
        seen[e0 as usize] = true;
        let mut e = next[e0 as usize];
        while e != e0 {
            assert!(e != u8::MAX && !seen[e as usize], "mask {m}: broken cycle");
            seen[e as usize] = true;
            cycle.push(e);
            e = next[e as usize];
        }
        let first = out.len() as u16;
        triangulate(&cycle, m, out);
        cycles.push(Cycle {
            edges: cycle,
            tris: first..out.len() as u16,
        });
    }
}

/// Triangulates the polygon `cycle` (in order, so the triangles keep its
/// orientation) with the shortest inner diagonals (lengths at the edge
/// midpoints) among those that never join two crossings of one face.
fn triangulate(cycle: &[CellEdge], m: u8, out: &mut Vec<[CellEdge; 3]>) {
    let n = cycle.len();
    let pos: Vec<[f64; 3]> = cycle.iter().map(|&e| midpoint(e)).collect();
    let weight = |i: usize, j: usize| -> f64 {
        if j == i + 1 || (i == 0 && j == n - 1) {
            0.0
        } else if share_face(cycle[i], cycle[j]) {
            f64::INFINITY
        } else {
            let d = sub(pos[i], pos[j]);
            dot(d, d).sqrt()
        }
    };
    // best[i][j]: cost of the sub-polygon i..=j, with the split vertex.
    let mut best = vec![vec![(0.0f64, usize::MAX); n]; n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            let cost = |k: usize| best[i][k].0 + best[k][j].0 + weight(i, k) + weight(k, j);
            let b = (i + 1..j).fold((f64::INFINITY, usize::MAX), |b, k| {
                let c = cost(k);
                if c < b.0 {
                    (c, k)
                } else {
                    b
                }
            });
            best[i][j] = b;
        }
    }
    assert!(
        best[0][n - 1].0.is_finite(),
        "mask {m}: no valid triangulation"
    );
    let mut stack = vec![(0, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j < i + 2 {
            continue;
        }
        let k = best[i][j].1;
        out.push([cycle[i], cycle[k], cycle[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tris(m: usize) -> &'static [[CellEdge; 3]] {
        let t = cell_table();
        &t.tris[t.start[m] as usize..t.start[m + 1] as usize]
    }

    #[test]
    fn uniform_cells_have_no_triangles_and_mixed_ones_do() {
        for m in 0..256usize {
            let n = tris(m).len();
            assert_eq!(n == 0, m == 0 || m == 255, "mask {m}");
            assert!(n <= 12, "mask {m}: {n}");
        }
    }

    #[test]
    fn cycles_cover_their_triangles_and_nothing_else() {
        let (t, c) = (cell_table(), cycle_table());
        for m in 0..256usize {
            let cs = &c.cycles[c.start[m] as usize..c.start[m + 1] as usize];
            let mut next = t.start[m];
            for cy in cs {
                assert_eq!(cy.tris.start, next, "mask {m}");
                assert_eq!(cy.tris.len() + 2, cy.edges.len(), "mask {m}");
                for tri in &t.tris[cy.tris.start as usize..cy.tris.end as usize] {
                    assert!(tri.iter().all(|e| cy.edges.contains(e)), "mask {m}");
                }
                next = cy.tris.end;
            }
            assert_eq!(next, t.start[m + 1], "mask {m}");
        }
    }

    #[test]
    fn single_inside_corner_gives_one_triangle_facing_away() {
        let t = tris(1);
        assert_eq!(t.len(), 1);
        let [a, b, c] = t[0].map(midpoint);
        assert!(dot(cross(sub(b, a), sub(c, a)), [1.0; 3]) > 0.0);
    }

    #[test]
    fn every_cell_surface_is_closed_within_the_cell_up_to_face_segments() {
        // Inner edges (not on a face) are used once in each direction; edges
        // on a face are used once, and no edge joins two crossings of a face
        // unless it is that face's segment.
        for m in 1..255usize {
            let mut count = std::collections::HashMap::new();
            for t in tris(m) {
                for i in 0..3 {
                    *count.entry((t[i], t[(i + 1) % 3])).or_insert(0) += 1;
                }
            }
            for (&(a, b), &k) in &count {
                assert_eq!(k, 1, "mask {m}");
                let back = count.contains_key(&(b, a));
                assert_eq!(back, !share_face(a, b), "mask {m}: edge {a}-{b}");
            }
        }
    }

    #[test]
    fn complementary_patterns_have_opposite_orientation_where_unambiguous() {
        // One inside corner vs one outside corner: same polygon, reversed.
        let a = tris(1)[0];
        let b = tris(254)[0];
        let mut ra = a;
        ra.sort();
        let mut rb = b;
        rb.sort();
        assert_eq!(ra, rb);
        let [p, q, r] = b.map(midpoint);
        assert!(dot(cross(sub(q, p), sub(r, p)), [1.0; 3]) < 0.0);
    }
}
