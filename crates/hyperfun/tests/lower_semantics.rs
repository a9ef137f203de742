//! Lowering: the four evaluation modes, the error output, parameters, the
//! per-point fallback, and robustness against mutated input.

use microfrep_core::{BatchEval, GradEval, Interval, IntervalEval, PointEval};
use microfrep_hyperfun::load;

fn model(src: &str) -> microfrep_hyperfun::Model {
    load(src, "test.hf", None).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn sphere_lowers_to_a_graph_usable_in_all_modes() {
    let m =
        model("my_model(x[3], a[1]) { array c[3]; c = [0, 0, 0]; my_model = hfSphere(x, c, 2); }");
    assert!(m.lowered);
    let tape = m.tape();
    assert_eq!(PointEval::new(&tape).eval([1.0, 1.0, 1.0]), 1.0);
    let (v, g) = GradEval::new(&tape).eval([1.0, 2.0, 0.5]);
    assert_eq!((v, g), (4.0 - 5.25, [-2.0, -4.0, -1.0]));
    let i = IntervalEval::new(&tape).eval(
        Interval::new(0.0, 1.0),
        Interval::new(0.0, 1.0),
        Interval::new(0.0, 1.0),
    );
    assert!(i.lo <= 1.0 && i.hi >= 4.0, "{i:?}");
    let mut out = [0.0f32; 2];
    BatchEval::new(&tape).eval(&[0.0, 2.0], &[0.0, 0.0], &[0.0, 0.0], &mut out);
    assert_eq!(out, [4.0, 0.0]);
}

#[test]
fn run_time_errors_carry_their_position_in_every_point() {
    let m = model("my_model(x[3], a[1]) {\n  y = 1 / x[1];\n  my_model = y;\n}\n");
    let r = m.eval_points(&[[2.0, 0.0, 0.0], [0.0000001, 0.0, 0.0]]);
    assert_eq!(r[0], Ok(0.5));
    let e = r[1].clone().unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("Division by zero", 2, 9)
    );
    // The batch evaluator sees the same error code.
    let tape = m.tape();
    let mut codes = [0.0f32; 2];
    BatchEval::new(&tape).eval_output(1, &[2.0, 0.0], &[0.0; 2], &[0.0; 2], &mut codes);
    assert_eq!(codes[0], 0.0);
    assert_eq!(m.errors.get(codes[1] as f64).unwrap(), e);
}

#[test]
fn if_with_both_branches_defined_becomes_a_select() {
    let src = "my_model(x[3], a[1]) { if x[1] > 0 then y = x[1]; else y = -2*x[1]; endif; my_model = y; }";
    let m = model(src);
    assert!(m.lowered);
    let r = m.eval_points(&[[3.0, 0.0, 0.0], [-3.0, 0.0, 0.0]]);
    assert_eq!(r, vec![Ok(3.0), Ok(6.0)]);
}

