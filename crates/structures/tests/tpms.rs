mod common;
use common::*;
use microfrep_core::Expr;
use microfrep_structures::sampling::{volume_fraction, volume_fraction_qmc};
use microfrep_structures::tpms::*;

fn vf(kind: Tpms, solid: Solid, level: f64) -> f64 {
    let e = tpms(kind, solid, &Expr::xyz(), 1.0, level);
    volume_fraction(&e, [0.0; 3], [1.0; 3], 48).unwrap()
}

#[test]
fn network_volume_fractions_match_known_values() {
    let table = [
        (Tpms::Gyroid, [0.170, 0.338, 0.5, 0.662, 0.830]),
        (Tpms::SchwarzP, [0.213, 0.357, 0.5, 0.643, 0.787]),
        (Tpms::SchwarzD, [0.081, 0.294, 0.5, 0.706, 0.919]),
    ];
    for (kind, want) in table {
        for (t, w) in [-1.0, -0.5, 0.0, 0.5, 1.0].into_iter().zip(want) {
            let got = vf(kind, Solid::Network, t);
            assert!(
                (got - w).abs() < 0.005,
                "{} level {t}: {got} vs {w}",
                kind.name()
            );
        }
    }
}

#[test]
fn every_surface_is_bounded_and_cell_size_scales() {
    for kind in Tpms::ALL {
        let f = kind.field(&Expr::xyz(), 1.0);
        let (lo, hi) = interval(&f, [0.0; 3], [1.0; 3]);
        assert!(
            lo >= -kind.bound() - 1e-9 && hi <= kind.bound() + 1e-9,
            "{}",
            kind.name()
        );
        // Cell size 2.5: same value at the scaled point.
        let g = kind.field(&Expr::xyz(), 2.5);
        for p in spread(0.0, 1.0, 20) {
            let q = p.map(|c| 2.5 * c);
            assert!((at(&f, p) - at(&g, q)).abs() < 1e-12);
        }
        // The sheet at level t is the set between network levels -t and t.
        let sheet = vf(kind, Solid::Sheet, 0.3);
        let band = vf(kind, Solid::Network, 0.3) - vf(kind, Solid::Network, -0.3);
        assert!(
            (sheet - band).abs() < 1e-3,
            "{}: {sheet} {band}",
            kind.name()
        );
    }
}

#[test]
fn schwarz_p_sheet_thickness_along_the_diagonal() {
    // Through (1/4, 1/4, 1/4) along (1, 1, 1)/sqrt 3: f(s) = -3 sin(2 pi s / sqrt 3),
    // so the sheet |f| < t spans s in +-sqrt(3)/(2 pi) asin(t/3).
    let t = 0.6;
    let e = tpms(Tpms::SchwarzP, Solid::Sheet, &Expr::xyz(), 1.0, t);
    let at_s = |s: f64| at(&e, [0.25 + s / 3f64.sqrt(); 3]);
    let (mut a, mut b) = (0.0, 0.2);
    assert!(at_s(a) > 0.0 && at_s(b) < 0.0);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if at_s(m) > 0.0 {
            a = m
        } else {
            b = m
        }
    }
    let want = 3f64.sqrt() / (2.0 * std::f64::consts::PI) * (t / 3.0).asin();
    assert!((a - want).abs() < 1e-9, "{a} {want}");
}

#[test]
fn graded_level_field() {
    // Level linear in x from -1 to 1 over four gyroid cells: denser along x.
    let level = Expr::x() * 0.5 - 1.0;
    let e = tpms(Tpms::Gyroid, Solid::Network, &Expr::xyz(), 1.0, level);
    let first = volume_fraction_qmc(&e, [0.0; 3], [1.0; 3], 40_000).unwrap();
    let last = volume_fraction_qmc(&e, [3.0, 0.0, 0.0], [4.0, 1.0, 1.0], 40_000).unwrap();
    assert!(first < 0.3 && last > 0.7, "{first} {last}");
}
