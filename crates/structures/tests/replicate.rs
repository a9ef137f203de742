mod common;
use common::*;
use microfrep_core::frep::union_all;
use microfrep_core::{Axis, Expr};
use microfrep_shapes::{cylinder, sphere, v3};
use microfrep_structures::cell_report::cell_report;
use microfrep_structures::examples::toriball_cell;
use microfrep_structures::replicate::*;
use microfrep_structures::Error;

const MIN: [f64; 3] = [-1.0; 3];
const MAX: [f64; 3] = [1.0; 3];

fn cylinders() -> Expr {
    let p = Expr::xyz();
    let c: Vec<Expr> = (0..3)
        .map(|a| cylinder(&p, &v3([0.0; 3]), a, 0.3))
        .collect();
    union_all(&c, 1.0)
}

fn off_centre_sphere() -> Expr {
    sphere(&Expr::xyz(), &v3([0.5, 0.0, 0.0]), 0.7)
}

#[test]
fn report_classifies_known_cells() {
    let r = cell_report(&cylinders(), MIN, MAX, 9, 1e-9).unwrap();
    assert!(r.full() && r.geometric() && r.symmetric(), "{r:?}");
    assert!((0..3).all(|a| r.axes[a].sawtooth_safe() && r.axes[a].triangle_safe()));

    // The sphere pokes through the x = 1 face only.
    let r = cell_report(&off_centre_sphere(), MIN, MAX, 9, 1e-9).unwrap();
    let x = r.axes[0];
    assert!(!x.geometric && !x.full && !x.symmetric, "{x:?}");
    assert!(!x.sawtooth_connected() && !x.triangle_safe());
    // Along y and z it is symmetric.
    assert!(r.axes[1].full && r.axes[2].symmetric);

    let r = cell_report(&toriball_cell(&Expr::xyz()), MIN, MAX, 9, 1e-9).unwrap();
    assert!(r.symmetric() && r.full());
}

#[test]
fn geometric_but_not_full_connectivity() {
    // Same zero set on both x faces (none), different values.
    let cell = sphere(&Expr::xyz(), &v3([0.2, 0.0, 0.0]), 0.5);
    let r = cell_report(&cell, MIN, MAX, 7, 1e-6).unwrap();
    assert!(r.axes[0].geometric && !r.axes[0].full);
    assert!(
        (r.axes[0].max_face_diff - 0.8).abs() < 1e-12,
        "{}",
        r.axes[0].max_face_diff
    );
}

#[test]
fn values_within_tolerance_count_as_connected() {
    // A plane through the x faces' centres, tilted by 1e-12 along x: signs
    // differ on the faces but the values agree within the tolerance.
    let cell = Expr::y() + Expr::x() * 1e-12;
    let r = cell_report(&cell, MIN, MAX, 9, 1e-9).unwrap();
    assert!(r.axes[0].full && r.axes[0].geometric, "{r:?}");
    let r = cell_report(&cell, MIN, MAX, 9, 0.0).unwrap();
    assert!(!r.axes[0].full && !r.axes[0].geometric, "{r:?}");
}

#[test]
fn report_rejects_bad_input() {
    let c = cylinders();
    assert!(matches!(
        cell_report(&c, MIN, [1.0, -1.0, 1.0], 5, 0.0),
        Err(Error::BadBox { axis: 1, .. })
    ));
    assert!(matches!(
        cell_report(&c, MIN, MAX, 1, 0.0),
        Err(Error::BadResolution { .. })
    ));
    assert!(matches!(
        cell_report(&c, MIN, MAX, 5, f64::NAN),
        Err(Error::OutOfRange { .. })
    ));
    let nan = Expr::x().ln();
    assert!(matches!(
        cell_report(&nan, MIN, MAX, 5, 0.0),
        Err(Error::NotFinite { .. })
    ));
}

#[test]
fn triangle_mirrors_every_second_cell() {
    let a = 0.5;
    let r = volumetric(&off_centre_sphere(), Kind::Triangle, a, MIN, MAX);
    for p in spread(-1.0, 1.0, 40) {
        // Mirror about the face at a/2 on x; period 2a.
        let s = p[0];
        let mirrored = at(&r, [a - s, p[1], p[2]]);
        assert!((at(&r, p) - mirrored).abs() < 1e-9);
        assert!((at(&r, p) - at(&r, [s + 2.0 * a, p[1], p[2]])).abs() < 1e-9);
    }
    // Not a plain translation: cell 1 differs from cell 0 at an asymmetric point.
    let p = [0.15, 0.0, 0.0];
    assert!((at(&r, p) - at(&r, [p[0] + a, 0.0, 0.0])).abs() > 0.1);
}

#[test]
fn sawtooth_is_continuous_only_for_fully_connected_cells() {
    let a = 0.4;
    let face = a / 2.0;
    let jump = |cell: &Expr, y: f64, z: f64| {
        let r = volumetric(cell, Kind::Sawtooth, a, MIN, MAX);
        (at(&r, [face - 1e-9, y, z]) - at(&r, [face + 1e-9, y, z])).abs()
    };
    for p in spread(-1.0, 1.0, 20) {
        assert!(jump(&cylinders(), p[1], p[2]) < 1e-6);
    }
    assert!(jump(&off_centre_sphere(), 0.0, 0.0) > 1.0);
}

#[test]
fn linear_and_plane_replication_leave_other_axes_alone() {
    let cell = off_centre_sphere();
    let lin = linear(&cell, Axis::Z, Kind::Sawtooth, 0.5, MIN, MAX);
    let pla = plane(&cell, Axis::Z, Kind::Sawtooth, 0.5, MIN, MAX);
    for p in spread(-2.0, 2.0, 30) {
        // Linear along z: x, y pass through; the z period is 0.5.
        let v = at(&lin, p);
        assert!((v - at(&lin, [p[0], p[1], p[2] + 0.5])).abs() < 1e-9);
        let zc = -1.0 + 2.0 * (0.5 + p[2] / 0.5 - (p[2] / 0.5 + 0.5).floor());
        assert!((v - at(&cell, [p[0], p[1], zc])).abs() < 1e-9);
        // Plane normal to z: z passes through, x and y repeat.
        let w = at(&pla, p);
        assert!((w - at(&pla, [p[0] + 0.5, p[1] - 0.5, p[2]])).abs() < 1e-9);
        let xc = -1.0 + 2.0 * (0.5 + p[0] / 0.5 - (p[0] / 0.5 + 0.5).floor());
        let yc = -1.0 + 2.0 * (0.5 + p[1] / 0.5 - (p[1] / 0.5 + 0.5).floor());
        assert!((w - at(&cell, [xc, yc, p[2]])).abs() < 1e-9);
    }
}
