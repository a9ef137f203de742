mod common;
use common::*;
use microfrep_core::Expr;
use microfrep_structures::sampling::volume_fraction_qmc;
use microfrep_structures::struts::*;

#[test]
fn node_degrees_match_the_crystals() {
    // Count bonds at an interior node: (1/2, 1/2, 1/2) for bcc centre, etc.
    let degree = |kind: StrutLattice, n: [f64; 3]| {
        kind.struts()
            .iter()
            .filter(|(a, b)| *a == n || *b == n)
            .count()
    };
    assert_eq!(degree(StrutLattice::SimpleCubic, [1.0, 1.0, 1.0]), 6);
    assert_eq!(degree(StrutLattice::Bcc, [0.5, 0.5, 0.5]), 8);
    assert_eq!(degree(StrutLattice::Octet, [0.5, 0.5, 1.0]), 12);
    assert_eq!(degree(StrutLattice::Fcc, [0.5, 0.5, 1.0]), 4);
    assert_eq!(degree(StrutLattice::Diamond, [0.25, 0.25, 0.25]), 4);
    assert_eq!(degree(StrutLattice::Kelvin, [0.5, 0.25, 1.0]), 4);
}

#[test]
fn cell_value_is_distance_to_nearest_strut() {
    // Simple cubic, radius 0.1: at (0.5, 0.5, 0) the nearest struts are the
    // cube edges at distance 0.5.
    let c = strut_cell(StrutLattice::SimpleCubic, &Expr::xyz(), 0.1);
    assert!((at(&c, [0.5, 0.5, 0.0]) - (0.1 - 0.5)).abs() < 1e-12);
    assert!((at(&c, [0.5, 0.02, 0.0]) - 0.08).abs() < 1e-12);
}

#[test]
fn replicated_lattice_is_periodic_and_seamless() {
    for kind in StrutLattice::ALL {
        let e = strut_lattice(kind, &Expr::xyz(), 0.5, 0.06);
        for p in spread(-1.0, 1.0, 50) {
            let q = [p[0] + 0.5, p[1] - 1.0, p[2] + 1.5];
            assert!((at(&e, p) - at(&e, q)).abs() < 1e-9, "{}", kind.name());
        }
        // Across a cell face the value is continuous.
        for p in spread(0.0, 0.5, 20) {
            let a = at(&e, [0.25 - 1e-7, p[1], p[2]]);
            let b = at(&e, [0.25 + 1e-7, p[1], p[2]]);
            assert!((a - b).abs() < 1e-5, "{} {p:?}: {a} {b}", kind.name());
        }
    }
}

#[test]
fn radius_field_grades_density() {
    let r = 0.02 + Expr::x() * 0.02;
    let e = strut_lattice(StrutLattice::Bcc, &Expr::xyz(), 0.5, r);
    let thin = volume_fraction_qmc(&e, [0.0; 3], [1.0; 3], 40_000).unwrap();
    let thick = volume_fraction_qmc(&e, [3.0, 0.0, 0.0], [4.0, 1.0, 1.0], 40_000).unwrap();
    assert!(thick > 3.0 * thin, "{thin} {thick}");
}
