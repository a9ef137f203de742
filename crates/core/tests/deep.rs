//! Expressions as long as generated models make them (a sum of 100k terms,
//! 100k chained statements): building, dropping, remapping, counting,
//! differentiating and evaluating them must not overflow the stack, and
//! the values must equal a direct computation.
//!
//! The test harness runs each test on a thread with a 2 MiB stack, so a
//! recursive walk over any of these chains would abort the run.

use microfrep_core::{Expr, GradEval, PointEval, Tape};
use proptest::prelude::*;

const N: usize = 200_000;

/// `t = t*0.5 + y` repeated `n` times from `t = 0`: a chain `2n` deep.
fn chain(n: usize) -> Expr {
    let y = Expr::y();
    let mut t = Expr::constant(0.0);
    for _ in 0..n {
        t = t * 0.5 + &y;
    }
    t
}

fn chain_value(n: usize, y: f64) -> f64 {
    (0..n).fold(0.0, |t, _| t * 0.5 + y)
}

#[test]
fn a_chain_of_200k_nodes_drops_without_recursing() {
    let e = chain(N);
    // Per step a constant 0.5, a product and a sum, plus y; the first
    // step folds `0 * 0.5` to one constant and has no product.
    assert_eq!(e.node_count(), 3 * N);
    drop(e);
    // A chain whose nodes are shared with another live chain: dropping one
    // must leave the other intact.
    let a = chain(N);
    let b = a.clone() + 1.0;
    drop(a);
    let tape = Tape::new(&b);
    let want = chain_value(N, 0.25) + 1.0;
    assert_eq!(PointEval::new(&tape).eval([0.0, 0.25, 0.0]), want);
}

#[test]
fn a_flat_sum_of_200k_terms_evaluates_exactly() {
    let x = Expr::x();
    let mut s = Expr::constant(0.0);
    for k in 0..N {
        s = s + &x * (k % 7) as f64;
    }
    let tape = Tape::new(&s);
    let want = (0..N).fold(0.0, |acc, k| acc + 0.5 * (k % 7) as f64);
    assert_eq!(PointEval::new(&tape).eval([0.5, 0.0, 0.0]), want);
}

#[test]
fn remap_of_a_deep_chain_matches_the_mapped_value() {
    let e = chain(N);
    // Replace y by 2x: the value at (x, *, *) is the chain at y = 2x.
    let m = e.remap(&[Expr::x(), 2.0 * Expr::x(), Expr::z()]);
    drop(e);
    let tape = Tape::new(&m);
    assert_eq!(
        PointEval::new(&tape).eval([0.125, 9.0, 9.0]),
        chain_value(N, 0.25)
    );
}

#[test]
fn gradient_of_a_deep_chain_matches_forward_mode() {
    let e = chain(N);
    let g = e.gradient();
    let tape = Tape::with_outputs(&[g[0].clone(), g[1].clone(), g[2].clone()]);
    let sym = PointEval::new(&tape).eval_all([0.0, 0.5, 0.0]);
    let (v, fwd) = GradEval::new(&Tape::new(&e)).eval([0.0, 0.5, 0.0]);
    assert_eq!(v, chain_value(N, 0.5));
    // d/dy of the chain is the geometric sum 2 (1 - 0.5^n) = 2 for large n.
    assert_eq!(sym, fwd.to_vec());
    assert!((sym[1] - 2.0).abs() < 1e-12, "{}", sym[1]);
    assert_eq!((sym[0], sym[2]), (0.0, 0.0));
}

/// One step of a random model: which operation joins the running value
/// and a coordinate.
#[derive(Clone, Copy, Debug)]
enum Step {
    Add(u8),
    Mul(u8),
    Max(u8),
    Neg,
    Select(u8),
}

fn step() -> impl Strategy<Value = Step> {
    prop_oneof![
        (0u8..3).prop_map(Step::Add),
        (0u8..3).prop_map(Step::Mul),
        (0u8..3).prop_map(Step::Max),
        Just(Step::Neg),
        (0u8..3).prop_map(Step::Select),
    ]
}

