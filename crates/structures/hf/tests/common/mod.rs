//! Loading and probing HyperFun models for the tests.
#![allow(dead_code)]

use microfrep_core::{Expr, PointEval, Tape};
use microfrep_hyperfun::lower::Model;
use std::path::PathBuf;

/// The repository's `examples/` folder.
pub fn examples_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../examples")
}

/// Loads object `object` (default `my_model`) of an example file; it must
/// lower to a graph (not the per-point fallback).
pub fn example(file: &str, object: Option<&str>) -> Model {
    let path = examples_dir().join(file);
    let src = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    load_src(&src, file, object)
}

/// Loads HyperFun source with the `mf*` library installed.
pub fn load_src(src: &str, name: &str, object: Option<&str>) -> Model {
    microfrep_structures_hf::install();
    let m = microfrep_hyperfun::load(src, name, object).unwrap_or_else(|e| panic!("{e}"));
    assert!(m.lowered, "{name}: not lowered to a graph");
    m
}

/// A model ready for f64 evaluation of value and error code.
pub struct Probe {
    tape: Tape,
}

impl Probe {
    pub fn new(m: &Model) -> Probe {
        Probe { tape: m.tape() }
    }
    pub fn of(e: &Expr) -> Probe {
        Probe {
            tape: Tape::with_outputs(&[e.clone(), Expr::constant(0.0)]),
        }
    }
    /// The value at `p`; a run-time error (code != 0) or NaN fails the test.
    pub fn at(&self, p: [f64; 3]) -> f64 {
        let v = PointEval::new(&self.tape).eval_all(p);
        assert!(v[1] == 0.0, "run-time error {} at {p:?}", v[1]);
        assert!(v[0].is_finite(), "value {} at {p:?}", v[0]);
        v[0]
    }
    /// Values at many points, with one evaluator.
    pub fn values(&self, pts: &[[f64; 3]]) -> Vec<f64> {
        let mut ev = PointEval::new(&self.tape);
        pts.iter()
            .map(|&p| {
                let v = ev.eval_all(p);
                assert!(v[1] == 0.0 && v[0].is_finite(), "{v:?} at {p:?}");
                v[0]
            })
            .collect()
    }
    pub fn inside(&self, p: [f64; 3]) -> bool {
        self.at(p) >= 0.0
    }
}

/// `count` quasi-random points (R3 sequence) in `[lo, hi]`.
pub fn points(lo: [f64; 3], hi: [f64; 3], count: usize) -> Vec<[f64; 3]> {
    let phi = 1.220_744_084_605_759_5_f64;
    let a = [1.0 / phi, 1.0 / (phi * phi), 1.0 / (phi * phi * phi)];
    (1..=count)
        .map(|i| std::array::from_fn(|k| lo[k] + (hi[k] - lo[k]) * (0.5 + a[k] * i as f64).fract()))
        .collect()
}

/// Share of `pts` inside the model.
pub fn fraction(p: &Probe, pts: &[[f64; 3]]) -> f64 {
    let v = p.values(pts);
    v.iter().filter(|&&f| f >= 0.0).count() as f64 / v.len().max(1) as f64
}

/// Number of inside/outside changes at `n` steps along the path `path(t)`,
/// `t` in [0, 1].
pub fn crossings(p: &Probe, n: usize, path: impl Fn(f64) -> [f64; 3]) -> usize {
    let pts: Vec<[f64; 3]> = (0..=n).map(|i| path(i as f64 / n as f64)).collect();
    let v = p.values(&pts);
    v.windows(2)
        .filter(|w| (w[0] >= 0.0) != (w[1] >= 0.0))
        .count()
}

pub fn norm(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

pub fn add(p: [f64; 3], q: [f64; 3]) -> [f64; 3] {
    [p[0] + q[0], p[1] + q[1], p[2] + q[2]]
}
