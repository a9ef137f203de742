//! Distances between points and a mesh, for checking a mesh against the
//! exact geometry it stands for (creases, corners, faces): brute force over
//! every triangle, so it is an independent reference, meant for tests and
//! benchmarks on meshes of a few ten thousand triangles.

use crate::Mesh;
use microfrep_core::geom::{dot, sub};

/// Distance from `p` to the triangle `a b c`: to the nearest point found by
/// the region (corner, edge or face) of the triangle's plane that `p`
/// projects to.
pub fn point_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let at = |q: [f64; 3]| dot(sub(p, q), sub(p, q)).sqrt();
    let along =
        |o: [f64; 3], e: [f64; 3], t: f64| -> [f64; 3] { std::array::from_fn(|k| o[k] + t * e[k]) };
    if d1 <= 0.0 && d2 <= 0.0 {
        return at(a);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return at(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(along(a, ab, d1 / (d1 - d3)));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return at(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(along(a, ac, d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return at(along(b, sub(c, b), t));
    }
    let den = 1.0 / (va + vb + vc);
    let (v, w) = (vb * den, vc * den);
    at(std::array::from_fn(|k| a[k] + v * ab[k] + w * ac[k]))
}

/// Distance from `p` to the nearest triangle of `m` (infinite for a mesh
/// without triangles).
pub fn to_mesh(m: &Mesh, p: [f64; 3]) -> f64 {
    let v = |i: u32| m.vertices[i as usize].map(|c| c as f64);
    m.triangles
        .iter()
        .map(|t| point_triangle(p, v(t[0]), v(t[1]), v(t[2])))
        .fold(f64::INFINITY, f64::min)
}

/// The largest distance from the points `pts` to `m`.
pub fn farthest(m: &Mesh, pts: &[[f64; 3]]) -> f64 {
    pts.iter().map(|&p| to_mesh(m, p)).fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_to_a_triangle_by_region() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        // Above the face, beyond a corner, beyond an edge.
        assert!((point_triangle([0.2, 0.2, 0.5], a, b, c) - 0.5).abs() < 1e-15);
        assert!((point_triangle([-1.0, -1.0, 0.0], a, b, c) - 2f64.sqrt()).abs() < 1e-15);
        let e = point_triangle([1.0, 1.0, 0.0], a, b, c);
        assert!((e - 0.5f64.sqrt()).abs() < 1e-15, "{e}");
        assert!((point_triangle([0.5, -2.0, 0.0], a, b, c) - 2.0).abs() < 1e-15);
        let m = Mesh {
            vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
        };
        assert!((farthest(&m, &[[0.2, 0.2, 0.5], [0.2, 0.2, -0.7]]) - 0.7).abs() < 1e-7);
    }
}
