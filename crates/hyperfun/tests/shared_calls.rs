//! Objects calling objects: a call repeated with the same arguments is
//! shared (the lowered graph is a DAG, its size linear in the program),
//! and a program whose graph really is exponential is refused with a
//! clear error while it grows, not after gigabytes. Dropping the shared
//! graph must not recurse.
//!
//! Each test runs on the harness's 2 MiB thread, so a recursive drop of a
//! shared chain would abort the run.

use microfrep_hyperfun::load;
use proptest::prelude::*;
use std::time::{Duration, Instant};

/// How a level calls the level below.
#[derive(Clone, Copy, Debug)]
enum Form {
    /// `f(x, a) + f(x, a) * 0.5`
    SumScaled,
    /// `f(x, a) | f(x, a)`
    Union,
    /// `max(f(x, a), f(x, a))`
    Max,
    /// `t = f(x, a); u = f(x, a); t - u + t`
    ViaVariables,
    /// both calls inside a point-dependent `if`, one per branch and one after
    Branches,
}

fn body(form: Form, callee: &str) -> String {
    let f = format!("{callee}(x, a)");
    match form {
        Form::SumScaled => format!("r = {f} + {f} * 0.5;"),
        Form::Union => format!("r = {f} | {f};"),
        Form::Max => format!("r = max({f}, {f});"),
        Form::ViaVariables => format!("t = {f}; u = {f}; r = t - u + t;"),
        Form::Branches => {
            format!("if (x[1] > 0) then r = {f}; else r = {f} * 0.5; endif; r = r + {f} * 0;")
        }
    }
}

/// `n` objects, each calling the one before twice with the same arguments;
/// the last is `my_model`.
fn chain(forms: &[Form], n: usize) -> String {
    let mut s = String::from("o0(x[3], a[1]) { o0 = 1 - x[1]*x[1] - x[2]*x[2] - x[3]*x[3]; }\n");
    for i in 1..n {
        let name = if i + 1 == n {
            "my_model".to_string()
        } else {
            format!("o{i}")
        };
        let b = body(forms[i % forms.len()], &format!("o{}", i - 1));
        s += &format!("{name}(x[3], a[1]) {{ {b} {name} = r; }}\n");
    }
    s
}

/// The value of [`chain`] at a point, computed directly.
fn chain_value(forms: &[Form], n: usize, p: [f64; 3]) -> f64 {
    let mut v = 1.0 - p[0] * p[0] - p[1] * p[1] - p[2] * p[2];
    for i in 1..n {
        v = match forms[i % forms.len()] {
            Form::SumScaled => v + v * 0.5,
            // The R-function union of a value with itself: 2v + |v| sqrt 2.
            Form::Union => v + v + (v * v + v * v).sqrt(),
            Form::Max => v,
            Form::ViaVariables => v - v + v,
            Form::Branches => {
                let r = if p[0] > 0.0 { v } else { v * 0.5 };
                r + v * 0.0
            }
        };
    }
    v
}

fn close(got: f64, want: f64) -> bool {
    got == want || (got - want).abs() <= 1e-9 * want.abs().max(1.0)
}

#[test]
fn the_issue_example_18_objects_calling_the_previous_twice() {
    // 850 bytes; the tree form had 2^18 copies of the first object and
    // the drop of its shared form overflowed the stack.
    let src = chain(&[Form::SumScaled], 18);
    assert!(src.len() < 1200, "{}", src.len());
    let m = load(&src, "chain.hf", None).unwrap_or_else(|d| panic!("{d}"));
    assert!(m.lowered);
    assert!(m.value.node_count() < 200, "{} nodes", m.value.node_count());
    let p = [0.1, 0.2, 0.3];
    let got = m.eval_points(&[p])[0].clone().unwrap();
    assert!(close(got, chain_value(&[Form::SumScaled], 18, p)), "{got}");
    drop(m);
}

#[test]
fn chains_of_increasing_length_stay_linear_in_size_and_time() {
    let forms = [
        Form::SumScaled,
        Form::Union,
        Form::ViaVariables,
        Form::Branches,
        Form::Max,
    ];
    let mut last = 0;
    for n in [10, 20, 40, 80, 160, 320] {
        let src = chain(&forms, n);
        let t = Instant::now();
        let m = load(&src, "chain.hf", None).unwrap_or_else(|d| panic!("{n}: {d}"));
        let nodes = m.value.node_count() + m.error.node_count();
        // A few dozen nodes per level, whatever the length.
        assert!(nodes < 60 * n, "{n} levels: {nodes} nodes");
        assert!(nodes > last, "{n} levels: {nodes} nodes");
        last = nodes;
        for p in [[0.1, 0.2, 0.3], [-0.4, 0.1, 0.0]] {
            let got = m.eval_points(&[p])[0].clone().unwrap();
            let want = chain_value(&forms, n, p);
            assert!(close(got, want), "{n} levels at {p:?}: {got} vs {want}");
        }
        // The interpreter (constant inputs, the fallback's path) shares
        // calls with equal constant arguments too.
        let i = m.interpreted();
        let got = i.eval_points(&[[0.1, 0.2, 0.3]])[0].clone().unwrap();
        assert!(
            close(got, chain_value(&forms, n, [0.1, 0.2, 0.3])),
            "{n}: {got}"
        );
        drop(m);
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "{n} levels took {:?}",
            t.elapsed()
        );
    }
}

