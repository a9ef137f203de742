//! `load::check_source`, the editor's view of a HyperFun text (the
//! studio's): every object checked as `microfrep check` does, the
//! evaluated one lowered even when another has errors.

use microfrep::hyperfun::{LoadOptions, Severity};
use microfrep::load::check_source;

const TWO: &str = "broken(x[3], a[1]) {\n  broken = x[1] + a[7];\n}\n\
my_model(x[3], a[1]) {\n  my_model = a[1] - sqrt(x[1]*x[1] + x[2]*x[2] + x[3]*x[3]) + 0*sign(x[1]);\n}\n";

#[test]
fn errors_elsewhere_leave_the_evaluated_object_and_are_all_reported() {
    let opts = LoadOptions {
        params: vec![(1, 0.5)],
        ..Default::default()
    };
    let c = check_source(TWO, "two.hf", &opts);
    let m = c.model.expect("my_model lowers");
    assert_eq!(m.object, "my_model");
    // The ball of radius a[1] = 0.5, through the facade's mf library.
    let mut ev = microfrep::core::PointEval::new(m.shape().tape());
    assert!((ev.eval([0.2, 0.0, 0.0]) - 0.3).abs() < 1e-12);
    let errors: Vec<_> = c.diagnostics.errors().collect();
    assert_eq!(errors.len(), 1, "{:?}", c.diagnostics.items);
    assert_eq!(errors[0].pos.line, 2);
    assert!(
        errors[0].message.contains("out of range"),
        "{}",
        errors[0].message
    );
    // `check`'s warnings too: sign() is 1 in the reference interpreter.
    assert!(c
        .diagnostics
        .items
        .iter()
        .any(|d| d.severity == Severity::Warning
            && d.message.contains("sign()")
            && d.pos.line == 5));
    assert!(c.rendered.contains("two.hf:2:21: error"), "{}", c.rendered);
    assert!(c.unlocated.is_empty());
}

#[test]
fn parse_errors_and_missing_objects_give_no_model() {
    let c = check_source(
        "my_model(x[3], a[1]) {\n  my_model = ;\n}\n",
        "bad.hf",
        &LoadOptions::default(),
    );
    assert!(c.model.is_none());
    assert!(
        c.diagnostics.has_errors() && c.rendered.contains("bad.hf:2:"),
        "{}",
        c.rendered
    );
    let opts = LoadOptions {
        object: Some("nothere".into()),
        ..Default::default()
    };
    let c = check_source(TWO, "two.hf", &opts);
    assert!(c.model.is_none());
    assert!(
        c.unlocated.iter().any(|m| m.contains("nothere")),
        "{:?}",
        c.unlocated
    );
    assert!(c.rendered.contains("two.hf: error:"), "{}", c.rendered);
}

#[test]
fn the_mf_library_is_there_without_an_install_call() {
    let src = "my_model(x[3], a[1]) {\n  my_model = mfLattice(x, 10, 0, 0.5, 0);\n}\n";
    let c = check_source(src, "lattice.hf", &LoadOptions::default());
    assert!(c.model.is_some(), "{}", c.rendered);
}
