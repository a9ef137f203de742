mod common;
use common::*;
use microfrep_core::frep::Blend;
use microfrep_core::Expr;
use microfrep_structures::lattice::*;
use microfrep_structures::sampling::volume_fraction_qmc;
use std::f64::consts::PI;

#[test]
fn alpha1_volume_fraction_matches_closed_form() {
    // Period 1 (q = 2 pi), four periods per axis in the box.
    for l in [-0.5, 0.0, 0.3, 0.6] {
        let g = rod_lattice(&Expr::xyz(), &Slabs::uniform(2.0 * PI, l), 1.0);
        let vf = volume_fraction_qmc(&g, [0.0; 3], [4.0; 3], 400_000).unwrap();
        let want = rod_lattice_volume_fraction(l);
        assert!((vf - want).abs() / want < 0.005, "l {l}: {vf} vs {want}");
    }
}

#[test]
fn field_threshold_thickens_rods_along_x() {
    // l linear in x (Pasko Fig. 2c): thinner rods (higher l) at larger x.
    let l = Expr::x() * 0.2;
    let g = rod_lattice(&Expr::xyz(), &Slabs::uniform(2.0 * PI, l), 1.0);
    let lo = volume_fraction_qmc(&g, [0.0, 0.0, 0.0], [1.0, 2.0, 2.0], 100_000).unwrap();
    let hi = volume_fraction_qmc(&g, [3.0, 0.0, 0.0], [4.0, 2.0, 2.0], 100_000).unwrap();
    assert!(lo > hi + 0.2, "{lo} {hi}");
    // On a rod axis (y, z at slab maxima) the value is 1 - l.
    let v = at(&g, [0.1, 0.25, 0.25]);
    assert!((v - (1.0 - 0.02)).abs() < 1e-12, "{v}");
}

#[test]
fn blended_junctions_add_material_and_agree_across_modes() {
    let s = Slabs::uniform(2.0 * PI, 0.5);
    let p = Expr::xyz();
    let plain = rod_lattice(&p, &s, 0.0);
    let blended = blended_rod_lattice(&p, &s, 0.0, &Blend::new(0.3, 0.5, 0.5));
    let a = volume_fraction_qmc(&plain, [0.0; 3], [1.0; 3], 50_000).unwrap();
    let b = volume_fraction_qmc(&blended, [0.0; 3], [1.0; 3], 50_000).unwrap();
    assert!(b > a + 0.01, "{a} {b}");
    let pts = spread(-1.0, 1.0, 300);
    for (p, v) in pts.iter().zip(batch(&blended, &pts)) {
        let r = at(&blended, *p);
        assert!((r - v as f64).abs() < 1e-4 * (1.0 + r.abs()), "{p:?}");
        let (lo, hi) = interval(&blended, *p, *p);
        assert!(lo <= r + 1e-9 && r <= hi + 1e-9);
    }
}
