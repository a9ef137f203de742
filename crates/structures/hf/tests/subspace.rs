//! `mfSubspace`, Park's material subspaces from HyperFun: the rewritten
//! Fig. 6 example gives the values of its former hand-coded form at 1000
//! points in every evaluation mode, the order of subspaces decides where
//! they overlap, the per-point interpreter agrees with the graph, and bad
//! arguments are load errors naming the function.
mod common;
use common::*;
use microfrep_core::{BatchEval, GradEval, Interval, IntervalEval, PointEval, Shape};

/// `examples/park_fig6_femur_gradient.hf` before it used `mfSubspace`:
/// the subspace written with `if` and `mfDepth`.
const FIG6_BEFORE: &str = "my_model(x[3], a[1], s[2]) {
  array p[3];
  newx = 0.5*x[1]*1.414 + 1 - 0.5*x[2];
  newy = 0.5*x[1] + 0.5*(-2 + x[2])*1.414;
  p[1] = 1 / max(x[2]*x[2]/7.5 + x[1]*x[1]/0.25 + x[3]*x[3]/0.25, 0.001);
  p[2] = 1 / max(newy*newy/0.6 + newx*newx/0.1 + x[3]*x[3]/0.1, 0.001);
  p[3] = 1 / max(((x[2] - 3.4)*4/3)^2 + ((x[1] - 0.6)*4/3)^2 + (x[3]*4/3)^2, 0.001);
  u = mfUnionA(p, 5);
  depth = mfDepth(1 - 1/sqrt(u));
  shell = 0.1;
  ramp = 0.2;
  if depth >= shell then
    s[2] = mfBias((depth - shell) / ramp, 0.7);
  else
    s[2] = 0;
  endif;
  s[1] = 1 - s[2];
  my_model = u - 1;
}
";

/// `examples/park_fig5_femur_implant.hf` (geometry only: Park's Fig. 5 has
/// no material, so it has no subspace to rewrite); kept to show the file is
/// the same model.
const FIG5_BEFORE: &str = "my_model(x[3], a[1]) {
  array p[3];
  newx = 0.5*x[1]*1.414 + 1 - 0.5*x[2];
  newy = 0.5*x[1] + 0.5*(-2 + x[2])*1.414;
  p[1] = 1 / max(x[2]*x[2]/7.5 + x[1]*x[1]/0.25 + x[3]*x[3]/0.25, 0.001);
  p[2] = 1 / max(newy*newy/0.6 + newx*newx/0.1 + x[3]*x[3]/0.1, 0.001);
  p[3] = 1 / max(((x[2] - 3.4)*4/3)^2 + ((x[1] - 0.6)*4/3)^2 + (x[3]*4/3)^2, 0.001);
  my_model = mfUnionA(p, 5) - 1;
}
";

const LO: [f64; 3] = [-1.3, -3.0, -0.9];
const HI: [f64; 3] = [1.6, 4.3, 0.9];

/// Value, then each attribute, of a shape at `p` in f64.
fn outputs(s: &Shape, p: [f64; 3]) -> Vec<f64> {
    let out = PointEval::new(s.outputs()).eval_all(p);
    let mut v = vec![out[0]];
    v.extend((0..s.attributes().len()).map(|k| out[s.attribute_output(k)]));
    v
}

/// Uniform pseudo-random points (a fixed xorshift sequence) in the box.
fn random_points(n: usize) -> Vec<[f64; 3]> {
    let mut st = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        st ^= st << 13;
        st ^= st >> 7;
        st ^= st << 17;
        (st >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| std::array::from_fn(|a| LO[a] + (HI[a] - LO[a]) * next()))
        .collect()
}

