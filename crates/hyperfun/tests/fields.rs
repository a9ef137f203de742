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

/// `check` takes what a load takes: bound fields are known functions and
/// parameters are checked against the object.
#[test]
fn check_knows_bound_fields_and_checks_parameters() {
    use microfrep_hyperfun::check::{check, check_with};
    let src = "my_model(x[3], a[1]) { my_model = part(x) - a[1]; }";
    // Without the field the name is unknown, as before.
    let unbound = check(src, "t.hf", None);
    let unknown = match unbound {
        Err(d) => d.items.iter().any(|i| i.message.contains("part")),
        Ok(r) => r.errors() > 0,
    };
    assert!(unknown);
    let opts = LoadOptions {
        params: vec![(1, 0.5)],
        fields: vec![("part".into(), ramp())],
        ..Default::default()
    };
    let r = check_with(src, "t.hf", &opts).unwrap();
    assert_eq!(r.errors(), 0, "{:?} {:?}", r.diagnostics.items, r.unlocated);
    // a[2] does not exist.
    let opts = LoadOptions {
        params: vec![(2, 0.5)],
        ..opts
    };
    let r = check_with(src, "t.hf", &opts).unwrap();
    assert_eq!(r.errors(), 1);
    assert!(
        r.unlocated[0].contains("a[2] out of range"),
        "{:?}",
        r.unlocated
    );
}

/// A constant index outside its array is an error of `check`, with the
/// index's position, wherever it is (even in a branch that depends on the
/// point); a computed index stays a run-time check.
#[test]
fn check_finds_constant_indices_out_of_range() {
    use microfrep_hyperfun::check::check;
    let cases = [
        ("my_model(x[3], a[1]) { my_model = x[4]; }", Some((1, 37))),
        (
            "my_model(x[3], a[1]) {\n array q[2];\n q[1] = 1; q[2] = 2;\n if x[1] > 0 then\n  r = q[3];\n else\n  r = 1;\n endif;\n my_model = r;\n}",
            Some((5, 9)),
        ),
        ("my_model(x[3], a[1]) { array q[2]; q[0] = 1; my_model = x[1]; }", Some((1, 38))),
        ("my_model(x[3], a[1]) { my_model = x[1 + 2]; }", None),
        ("my_model(x[3], a[1]) { my_model = x[a[1] + 5]; }", None),
    ];
    for (src, want) in cases {
        let r = check(src, "t.hf", None).unwrap();
        let found: Vec<_> = r
            .diagnostics
            .items
            .iter()
            .filter(|d| d.message.contains("Array index out of range"))
            .map(|d| (d.pos.line, d.pos.col))
            .collect();
        match want {
            Some(pos) => assert_eq!(found, vec![pos], "{src}: {:?}", r.diagnostics.items),
            None => assert!(found.is_empty(), "{src}: {:?}", r.diagnostics.items),
        }
    }
}
