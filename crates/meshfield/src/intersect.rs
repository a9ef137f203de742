//! Self-intersection test: pairs of triangles that cross each other, found
//! through the BVH (boxes that overlap), so the pseudo-normal sign is only
//! used on meshes where it is exact.

use crate::bvh::Bvh;
use crate::mesh::{cross, dot, sub};

/// Orientation of `d` against the plane through `a b c` (sign of the
/// determinant).
fn orient(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    dot(sub(d, a), cross(sub(b, a), sub(c, a)))
}

/// Whether the segment `p q` crosses the triangle `t` (properly: its ends
/// on opposite sides of the plane, the crossing inside the triangle).
fn segment_crosses(p: [f64; 3], q: [f64; 3], t: &[[f64; 3]; 3]) -> bool {
    let sp = orient(t[0], t[1], t[2], p);
    let sq = orient(t[0], t[1], t[2], q);
    if (sp > 0.0 && sq > 0.0) || (sp < 0.0 && sq < 0.0) || sp == 0.0 || sq == 0.0 {
        return false;
    }
    // The line through p q passes inside the triangle when it sees the three
    // edges with the same orientation.
    let s0 = orient(p, q, t[0], t[1]);
    let s1 = orient(p, q, t[1], t[2]);
    let s2 = orient(p, q, t[2], t[0]);
    (s0 > 0.0 && s1 > 0.0 && s2 > 0.0) || (s0 < 0.0 && s1 < 0.0 && s2 < 0.0)
}

/// Whether two triangles (with their mesh vertex indices) intersect other
/// than along what they share. Coplanar contacts of unrelated triangles are
/// not reported.
fn pair_intersects(a: &[[f64; 3]; 3], ia: [u32; 3], b: &[[f64; 3]; 3], ib: [u32; 3]) -> bool {
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| ia[i] == ib[j])
        .collect();
    match shared.len() {
        0 => (0..3).any(|k| {
            segment_crosses(a[k], a[(k + 1) % 3], b) || segment_crosses(b[k], b[(k + 1) % 3], a)
        }),
        1 => {
            // Sharing a corner: they overlap beyond it iff the edge opposite
            // the corner in one crosses the other.
            let (i, j) = shared[0];
            segment_crosses(a[(i + 1) % 3], a[(i + 2) % 3], b)
                || segment_crosses(b[(j + 1) % 3], b[(j + 2) % 3], a)
        }
        2 => {
            // Sharing an edge: only a fold onto the same plane overlaps.
            let ka = (0..3)
                .find(|&i| shared.iter().all(|s| s.0 != i))
                .unwrap_or(0);
            let kb = (0..3)
                .find(|&j| shared.iter().all(|s| s.1 != j))
                .unwrap_or(0);
            let (e0, e1) = (a[shared[0].0], a[shared[1].0]);
            let n = cross(sub(e1, e0), sub(a[ka], e0));
            let off = dot(sub(b[kb], e0), n);
            let scale = dot(n, n).sqrt() * dot(sub(b[kb], e0), sub(b[kb], e0)).sqrt();
            if off.abs() > 1e-12 * scale {
                return false;
            }
            // Coplanar: overlapping when both apexes lie on one side of the edge.
            let m = cross(sub(e1, e0), n);
            dot(sub(a[ka], e0), m) * dot(sub(b[kb], e0), m) > 0.0
        }
        _ => false,
    }
}

fn boxes_overlap(bvh: &Bvh, x: usize, y: usize) -> bool {
    let (a, b) = (&bvh.nodes[x], &bvh.nodes[y]);
    (0..3).all(|k| a.lo[k] <= b.hi[k] && b.lo[k] <= a.hi[k])
}

/// Whether any two triangles of the mesh cross; `corners[t]` are the mesh
/// vertex indices of leaf-order triangle `t`. Stops at the first found.
pub fn has_self_intersection(bvh: &Bvh, corners: &[[u32; 3]]) -> bool {
    use std::sync::atomic::{AtomicBool, Ordering};
    let found = AtomicBool::new(false);
    fn leaf_pair(bvh: &Bvh, corners: &[[u32; 3]], x: usize, y: usize, found: &AtomicBool) {
        let (a, b) = (&bvh.nodes[x], &bvh.nodes[y]);
        for i in a.index..a.index + a.count {
            let lo = if x == y { i + 1 } else { b.index };
            for j in lo..b.index + b.count {
                let (i, j) = (i as usize, j as usize);
                if pair_intersects(&bvh.tris[i], corners[i], &bvh.tris[j], corners[j]) {
                    found.store(true, Ordering::Relaxed);
                    return;
                }
            }
        }
    }
    fn go(bvh: &Bvh, corners: &[[u32; 3]], x: usize, y: usize, found: &AtomicBool, depth: usize) {
        if found.load(Ordering::Relaxed) || !boxes_overlap(bvh, x, y) {
            return;
        }
        let (a, b) = (bvh.nodes[x], bvh.nodes[y]);
        match (a.is_leaf(), b.is_leaf()) {
            (true, true) => leaf_pair(bvh, corners, x, y, found),
            _ if x == y => {
                let (l, r) = (x + 1, a.index as usize);
                if depth < 12 {
                    rayon::join(
                        || {
                            rayon::join(
                                || go(bvh, corners, l, l, found, depth + 1),
                                || go(bvh, corners, r, r, found, depth + 1),
                            )
                        },
                        || go(bvh, corners, l, r, found, depth + 1),
                    );
                } else {
                    go(bvh, corners, l, l, found, depth + 1);
                    go(bvh, corners, r, r, found, depth + 1);
                    go(bvh, corners, l, r, found, depth + 1);
                }
            }
            _ => {
                // Descend an inner node (the first one when both are).
                if !a.is_leaf() && (b.is_leaf() || x <= y) {
                    go(bvh, corners, x + 1, y, found, depth + 1);
                    go(bvh, corners, a.index as usize, y, found, depth + 1);
                } else {
                    go(bvh, corners, x, y + 1, found, depth + 1);
                    go(bvh, corners, x, b.index as usize, found, depth + 1);
                }
            }
        }
    }
    go(bvh, corners, 0, 0, &found, 0);
    found.load(Ordering::Relaxed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_touching_and_folded_pairs() {
        let a = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];
        // Pierces a.
        let b = [[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]];
        assert!(pair_intersects(&a, [0, 1, 2], &b, [3, 4, 5]));
        // Above a.
        let c = [[0.5, 0.5, 0.1], [0.5, 0.6, 1.0], [3.0, 3.0, 0.5]];
        assert!(!pair_intersects(&a, [0, 1, 2], &c, [3, 4, 5]));
        // Shares corner 0 and dips through a.
        let d = [[0.0, 0.0, 0.0], [1.0, 0.5, -1.0], [0.5, 1.0, 1.0]];
        assert!(pair_intersects(&a, [0, 1, 2], &d, [0, 6, 7]));
        // Shares corner 0, stays above.
        let e = [[0.0, 0.0, 0.0], [1.0, 0.5, 1.0], [0.5, 1.0, 1.0]];
        assert!(!pair_intersects(&a, [0, 1, 2], &e, [0, 6, 7]));
        // Shares the edge 0-1: a hinge is fine, a fold onto a is not.
        let hinge = [[2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, -1.0, 0.5]];
        assert!(!pair_intersects(&a, [0, 1, 2], &hinge, [1, 0, 8]));
        let fold = [[2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.5, 0.0]];
        assert!(pair_intersects(&a, [0, 1, 2], &fold, [1, 0, 8]));
    }
}
