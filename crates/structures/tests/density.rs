mod common;
use microfrep_core::Expr;
use microfrep_structures::density::*;
use microfrep_structures::sampling::{volume_fraction_qmc, Samples};
use microfrep_structures::struts::{strut_cell, strut_lattice, StrutLattice};
use microfrep_structures::tpms::*;
use microfrep_structures::Error;

const TARGETS: [f64; 4] = [0.1, 0.2, 0.3, 0.5];

#[test]
fn tpms_levels_hit_target_densities() {
    for kind in Tpms::ALL {
        for solid in [Solid::Network, Solid::Sheet] {
            for t in TARGETS {
                let level = tpms_level(kind, solid, t, 50_000).unwrap();
                let e = tpms(kind, solid, &Expr::xyz(), 1.0, level);
                let same = volume_fraction_qmc(&e, [0.0; 3], [1.0; 3], 50_000).unwrap();
                assert!(
                    (same - t).abs() / t < 0.005,
                    "{} {solid:?} {t}: {same}",
                    kind.name()
                );
                // Checked on an independent sample: more points on a shifted cell.
                let got = volume_fraction_qmc(&e, [0.37; 3], [1.37; 3], 200_000).unwrap();
                assert!(
                    (got - t).abs() / t < 0.015,
                    "{} {solid:?} {t}: {got}",
                    kind.name()
                );
            }
        }
    }
}

#[test]
fn strut_radii_hit_target_densities() {
    for kind in StrutLattice::ALL {
        let mut last = 0.0;
        for t in TARGETS {
            let r = strut_radius(kind, t, 20_000).unwrap();
            assert!(r > last, "{} radius grows with density", kind.name());
            last = r;
            let e = strut_cell(kind, &Expr::xyz(), r);
            let same = volume_fraction_qmc(&e, [0.0; 3], [1.0; 3], 20_000).unwrap();
            assert!((same - t).abs() / t < 0.005, "{} {t}: {same}", kind.name());
            // Independently: the replicated lattice on a shifted box of 8 cells.
            let lat = strut_lattice(kind, &Expr::xyz(), 1.0, r);
            let got = volume_fraction_qmc(&lat, [-0.3; 3], [1.7; 3], 200_000).unwrap();
            assert!((got - t).abs() / t < 0.015, "{} {t}: {got}", kind.name());
        }
    }
}

#[test]
fn unreachable_and_bad_targets_are_errors() {
    assert!(matches!(
        strut_radius(StrutLattice::SimpleCubic, 0.99, 1000),
        Err(Error::Unreachable { .. })
    ));
    assert!(matches!(
        tpms_level(Tpms::Gyroid, Solid::Network, 1.5, 1000),
        Err(Error::OutOfRange { .. })
    ));
    let e = Expr::x();
    assert!(matches!(
        solve_param(
            &e,
            "nope",
            (0.0, 1.0),
            0.5,
            &Samples::grid([0.0; 3], [1.0; 3], 4).unwrap()
        ),
        Err(Error::NoParam(_))
    ));
    assert!(LevelTable::build(&[], Ok).is_err());
    assert!(LevelTable::build(&[0.3, 0.2], Ok).is_err());
    assert!(LevelTable::build(&[0.3, f64::NAN], Ok).is_err());
}

#[test]
fn density_field_through_level_table() {
    let ds: Vec<f64> = (1..10).map(|i| i as f64 / 10.0).collect();
    let table =
        LevelTable::build(&ds, |d| tpms_level(Tpms::Gyroid, Solid::Network, d, 20_000)).unwrap();
    // Gyroid network level 0 is density 0.5 (by symmetry).
    assert!(table.level()[4].abs() < 0.02, "{:?}", table.level());
    let coeffs = table.fit_polynomial(3).unwrap();
    // Density 0.2 + 0.15 x over four cells along x.
    let density = 0.2 + Expr::x() * 0.15;
    for level in [table.piecewise(&density), polynomial(&coeffs, &density)] {
        let e = tpms(Tpms::Gyroid, Solid::Network, &Expr::xyz(), 1.0, level);
        for k in 0..4 {
            let k = k as f64;
            let got = volume_fraction_qmc(&e, [k, 0.0, 0.0], [k + 1.0, 1.0, 1.0], 40_000).unwrap();
            let want = 0.2 + 0.15 * (k + 0.5);
            assert!((got - want).abs() < 0.02, "cell {k}: {got} vs {want}");
        }
    }
}
