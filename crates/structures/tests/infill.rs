mod common;
use common::*;
use microfrep_core::frep::Blend;
use microfrep_core::Expr;
use microfrep_structures::examples::unit_sphere;
use microfrep_structures::infill::*;
use microfrep_structures::lattice::{rod_lattice, Slabs};
use microfrep_structures::sampling::volume_fraction_qmc;

#[test]
fn normalized_depth_of_sphere_is_closed_form() {
    // f = 1 - r^2: f / sqrt(f^2 + 4 r^2) = (1 - r^2) / (1 + r^2).
    let d = depth(&unit_sphere(), Depth::Normalized);
    for r in [0.2, 0.7, 0.95, 1.3] {
        let want = (1.0 - r * r) / (1.0 + r * r);
        assert!((at(&d, [0.0, r, 0.0]) - want).abs() < 1e-12);
    }
    let f = depth(&unit_sphere(), Depth::Function);
    assert_eq!(at(&f, [0.5, 0.0, 0.0]), 0.75);
}

#[test]
fn shell_and_lattice_regions() {
    let f = unit_sphere();
    let g = rod_lattice(&Expr::xyz(), &Slabs::uniform(12.0, 0.4), 1.0);
    let m = shell_with_infill(&f, 0.2, &g, 1.0, &Join::Plain);
    // Shell: 0 <= f <= 0.2, i.e. r in [sqrt(0.8), 1].
    assert!(at(&m, [0.95, 0.0, 0.0]) >= 0.0);
    assert!(at(&m, [0.0, 0.0, -0.95]) >= 0.0);
    assert!(at(&m, [1.05, 0.0, 0.0]) < 0.0);
    // Inside: lattice where g >= 0, empty where g < 0.
    for p in spread(-0.6, 0.6, 200) {
        let (gv, mv) = (at(&g, p), at(&m, p));
        if at(&f, p) > 0.25 && gv.abs() > 1e-9 {
            assert_eq!(gv >= 0.0, mv >= 0.0, "{p:?}");
        }
    }
}

#[test]
fn blended_join_adds_material_near_shell() {
    let f = unit_sphere();
    let g = rod_lattice(&Expr::xyz(), &Slabs::uniform(12.0, 0.4), 0.0);
    let plain = shell_with_infill(&f, 0.2, &g, 0.0, &Join::Plain);
    let blend = shell_with_infill(&f, 0.2, &g, 0.0, &Join::Blended(Blend::new(0.2, 0.2, 0.2)));
    let a = volume_fraction_qmc(&plain, [-1.0; 3], [1.0; 3], 60_000).unwrap();
    let b = volume_fraction_qmc(&blend, [-1.0; 3], [1.0; 3], 60_000).unwrap();
    assert!(b > a, "{a} {b}");
}

#[test]
fn threshold_graded_by_depth_is_denser_near_surface() {
    let f = unit_sphere();
    // l = -0.5 (thick rods) at the surface, 0.7 (thin) from depth 0.3 on.
    let l = graded_by_depth(&f, Depth::Normalized, 0.3, -0.5, 0.7);
    assert!((at(&l, [1.0, 0.0, 0.0]) + 0.5).abs() < 1e-12);
    assert!((at(&l, [0.0, 0.1, 0.0]) - 0.7).abs() < 1e-12);
    let g = rod_lattice(&Expr::xyz(), &Slabs::uniform(30.0, l), 1.0);
    let m = shell_with_infill(&f, 0.05, &g, 1.0, &Join::Plain);
    let core = volume_fraction_qmc(&m, [-0.3; 3], [0.3; 3], 50_000).unwrap();
    // A box in the outer layer (normalised depth 0.06 to 0.22), under the shell.
    let outer = volume_fraction_qmc(&m, [0.8, -0.2, -0.2], [0.9, 0.2, 0.2], 50_000).unwrap();
    assert!(outer > core + 0.15, "outer {outer} core {core}");
}