#[test]
fn variable_set_in_one_branch_is_an_error_only_where_unset() {
    let src = "my_model(x[3], a[1]) { if x[1] > 0 then y = 1; endif; my_model = y; }";
    let m = model(src);
    assert!(m.lowered);
    let r = m.eval_points(&[[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]);
    assert_eq!(r[0], Ok(1.0));
    assert_eq!(
        r[1].clone().unwrap_err().message,
        "Not initialized variable"
    );
}

#[test]
fn constant_trip_count_loops_unroll() {
    let src = "my_model(x[3], a[1]) { i = 0; s1 = 0; while i < 10 loop i = i + 1; s1 = s1 + x[1]; endloop; my_model = s1; }";
    let m = model(src);
    assert!(m.lowered);
    assert_eq!(m.eval_points(&[[0.5, 0.0, 0.0]]), vec![Ok(5.0)]);
}

#[test]
fn point_dependent_loops_use_the_fallback_with_the_same_semantics() {
    // Counts how many halvings bring |x| below 1: floor(log2|x|) + 1 for |x| >= 1.
    let src = "my_model(x[3], a[1]) { v = abs(x[1]); n = 0; while v >= 1 loop v = v / 2; n = n + 1; endloop; my_model = n - 1/x[2]; }";
    let m = model(src);
    assert!(!m.lowered);
    let r = m.eval_points(&[[5.0, 1.0, 0.0], [0.5, 0.5, 0.0], [1000.0, 0.0, 0.0]]);
    assert_eq!(r[0], Ok(3.0 - 1.0));
    assert_eq!(r[1], Ok(-2.0));
    let e = r[2].clone().unwrap_err();
    let slash = src.find("/x[2]").unwrap() as u32 + 1;
    assert_eq!((e.message.as_str(), e.col), ("Division by zero", slash));
    let tape = m.tape();
    let i = IntervalEval::new(&tape).eval(
        Interval::new(0.0, 1.0),
        Interval::new(1.0, 2.0),
        Interval::new(0.0, 0.0),
    );
    assert!(
        i.lo == f64::NEG_INFINITY && i.hi == f64::INFINITY,
        "fallback bounds are conservative: {i:?}"
    );
}

#[test]
fn parameters_are_graph_parameters() {
    let m = model("my_model(x[3], a[2]) { my_model = a[1] * x[1] + a[2]; }");
    assert_eq!(
        m.params.iter().map(|p| p.0.as_str()).collect::<Vec<_>>(),
        ["a1", "a2"]
    );
    let tape = m.tape();
    let mut pe = PointEval::new(&tape);
    pe.set_param(tape.param_index("a1").unwrap(), 3.0);
    pe.set_param(tape.param_index("a2").unwrap(), 0.5);
    assert_eq!(pe.eval([2.0, 0.0, 0.0]), 6.5);
}

#[test]
fn runaway_loops_stop_with_an_error_instead_of_hanging() {
    let m =
        model("my_model(x[3], a[1]) { i = 0; while i < 1 loop i = i * 1; endloop; my_model = i; }");
    let r = m.eval_points(&[[0.0; 3]]);
    assert!(r[0]
        .clone()
        .unwrap_err()
        .message
        .contains("iteration limit"));
}

/// Deterministic mutations (delete, duplicate, replace a byte) of the corpus:
/// loading and evaluating must never panic.
#[test]
fn mutated_corpus_files_never_panic() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/corpus");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| Some(e.ok()?.path()))
        .collect();
    files.retain(|p| p.extension().is_some_and(|e| e == "hf"));
    files.sort();
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let alphabet = b"()[]{},;+-*/^|&\\@~=<>.0123456789exasif \n";
    let mut loaded = 0;
    for f in &files {
        let src = std::fs::read(f).unwrap();
        for _ in 0..12 {
            let mut s = src.clone();
            for _ in 0..1 + next() % 3 {
                let i = (next() as usize) % s.len().max(1);
                match next() % 3 {
                    0 if !s.is_empty() => {
                        s.remove(i);
                    }
                    1 => s.insert(i, alphabet[next() as usize % alphabet.len()]),
                    _ if !s.is_empty() => s[i] = alphabet[next() as usize % alphabet.len()],
                    _ => {}
                }
            }
            let text = String::from_utf8_lossy(&s);
            if let Ok(m) = load(&text, "mutant.hf", None) {
                loaded += 1;
                let _ = m.eval_points(&[[0.1, -0.2, 0.3], [1.0, 1.0, 1.0]]);
            }
        }
    }
    assert!(loaded > 0, "some mutants should still load");
}

#[test]
fn unreachable_error_sites_are_pruned_and_reachable_ones_kept() {
    // sqrt of a sum of squares (written with `*`) can never fail.
    let m = model(
        "my_model(x[3], a[1]) { r = sqrt(x[1]*x[1] + x[2]*x[2] + x[3]*x[3]); my_model = 1 - r; }",
    );
    assert_eq!(m.error.as_const(), Some(0.0));
    // sqrt(x[1]) can; a parameter counts as unbounded.
    let m = model("my_model(x[3], a[1]) { my_model = sqrt(a[1]*a[1]) + 1/a[1] + sqrt(x[1]); }");
    assert_eq!(m.error.as_const(), None);
    let r = m.eval_points(&[[-1.0, 0.0, 0.0], [4.0, 0.0, 0.0]]);
    assert_eq!(
        r[0].clone().unwrap_err().message,
        "Negative value for square root"
    );
    assert_eq!(r[1].clone().unwrap_err().message, "Division by zero");
}

