//! The attribute array `s[1..n]` of the evaluated object as channels of the
//! model (`Model::attributes`, the Shape's channels `s1..sn`): values
//! against their formulas in the point and batch evaluators, through
//! branches, object calls, run-time errors and the per-point fallback.

use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::{BatchEval, Expr, Field, Interval, IntervalEval, PointEval};
use microfrep_hyperfun::{load, load_with_params, Model};

fn model(src: &str) -> Model {
    load(src, "attrs.hf", None).unwrap_or_else(|e| panic!("{e}"))
}

/// Deterministic points in `[lo, hi]^3` (xorshift).
fn points(n: usize, lo: f64, hi: f64, seed: u64) -> Vec<[f64; 3]> {
    let mut s = seed | 1;
    let mut unit = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| std::array::from_fn(|_| lo + (hi - lo) * unit()))
        .collect()
}

/// A unit cube graded along x (s[1]) and in y, z (s[2]), and a[1] in s[3].
const GRADED_CUBE: &str = "my_model(x[3], a[1], s[3]) {
  s[1] = x[1];
  s[2] = 0.5 + 0.25*x[2]*x[3];
  s[3] = a[1];
  my_model = (1 - x[1]^2) & (1 - x[2]^2) & (1 - x[3]^2);
}";

fn graded_formulas(p: [f64; 3], a1: f64) -> [f64; 3] {
    [p[0], 0.5 + 0.25 * p[1] * p[2], a1]
}

#[test]
fn graded_cube_channels_equal_their_formulas_in_point_and_batch() {
    let m = load_with_params(GRADED_CUBE, "c.hf", None, &[(1, 0.75)]).unwrap();
    assert!(m.lowered);
    assert_eq!(m.attributes.len(), 3);
    assert_eq!(m.attribute_names(), ["s1", "s2", "s3"]);
    let shape = m.shape();
    let names: Vec<&str> = shape.attributes().iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["s1", "s2", "s3"]);
    let tape = shape.outputs();
    let pts = points(500, -1.5, 1.5, 7);
    // Point evaluation (f64): exactly the formulas.
    let mut pe = PointEval::new(tape);
    pe.set_param(tape.param_index("a1").unwrap(), 0.75);
    for &p in &pts {
        let out = pe.eval_all(p);
        let want = graded_formulas(p, 0.75);
        for k in 0..3 {
            assert_eq!(
                out[shape.attribute_output(k)],
                want[k],
                "s{} at {p:?}",
                k + 1
            );
        }
    }
    // The same through the model's own helper.
    for (p, r) in pts.iter().zip(m.eval_points_with_attributes(&pts)) {
        let (v, s) = r.unwrap();
        assert_eq!(s, graded_formulas(*p, 0.75));
        assert_eq!(v >= 0.0, p.iter().all(|c| c.abs() <= 1.0), "{p:?}");
    }
    // Batch evaluation (f32): the formulas to f32 rounding.
    let xs: Vec<f32> = pts.iter().map(|p| p[0] as f32).collect();
    let ys: Vec<f32> = pts.iter().map(|p| p[1] as f32).collect();
    let zs: Vec<f32> = pts.iter().map(|p| p[2] as f32).collect();
    let mut be = BatchEval::new(tape);
    be.set_param(tape.param_index("a1").unwrap(), 0.75);
    for k in 0..3 {
        let mut out = vec![0.0f32; pts.len()];
        be.eval_output(shape.attribute_output(k), &xs, &ys, &zs, &mut out);
        for (i, &p) in pts.iter().enumerate() {
            let q = [xs[i] as f64, ys[i] as f64, zs[i] as f64];
            let want = graded_formulas(q, 0.75)[k];
            assert!(
                (out[i] as f64 - want).abs() <= 1e-6 * (1.0 + want.abs()),
                "s{} at {p:?}: {} vs {want}",
                k + 1,
                out[i]
            );
        }
    }
    // Interval bounds of a channel hold its values.
    let mut ie = IntervalEval::new(tape);
    ie.set_param(tape.param_index("a1").unwrap(), 0.75);
    let b = [
        Interval::new(-0.5, 1.0),
        Interval::new(0.25, 1.25),
        Interval::new(-1.0, 0.0),
    ];
    let iv = ie.eval_output(shape.attribute_output(1), b[0], b[1], b[2]);
    for p in points(200, 0.0, 1.0, 3) {
        let q = [-0.5 + 1.5 * p[0], 0.25 + p[1], -p[2]];
        let v = graded_formulas(q, 0.75)[1];
        assert!(iv.lo <= v && v <= iv.hi, "{v} not in {iv:?}");
    }
}

