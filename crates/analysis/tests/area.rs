//! Surface area against closed forms: sphere, torus, block within 0.1 % at
//! the default resolution (256); TPMS area per unit cell against the
//! literature values (gyroid 3.0917, Schwarz P 2.3526, diamond 3.8383).

mod common;
use common::{close, measures};
use microfrep_core::Expr;
use microfrep_shapes::{block, sphere, torus, v3};
use microfrep_structures::tpms::{tpms, Solid, Tpms};
use std::f64::consts::PI;

const N: usize = 256;

#[test]
fn sphere_area() {
    let p = Expr::xyz();
    let r = 0.9;
    let m = measures(
        &sphere(&p, &v3([0.013, 0.021, -0.017]), r),
        None,
        [[-1.0; 3], [1.0; 3]],
        N,
    );
    close(
        "sphere",
        m.area.value,
        m.area.error(),
        4.0 * PI * r * r,
        1e-3,
    );
}

#[test]
fn torus_area() {
    let p = Expr::xyz();
    let (big, r) = (0.7, 0.25);
    let e = torus(&p, &v3([0.0; 3]), 2, big, r);
    let m = measures(&e, None, [[-1.0, -1.0, -0.3], [1.0, 1.0, 0.3]], N);
    close(
        "torus",
        m.area.value,
        m.area.error(),
        4.0 * PI * PI * big * r,
        1e-3,
    );
}

#[test]
fn block_area_with_creased_edges() {
    // The block's edges are creases: the cells around them are refined.
    let p = Expr::xyz();
    let w = [1.17, 1.03, 0.91];
    let e = block(&p, &v3([-0.61, -0.53, -0.47]), &v3(w));
    let m = measures(&e, None, [[-1.0; 3], [1.0; 3]], N);
    assert!(m.refine_depth > 0);
    let want = 2.0 * (w[0] * w[1] + w[1] * w[2] + w[0] * w[2]);
    close("block", m.area.value, m.area.error(), want, 1e-3);
}

#[test]
fn tpms_area_per_cell() {
    let p = Expr::xyz();
    for (k, want) in [
        (Tpms::Gyroid, 3.0917),
        (Tpms::SchwarzP, 2.3526),
        (Tpms::SchwarzD, 3.8383),
    ] {
        let m = measures(
            &tpms(k, Solid::Network, &p, 1.0, 0.0),
            None,
            [[0.0; 3], [1.0; 3]],
            128,
        );
        close(k.name(), m.area.value, m.area.error(), want, 3e-3);
    }
}

#[test]
fn area_inside_a_region_is_cut_by_it() {
    // A plane through a ball-shaped region: the disc's area.
    let p = Expr::xyz();
    let ball = sphere(&p, &v3([0.0; 3]), 0.8);
    let plane = &p[2] - 0.1;
    let m = measures(&plane, Some(&ball), [[-1.0; 3], [1.0; 3]], 128);
    let disc = PI * (0.64 - 0.01);
    assert!((m.area.value / disc - 1.0).abs() < 5e-3, "{}", m.area.value);
}

#[test]
fn undefined_values_count_as_outside() {
    // sqrt(x) - 1/2 is NaN for x < 0: the solid is x >= 1/4.
    let p = Expr::xyz();
    let e = p[0].sqrt() - 0.5;
    let m = measures(&e, None, [[-1.0; 3], [1.0; 3]], 64);
    assert!((m.volume.value - 3.0).abs() < 1e-3, "{:?}", m.volume);
    assert!((m.area.value - 4.0).abs() < 1e-3, "{:?}", m.area);
}
