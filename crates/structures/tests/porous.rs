mod common;
use common::*;
use microfrep_core::noise::{gradient_noise, noise_g, NOISE_BOUND};
use microfrep_core::Expr;
use microfrep_shapes::{ellipsoid, sphere, v3};
use microfrep_structures::examples::unit_sphere;
use microfrep_structures::infill::{graded_by_depth, Depth};
use microfrep_structures::porous::*;
use microfrep_structures::sampling::volume_fraction_qmc;
use std::f64::consts::PI;

#[test]
fn pores_sit_on_the_mapped_lattice() {
    let p = Expr::xyz();
    let q = 10.0;
    let map = PeriodicMap::uniform(1.0, q);
    let r = pores(&p, &map, |m| sphere(m, &v3([0.0; 3]), 0.5));
    // Pore centres at k pi / q on each axis; mapped value is exact.
    for k in [-2.0, 0.0, 3.0] {
        let c = k * PI / q;
        assert!((at(&r, [c, 0.0, c]) - 0.25).abs() < 1e-12);
    }
    // Half way between pores the mapped point is (1, 1, 1): solid left.
    let h = PI / (2.0 * q);
    assert!((at(&r, [h, h, h]) - (0.25 - 3.0)).abs() < 1e-12);
    let part = porous(&unit_sphere(), &r, 1.0);
    assert!(at(&part, [0.0; 3]) < 0.0 && at(&part, [h, h, h]) > 0.0);
}

#[test]
fn per_axis_map_and_any_pore_shape() {
    let p = Expr::xyz();
    let map = PeriodicMap {
        amp: [
            Expr::constant(1.0),
            Expr::constant(2.0),
            Expr::constant(1.0),
        ],
        freq: [
            Expr::constant(5.0),
            Expr::constant(10.0),
            Expr::constant(20.0),
        ],
    };
    let r = pores(&p, &map, |m| {
        ellipsoid(m, &v3([0.0; 3]), &v3([0.5, 0.3, 0.2]))
    });
    let pt: [f64; 3] = [0.1, 0.07, 0.02];
    let m = [
        (5.0 * pt[0]).sin(),
        2.0 * (10.0 * pt[1]).sin(),
        (20.0 * pt[2]).sin(),
    ];
    let want = 1.0 - (m[0] / 0.5).powi(2) - (m[1] / 0.3).powi(2) - (m[2] / 0.2).powi(2);
    assert!((at(&r, pt) - want).abs() < 1e-12);
}

#[test]
fn pore_size_graded_by_depth() {
    let f = unit_sphere();
    // Pore radius (in mapped units) 0.2 at the surface, 1.2 deep inside.
    let size = graded_by_depth(&f, Depth::Normalized, 0.5, 0.2, 1.2);
    let r = pores(&Expr::xyz(), &PeriodicMap::uniform(1.0, 25.0), |m| {
        sphere(m, &v3([0.0; 3]), size.clone())
    });
    let part = porous(&f, &r, 1.0);
    // At a pore centre the pore value is the squared local radius.
    let c = 4.0 * PI / 25.0;
    assert!((at(&r, [c, 0.0, 0.0]) - at(&size, [c, 0.0, 0.0]).powi(2)).abs() < 1e-12);
    let deep = volume_fraction_qmc(&part, [-0.2; 3], [0.2; 3], 40_000).unwrap();
    let near = volume_fraction_qmc(&part, [0.85, -0.1, -0.1], [0.95, 0.1, 0.1], 40_000).unwrap();
    assert!(near > deep + 0.2, "near {near} deep {deep}");
}

#[test]
fn gardner_noise_is_bounded_and_varies_pores() {
    let p = Expr::xyz();
    let n = noise_g(&p, 0.1, 7.0, 2.0);
    let bound = (0.1f64 * 2.17 / 1.17).powi(3);
    let mut spread_seen = (f64::INFINITY, f64::NEG_INFINITY);
    for q in spread(-2.0, 2.0, 500) {
        let v = at(&n, q);
        assert!(v.abs() <= bound + 1e-12);
        spread_seen = (spread_seen.0.min(v), spread_seen.1.max(v));
    }
    assert!(
        spread_seen.1 - spread_seen.0 > 0.2 * bound,
        "{spread_seen:?}"
    );
    // Noise on the pore size: the mapped-pore field moves by exactly the noise.
    let map = PeriodicMap::uniform(1.0, 20.0);
    let plain = pores(&p, &map, |m| sphere(m, &v3([0.0; 3]), 0.5));
    let noisy = pores(&p, &map, |m| sphere(m, &v3([0.0; 3]), 0.5) + &n);
    for q in spread(-1.0, 1.0, 50) {
        assert!((at(&noisy, q) - at(&plain, q) - at(&n, q)).abs() < 1e-12);
    }
}

#[test]
fn gradient_noise_varies_pore_size_within_bounds() {
    let p = Expr::xyz();
    let map = PeriodicMap::uniform(1.0, 20.0);
    // Radius 0.6 +- 0.1 * noise, noise sampled at 8 x the point for variation.
    let noise = gradient_noise(&p.clone().map(|c| c * 8.0), 7);
    let size = 0.6 + &noise * 0.05;
    let r = pores(&p, &map, |m| sphere(m, &v3([0.0; 3]), size.clone()));
    let mut radii = Vec::new();
    for k in 0..6 {
        // Pore centres: the value there is the squared local radius.
        let c = [k as f64 * PI / 20.0, 0.0, 0.0];
        let rad = at(&r, c).sqrt();
        assert!((rad - 0.6).abs() <= 0.05 * NOISE_BOUND + 1e-12);
        radii.push(rad);
    }
    assert!(
        radii.iter().any(|&x| (x - radii[0]).abs() > 1e-3),
        "{radii:?}"
    );
}
