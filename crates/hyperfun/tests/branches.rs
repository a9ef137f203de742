//! Point-dependent `if`s lowered with `select`, checked against the
//! per-point interpreter (`Model::interpreted`) on random points: values,
//! attributes and run-time errors (message and position) must agree
//! exactly, including errors raised in one branch only. Also: such models
//! get interval bounds, and branch merging stays linear in what the
//! branches write.

use microfrep_core::{Interval, IntervalEval};
use microfrep_hyperfun::{load, load_with_params, Model};

fn model(src: &str) -> Model {
    load(src, "if.hf", None).unwrap_or_else(|e| panic!("{e}"))
}

/// Deterministic points in `[-2, 2]^3`; every other one on the quarter
/// grid, so equalities and branch boundaries (`x[1] = 0`) are hit.
fn points(n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut s = seed | 1;
    let mut unit = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|i| {
            std::array::from_fn(|_| {
                let v = -2.0 + 4.0 * unit();
                if i % 2 == 0 {
                    (v * 4.0).round() / 4.0
                } else {
                    v
                }
            })
        })
        .collect()
}

/// Points where lowering and the interpreter gave values, and errors.
#[derive(Debug, Default)]
struct Agreement {
    ok: usize,
    errors: usize,
}

/// Lowered (must be) against interpreted at 2000 points: the same bits.
fn agree(m: &Model) -> Agreement {
    assert!(m.lowered, "{:?}", m.per_point);
    let per_point = m.interpreted();
    assert!(!per_point.lowered);
    let pts = points(2000, 0x1234_5678);
    let lowered = m.eval_points_with_attributes(&pts);
    let interp = per_point.eval_points_with_attributes(&pts);
    let mut a = Agreement::default();
    let same = |x: f64, y: f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
    for ((p, l), i) in pts.iter().zip(lowered).zip(interp) {
        match (l, i) {
            (Ok((v, s)), Ok((w, t))) => {
                assert!(same(v, w), "value at {p:?}: lowered {v}, interpreted {w}");
                assert_eq!(s.len(), t.len());
                for k in 0..s.len() {
                    assert!(
                        same(s[k], t[k]),
                        "s[{}] at {p:?}: {} vs {}",
                        k + 1,
                        s[k],
                        t[k]
                    );
                }
                a.ok += 1;
            }
            (Err(e), Err(f)) => {
                assert_eq!(e, f, "at {p:?}");
                a.errors += 1;
            }
            (l, i) => panic!("at {p:?}: lowered {l:?}, interpreted {i:?}"),
        }
    }
    a
}

#[test]
fn an_error_in_the_branch_not_taken_is_no_error() {
    // Each branch takes the square root of what is negative in the other.
    let m = model(
        "my_model(x[3], a[1]) {
          if x[1] > 0 then r = sqrt(x[1]); else r = 2*sqrt(-x[1]); endif;
          my_model = 1 - r; }",
    );
    let a = agree(&m);
    assert_eq!(a.errors, 0, "{a:?}");
    assert_eq!(m.eval_points(&[[-4.0, 0.0, 0.0]])[0], Ok(-3.0));
    // An error in the branch taken is one, at its own position.
    let m = model(
        "my_model(x[3], a[1]) {\n  if x[2] > 0 then r = log(x[1]); else r = 1; endif;\n  my_model = r; }",
    );
    let a = agree(&m);
    assert!(a.errors > 200 && a.ok > 200, "{a:?}");
    let e = m.eval_points(&[[-1.0, 1.0, 0.0]])[0].clone().unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("Negative for log function", 2, 24)
    );
    assert_eq!(m.eval_points(&[[-1.0, -1.0, 0.0]])[0], Ok(1.0));
}

