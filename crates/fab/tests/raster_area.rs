//! Layer areas against closed forms: sphere discs (binary and anti-aliased)
//! and the alpha = 1 rod lattice.

use microfrep_core::{Expr, Shape};
use microfrep_fab::coverage::coverage;
use microfrep_fab::{rasterize_at, SliceGrid};
use microfrep_structures::examples::unit_sphere;
use microfrep_structures::lattice::{rod_lattice, Slabs};
use std::f64::consts::PI;

fn inside_count(tape: &Shape, grid: &SliceGrid, z: f64) -> usize {
    let l = rasterize_at(tape, grid, z);
    l.values.iter().filter(|&&v| v >= 0.0).count()
}

fn covered_area(tape: &Shape, grid: &SliceGrid, z: f64) -> f64 {
    let l = rasterize_at(tape, grid, z);
    let cov = coverage(tape, &l, grid.pixel, [grid.min[0], grid.min[1]]);
    cov.iter().map(|&c| c as f64 / 255.0).sum::<f64>() * grid.pixel * grid.pixel
}

#[test]
fn sphere_layers_match_disc_area() {
    let tape = Shape::from(&unit_sphere());
    let p = 0.01;
    let grid = SliceGrid::new([-1.1; 3], [1.1; 3], 0.05, p).unwrap();
    for z in [0.0, 0.3, -0.6, 0.9] {
        let r2: f64 = 1.0 - z * z;
        let exact = PI * r2 / (p * p);
        let n = inside_count(&tape, &grid, z) as f64;
        // Only pixels the circle crosses can be wrong: about perimeter / p.
        let boundary = 2.0 * PI * r2.sqrt() / p;
        assert!(
            (n - exact).abs() <= boundary,
            "z={z}: {n} px vs {exact} (tolerance {boundary})"
        );
        let area = covered_area(&tape, &grid, z);
        let rel = (area - PI * r2).abs() / (PI * r2);
        assert!(rel < 0.005, "z={z}: coverage area {area} vs {}", PI * r2);
    }
}

#[test]
fn anti_aliasing_beats_binary_on_a_small_disc() {
    // A coarse grid, where pixel counting is visibly off but coverage is not.
    let tape = Shape::from(&unit_sphere());
    let grid = SliceGrid::new([-1.0; 3], [1.0; 3], 0.1, 0.1).unwrap();
    let z = 0.5;
    let exact = PI * 0.75;
    let binary = inside_count(&tape, &grid, z) as f64 * 0.01;
    let aa = covered_area(&tape, &grid, z);
    assert!((aa - exact).abs() / exact < 0.005, "aa {aa} vs {exact}");
    assert!((aa - exact).abs() < (binary - exact).abs());
}

#[test]
fn rod_lattice_area_fraction_matches_square_rod_grid() {
    // Period 1 on every axis, threshold l: a slab is positive on a fraction
    // w of each period. A layer through the z-slabs shows the union of the x
    // and y bands (2w - w^2); a layer between them the z-rods only (w^2).
    let l = 0.3;
    let p = Expr::xyz();
    let lattice = rod_lattice(&p, &Slabs::uniform(2.0 * PI, l), 1.0);
    let tape = Shape::from(&lattice);
    let w = (PI - 2.0 * f64::asin(l)) / (2.0 * PI);
    let grid = SliceGrid::new([0.0; 3], [4.0; 3], 0.1, 0.01).unwrap();
    let total = 16.0;
    for (z, expect) in [(0.25, 2.0 * w - w * w), (0.75, w * w)] {
        let aa = covered_area(&tape, &grid, z) / total;
        assert!(
            (aa - expect).abs() < 2e-3,
            "z={z}: coverage {aa} vs {expect}"
        );
        let n = inside_count(&tape, &grid, z) as f64 * 1e-4 / total;
        // Axis-aligned band edges: at most one wrong pixel column or row per
        // edge, 16 edges over 400 pixels.
        assert!((n - expect).abs() < 16.0 / 400.0, "z={z}: {n} vs {expect}");
    }
}
