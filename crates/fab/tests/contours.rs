//! Contours of the shell-with-lattice model against a flood fill of the same
//! layer's image; orientation, closure and simplicity of every polygon; the
//! SVG writer and reader agree.

use microfrep_core::Shape;
use microfrep_fab::contour::{signed_area, Polygon};
use microfrep_fab::svg::{layer_svg, read_layer_svg};
use microfrep_fab::{layer_polygons, rasterize_at, LayerValues, SliceGrid};
use microfrep_structures::examples::shell_lattice;

/// Components by flood fill: solid 8-connected, empty 4-connected (the rule
/// the contours follow). Returns (solid components, empty components not
/// reaching the image border).
fn flood_counts(l: &LayerValues) -> (usize, usize) {
    let (nx, ny) = (l.nx as i64, l.ny as i64);
    let mut seen = vec![false; l.values.len()];
    let (mut solids, mut holes) = (0, 0);
    for start in 0..l.values.len() {
        if seen[start] {
            continue;
        }
        let solid = l.values[start] >= 0.0;
        let nbrs: &[(i64, i64)] = if solid {
            &[
                (1, 0),
                (-1, 0),
                (0, 1),
                (0, -1),
                (1, 1),
                (1, -1),
                (-1, 1),
                (-1, -1),
            ]
        } else {
            &[(1, 0), (-1, 0), (0, 1), (0, -1)]
        };
        let mut border = false;
        let mut stack = vec![start];
        seen[start] = true;
        while let Some(k) = stack.pop() {
            let (i, j) = ((k % l.nx) as i64, (k / l.nx) as i64);
            border |= i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
            for (di, dj) in nbrs {
                let (a, b) = (i + di, j + dj);
                if a < 0 || b < 0 || a >= nx || b >= ny {
                    continue;
                }
                let q = (b * nx + a) as usize;
                if !seen[q] && (l.values[q] >= 0.0) == solid {
                    seen[q] = true;
                    stack.push(q);
                }
            }
        }
        if solid {
            solids += 1;
        } else if !border {
            holes += 1;
        }
    }
    (solids, holes)
}

fn segments_cross(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let orient = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let (d1, d2) = (orient(a, b, c), orient(a, b, d));
    let (d3, d4) = (orient(c, d, a), orient(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

fn is_simple(p: &Polygon) -> bool {
    let n = p.len();
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // neighbours through the closing edge
            }
            if segments_cross(p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]) {
                return false;
            }
        }
    }
    true
}

fn point_in(p: [f64; 2], poly: &Polygon) -> bool {
    let n = poly.len();
    let mut inside = false;
    for k in 0..n {
        let (a, b) = (poly[k], poly[(k + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

#[test]
fn shell_lattice_loops_match_flood_fill() {
    let tape = Shape::from(&shell_lattice());
    let grid = SliceGrid::new([-1.05; 3], [1.05; 3], 0.1, 0.01).unwrap();
    for z in [0.05, 0.3, 0.7] {
        let layer = rasterize_at(&tape, &grid, z);
        let (solids, holes) = flood_counts(&layer);
        let polys = layer_polygons(&tape, &grid, &layer);
        let outer = polys.iter().filter(|p| signed_area(p) > 0.0).count();
        let inner = polys.len() - outer;
        assert!(
            solids >= 1 && holes >= 1,
            "z={z}: a trivial layer tests nothing"
        );
        assert_eq!((outer, inner), (solids, holes), "z={z}");
        for (k, p) in polys.iter().enumerate() {
            assert!(
                p.len() >= 3 && p.first() != p.last(),
                "z={z}: loop {k} degenerate"
            );
            assert!(is_simple(p), "z={z}: loop {k} self-intersects");
            // Nesting depth from a vertex: outer loops at even depth run
            // counter-clockwise, holes at odd depth clockwise.
            let depth = polys
                .iter()
                .enumerate()
                .filter(|&(m, q)| m != k && point_in(p[0], q))
                .count();
            assert_eq!(signed_area(p) > 0.0, depth % 2 == 0, "z={z}: loop {k}");
        }
    }
}

#[test]
fn sphere_contour_is_one_ccw_circle_within_tolerance() {
    let tape = Shape::from(&microfrep_structures::examples::unit_sphere());
    let grid = SliceGrid::new([-1.1; 3], [1.1; 3], 0.1, 0.02).unwrap();
    let layer = rasterize_at(&tape, &grid, 0.6);
    let polys = layer_polygons(&tape, &grid, &layer);
    assert_eq!(polys.len(), 1);
    assert!(signed_area(&polys[0]) > 0.0);
    for v in &polys[0] {
        // Vertices are refined onto the circle of radius 0.8.
        let r = (v[0] * v[0] + v[1] * v[1]).sqrt();
        assert!((r - 0.8).abs() < 1e-6, "vertex at radius {r}");
    }
    // Simplification keeps the area within the tolerance band.
    let a = signed_area(&polys[0]);
    let exact = std::f64::consts::PI * 0.64;
    assert!((a - exact).abs() < 2.0 * std::f64::consts::PI * 0.8 * 0.25 * 0.02);
}

#[test]
fn svg_round_trip_keeps_loops() {
    let tape = Shape::from(&shell_lattice());
    let grid = SliceGrid::new([-1.05; 3], [1.05; 3], 0.1, 0.02).unwrap();
    let layer = rasterize_at(&tape, &grid, 0.3);
    let polys = layer_polygons(&tape, &grid, &layer);
    let svg = layer_svg(&polys, 0.3, [-1.05, -1.05], [1.05, 1.05], 0.005);
    assert_eq!(read_layer_svg(&svg), polys);
}
