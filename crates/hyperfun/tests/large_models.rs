//! Models as large as generators write them (a thousand pores, a point
//! cloud of spheres, long chains of statements) load, evaluate and print
//! without overflowing the stack, and their values equal a direct
//! computation. Nesting beyond the parser's limits is a clear error.
//!
//! Each test runs on the harness's 2 MiB thread, where a recursion per
//! operator or statement would abort the whole run.

use microfrep_hyperfun::lower::calls_of;
use microfrep_hyperfun::printer::to_hyperfun;
use microfrep_hyperfun::{load, parse};
use proptest::prelude::*;

fn value_at(src: &str, p: [f64; 3]) -> f64 {
    let m = load(src, "big.hf", None).unwrap_or_else(|d| panic!("{d}"));
    m.eval_points(&[p])[0].clone().unwrap()
}

fn close(got: f64, want: f64) -> bool {
    got == want || (got - want).abs() <= 1e-12 * want.abs().max(1.0)
}

#[test]
fn a_flat_sum_of_20k_terms_loads_and_evaluates() {
    let n = 20_000;
    let terms: Vec<String> = (0..n).map(|k| format!("x[{}]", k % 3 + 1)).collect();
    let src = format!(
        "my_model(x[3], a[1]) {{ my_model = {}; }}",
        terms.join(" + ")
    );
    let p = [0.5, -0.25, 0.125];
    let want = (0..n).fold(0.0, |s, k| if k == 0 { p[0] } else { s + p[k % 3] });
    assert_eq!(value_at(&src, p), want);
}

/// `hfSphere(x, c, r_k) | ...` over 15k radii, against the R-function
/// union computed here in the same order.
#[test]
fn a_union_of_15k_spheres_loads_and_evaluates() {
    let n = 15_000;
    let radius = |k: usize| 0.5 + (k % 10) as f64 * 0.05;
    let calls: Vec<String> = (0..n)
        .map(|k| format!("hfSphere(x, c, {})", radius(k)))
        .collect();
    let src = format!(
        "my_model(x[3], a[1]) {{ array c[3]; c = [0.5, 0, 0]; my_model = {}; }}",
        calls.join(" | ")
    );
    let p = [2.0, 0.5, 0.25];
    let d2 = (p[0] - 0.5f64).powi(2) + p[1] * p[1] + p[2] * p[2];
    let sphere =
        |k: usize| radius(k) * radius(k) - (p[0] - 0.5).powi(2) - p[1] * p[1] - p[2] * p[2];
    assert!(d2 > 1.0, "the point is outside every sphere");
    let mut u = sphere(0);
    for k in 1..n {
        let s = sphere(k);
        u = u + s + (u * u + s * s).sqrt();
    }
    let got = value_at(&src, p);
    assert!(u < 0.0 && close(got, u), "{got} vs {u}");
    let program = parse(&src, "big.hf").unwrap();
    assert_eq!(calls_of(&program, "hfsphere").len(), n);
}

/// 90k statements `t = t*0.5 + x[2];` make a chain 180k nodes deep.
#[test]
fn ninety_thousand_chained_statements_load_evaluate_and_print() {
    let n = 90_000;
    let mut src = String::from("my_model(x[3], a[1]) {\n  t = 0;\n");
    for _ in 0..n {
        src += "  t = t*0.5 + x[2];\n";
    }
    src += "  my_model = t;\n}\n";
    let p = [0.0, 0.75, 0.0];
    let want = (0..n).fold(0.0, |t, _| t * 0.5 + p[1]);
    let m = load(&src, "big.hf", None).unwrap();
    assert!(m.lowered);
    assert_eq!(m.eval_points(&[p])[0].clone().unwrap(), want);
    // Written back as HyperFun and read again: same value.
    let text = to_hyperfun(&m.value, "my_model");
    assert_eq!(value_at(&text, p), want);
}

#[test]
fn nesting_beyond_the_limits_is_a_clear_error() {
    let n = 100_000;
    let parens = format!(
        "my_model(x[3], a[1]) {{ my_model = {}1{}; }}",
        "(".repeat(n),
        ")".repeat(n)
    );
    let d = load(&parens, "deep.hf", None).unwrap_err();
    assert!(
        d.message.starts_with("Expression is nested too deeply"),
        "{d}"
    );
    let calls = format!(
        "my_model(x[3], a[1]) {{ my_model = {}x[1]{}; }}",
        "sin(".repeat(n),
        ")".repeat(n)
    );
    let d = load(&calls, "deep.hf", None).unwrap_err();
    assert!(
        d.message.starts_with("Expression is nested too deeply"),
        "{d}"
    );
    let ifs = format!(
        "my_model(x[3], a[1]) {{ t = 0; {}t = 1; {}my_model = t; }}",
        "if x[1] > 0 then ".repeat(n),
        "endif; ".repeat(n)
    );
    let d = load(&ifs, "deep.hf", None).unwrap_err();
    assert!(
        d.message.starts_with("Statements are nested too deeply"),
        "{d}"
    );
    // Just inside the limits it works.
    let ok = format!(
        "my_model(x[3], a[1]) {{ t = 0; {}t = 1; {}my_model = t + {}x[1]{}; }}",
        "if x[1] > 0 then ".repeat(99),
        "endif; ".repeat(99),
        "sin(".repeat(190),
        ")".repeat(190)
    );
    let p = [0.5, 0.0, 0.0];
    let want = 1.0 + (0..190).fold(0.5f64, |v, _| v.sin());
    assert_eq!(value_at(&ok, p), want);
}

