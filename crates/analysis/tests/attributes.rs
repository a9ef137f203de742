//! Attribute channels over the solid against closed forms.

use microfrep_analysis::{analyze, AnalyzeOptions, Grid};
use microfrep_core::{Expr, Shape};

#[test]
fn a_graded_ball_integrates_its_channel() {
    let [x, y, z] = Expr::xyz();
    let ball = 1.0 - (x.square() + y.square() + z.square());
    // s1 = x^2 over the unit ball: integral 4 pi / 15; s2 = 2 (constant).
    let shape = Shape::new(ball)
        .with_attribute("s1", x.square())
        .with_attribute("s2", Expr::constant(2.0));
    let grid = Grid::new([[-1.0; 3], [1.0; 3]], 96).unwrap();
    let opts = AnalyzeOptions {
        connectivity: false,
        thickness: false,
        ..AnalyzeOptions::default()
    };
    let r = analyze(&shape, None, grid, &opts, &|_, _, _| {}).unwrap();
    let (a, b) = (&r.attributes[0], &r.attributes[1]);
    let want = 4.0 * std::f64::consts::PI / 15.0;
    assert!((a.integral - want).abs() / want < 0.005, "{a:?} vs {want}");
    assert!(a.error < 0.01 * want, "{a:?}");
    assert!((a.mean - 0.2).abs() < 0.002, "{a:?}");
    assert!(
        a.min >= 0.0 && a.min < 1e-3 && a.max > 0.97 && a.max <= 1.0,
        "{a:?}"
    );
    let vol = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(
        (b.integral - 2.0 * vol).abs() / (2.0 * vol) < 0.005,
        "{b:?}"
    );
    assert_eq!((b.min, b.max, b.mean), (2.0, 2.0, 2.0));
    let j = microfrep_analysis::summary::to_json(&r, "ball", None);
    assert_eq!(j["attributes"][0]["index"], 1);
    assert!(j["attributes"][1]["integral"]["value"].as_f64().unwrap() > 8.0);
}