/// Builds the chain as an expression and computes it directly.
fn build(steps: &[Step], reps: usize, p: [f64; 3]) -> (Expr, f64) {
    let xyz = Expr::xyz();
    let (mut e, mut v) = (Expr::constant(0.5), 0.5f64);
    for _ in 0..reps {
        for s in steps {
            match *s {
                Step::Add(a) => {
                    e = e + &xyz[a as usize];
                    v += p[a as usize];
                }
                Step::Mul(a) => {
                    // Keep values bounded: multiply by a number in [0.5, 1].
                    e = e * (0.75 + 0.25 * xyz[a as usize].sin());
                    v *= 0.75 + 0.25 * p[a as usize].sin();
                }
                Step::Max(a) => {
                    e = e.max(&xyz[a as usize]);
                    v = v.max(p[a as usize]);
                }
                Step::Neg => {
                    e = -e;
                    v = -v;
                }
                Step::Select(a) => {
                    e = Expr::select(xyz[a as usize].gt(0.0), e.clone(), e * 0.5);
                    v = if p[a as usize] > 0.0 { v } else { v * 0.5 };
                }
            }
        }
    }
    (e, v)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Random chains of 20k to 60k operations: compiled, evaluated at a
    /// point (equal to the direct computation), differentiated, remapped
    /// and dropped without a stack overflow.
    #[test]
    fn random_deep_chains_evaluate_like_a_direct_computation(
        steps in prop::collection::vec(step(), 1..6),
        reps in 4000usize..10000,
        p in prop::array::uniform3(-2.0f64..2.0),
    ) {
        let (e, want) = build(&steps, reps, p);
        let got = PointEval::new(&Tape::new(&e)).eval(p);
        prop_assert!(got == want || (got - want).abs() <= 1e-9 * want.abs().max(1.0), "{got} vs {want}");
        let g = e.gradient();
        prop_assert!(g[0].node_count() > 0);
        let shifted = e.remap(&Expr::xyz());
        prop_assert_eq!(PointEval::new(&Tape::new(&shifted)).eval(p), got);
    }
}

/// How one level of a shared chain refers to the level below, `v`: every
/// kind holds `v` at least twice, so the last reference to `v` goes away
/// inside the drop of its parent.
#[derive(Clone, Copy, Debug)]
enum Twice {
    Sum,
    Min,
    Select,
    Set,
    Blend,
    PowOfItself,
}

fn twice() -> impl Strategy<Value = Twice> {
    prop_oneof![
        Just(Twice::Sum),
        Just(Twice::Min),
        Just(Twice::Select),
        Just(Twice::Set),
        Just(Twice::Blend),
        Just(Twice::PowOfItself),
    ]
}

/// A chain `n` levels deep where each level holds the one below twice (a
/// DAG: as a tree it would have 2^n nodes).
fn shared_chain(kinds: &[Twice], n: usize) -> Expr {
    let alpha = Expr::param("alpha", 0.5);
    let mut v = Expr::x();
    for k in 0..n {
        v = match kinds[k % kinds.len()] {
            Twice::Sum => &v + &v,
            Twice::Min => v.min(&v),
            Twice::Select => Expr::select(Expr::y().gt(0.0), v.clone(), v.clone()),
            Twice::Set => Expr::set(microfrep_core::SetOp::Union, &v, &v, alpha.clone()),
            Twice::Blend => Expr::blend(
                microfrep_core::SetOp::Intersection,
                [
                    v.clone(),
                    v.clone(),
                    alpha.clone(),
                    v.clone(),
                    1.0.into(),
                    1.0.into(),
                ],
            ),
            Twice::PowOfItself => v.pow(&v),
        };
    }
    v
}

#[test]
fn a_node_holding_its_child_twice_drops_without_recursing() {
    // The class: `y = min(y, y)` 200k times in a HyperFun loop
    // overflowed the stack when the model was dropped.
    let mut v = Expr::x();
    for _ in 0..N {
        v = v.min(&v);
    }
    assert_eq!(v.node_count(), N + 1);
    drop(v);
    let mut s = Expr::x();
    for _ in 0..N {
        s = &s + &s;
    }
    // Still evaluable: 2^N overflows to infinity, the graph stays N nodes.
    assert_eq!(
        PointEval::new(&Tape::new(&s)).eval([1.0, 0.0, 0.0]),
        f64::INFINITY
    );
    drop(s);
}

#[test]
fn shared_chains_dropped_from_many_threads_at_once() {
    // Several threads drop their references to one DAG concurrently: the
    // last one takes it apart, none recurses, nothing is freed twice.
    let v = shared_chain(&[Twice::Sum, Twice::Select, Twice::Set], N);
    let handles: Vec<_> = (0..4)
        .map(|k| {
            let mine = v.clone() + k as f64;
            std::thread::Builder::new()
                .stack_size(256 * 1024)
                .spawn(move || drop(mine))
                .expect("thread")
        })
        .collect();
    drop(v);
    for h in handles {
        h.join().expect("a drop panicked");
    }
}

#[test]
fn nodes_created_counts_the_nodes_this_thread_builds() {
    let before = Expr::nodes_created();
    let x = Expr::x();
    let e = &x + 1.0;
    // x, the constant 1 and the sum.
    assert_eq!(Expr::nodes_created() - before, 3);
    drop(e);
    // Another thread's nodes are its own.
    std::thread::spawn(|| {
        let _ = Expr::x() * 2.0;
    })
    .join()
    .expect("thread");
    assert_eq!(Expr::nodes_created() - before, 3);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]

    /// Random mixes of node kinds, each level holding the one below two or
    /// three times, 50k to 150k levels: dropped on the 2 MiB test stack.
    #[test]
    fn random_shared_chains_drop_without_recursing(
        kinds in prop::collection::vec(twice(), 1..6),
        n in 50_000usize..150_000,
    ) {
        let v = shared_chain(&kinds, n);
        prop_assert!(v.node_count() >= n);
        drop(v);
    }
}