#[test]
fn long_condition_chains_evaluate() {
    let n = 100_000;
    let conds: Vec<String> = (0..n).map(|k| format!("x[1] > {}", -(k as f64))).collect();
    let src = format!(
        "my_model(x[3], a[1]) {{ t = 0; if {} then t = 1; endif; my_model = t; }}",
        conds.join(" and ")
    );
    assert_eq!(value_at(&src, [0.5, 0.0, 0.0]), 1.0);
    assert_eq!(value_at(&src, [-0.5, 0.0, 0.0]), 0.0);
}

/// 3000 objects, each calling the previous one, under a loop whose trip
/// count depends on the point (so every evaluation runs the per-point
/// interpreter), evaluated on a thread with a 256 KiB stack.
#[test]
fn long_object_call_chains_run_on_small_stacks() {
    let n = 3000;
    let mut src =
        "o0(x[3], a[1]) { i = 0; while i < x[1] loop i = i + 1; endloop; o0 = i; }\n".to_string();
    for k in 1..n {
        src += &format!("o{k}(x[3], a[1]) {{ o{k} = o{}(x, a) + 1; }}\n", k - 1);
    }
    src += &format!("my_model(x[3], a[1]) {{ my_model = o{}(x, a); }}\n", n - 1);
    let m = load(&src, "chain.hf", None).unwrap();
    assert!(!m.lowered);
    let r = std::thread::Builder::new()
        .stack_size(256 << 10)
        .spawn(move || m.eval_points(&[[2.5, 0.0, 0.0]]))
        .unwrap()
        .join()
        .unwrap();
    assert_eq!(r[0].clone().unwrap(), 3.0 + (n - 1) as f64);
}

/// A random model: a chain of binary operators over coordinates and
/// literals, parts of it wrapped in parentheses (possibly past the nesting
/// limit), with its value computed directly.
#[derive(Clone, Debug)]
struct Gen {
    ops: Vec<(u8, u8)>,
    wrap: usize,
}

fn gen() -> impl Strategy<Value = Gen> {
    (prop::collection::vec((0u8..5, 0u8..4), 1..40), 0usize..400)
        .prop_map(|(ops, wrap)| Gen { ops, wrap })
}

impl Gen {
    /// Source text and value at `p` of the model repeated `reps` times.
    fn build(&self, reps: usize, p: [f64; 3]) -> (String, f64) {
        let mut text = String::from("x[1]");
        let mut v = p[0];
        let mut depth = 0;
        for r in 0..reps {
            for (i, &(op, term)) in self.ops.iter().enumerate() {
                let (t, tv) = match term {
                    0..=2 => (format!("x[{}]", term + 1), p[term as usize]),
                    _ => ("0.5".to_string(), 0.5),
                };
                let (sym, nv) = match op {
                    0 => ("+", v + tv),
                    1 => ("-", v - tv),
                    // A product binds tighter: it is one term of the sum.
                    2 => ("+", v + tv * 0.5),
                    3 => ("|", v + tv + (v * v + tv * tv).sqrt()),
                    _ => ("&", v + tv - (v * v + tv * tv).sqrt()),
                };
                let t = if op == 2 { format!("{t} * 0.5") } else { t };
                text.push_str(&format!(" {sym} {t}"));
                v = nv;
                // Wrap the whole text so far in parentheses now and then;
                // past 200 levels the parser refuses the model.
                if (r + i) % 2 == 0 && depth < self.wrap {
                    text.insert(0, '(');
                    text.push(')');
                    depth += 1;
                }
            }
        }
        (format!("my_model(x[3], a[1]) {{ my_model = {text}; }}"), v)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random flat models of up to ~40k operators: either the value equals
    /// the direct computation or the load fails with the nesting message.
    #[test]
    fn random_large_models_evaluate_or_fail_clearly(
        g in gen(),
        reps in 1usize..1000,
        p in prop::array::uniform3(-1.0f64..1.0),
    ) {
        let (src, want) = g.build(reps, p);
        match load(&src, "random.hf", None) {
            Ok(m) => {
                prop_assert!(g.wrap < 199 || reps * g.ops.len() < 398, "accepted {} levels", g.wrap);
                let got = m.eval_points(&[p])[0].clone().unwrap();
                let ok = (want.is_nan() && got.is_nan()) || got == want
                    || (got - want).abs() <= 1e-9 * want.abs().max(1.0);
                prop_assert!(ok, "{got} vs {want}");
            }
            Err(d) => {
                // 199 parentheses are 200 levels with the operand inside them.
                prop_assert!(g.wrap >= 199, "{d}");
                prop_assert!(d.message.starts_with("Expression is nested too deeply"), "{d}");
            }
        }
    }
}