#[test]
fn unassigned_entries_are_zero_and_no_header_means_no_channels() {
    let m = model("my_model(x[3], a[1], s[4]) { s[2] = 7; s[4] = x[3]; my_model = x[1]; }");
    let r = m.eval_points_with_attributes(&[[1.0, 2.0, 3.0]]);
    assert_eq!(r[0].clone().unwrap(), (1.0, vec![0.0, 7.0, 0.0, 3.0]));
    // A whole-array assignment, then one element over it.
    let m = model("my_model(x[3], a[1], s[3]) { s = [1, -2, 3.5]; s[3] = x[2]; my_model = 0; }");
    let r = m.eval_points_with_attributes(&[[0.0, 9.0, 0.0]]);
    assert_eq!(r[0].clone().unwrap().1, [1.0, -2.0, 9.0]);
    // Without `s` in the header the object has no attributes.
    let m = model("my_model(x[3], a[1]) { s[1] = 5; my_model = x[1]; }");
    assert!(m.attributes.is_empty() && m.shape().attributes().is_empty());
}

#[test]
fn attributes_assigned_in_both_branches_of_an_if_are_selected() {
    let src = "my_model(x[3], a[1], s[2]) {
      if x[1] > 0 then s[1] = 1; s[2] = x[2]; else s[1] = 2; endif;
      my_model = 1 - x[1]*x[1];
    }";
    let m = model(src);
    assert!(m.lowered, "{:?}", m.per_point);
    let pts = [[0.5, 3.0, 0.0], [-0.5, 3.0, 0.0], [0.0, 3.0, 0.0]];
    let r: Vec<Vec<f64>> = m
        .eval_points_with_attributes(&pts)
        .into_iter()
        .map(|r| r.unwrap().1)
        .collect();
    assert_eq!(r, [vec![1.0, 3.0], vec![2.0, 0.0], vec![2.0, 0.0]]);
    // Batch mode picks the same branches.
    let shape = m.shape();
    let mut out = [0.0f32; 2];
    BatchEval::new(shape.outputs()).eval_output(
        shape.attribute_output(1),
        &[0.5, -0.5],
        &[3.0, 3.0],
        &[0.0, 0.0],
        &mut out,
    );
    assert_eq!(out, [3.0, 0.0]);
}

#[test]
fn callee_attribute_writes_come_back_as_in_the_reference() {
    // The callee gets a copy of the caller's third argument and its final
    // `s` is copied back into it.
    let src = "mat(x[3], a[1], s[2]) { s[2] = x[1] + s[1]; mat = 1 - x[2]*x[2]; }
    my_model(x[3], a[1], s[2]) {
      array t[2];
      t = [10, 20];
      s[1] = 5;
      u = mat(x, a, s);
      v = mat(x, a, t);
      s[1] = s[1] + t[2];
      my_model = u & v;
    }";
    let m = model(src);
    let p = [0.25, 0.5, 0.0];
    let (_, s) = m.eval_points_with_attributes(&[p])[0].clone().unwrap();
    // s after the first call: [5, 0.25 + 5]; t after the second: [10, 10.25].
    assert_eq!(s, [5.0 + 10.25, 5.25]);
    // A two-argument call runs the callee with its own s[1]: nothing comes back.
    let src = "o(x[3], a[1]) { s[1] = 99; o = x[1]; }
    my_model(x[3], a[1], s[1]) { s[1] = 4; v = o(x, a); my_model = v; }";
    let (_, s) = model(src).eval_points_with_attributes(&[p])[0]
        .clone()
        .unwrap();
    assert_eq!(s, [4.0]);
    // A callee whose writes depend on the point, called in a branch.
    let src = "mat(x[3], a[1], s[2]) {
      if x[1] > 0 then s[1] = x[1]; else s[2] = -x[1]; endif;
      mat = x[3];
    }
    my_model(x[3], a[1], s[2]) {
      s = [7, 8];
      if x[2] > 0 then v = mat(x, a, s); else v = 0; endif;
      my_model = v;
    }";
    let m = model(src);
    assert!(m.lowered);
    let pts = [
        [0.5, 1.0, 0.0],
        [-0.5, 1.0, 0.0],
        [0.5, -1.0, 0.0],
        [-0.5, -1.0, 0.0],
    ];
    let got: Vec<Vec<f64>> = m
        .eval_points_with_attributes(&pts)
        .into_iter()
        .map(|r| r.unwrap().1)
        .collect();
    assert_eq!(
        got,
        [
            vec![0.5, 8.0],
            vec![7.0, 0.5],
            vec![7.0, 8.0],
            vec![7.0, 8.0]
        ]
    );
}

