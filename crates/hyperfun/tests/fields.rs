//! Data fields bound by name (`--field NAME=FILE`) are functions `NAME(x)`
//! of HyperFun models, composable like any other call.

use microfrep_core::{Field, GridField};
use microfrep_hyperfun::{load_with_options, LoadOptions};
use std::sync::Arc;

fn ramp() -> Arc<dyn Field> {
    Arc::new(
        GridField::sample("ramp", [5, 5, 5], [-1.0; 3], [1.0; 3], |p| {
            p[0] + 2.0 * p[1] - p[2]
        })
        .unwrap(),
    )
}

#[test]
fn bound_fields_are_callable_with_mapped_points() {
    let src = "my_model(x[3], a[1]) {
        array q[3];
        q[1] = x[1] * 0.5; q[2] = x[2]; q[3] = x[3];
        my_model = (Part(q) - a[1]) & (1 - x[1]*x[1]);
    }";
    let opts = LoadOptions {
        params: vec![(1, 0.25)],
        fields: vec![("part".into(), ramp())],
        ..Default::default()
    };
    let m = load_with_options(src, "t.hf", &opts).unwrap();
    for p in [[0.2, 0.1, -0.3], [-0.6, 0.4, 0.5], [0.9, -0.9, 0.0]] {
        let f: f64 = 0.5 * p[0] + 2.0 * p[1] - p[2] - 0.25;
        let g = 1.0 - p[0] * p[0];
        let want = f + g - (f * f + g * g).sqrt();
        let got = m.eval_points(&[p])[0].clone().unwrap();
        assert!((got - want).abs() < 1e-12, "{p:?}: {got} vs {want}");
    }
}

#[test]
fn wrong_uses_of_a_bound_field_are_load_errors() {
    let opts = LoadOptions {
        fields: vec![("part".into(), ramp())],
        ..Default::default()
    };
    let e = load_with_options(
        "my_model(x[3], a[1]) { array q[2]; q[1] = 0; q[2] = 0; my_model = part(q); }",
        "t.hf",
        &opts,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("3 elements"), "{e}");
    // Without the binding the name is unknown.
    let e = load_with_options(
        "my_model(x[3], a[1]) { my_model = part(x); }",
        "t.hf",
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("part"), "{e}");
}