#[test]
fn nested_ifs_with_arrays_and_attributes_agree_with_the_interpreter() {
    let m = model(
        "my_model(x[3], a[1], s[3]) {
          array p[3];
          p = [0, 0, 0];
          if x[1] > 0 then
            p[1] = x[1];
            if x[2] > x[1] then p[2] = sqrt(x[3]); s[1] = 1; else p[3] = x[2]; s[2] = x[1]*x[2]; endif;
          else
            if x[3] < -0.5 or x[2] = 0 then s[3] = 2; p[1] = -x[1]; endif;
          endif;
          my_model = p[1] + p[2] - p[3];
        }",
    );
    let a = agree(&m);
    // sqrt(x[3]) fails for x[3] < 0 where that branch runs.
    assert!(a.errors > 10 && a.ok > 1000, "{a:?}");
}

#[test]
fn variables_set_in_one_branch_fail_only_where_read_unset() {
    let m = model(
        "my_model(x[3], a[1]) {
          if x[1] > 0 then y = 1; endif;
          if x[2] > 0 then z = y; else z = 0; endif;
          my_model = z; }",
    );
    let a = agree(&m);
    assert!(a.errors > 300 && a.ok > 1000, "{a:?}");
    let e = m.eval_points(&[[-1.0, 1.0, 0.0]])[0].clone().unwrap_err();
    assert_eq!(e.message, "Not initialized variable");
}

#[test]
fn point_dependent_index_writes_in_a_branch() {
    let m = model(
        "my_model(x[3], a[1]) {
          array v[3];
          v = [1, 2, 3];
          if x[1] > 0 then v[x[2]*2 + 2] = 10*x[3]; endif;
          my_model = v[1] + 10*v[2] + 100*v[3]; }",
    );
    let a = agree(&m);
    // The index leaves 1..3 for part of the points, only where x[1] > 0.
    assert!(a.errors > 100 && a.ok > 1000, "{a:?}");
}

#[test]
fn objects_with_ifs_called_in_branches() {
    let m = model(
        "mat(x[3], a[1], s[2]) {
          if x[1] > 0 then s[1] = x[1]; else s[2] = 1 / x[2]; endif;
          mat = x[3];
        }
        my_model(x[3], a[1], s[2]) {
          array t[2];
          t = [3, 4];
          if x[3] > 0 then v = mat(x, a, s); else v = mat(x, a, t); s[1] = t[1] + t[2]; endif;
          my_model = v;
        }",
    );
    let a = agree(&m);
    assert!(a.errors > 10 && a.ok > 1000, "{a:?}");
}

#[test]
fn truth_values_and_logic_follow_hyperfun() {
    // A bare value is true when |v| >= EPS; `and`, `or`, `not`, `=`, `/=`.
    let m = model(
        "my_model(x[3], a[1], s[1]) {
          t = 0;
          if x[1] and not (x[2] > 0.5) then t = 1; endif;
          if x[1] = x[2] or x[3] /= 0 then s[1] = t + 1; else s[1] = -1; endif;
          my_model = t; }",
    );
    agree(&m);
    let r = m.eval_points_with_attributes(&[[0.0, 0.0, 0.0], [1e-7, 0.0, 1.0], [1.0, 0.0, 0.0]]);
    assert_eq!(r[0].clone().unwrap(), (0.0, vec![1.0]));
    assert_eq!(r[1].clone().unwrap(), (0.0, vec![1.0]));
    assert_eq!(r[2].clone().unwrap(), (1.0, vec![-1.0]));
}

#[test]
fn constant_loops_and_library_writes_inside_branches() {
    let m = model(
        "my_model(x[3], a[1]) {
          array c[3];
          c = [0, 0, 0];
          if x[1] > 0 then
            i = 0; t = 0;
            while i < 5 loop t = t + x[2]; i = i + 1; endloop;
            u = hfShift3D(x, 0.5, 0, 0);
          else
            t = -1;
          endif;
          my_model = hfSphere(x, c, 1) + t; }",
    );
    let a = agree(&m);
    assert_eq!(a.errors, 0);
}