#[test]
fn attributes_are_nan_where_an_error_is_raised() {
    // The error site comes after the attributes are set: still no
    // attributes there, like no value.
    let src =
        "my_model(x[3], a[1], s[2]) {\n  s[1] = x[1];\n  s[2] = 2;\n  my_model = 1 / x[2];\n}";
    let m = model(src);
    let shape = m.shape();
    let mut pe = PointEval::new(shape.outputs());
    let bad = pe.eval_all([3.0, 0.0, 0.0]);
    assert!(bad[0].is_nan() && bad[shape.error_output().unwrap()] != 0.0);
    assert!(bad[shape.attribute_output(0)].is_nan() && bad[shape.attribute_output(1)].is_nan());
    let good = pe.eval_all([3.0, 0.5, 0.0]);
    assert_eq!(
        [
            good[shape.attribute_output(0)],
            good[shape.attribute_output(1)]
        ],
        [3.0, 2.0]
    );
    let e = m.eval_points_with_attributes(&[[3.0, 0.0, 0.0]])[0]
        .clone()
        .unwrap_err();
    assert_eq!((e.message.as_str(), e.line), ("Division by zero", 4));
}

/// Escape-time count in a point-dependent loop (so the model runs per
/// point), with attributes set after it.
const PER_POINT: &str = "my_model(x[3], a[1], s[2]) {
  v = abs(x[1]) + 1; n = 0;
  while v > 1.5 loop v = v / 2; n = n + 1; endloop;
  s[1] = n;
  s[2] = x[2] * x[3];
  my_model = 2 - abs(x[1]) - abs(x[2]);
}";

fn halvings(x: f64) -> f64 {
    let (mut v, mut n) = (x.abs() + 1.0, 0.0);
    while v > 1.5 {
        v /= 2.0;
        n += 1.0;
    }
    n
}

#[test]
fn per_point_models_have_attribute_channels_too() {
    let m = model(PER_POINT);
    assert!(!m.lowered);
    let why = m.per_point.clone().unwrap();
    assert!(why.message.contains("loop"), "{why:?}");
    assert_eq!(why.pos.line, 3);
    let shape = m.shape();
    assert_eq!(shape.attributes().len(), 2);
    let pts = points(300, -4.0, 4.0, 11);
    let mut pe = PointEval::new(shape.outputs());
    for &p in &pts {
        let out = pe.eval_all(p);
        assert_eq!(out[shape.attribute_output(0)], halvings(p[0]), "{p:?}");
        assert_eq!(out[shape.attribute_output(1)], p[1] * p[2], "{p:?}");
    }
    let xs: Vec<f32> = pts.iter().map(|p| p[0] as f32).collect();
    let ys: Vec<f32> = pts.iter().map(|p| p[1] as f32).collect();
    let zs: Vec<f32> = pts.iter().map(|p| p[2] as f32).collect();
    let mut out = vec![0.0f32; pts.len()];
    BatchEval::new(shape.outputs()).eval_output(shape.attribute_output(0), &xs, &ys, &zs, &mut out);
    for i in 0..pts.len() {
        assert_eq!(out[i] as f64, halvings(xs[i] as f64));
    }
}

/// Every output of the per-point fallback is a Field that passes the
/// core's four-mode check (its intervals are unbounded, which is sound).
#[test]
fn per_point_outputs_pass_the_field_check() {
    let m = model(PER_POINT);
    let src = "my_model(x[3], a[1], s[1]) {
      i = 0; while i < x[1] loop i = i + 1; endloop;
      s[1] = sin(x[2]) * x[3];
      my_model = 1 / x[1];
    }";
    let e = model(src);
    assert!(!e.lowered);
    let mut fields: Vec<Expr> = vec![m.value.clone(), m.error.clone()];
    fields.extend(m.attributes.iter().cloned());
    fields.push(e.error.clone());
    fields.extend(e.attributes.iter().cloned());
    for f in fields {
        let microfrep_core::ExprNode::Field { field, .. } = f.node() else {
            panic!("not a field: {f:?}");
        };
        let field: std::sync::Arc<dyn Field> = field.clone();
        // Away from the loop's and the halving's jumps: x[1] in (-1.4, -0.6).
        let mut cfg = FieldCheck::new([[-1.4, -2.0, -2.0], [-0.6, 2.0, 2.0]]);
        cfg.points = 300;
        cfg.boxes = 60;
        let r = check_field(&field, &cfg).unwrap_or_else(|e| panic!("{}: {e}", field.name()));
        assert_eq!(r.points, 300);
    }
}
