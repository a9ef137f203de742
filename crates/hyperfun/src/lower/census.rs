//! Counting run-time errors over the sample points of a mesher or slicer.
//!
//! The value output is NaN wherever the model raises a run-time error, so
//! such points are outside for every consumer (the reference polygonizer
//! silently reused the previous sample's value instead). A consumer reports
//! how many of its samples that affected with [`Model::error_census`].

use super::{Model, RuntimeError};
use microfrep_core::{Interval, IntervalEval, PointEval, Tape};

/// Run-time errors on a grid of sample points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorCensus {
    /// Points looked at.
    pub samples: u64,
    /// Points where the model raised a run-time error.
    pub errors: u64,
    /// Per error site (message and position), how many points hit it; in
    /// order of first occurrence in the error table.
    pub sites: Vec<(RuntimeError, u64)>,
}

impl std::fmt::Display for ErrorCensus {
    /// `N of M samples` plus the most frequent site, e.g. for a summary line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} of {} samples", self.errors, self.samples)?;
        if let Some((e, n)) = self.sites.iter().max_by_key(|(_, n)| *n) {
            write!(f, " (most: {e}, {n} times)")?;
        }
        Ok(())
    }
}

/// Boxes of at most this many points are sampled point by point.
const LEAF: usize = 4096;

struct Walk<'a> {
    axes: [&'a [f64]; 3],
    ie: IntervalEval<'a>,
    pe: PointEval<'a>,
    codes: Vec<u64>,
    unknown: u64,
}

impl Walk<'_> {
    /// Index ranges `lo..hi` per axis.
    fn visit(&mut self, lo: [usize; 3], hi: [usize; 3]) {
        let n: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        if n.contains(&0) {
            return;
        }
        let b: [Interval; 3] = std::array::from_fn(|a| span(&self.axes[a][lo[a]..hi[a]]));
        let r = self.ie.eval(b[0], b[1], b[2]);
        if !r.may_be_nan() && r.lo == 0.0 && r.hi == 0.0 {
            return;
        }
        if n[0] * n[1] * n[2] <= LEAF {
            for k in lo[2]..hi[2] {
                for j in lo[1]..hi[1] {
                    for i in lo[0]..hi[0] {
                        let p = [self.axes[0][i], self.axes[1][j], self.axes[2][k]];
                        let code = self.pe.eval(p);
                        self.count(code);
                    }
                }
            }
            return;
        }
        let a = (0..3).max_by_key(|&a| n[a]).unwrap_or(0);
        let mid = lo[a] + n[a] / 2;
        let (mut hi1, mut lo2) = (hi, lo);
        hi1[a] = mid;
        lo2[a] = mid;
        self.visit(lo, hi1);
        self.visit(lo2, hi);
    }

    fn count(&mut self, code: f64) {
        if code == 0.0 {
            return;
        }
        if code.is_nan() || code < 1.0 {
            self.unknown += 1;
            return;
        }
        let k = code.round() as usize - 1;
        if self.codes.len() <= k {
            self.codes.resize(k + 1, 0);
        }
        self.codes[k] += 1;
    }
}

/// Bounds of a list of coordinates (NaN-free lists; empty gives ENTIRE).
fn span(v: &[f64]) -> Interval {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if lo <= hi {
        Interval::new(lo, hi)
    } else {
        Interval::ENTIRE
    }
}

impl Model {
    /// Counts run-time errors at the points `xs x ys x zs` (every
    /// combination), evaluated like `eval` does (f64). Boxes where interval
    /// evaluation proves the error output 0 are skipped, so a model with no
    /// reachable error site costs nothing.
    pub fn error_census(&self, xs: &[f64], ys: &[f64], zs: &[f64]) -> ErrorCensus {
        let samples = (xs.len() as u64) * (ys.len() as u64) * (zs.len() as u64);
        if self.error.as_const() == Some(0.0) {
            return ErrorCensus {
                samples,
                ..Default::default()
            };
        }
        let tape = Tape::new(&self.error);
        let mut ie = IntervalEval::new(&tape);
        let mut pe = PointEval::new(&tape);
        for (name, v) in &self.params {
            if let Some(i) = tape.param_index(name) {
                ie.set_param(i, *v);
                pe.set_param(i, *v);
            }
        }
        let mut w = Walk {
            axes: [xs, ys, zs],
            ie,
            pe,
            codes: Vec::new(),
            unknown: 0,
        };
        w.visit([0; 3], [xs.len(), ys.len(), zs.len()]);
        let mut sites = Vec::new();
        for (k, &n) in w.codes.iter().enumerate() {
            if n > 0 {
                let e = self.errors.get((k + 1) as f64).unwrap_or(RuntimeError {
                    message: "evaluation failed".into(),
                    line: 0,
                    col: 0,
                });
                sites.push((e, n));
            }
        }
        if w.unknown > 0 {
            let e = RuntimeError {
                message: "evaluation failed".into(),
                line: 0,
                col: 0,
            };
            sites.push((e, w.unknown));
        }
        let errors = sites.iter().map(|(_, n)| n).sum();
        ErrorCensus {
            samples,
            errors,
            sites,
        }
    }
}
