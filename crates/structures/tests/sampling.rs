use microfrep_core::Expr;
use microfrep_structures::examples::unit_sphere;
use microfrep_structures::sampling::*;
use microfrep_structures::Error;

#[test]
fn ball_fraction_is_pi_over_six() {
    let want = std::f64::consts::PI / 6.0;
    let grid = volume_fraction(&unit_sphere(), [-1.0; 3], [1.0; 3], 64).unwrap();
    let qmc = volume_fraction_qmc(&unit_sphere(), [-1.0; 3], [1.0; 3], 100_000).unwrap();
    assert!((grid - want).abs() < 2e-3, "{grid}");
    assert!((qmc - want).abs() < 1e-3, "{qmc}");
}

#[test]
fn bad_input_is_reported_with_location() {
    let e = Expr::x().sqrt();
    match volume_fraction(&e, [-1.0, 0.0, 0.0], [1.0; 3], 4) {
        Err(Error::NotFinite { x, .. }) => assert!(x < 0.0),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        volume_fraction(&e, [0.0; 3], [1.0, 1.0, f64::INFINITY], 4),
        Err(Error::BadBox { axis: 2, .. })
    ));
    assert!(matches!(
        volume_fraction_qmc(&e, [0.0; 3], [1.0; 3], 0),
        Err(Error::BadResolution { .. })
    ));
    assert!(matches!(
        Samples::grid([0.0; 3], [1.0; 3], 100_000),
        Err(Error::BadResolution { .. })
    ));
}