#[test]
fn fig6_with_subspace_equals_the_hand_coded_model_in_every_mode() {
    let new = example("park_fig6_femur_gradient.hf", None).shape();
    let old = load_src(FIG6_BEFORE, "fig6_before.hf", None).shape();
    assert!(source_has("park_fig6_femur_gradient.hf", "mfSubspace("));
    assert_eq!(new.attributes().len(), 2);
    let pts = random_points(1000);
    let (mut graded, mut shell, mut outside) = (0, 0, 0);
    let (mut pn, mut po) = (PointEval::new(new.outputs()), PointEval::new(old.outputs()));
    for &p in &pts {
        // f64 point values: value, error code and both attributes, bit for bit.
        let (a, b) = (pn.eval_all(p), po.eval_all(p));
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.to_bits(), y.to_bits(), "at {p:?}: {a:?} vs {b:?}");
        }
        let o = outputs(&new, p);
        if o[0] < 0.0 {
            outside += 1;
        } else if o[2] > 0.0 {
            graded += 1;
        } else {
            shell += 1;
        }
    }
    assert!(
        graded > 20 && shell > 20 && outside > 500,
        "{graded} {shell} {outside}"
    );
    // f32 batch, every output.
    let lanes = |a: usize| pts.iter().map(|q| q[a] as f32).collect::<Vec<f32>>();
    let (x, y, z) = (lanes(0), lanes(1), lanes(2));
    for k in [0, new.attribute_output(0), new.attribute_output(1)] {
        let (mut bn, mut bo) = (vec![0f32; pts.len()], vec![0f32; pts.len()]);
        BatchEval::new(new.outputs()).eval_output(k, &x, &y, &z, &mut bn);
        BatchEval::new(old.outputs()).eval_output(k, &x, &y, &z, &mut bo);
        for (i, (u, v)) in bn.iter().zip(&bo).enumerate() {
            assert_eq!(u.to_bits(), v.to_bits(), "batch output {k} at {:?}", pts[i]);
        }
    }
    // Gradients and interval bounds of the graded channel.
    let k = new.attribute_output(1);
    let (mut gn, mut go) = (GradEval::new(new.outputs()), GradEval::new(old.outputs()));
    let (mut inn, mut ino) = (
        IntervalEval::new(new.outputs()),
        IntervalEval::new(old.outputs()),
    );
    for &p in &pts {
        let (a, b) = (gn.eval_output(k, p), go.eval_output(k, p));
        assert_eq!(a.0.to_bits(), b.0.to_bits(), "grad value at {p:?}");
        for i in 0..3 {
            assert_eq!(a.1[i].to_bits(), b.1[i].to_bits(), "gradient at {p:?}");
        }
        let iv = |c: f64| Interval::new(c - 0.01, c + 0.01);
        let (x, y, z) = (iv(p[0]), iv(p[1]), iv(p[2]));
        let (a, b) = (inn.eval_output(k, x, y, z), ino.eval_output(k, x, y, z));
        assert!(
            a.lo <= outputs(&new, p)[2] && outputs(&new, p)[2] <= a.hi,
            "interval {a:?} misses the value at {p:?}"
        );
        // No looser than the hand-coded form's bounds.
        assert!(
            a.lo >= b.lo - 1e-12 && a.hi <= b.hi + 1e-12,
            "{a:?} vs {b:?}"
        );
    }
}

fn source_has(file: &str, what: &str) -> bool {
    std::fs::read_to_string(examples_dir().join(file))
        .unwrap()
        .contains(what)
}

#[test]
fn fig5_is_the_same_model() {
    let new = example("park_fig5_femur_implant.hf", None).shape();
    let old = load_src(FIG5_BEFORE, "fig5_before.hf", None).shape();
    for p in random_points(1000) {
        assert_eq!(outputs(&new, p)[0].to_bits(), outputs(&old, p)[0].to_bits());
    }
}

/// A unit cube of three materials: material 1 fills it, a subspace
/// `x > 0.5` grades material 2 as `2x - 1` over material 1, and a later
/// slab `z > 0.75` of pure material 3 overrides both.
const LAYERS: &str = "my_model(x[3], a[1], s[3]) {
  s[1] = 1;
  s[2] = 0;
  s[3] = 0;
  g = mfSubspace(s, x[1] - 0.5, 2*x[1] - 1, 2, 1);
  g = mfSubspace(s, x[3] - 0.75, 2, 3, 1);
  my_model = min(min(x[1], 1 - x[1]), min(min(x[2], 1 - x[2]), min(x[3], 1 - x[3])));
}
";