/// `n` objects each calling the one before at two different points, so
/// the graph really has 2^n copies of the first.
fn branching(n: usize) -> String {
    let mut s = String::from("o0(x[3], a[1]) { o0 = 1 - x[1]*x[1] - x[2]*x[2] - x[3]*x[3]; }\n");
    for i in 1..n {
        let name = if i + 1 == n {
            "my_model".to_string()
        } else {
            format!("o{i}")
        };
        let p = i - 1;
        s += &format!(
            "{name}(x[3], a[1]) {{ array y[3]; y[1] = x[1] * 0.5; y[2] = x[2]; y[3] = x[3]; \
             {name} = o{p}(x, a) + o{p}(y, a); }}\n"
        );
    }
    s
}

#[test]
fn a_really_exponential_program_is_refused_while_it_grows() {
    // 2^12 copies are fine.
    let m = load(&branching(12), "b.hf", None).unwrap_or_else(|d| panic!("{d}"));
    assert!(m.lowered);
    drop(m);
    // 2^40 are refused with the reason, quickly and in bounded memory.
    for n in [30, 40, 64] {
        let t = Instant::now();
        let err = load(&branching(n), "b.hf", None).expect_err("must be refused");
        let msg = err.to_string();
        assert!(msg.contains("expression nodes"), "{msg}");
        assert!(msg.contains("b.hf"), "{msg}");
        assert!(
            t.elapsed() < Duration::from_secs(30),
            "{n}: {:?}",
            t.elapsed()
        );
    }
}

#[test]
fn a_loop_doubling_a_shared_value_loads_and_drops() {
    // `y = min(y, y)` 200k times: one node per iteration, each holding the
    // one before twice.
    let src = "my_model(x[3], a[1]) { i = 0; y = x[1]; \
               while (i < 200000) loop y = min(y, y); i = i + 1; endloop; my_model = y; }";
    let m = load(src, "loop.hf", None).unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(m.eval_points(&[[0.25, 0.0, 0.0]])[0].clone().unwrap(), 0.25);
    drop(m);
}

#[test]
fn calls_writing_s_and_raising_errors_keep_their_meaning_when_shared() {
    // The shared call writes s back each time, and its error site counts
    // where either call is reached.
    let src = "o0(x[3], a[1], s[2]) { s[1] = x[1]; s[2] = 2; o0 = sqrt(x[2]); }\n\
               my_model(x[3], a[1], s[2]) { t = o0(x, a, s); s[2] = 5; \
               u = o0(x, a, s); my_model = t + u; }";
    let m = load(src, "s.hf", None).unwrap_or_else(|d| panic!("{d}"));
    let i = m.interpreted();
    for p in [[0.5, 4.0, 0.0], [0.5, -1.0, 0.0]] {
        let a = m.eval_points_with_attributes(&[p]).remove(0);
        let b = i.eval_points_with_attributes(&[p]).remove(0);
        match (&a, &b) {
            (Ok((va, sa)), Ok((vb, sb))) => {
                assert_eq!((va, sa), (vb, sb));
                assert_eq!(*va, 4.0);
                // The second call wrote s[2] = 2 over the 5.
                assert_eq!(sa, &vec![0.5, 2.0]);
            }
            (Err(ea), Err(eb)) => assert_eq!(ea.message, eb.message),
            _ => panic!("{p:?}: lowered {a:?}, interpreted {b:?}"),
        }
    }
}

fn form() -> impl Strategy<Value = Form> {
    prop_oneof![
        Just(Form::SumScaled),
        Just(Form::Union),
        Just(Form::Max),
        Just(Form::ViaVariables),
        Just(Form::Branches),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Random mixes of call forms, 20 to 200 levels: linear size, the
    /// value of a direct computation.
    #[test]
    fn random_shared_call_chains(
        forms in prop::collection::vec(form(), 1..5),
        n in 20usize..200,
        p in prop::array::uniform3(-1.0f64..1.0),
    ) {
        let m = load(&chain(&forms, n), "chain.hf", None).map_err(|d| TestCaseError::fail(d.to_string()))?;
        prop_assert!(m.value.node_count() < 60 * n);
        let got = m.eval_points(&[p])[0].clone().unwrap();
        let want = chain_value(&forms, n, p);
        prop_assert!(close(got, want), "{} vs {}", got, want);
    }
}

#[test]
fn a_shared_call_raises_its_errors_only_where_it_is_reached_and_in_order() {
    // o0 fails (sqrt of a negative) where x[2] < 0; it is called in one
    // branch only, after a division that fails first where x[3] = 0, and
    // again unguarded in the other object.
    let src = "o0(x[3], a[1]) { o0 = sqrt(x[2]); }\n\
               o1(x[3], a[1]) { d = 1 / x[3]; \
               if (x[1] > 0) then r = o0(x, a); else r = d; endif; o1 = r + o0(x, a) * 0; }\n\
               my_model(x[3], a[1]) { if (x[1] > 0.5) then r = o1(x, a); \
               else r = o0(x, a) + o1(x, a); endif; my_model = r; }";
    let m = load(src, "e.hf", None).unwrap_or_else(|d| panic!("{d}"));
    let i = m.interpreted();
    let vals = [-1.0, 0.0, 0.25, 0.75];
    let mut errors = 0;
    for &a in &vals {
        for &b in &vals {
            for &c in &vals {
                let p = [a, b, c];
                let l = m.eval_points(&[p]).remove(0);
                let r = i.eval_points(&[p]).remove(0);
                match (&l, &r) {
                    (Ok(x), Ok(y)) => assert!(close(*x, *y), "{p:?}: {x} vs {y}"),
                    (Err(x), Err(y)) => {
                        errors += 1;
                        assert_eq!(
                            (&x.message, x.line, x.col),
                            (&y.message, y.line, y.col),
                            "{p:?}"
                        );
                    }
                    _ => panic!("{p:?}: lowered {l:?}, interpreted {r:?}"),
                }
            }
        }
    }
    assert!(errors > 0 && errors < 64, "{errors}");
}
