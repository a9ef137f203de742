mod common;
use common::*;
use microfrep_core::Expr;
use microfrep_shapes::half_space;
use microfrep_structures::examples::unit_sphere;
use microfrep_structures::infill::Depth;
use microfrep_structures::lattice::{rod_lattice, Slabs};
use microfrep_structures::surficial::*;

#[test]
fn intersection_curve_of_sphere_and_plane() {
    let plane = half_space(&Expr::xyz(), [0.0; 3], [0.0, 0.0, 1.0]);
    let c = intersection_curve(&unit_sphere(), &plane, 0.1, Depth::Normalized, 1.0);
    // On the circle; within 0.1 of it radially and in z; outside beyond.
    assert!(at(&c, [1.0, 0.0, 0.0]) > 0.0);
    assert!(at(&c, [0.0, 1.06, 0.05]) > 0.0);
    assert!(at(&c, [1.0, 0.0, 0.12]) < 0.0);
    assert!(at(&c, [0.0, 0.8, 0.0]) < 0.0);
    assert!(at(&c, [0.0, 0.0, 0.0]) < 0.0);
    // Closed form at (r, 0, z): t^2 - max(g1^2, g2^2), g1 = (1 - r^2 - z^2)/(1 + r^2 + z^2).
    let (r, z) = (0.97, 0.03);
    let s = r * r + z * z;
    let g1 = (1.0 - s) / (1.0 + s);
    let g2 = -z / (z * z + 1.0f64).sqrt();
    let want = 0.01 - (g1 * g1).max(g2 * g2);
    assert!((at(&c, [r, 0.0, z]) - want).abs() < 1e-12);
}

#[test]
fn shells_constant_and_normalised() {
    let f = unit_sphere();
    // Normalised: thickness 0.1 means depth (1 - r^2)/(1 + r^2) <= 0.1, r >= sqrt(0.9/1.1).
    let n = shell(&f, 0.1, Depth::Normalized, 1.0);
    let edge = (0.9f64 / 1.1).sqrt();
    assert!(at(&n, [edge + 1e-6, 0.0, 0.0]) > 0.0 && at(&n, [edge - 1e-6, 0.0, 0.0]) < 0.0);
    // Constant: f <= 0.1 means r >= sqrt(0.9).
    let c = shell(&f, 0.1, Depth::Function, 1.0);
    let edge = 0.9f64.sqrt();
    assert!(at(&c, [0.0, edge + 1e-6, 0.0]) > 0.0 && at(&c, [0.0, edge - 1e-6, 0.0]) < 0.0);
    assert!(at(&c, [0.0, 1.0 + 1e-6, 0.0]) < 0.0);
}

#[test]
fn shell_intersected_with_cells() {
    let f = unit_sphere();
    let cells = rod_lattice(&Expr::xyz(), &Slabs::uniform(20.0, 0.3), 1.0);
    let s = cellular_shell(&f, 0.2, Depth::Normalized, &cells, 1.0);
    let sh = shell(&f, 0.2, Depth::Normalized, 1.0);
    for p in spread(-1.1, 1.1, 300) {
        let want = at(&sh, p) >= 0.0 && at(&cells, p) >= 0.0;
        assert_eq!(at(&s, p) >= 0.0, want, "{p:?}");
    }
}