#[test]
fn later_subspaces_override_earlier_ones() {
    let m = load_src(LAYERS, "layers.hf", None);
    let s = m.shape();
    let at = |p| outputs(&s, p)[1..].to_vec();
    assert_eq!(at([0.25, 0.5, 0.5]), [1.0, 0.0, 0.0]); // primary
    assert_eq!(at([0.75, 0.5, 0.5]), [0.5, 0.5, 0.0]); // graded
    assert_eq!(at([1.0, 0.5, 0.5]), [0.0, 1.0, 0.0]);
    assert_eq!(at([0.75, 0.5, 0.9]), [0.0, 0.0, 1.0]); // fraction 2 clamped to 1
    assert_eq!(at([0.25, 0.5, 0.9]), [0.0, 0.0, 1.0]);
    // The per-point interpreter gives the same attributes.
    let interp = m.interpreted();
    let pts = points([0.0; 3], [1.0; 3], 200);
    let a = m.eval_points_with_attributes(&pts);
    let b = interp.eval_points_with_attributes(&pts);
    for ((p, a), b) in pts.iter().zip(a).zip(b) {
        assert_eq!(a.unwrap(), b.unwrap(), "at {p:?}");
    }
}

/// A material number known only per point sends the model to the per-point
/// interpreter, which still evaluates it.
#[test]
fn point_dependent_material_runs_on_the_interpreter() {
    let src = "my_model(x[3], a[1], s[3]) {
  s[1] = 1;
  s[2] = 0;
  s[3] = 0;
  m = 2;
  if x[2] > 0.5 then
    m = 3;
  endif;
  g = mfSubspace(s, x[1] - 0.5, 1, m, 1);
  my_model = 1 - x[1]*x[1] - x[2]*x[2] - x[3]*x[3];
}
";
    microfrep_structures_hf::install();
    let m = microfrep_hyperfun::load(src, "pp.hf", None).unwrap();
    assert!(!m.lowered);
    let v = m.eval_points_with_attributes(&[[0.75, 0.25, 0.0], [0.75, 0.6, 0.0], [0.25, 0.6, 0.0]]);
    let s: Vec<Vec<f64>> = v.into_iter().map(|r| r.unwrap().1).collect();
    assert_eq!(
        s,
        [
            vec![0.0, 1.0, 0.0],
            vec![0.0, 0.0, 1.0],
            vec![1.0, 0.0, 0.0]
        ]
    );
}

#[test]
fn bad_arguments_are_load_errors() {
    microfrep_structures_hf::install();
    let cases = [
        (
            "s[2]",
            "g = mfSubspace(s, x[1], 0.5, 3, 1);",
            "material must be an integer from 1 to 2, not 3",
        ),
        (
            "s[2]",
            "g = mfSubspace(s, x[1], 0.5, 0, 1);",
            "material must be an integer from 1 to 2, not 0",
        ),
        (
            "s[2]",
            "g = mfSubspace(s, x[1], 0.5, 1.5, 2);",
            "material must be an integer",
        ),
        (
            "s[2]",
            "g = mfSubspace(s, x[1], 0.5, 2, 2);",
            "material and base are both 2",
        ),
        (
            "s[2]",
            "g = mfSubspace(s, x[1], 0.5, 2, 4);",
            "base must be an integer from 1 to 2, not 4",
        ),
        (
            "s[1]",
            "g = mfSubspace(s, x[1], 0.5, 1, 1);",
            "at least 2 elements",
        ),
    ];
    for (attrs, call, want) in cases {
        let src = format!("my_model(x[3], a[1], {attrs}) {{\n  {call}\n  my_model = 1;\n}}\n");
        let e = match microfrep_hyperfun::load(&src, "bad.hf", None) {
            Ok(_) => panic!("{call}: loaded"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.to_lowercase().contains("mfsubspace") && e.contains(want),
            "{call}: {e}"
        );
    }
}