#[test]
fn value_is_nan_where_an_error_is_raised() {
    let m = model("my_model(x[3], a[1]) {\n  my_model = 1 / x[1] - 2;\n}\n");
    let tape = m.tape();
    let mut pe = PointEval::new(&tape);
    assert!(pe.eval([0.0, 0.0, 0.0]).is_nan());
    assert_eq!(pe.eval([0.25, 0.0, 0.0]), 2.0);
    let mut out = [0.0f32; 2];
    BatchEval::new(&tape).eval(&[0.0, 0.25], &[0.0; 2], &[0.0; 2], &mut out);
    assert!(out[0].is_nan() && out[1] == 2.0);
}

#[test]
fn error_census_counts_grid_points_per_site() {
    let m = model("my_model(x[3], a[1]) {\n  my_model = sqrt(x[1]) + 1 / x[2];\n}\n");
    let xs: Vec<f64> = (0..10).map(|i| i as f64 - 4.5).collect(); // 5 negative
    let ys: Vec<f64> = (0..4).map(|j| j as f64 - 1.0).collect(); // one 0
    let zs = [0.0, 1.0, 2.0];
    let c = m.error_census(&xs, &ys, &zs);
    assert_eq!(c.samples, 120);
    // The right operand runs first: y = 0 fails at "/" wherever it is 0;
    // elsewhere x < 0 fails at sqrt.
    let div = 10 * 3;
    let sqrt = 5 * 3 * 3;
    assert_eq!(c.errors, div + sqrt);
    let by: Vec<(&str, u64)> = c
        .sites
        .iter()
        .map(|(e, n)| (e.message.as_str(), *n))
        .collect();
    assert!(by.contains(&("Division by zero", div)), "{by:?}");
    assert!(
        by.contains(&("Negative value for square root", sqrt)),
        "{by:?}"
    );
    // No reachable site: nothing evaluated, nothing counted.
    let ok = model("my_model(x[3], a[1]) { my_model = x[1]*x[1] - 1; }");
    let c = ok.error_census(&xs, &ys, &zs);
    assert_eq!((c.samples, c.errors), (120, 0));
    // A big grid where errors sit in one corner: intervals skip the rest.
    let big: Vec<f64> = (0..200).map(|i| i as f64 * 0.01 - 0.005).collect();
    let m = model("my_model(x[3], a[1]) { my_model = sqrt(x[1]) + 1; }");
    let c = m.error_census(&big, &big, &big);
    assert_eq!(c.errors, 200 * 200);
}

#[test]
fn distance_ellipsoid_with_constant_axes_stays_lowered() {
    let src = "my_model(x[3], a[1]) { array c[3]; c = [0.5, 0, -0.25]; \
               t = hfShift3D(x, 0.1, 0, 0); my_model = hfDEllipsoid(x, c, 1, 2, 0.5); }";
    let m = model(src);
    assert!(m.lowered);
    // Same values as the per-point evaluation with constant coordinates
    // (the coordinates folded into the program).
    for p in [
        [0.3, 0.4, 0.5],
        [1.5, -0.7, 2.2],
        [0.6, 0.0, -0.25],
        [-2.0, 1.0, 0.1],
    ] {
        let fixed = src.replace("array c[3];", "array c[3], q[3];").replace(
            "t = hfShift3D(x, 0.1, 0, 0);",
            &format!(
                "q = [{}, {}, {}]; t = hfShift3D(q, 0.1, 0, 0);",
                p[0], p[1], p[2]
            ),
        );
        let fixed = fixed.replace("hfDEllipsoid(x,", "hfDEllipsoid(q,");
        let want = model(&fixed).eval_points(&[[0.0; 3]])[0].clone().unwrap();
        let got = m.eval_points(&[p])[0].clone().unwrap();
        assert_eq!(got, want, "{p:?}");
    }
    // Its interval bounds the values in a box, and its gradient is a unit
    // vector away from the centre.
    let tape = m.tape();
    let b = IntervalEval::new(&tape).eval(
        Interval::new(0.0, 0.5),
        Interval::new(0.5, 1.0),
        Interval::new(-0.5, 0.0),
    );
    for i in 0..=4 {
        let p = [0.125 * i as f64, 0.5 + 0.125 * i as f64, -0.125 * i as f64];
        let v = m.eval_points(&[p])[0].clone().unwrap();
        assert!(b.lo <= v && v <= b.hi, "{v} not in {b:?}");
        let (_, g) = GradEval::new(&tape).eval(p);
        let n = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        assert!((n - 1.0).abs() < 1e-9, "{g:?}");
    }
}