#[test]
fn parameters_in_conditions() {
    let src = "my_model(x[3], a[2]) {
      if a[1] > 0 then r = a[2]; else r = sqrt(x[1]); endif;
      my_model = r - x[2]; }";
    for (a1, errors) in [(1.0, false), (-1.0, true)] {
        let m = load_with_params(src, "p.hf", None, &[(1, a1), (2, 0.5)]).unwrap();
        let a = agree(&m);
        assert_eq!(a.errors > 0, errors, "{a1}: {a:?}");
    }
}

#[test]
fn models_with_point_dependent_ifs_get_interval_bounds() {
    // A ball of radius 1 above z = 0 and 0.5 below.
    let m = model(
        "my_model(x[3], a[1]) {
          if x[3] > 0 then r = 1; else r = 0.5; endif;
          my_model = r*r - (x[1]*x[1] + x[2]*x[2] + x[3]*x[3]); }",
    );
    assert!(m.lowered);
    let b = m.shape().bounds().unwrap();
    assert!(
        (b.max[2] - 1.0).abs() < 0.02 && (b.min[2] + 0.5).abs() < 0.02,
        "{b:?}"
    );
    assert!(
        (b.max[0] - 1.0).abs() < 0.02 && (b.min[1] + 1.0).abs() < 0.02,
        "{b:?}"
    );
    // Each branch bounds its half: far from the ball the interval is negative.
    let tape = m.tape();
    let i = IntervalEval::new(&tape).eval(
        Interval::new(0.6, 0.7),
        Interval::new(-0.1, 0.1),
        Interval::new(-0.4, -0.1),
    );
    assert!(i.hi < 0.0, "{i:?}");
    // The interpreter knows nothing.
    assert!(m.interpreted().shape().bounds().is_err());
}

/// An `if` in a loop next to a large array: merging costs what the branch
/// writes (one scalar), not the array, so the graph stays small.
#[test]
fn merging_costs_what_the_branches_write() {
    let src = "my_model(x[3], a[1]) {
      array big[20000];
      big[1] = 0;
      i = 0; t = 0;
      while i < 300 loop
        if x[1] > i / 300 then t = t + 1; endif;
        i = i + 1;
      endloop;
      my_model = t + big[1]; }";
    let m = model(src);
    assert!(m.lowered);
    let n = m.value.node_count();
    assert!(n < 5_000, "{n} nodes");
    assert_eq!(m.eval_points(&[[0.5, 0.0, 0.0]])[0], Ok(150.0));
}

/// Deeply nested `if`s around many assignments would merge each one at
/// every level: past the budget the model takes the per-point
/// interpreter (with the reason), and still evaluates right.
#[test]
fn merging_past_the_budget_falls_back() {
    let depth = 99;
    let vars = 11_000; // 2 selects per variable and level: > 2^21 in all
    let assigns: String = (0..vars).map(|k| format!("v{k} = x[2] + {k};\n")).collect();
    let src = format!(
        "my_model(x[3], a[1]) {{\n{}{assigns}{}my_model = v7 + v{};\n}}",
        "if x[1] > 0 then\n".repeat(depth),
        "endif;\n".repeat(depth),
        vars - 1
    );
    let m = model(&src);
    assert!(!m.lowered);
    let why = m.per_point.clone().unwrap();
    assert!(why.message.contains("select nodes"), "{why:?}");
    let want = 0.5 + 7.0 + 0.5 + (vars - 1) as f64;
    assert_eq!(m.eval_points(&[[1.0, 0.5, 0.0]])[0], Ok(want));
    let e = m.eval_points(&[[-1.0, 0.5, 0.0]])[0].clone().unwrap_err();
    assert_eq!(e.message, "Not initialized variable");
    // A tenth of it lowers.
    let small = src.replace(&assigns, &assigns[..assigns.find("v1100 ").unwrap()]);
    let small = small.replace(&format!("v{}", vars - 1), "v1099");
    let m = model(&small);
    assert!(m.lowered, "{:?}", m.per_point);
    assert_eq!(
        m.eval_points(&[[1.0, 0.5, 0.0]])[0],
        Ok(0.5 + 7.0 + 0.5 + 1099.0)
    );
}
