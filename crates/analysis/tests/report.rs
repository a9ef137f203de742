//! The whole analysis in one call: figures agree with each other and with
//! closed forms.

use microfrep_analysis::thickness::PhaseThickness;
use microfrep_analysis::{analyze, AnalyzeOptions, Grid};
use microfrep_core::frep::subtraction;
use microfrep_core::{Expr, Shape};
use microfrep_shapes::{sphere, v3};
use std::f64::consts::PI;

#[test]
fn hollow_ball_report() {
    let p = Expr::xyz();
    let e = subtraction(
        &sphere(&p, &v3([0.0; 3]), 1.0),
        &sphere(&p, &v3([0.0; 3]), 0.5),
        1.0,
    );
    let t = Shape::from(&e);
    let g = Grid::new([[-1.1; 3], [1.1; 3]], 64).unwrap();
    let r = analyze(&t, None, g, &AnalyzeOptions::default(), &|_, _, _| {}).unwrap();
    let vol = 4.0 / 3.0 * PI * (1.0 - 0.125);
    let area = 4.0 * PI * (1.0 + 0.25);
    assert!((r.volume() / vol - 1.0).abs() < 5e-3);
    assert!((r.area() / area - 1.0).abs() < 5e-3);
    assert!((r.volume_fraction() - vol / 2.2f64.powi(3)).abs() < 1e-3);
    assert!((r.porosity() + r.volume_fraction() - 1.0).abs() < 1e-12);
    assert!((r.specific_surface() - r.area() / r.volume()).abs() < 1e-12);
    assert!(r.volume_error() > 0.0 && r.area_error() > 0.0);
    let c = r.connectivity.as_ref().unwrap();
    assert_eq!((c.solid_components, c.closed_pores), (1, 1));
    // The wall is 0.5 thick; local thickness within about a voxel.
    let th = r.thickness.as_ref().unwrap();
    match &th.solid {
        PhaseThickness::Measured(s) => {
            assert!((s.max - 0.5).abs() < 2.0 * 2.2 / 64.0, "{s:?}")
        }
        other => panic!("{other:?}"),
    }
}
